"""Benchmark: evaluate a full body with Avatar against anny's forward pass, same CPU, same run.

Usage (from the repository root)::

    bash bench/setup_env.sh                    # once: .bench-venv with torch 2.13.0 (CPU) + anny
    .bench-venv/bin/python bench/shape.py      # Avatar and anny: default threads, then 1 thread
    .venv/bin/python bench/shape.py            # Avatar only (anny is skipped, and it says why)

Options: ``--threads N`` runs one pass with N threads (BLAS and torch); ``--batch B`` sets the
informational batch size (32); ``--seconds S`` the time budget of each timing (2);
``--no-cache`` skips the asset-cache timings. The goal (issue 2): at batch 1, Avatar at least
20x faster than anny and under 1 ms per update.

What is timed, each as the median of many single calls after a warm-up:

- Avatar "full update": ``model.shape(params)`` with all eleven macros, the seven attributes
  and twelve local targets, all changed on every call (16 random parameter sets in turn, so no
  memo helps), then the default 163-bone rig placed on it: ``rig.skeleton(vertices)`` (joint
  heads/tails and rest matrices with rolls; ``joint_positions`` alone is shown as well).
- Avatar "edits": one local slider, or one macro slider being dragged, changed per call: what
  an interactive update costs (``BodyModel`` memoises the macro sum; see ``MacroSum``).
- anny's forward pass ``model(phenotype_kwargs=..., local_changes_kwargs=...)`` (float32, no
  grad, identity pose, so it includes its skinning step) and its rest model alone
  (blend-shape coefficients -> ``get_rest_model``: vertices, bone heads/tails, rest poses),
  the like-for-like part. Two anny models: its defaults (``Anny(local_changes="default")``,
  6 phenotypes, 104-bone rig; local changes must be enabled to set twelve of them) and the
  closest match to Avatar (``rig="makehuman"``: the 163-bone rig, ``phenotypes="all"``).
- At batch B: Avatar has no batched API, so B bodies in a loop; anny takes (B, n) inputs.
- Asset cache: a cold build into a temporary ``AVATAR_CACHE`` (compile, then the attribute
  basis on first use) and a warm ``BodyModel.load()``.
"""

from __future__ import annotations

import argparse
import itertools
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from datetime import date

THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
MACRO_NAMES = ("gender", "age", "muscle", "weight", "height", "proportions", "cupsize",
               "firmness", "african", "asian", "caucasian")  # fmt: skip
ATTRIBUTES = ("breast", "shoulders_fat", "limbs_fat", "hips_fat", "weight", "strength", "belly")
LOCAL_TARGETS = (
    "torso/torso-scale-depth-decr|incr", "stomach/stomach-pregnant-decr|incr",
    "hip/hip-scale-horiz-decr|incr", "armslegs/l-upperarm-fat-decr|incr",
    "armslegs/r-upperarm-fat-decr|incr", "neck/neck-scale-depth-decr|incr",
    "head/head-scale-vert-decr|incr", "buttocks/buttocks-volume-decr|incr",
    "breast/breast-dist-decr|incr", "measure/measure-waist-circ-decr|incr",
    "armslegs/l-lowerleg-fat-decr|incr", "armslegs/r-lowerleg-fat-decr|incr",
)  # fmt: skip
SETS = 16  # distinct parameter sets cycled through, so every call changes every parameter


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--threads", type=int, help="one pass with this many threads")
    parser.add_argument("--batch", type=int, default=32)
    parser.add_argument("--seconds", type=float, default=2.0, help="budget of each timing")
    parser.add_argument("--no-cache", action="store_true", help="skip the asset-cache timings")
    args = parser.parse_args()
    if args.threads is None:  # both passes: this process, then a child limited to one thread
        run_pass(args, threads=None)
        env = os.environ | {v: "1" for v in THREAD_VARIABLES}
        cmd = [sys.executable, __file__, "--threads", "1", "--no-cache",
               "--batch", str(args.batch), "--seconds", str(args.seconds)]  # fmt: skip
        sys.stdout.flush()
        sys.exit(subprocess.call(cmd, env=env))
    for v in THREAD_VARIABLES:  # must precede numpy's import to bind its BLAS pool
        os.environ.setdefault(v, str(args.threads))
    run_pass(args, threads=args.threads)


