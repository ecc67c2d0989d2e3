"""Build and validate the Avatar Blender extension zip.

    python addon/build.py [--output dist/] [--platform linux-x64] [--python 3.11] [--no-wheel]

Steps: stage ``addon/avatar_addon`` in ``build/extension/``, stamp the manifest's version
from pyproject.toml, build the ``avatar`` library as a wheel into the stage's ``wheels/``,
download the wheels of the dependencies Blender lacks (SciPy, pykdtree for the clothes'
searches, Pillow for garment textures, and tqdm, which the garment bake of Apply (Motion)
imports; Blender ships numpy, and pygltflib is imported only by glTF export and the CLI,
which the add-on never calls: tests/blender/test_extension_envs.py runs it with pygltflib
blocked) for the target platform and
Blender's Python, list them in the manifest, then run Blender's own ``blender_ext.py build``
and ``validate`` on the result. ``blender_ext.py`` ships inside the pip ``bpy`` wheel
(``bpy/<version>/scripts/addons_core/bl_pkg/cli/blender_ext.py``) and runs on plain Python,
so no Blender binary is needed. Prints the zip's path.
"""

from __future__ import annotations

import argparse
import importlib.util
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SOURCE = ROOT / "addon" / "avatar_addon"
STAGE = ROOT / "build" / "extension"


def main(argv: list[str] | None = None) -> Path:
    args = _parse(argv)
    version = project_version()
    stage = stage_sources(STAGE / "avatar_addon")
    wheels = []
    if not args.no_wheel:
        wheels = [
            build_wheel(stage / "wheels"),
            *download_binary_wheels(stage / "wheels", args.platform, args.python),
        ]
    platforms = [args.platform] if wheels else []
    stamp_manifest(stage / "blender_manifest.toml", version, wheels, platforms)
    tool = args.blender_ext or find_blender_ext()
    args.output.mkdir(parents=True, exist_ok=True)
    suffix = f"-{args.platform}" if wheels else ""
    zip_path = args.output.resolve() / f"avatar_addon-{version}{suffix}.zip"
    _run(tool, "build", "--source-dir", stage, "--output-filepath", zip_path)
    _run(tool, "validate", zip_path)
    print(zip_path)
    return zip_path


def _parse(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", type=Path, default=ROOT / "dist")
    parser.add_argument("--blender-ext", type=Path, help="path to blender_ext.py")
    parser.add_argument(
        "--platform",
        default=host_platform(),
        choices=sorted(PIP_PLATFORMS),
        help="Blender platform the zip is for (default: this machine's)",
    )
    parser.add_argument(
        "--python",
        default="3.11",
        help="Blender's Python version (3.11: Blender 4.2-5.0; 3.13: 5.1+)",
    )
    parser.add_argument(
        "--no-wheel", action="store_true", help="leave the avatar library out (needs sys.path)"
    )
    return parser.parse_args(argv)


def project_version() -> str:
    """The one version, from pyproject.toml."""
    with open(ROOT / "pyproject.toml", "rb") as f:
        return tomllib.load(f)["project"]["version"]


def stage_sources(stage: Path) -> Path:
    """A clean copy of the add-on sources (no caches) at ``stage``."""
    if stage.exists():
        shutil.rmtree(stage)
    shutil.copytree(SOURCE, stage, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    return stage


def build_wheel(folder: Path) -> Path:
    """The avatar library as a pure-Python wheel in ``folder`` (no dependencies bundled:
    Blender ships numpy, and the modules the extension uses import nothing else eagerly)."""
    folder.mkdir(parents=True, exist_ok=True)
    _run(sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet", "-w", folder, ROOT)
    wheels = sorted(folder.glob("avatar-*.whl"))
    if not wheels:
        raise SystemExit(f"pip wheel produced no avatar wheel in {folder}")
    return wheels[-1]


def download_binary_wheels(folder: Path, platform: str, python: str) -> list[Path]:
    """SciPy's, Pillow's and pykdtree's binary wheels for ``platform`` and ``python``, the
    versions installed here (Blender ships numpy but none of these). pykdtree has no wheel
    for some platforms (older macOS tags); there the clothes code uses SciPy's k-d tree."""
    from importlib.metadata import version

    before = set(folder.glob("*.whl"))
    for packages, required in bundled_requirements(version):
        try:
            _run(sys.executable, "-m", "pip", "download", "--quiet", "--no-deps",
                 "--only-binary=:all:", "--python-version", python, "--platform",
                 PIP_PLATFORMS[platform], "-d", folder, *packages)  # fmt: skip
        except subprocess.CalledProcessError:
            if required:
                raise
            print(f"build: no {packages[0]} wheel for {platform}: SciPy's k-d tree is used")
    return sorted(set(folder.glob("*.whl")) - before)


def bundled_requirements(version) -> list[tuple[list[str], bool]]:
    """(pip requirements, required?) of the wheels the zip carries, pinned to the versions
    installed here (``version``: importlib.metadata.version). tqdm is pure Python."""
    return [
        ([f"scipy=={version('scipy')}", f"pillow=={version('pillow')}"], True),
        ([f"tqdm=={version('tqdm')}"], True),
        ([f"pykdtree=={version('pykdtree')}"], False),
    ]


PIP_PLATFORMS = {  # Blender platform name -> pip platform tag
    "linux-x64": "manylinux_2_28_x86_64",  # Blender 4.2+ itself needs glibc 2.28
    "linux-arm64": "manylinux_2_28_aarch64",
    "windows-x64": "win_amd64",
    "macos-arm64": "macosx_12_0_arm64",
    "macos-x64": "macosx_10_14_x86_64",
}


def host_platform() -> str:
    import platform

    machine = {"x86_64": "x64", "amd64": "x64", "aarch64": "arm64", "arm64": "arm64"}
    system = {"linux": "linux", "darwin": "macos", "windows": "windows"}
    return f"{system[platform.system().lower()]}-{machine[platform.machine().lower()]}"


def stamp_manifest(manifest: Path, version: str, wheels: list[Path], platforms: list[str]) -> None:
    """Set ``version``, ``wheels`` (paths relative to the manifest) and, when wheels are
    platform-specific, ``platforms`` in place."""
    text = manifest.read_text()
    text = re.sub(r'(?m)^version = ".*"$', f'version = "{version}"', text)
    listed = ", ".join(f'"./wheels/{w.name}"' for w in wheels)
    text = re.sub(r"(?m)^wheels = \[.*\]$", f"wheels = [{listed}]", text)
    if platforms:
        text = text.replace(
            "\nwheels = ", f"\nplatforms = {platforms!r}\nwheels = ".replace("'", '"')
        )
    manifest.write_text(text)


def find_blender_ext() -> Path:
    """blender_ext.py from the installed ``bpy`` module."""
    spec = importlib.util.find_spec("bpy")
    if spec is None or spec.origin is None:
        raise SystemExit("bpy is not installed: pip install bpy==5.0.1, or pass --blender-ext")
    found = sorted(Path(spec.origin).parent.glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
    if not found:
        raise SystemExit("blender_ext.py not found inside the bpy package; pass --blender-ext")
    return found[-1]


def _run(*command: object) -> None:
    # blender_ext.py only needs the standard library: run it on this interpreter.
    if str(command[0]).endswith(".py"):
        command = (sys.executable, *command)
    subprocess.run([str(c) for c in command], check=True)


if __name__ == "__main__":
    main()
