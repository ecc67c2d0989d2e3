"""Where an MPFB2 package is and which version it is, for ``bench/blender.py --mpfb``
(no Blender needed: the bench checks ``--mpfb`` before starting bpy)."""

from __future__ import annotations

import subprocess
import tomllib
from dataclasses import dataclass
from pathlib import Path


class MpfbError(RuntimeError):
    """MPFB2 cannot be registered or driven (one line for the bench to print)."""


@dataclass(frozen=True)
class Source:
    """Which MPFB2 is driven: its package folder, version and (when known) commit."""

    package: Path
    version: str
    commit: str | None

    def describe(self) -> str:
        return f"MPFB2 {self.version}" + (f" ({self.commit[:10]})" if self.commit else "")


def find_source(path: Path) -> Source:
    """The MPFB2 package under ``path``: a checkout's root (``src/mpfb``), ``src/`` or the
    package folder itself. Raises MpfbError when none is there or its data is incomplete."""
    candidates = [path, path / "mpfb", path / "src" / "mpfb"]
    package = next((p for p in candidates if (p / "blender_manifest.toml").is_file()), None)
    if package is None:
        raise MpfbError(f"{path}: no MPFB2 package (src/mpfb/blender_manifest.toml) there")
    manifest = tomllib.loads((package / "blender_manifest.toml").read_text())
    if manifest.get("id") != "mpfb":
        raise MpfbError(f"{package}: its manifest's id is {manifest.get('id')!r}, not 'mpfb'")
    weights = package / "data/rigs/standard/weights.default.json"
    if not weights.is_file() or weights.stat().st_size < 1000:
        raise MpfbError(f"{weights}: missing or a placeholder (a partial clone? "
                        "bench/mpfb_checkout.py fills it)")  # fmt: skip
    return Source(package.resolve(), str(manifest.get("version")), _commit(package))


def _commit(package: Path) -> str | None:
    """The commit of the checkout ``package`` is in: ``SOURCE.txt`` (bench/mpfb_checkout.py)
    or the git repository around it."""
    for folder in package.parents:
        record = folder / "SOURCE.txt"
        if record.is_file():
            return record.read_text().split()[2]
        head = folder / ".git"
        if head.exists():
            done = subprocess.run(["git", "-C", str(folder), "rev-parse", "HEAD"],
                                  capture_output=True, text=True)  # fmt: skip
            return done.stdout.strip() or None
    return None