def run_pass(args: argparse.Namespace, threads: int | None) -> None:
    import numpy as np

    torch, anny, why_not = import_anny()
    if torch is not None and threads is not None:
        torch.set_num_threads(threads)
    label = "default threads" if threads is None else f"{threads} thread(s)"
    print(f"\n=== pass: {label} ===")
    print_machine(np, torch, anny)
    if not args.no_cache:
        time_cache()

    from avatar.body.model import BodyModel
    from avatar.rig.placement import RigDefinition

    model = BodyModel.load()
    rig = RigDefinition.from_json("default", model.assets.rig("default"), model.base.groups)
    sets = parameter_sets(np.random.default_rng(2026), max(SETS, args.batch))
    avatar = time_avatar(model, rig, sets, args)
    if torch is None:
        print(f"\nanny: skipped ({why_not})")
        return
    for name, kwargs in ANNY_MODELS.items():
        t = time_anny(torch, anny, name, kwargs, sets, args)
        if t is None:
            continue
        print(f"  ratio anny/Avatar at batch 1 [{name}, {label}]:")
        for what, mine in (("forward", "full update"), ("rest model", "full update"),
                           ("forward", "local edit"), ("forward", "macro drag")):  # fmt: skip
            print(f"    anny {what:10s} / Avatar {mine:11s} {t[what] / avatar[mine]:6.1f}x")
        print("  goal at batch 1 (>= 20x anny's forward pass and < 1 ms per update):")
        for mine in ("full update", "local edit", "macro drag"):
            ratio, ms = t["forward"] / avatar[mine], avatar[mine] * 1e3
            verdict = "MET" if ratio >= 20 and ms < 1 else "NOT MET"
            print(f"    Avatar {mine:11s}: {verdict:7s} ({ratio:.1f}x, {ms:.3f} ms)")


# ----------------------------------------------------------------------------- environment


def import_anny():
    """(torch, anny, None) or (None, None, why they cannot be used)."""
    try:
        import torch  # type: ignore[import-not-found]
    except ImportError as exc:
        return None, None, f"torch is not importable: {exc}; run bash bench/setup_env.sh"
    try:
        import anny  # type: ignore[import-not-found]
    except Exception as exc:  # anny imports warp and more; any failure means no comparison
        return None, None, f"anny is not importable: {exc!r}; run bash bench/setup_env.sh"
    return torch, anny, None


def print_machine(np, torch, anny) -> None:
    import scipy

    print(f"date: {date.today()}  cpu: {cpu_model()}  cores: {os.cpu_count()}")
    print(f"python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}"
          + (f", torch {torch.__version__} ({torch.get_num_threads()} threads)" if torch else "")
          + (f", anny {anny.__version__}" if anny else ""))  # fmt: skip
    print("thread limits: " + (", ".join(f"{v}={os.environ[v]}" for v in THREAD_VARIABLES
                                         if v in os.environ) or "none"))  # fmt: skip


def cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


# ----------------------------------------------------------------------------- timing


def median_time(fn: Callable[[], object], seconds: float, warmup: int = 5) -> tuple[float, int]:
    """(median seconds of one call, calls timed): warm up, then time single calls."""
    for _ in range(warmup):
        fn()
    times: list[float] = []
    deadline = time.perf_counter() + seconds
    while len(times) < 10 or (time.perf_counter() < deadline and len(times) < 5000):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), len(times)


