"""The Blender extension's speed in pip bpy: create, dressed create, slider changes.

    .venv/bin/python bench/blender.py [--repeat 15] [--garments tshirt,jeans,shoes]

Installs the extension zip (built here, ``--no-wheel``) into a private user folder and
drives it as a script or slider does:

- create a bare human (no rig, no clothes) and a dressed, rigged one (hair, brows, lashes
  and ``--garments``) with ``bpy.ops.avatar.create_human`` + ``wear``-equivalent recipes;
- one slider change (``obj.avatar.weight = v``) on each: mesh, rest bones and garments
  written in place (real-time garment fit), timed until the property assignment returns;
- the settle that follows a change (exact garments, skin texture, measurements).

Anchor, measured in the same run: the pre-live extension's path for a change, a whole
rebuild of the character (``export.character`` + ``scene.build_character``, what the
**Update** button did). The issue's MPFB2 2.0.17 figures (same kind of machine, same
process) are printed beside: 0.29 s create, 1.71 s dressed create, 42 ms bare change,
0.28 s dressed change. ``--mpfb`` is not driven yet (no MPFB2 checkout on these machines).

Medians over ``--repeat`` runs, after one warm-up (which builds the garments, skin texture
and template meshes once per session). Threads: numpy/BLAS and pykdtree may use all cores;
on shared machines set OMP_NUM_THREADS=1 (the README's figures say which).
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MPFB2 = {"create": 0.29, "dressed create": 1.71, "bare change": 0.042, "dressed change": 0.28}
GOALS = {"dressed create": 0.2, "bare change": 0.005, "dressed change": 0.017}


def main() -> None:
    args = _parse()
    os.environ["BLENDER_USER_RESOURCES"] = tempfile.mkdtemp(prefix="avatar-bench-")
    import bpy

    zip_path = _build_zip()
    assert bpy.ops.extensions.package_install_files(
        filepath=str(zip_path), repo="user_default", enable_on_install=True
    ) == {"FINISHED"}
    from avatar.blender import character, scene

    dressed = ["hair-short", "eyebrows", "eyelashes", *args.garments.split(",")]
    scene.clear_scene()
    results = {
        "create": _time_create(bpy, [], False, args.repeat),
        "dressed create": _time_create(bpy, dressed, True, args.repeat),
    }
    bare = character.create({"params": {}}, rigged=False, exact=True).root
    rigged = character.create({"params": {}, "clothes": dressed}, exact=True).root
    results["bare change"] = _time_changes(bare, args.repeat)
    results["dressed change"] = _time_changes(rigged, args.repeat)
    results["dressed settle"] = _time_settle(bpy, rigged, args.repeat)
    anchor = _time_rebuild(rigged, max(3, args.repeat // 3))
    _report(bpy, results, anchor, dressed)


def _parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--garments", default="tshirt,jeans,shoes")
    parser.add_argument("--mpfb", type=Path, help="an MPFB2 checkout (not driven yet)")
    args = parser.parse_args()
    if args.mpfb is not None:
        sys.exit("--mpfb: driving MPFB2 is not implemented; the issue's figures are printed")
    return args


def _build_zip() -> Path:
    spec = importlib.util.spec_from_file_location("avatar_addon_build", ROOT / "addon/build.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.main(["--output", tempfile.mkdtemp(prefix="avatar-bench-zip-"), "--no-wheel"])


def _time_create(bpy, clothes, rigged, repeat) -> list[float]:
    """Seconds of ``character.create`` (real-time garment fit, as the Create button), each
    human added next to the others, as a user adds them (they share materials)."""
    from avatar.blender import character, scene

    times = []
    for _ in range(repeat + 1):
        start = time.perf_counter()
        character.create({"params": {}, "clothes": clothes}, rigged=rigged, exact=False)
        times.append(time.perf_counter() - start)
    scene.clear_scene()
    return times[1:]


def _time_changes(root, repeat) -> list[float]:
    """Seconds of one ``obj.avatar.weight = v`` (what a slider step does)."""
    times = []
    for i in range(repeat + 1):
        start = time.perf_counter()
        root.avatar.weight = 0.3 + 0.4 * (i % 2) + 0.001 * i
        times.append(time.perf_counter() - start)
    return times[1:]


def _time_settle(bpy, root, repeat) -> list[float]:
    from avatar.blender import live

    times = []
    for i in range(repeat):
        root.avatar.weight = 0.4 + 0.01 * i
        start = time.perf_counter()
        live.settle(root)
        times.append(time.perf_counter() - start)
    return times


def _time_rebuild(root, repeat) -> list[float]:
    """The anchor: a whole rebuild of the dressed character (the old Update button)."""
    import json

    from avatar import export
    from avatar.blender import character, scene
    from avatar.human import Human

    recipe = json.loads(root["avatar_recipe"])
    times = []
    for i in range(repeat):
        recipe["params"]["weight"] = 0.35 + 0.01 * i
        start = time.perf_counter()
        human = Human.from_recipe(recipe)
        built = scene.build_character(export.character(human, name="anchor"))
        times.append(time.perf_counter() - start)
        character.remove(built.root)
    return times


def _report(bpy, results, anchor, dressed) -> None:
    print(f"bpy {bpy.app.version_string}, {os.cpu_count()} cores, "
          f"OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS', 'unset')}")  # fmt: skip
    print(f"dressed = {', '.join(dressed)}; medians (min-max), seconds")
    rebuild = statistics.median(anchor)
    print(f"  anchor: whole rebuild (old Update)   {rebuild:8.4f}")
    for name, times in results.items():
        median = statistics.median(times)
        line = f"  {name:<16} {median:8.4f} ({min(times):.4f}-{max(times):.4f})"
        line += f"  x{rebuild / median:6.1f} faster than the rebuild"
        if name in MPFB2:
            line += f", x{MPFB2[name] / median:5.1f} vs MPFB2's {MPFB2[name]:g}"
        if name in GOALS:
            line += f", goal {GOALS[name]:g}: {'met' if median < GOALS[name] else 'MISSED'}"
        print(line)


if __name__ == "__main__":
    main()
