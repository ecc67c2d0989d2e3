"""`avatar create --wear tshirt` end to end (a fresh process each time), against an anchor:
the same command on another commit (default: HEAD~1, or --against REV), checked out into a
temporary git worktree and run in the same session, alternating runs.

    python bench/create.py --against <commit-before-the-change> --runs 7

Prints the median wall time of each and the ratio (this tree / anchor).
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RUN = "import sys; from avatar.cli import main; sys.exit(main(sys.argv[1:]))"
ARGS = ["create", "--set", "gender=0.3", "--set", "pca/belly=1.5", "--wear", "tshirt",
        "--wear", "jeans", "--wear", "shoes"]  # fmt: skip


def once(src: Path, out: Path) -> float:
    env = dict(os.environ, PYTHONPATH=str(src))
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", RUN, *ARGS, "-o", str(out)], env=env, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
    return time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", default="HEAD~1", help="anchor commit (default HEAD~1)")
    parser.add_argument("--runs", type=int, default=5)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        anchor = Path(tmp) / "anchor"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(anchor),
                        args.against], check=True, capture_output=True)  # fmt: skip
        try:
            trees = {"this tree": ROOT / "src", f"anchor {args.against}": anchor / "src"}
            for src in trees.values():  # warm the asset cache and the page cache
                once(src, Path(tmp) / "warm.glb")
            times: dict[str, list[float]] = {k: [] for k in trees}
            for _ in range(args.runs):
                for key, src in trees.items():
                    times[key].append(once(src, Path(tmp) / "out.glb"))
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force",
                            str(anchor)], check=False, capture_output=True)  # fmt: skip
    median = {k: statistics.median(v) for k, v in times.items()}
    for key, value in median.items():
        print(f"{key:>24}: {value:.3f} s median of {args.runs} "
              f"({', '.join(f'{t:.2f}' for t in times[key])})")  # fmt: skip
    this, anchor_time = median.values()
    print(f"ratio this/anchor: {this / anchor_time:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