def report(name: str, seconds: float, calls: int, per: int = 1) -> None:
    extra = f"  ({seconds / per * 1e3:.3f} ms per body)" if per > 1 else ""
    print(f"  {name:44s} {seconds * 1e3:9.3f} ms  (median of {calls}){extra}")


# ----------------------------------------------------------------------------- the cache


def time_cache() -> None:
    """Cold build into a temporary AVATAR_CACHE (compile + attribute basis), then warm loads."""
    from avatar.body import assets
    from avatar.body.attributes import basis
    from avatar.body.model import BodyModel

    saved = os.environ.get("AVATAR_CACHE")
    print("asset cache (Avatar):")
    with tempfile.TemporaryDirectory(prefix="avatar-bench-cache-") as tmp:
        os.environ["AVATAR_CACHE"] = tmp
        try:
            t0 = time.perf_counter()
            assets.load()
            t1 = time.perf_counter()
            basis(BodyModel.load())  # the seven PCA attributes, computed once and cached
            t2 = time.perf_counter()
            print(f"  cold build: compile {t1 - t0:.2f} s + attribute basis {t2 - t1:.2f} s "
                  f"= {t2 - t0:.2f} s")  # fmt: skip
            loads = []
            for _ in range(5):
                t0 = time.perf_counter()
                model = BodyModel.load()
                t1 = time.perf_counter()
                model.shape({"pca/belly": 1.0})  # maps the arrays it needs, reads the basis
                loads.append((t1 - t0, time.perf_counter() - t1))
            load = statistics.median(a for a, _ in loads)
            first = statistics.median(b for _, b in loads)
            print(f"  warm BodyModel.load(): {load * 1e3:.1f} ms; then first shape "
                  f"{first * 1e3:.1f} ms (median of 5, page cache warm)")  # fmt: skip
        finally:
            if saved is None:
                os.environ.pop("AVATAR_CACHE", None)
            else:
                os.environ["AVATAR_CACHE"] = saved


# ----------------------------------------------------------------------------- Avatar


def parameter_sets(rng, n: int) -> list[dict[str, float]]:
    """n random full-body parameter sets (Avatar names): macros, attributes, local targets."""
    sets = []
    for _ in range(n):
        p = {m: rng.uniform(0.05, 0.95) for m in MACRO_NAMES}
        p |= {f"pca/{a}": rng.uniform(-2.0, 2.0) for a in ATTRIBUTES}
        p |= {t: rng.uniform(-1.0, 1.0) for t in LOCAL_TARGETS}
        sets.append(p)
    return sets


def time_avatar(model, rig, sets, args) -> dict[str, float]:
    """Print and return Avatar's timings (seconds)."""
    print(f"Avatar (numpy; {len(rig.names)}-bone '{rig.name}' rig; "
          f"{len(MACRO_NAMES)} macros + {len(ATTRIBUTES)} attributes + {len(LOCAL_TARGETS)} "
          "local targets):")  # fmt: skip
    model.shape(sets[0])  # loads the attribute basis
    counter = iter(range(10**9))

    def nxt() -> dict[str, float]:
        return sets[next(counter) % SETS]

    def full():
        return rig.skeleton(model.shape(nxt()))

    vertices = model.shape(sets[0])
    edit = dict(sets[0])
    values = itertools.cycle([-0.9, -0.3, 0.2, 0.7, 0.95])  # one slider's successive values

    def local_edit():
        edit[LOCAL_TARGETS[0]] = next(values)
        return rig.skeleton(model.shape(edit))

    drag = dict(sets[0])

    def macro_drag():
        drag["weight"] = (next(values) + 1.0) / 2.0
        return rig.skeleton(model.shape(drag))

    out = {}
    rows = [
        ("full update", full, 1),
        ("shape only", lambda: model.shape(nxt()), 1),
        ("skeleton (joints + rest matrices)", lambda: rig.skeleton(vertices), 1),
        ("joint_positions only", lambda: rig.joint_positions(vertices), 1),
        ("local edit (1 local slider) + skeleton", local_edit, 1),
        ("macro drag (weight slider) + skeleton", macro_drag, 1),
        (f"batch {args.batch}: full updates in a loop",
         lambda: [rig.skeleton(model.shape(p)) for p in sets[: args.batch]], args.batch),
    ]  # fmt: skip
    for name, fn, per in rows:
        t, n = median_time(fn, args.seconds)
        report(name, t, n, per)
        out[name.split(" (")[0].split(":")[0]] = t
    return out


# ----------------------------------------------------------------------------- anny

ANNY_MODELS = {
    "anny defaults": {"local_changes": "default"},
    "anny 163-bone rig, all phenotypes": {
        "rig": "makehuman", "phenotypes": "all", "local_changes": "default"},
}  # fmt: skip


def anny_local_name(avatar_name: str) -> str:
    """'torso/torso-scale-depth-decr|incr' -> anny's 'torso-scale-depth-incr' (value -1..1)."""
    short = avatar_name.split("/", 1)[1]
    stem, _, pair = short.rpartition("-")
    return f"{stem}-{pair.split('|')[1]}"


def time_anny(torch, anny, name, kwargs, sets, args) -> dict[str, float] | None:
    """Print and return anny's timings (seconds) for one model configuration."""
    t0 = time.perf_counter()
    try:
        model = anny.Anny(**kwargs).to(dtype=torch.float32)
    except Exception as exc:  # e.g. its first-use build failing: report and go on
        print(f"\n{name}: skipped ({exc!r})")
        return None
    build = time.perf_counter() - t0
    model.eval()
    pairs = [(t, anny_local_name(t)) for t in LOCAL_TARGETS]  # Avatar name, anny name
    pairs = [(t, a) for t, a in pairs if a in model.local_change_labels]
    print(f"{name}: Anny({', '.join(f'{k}={v!r}' for k, v in kwargs.items())}), float32, "
          f"{model.bone_count} bones, {len(model.phenotype_labels)} phenotypes, "
          f"{len(pairs)} local changes set, {model.blendshapes.shape[0]} blend shapes, "
          f"skinning {model._skinning_method.__module__}; built in {build:.1f} s")  # fmt: skip

    out = {}
    for batch in (1, args.batch):
        prepared = [anny_inputs(torch, model, sets, pairs, batch, i) for i in range(SETS)]
        with torch.inference_mode():
            for what, fn in anny_calls(model, prepared).items():
                t, n = median_time(fn, args.seconds, warmup=3)
                report(f"{what}, batch {batch}", t, n, batch)
                if batch == 1:
                    out[what] = t
    return out


def anny_inputs(torch, model, sets, pairs, batch: int, i: int):
    """(phenotype kwargs, local-change kwargs) for ``batch`` bodies from parameter set ``i`` on."""
    chosen = [sets[(i + b) % len(sets)] for b in range(batch)]
    if batch == 1:  # plain floats, as a caller would pass them
        one = chosen[0]
        return {k: one[k] for k in model.phenotype_labels}, {a: one[t] for t, a in pairs}
    ph = {k: torch.tensor([c[k] for c in chosen]) for k in model.phenotype_labels}
    return ph, {a: torch.tensor([c[t] for c in chosen]) for t, a in pairs}


def anny_calls(model, prepared) -> dict[str, Callable[[], object]]:
    """The two anny calls timed, each cycling through ``prepared`` inputs."""
    counter = iter(range(10**9))

    def forward():
        ph, lc = prepared[next(counter) % len(prepared)]
        return model(phenotype_kwargs=ph, local_changes_kwargs=lc)

    def rest():
        ph, lc = prepared[next(counter) % len(prepared)]
        _, p, c, f = model.get_tensor_inputs(None, ph, lc, None)
        return model.get_rest_model(model._get_phenotype_blendshape_coefficients(p, c, f))

    return {"forward": forward, "rest model": rest}


if __name__ == "__main__":
    main()
