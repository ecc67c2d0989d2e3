"""Kill `avatar dataset run` with SIGKILL at random moments, N times, then let it finish:
the resumed set must equal a clean run's (same files, same label bytes).

    python bench/dataset_kill.py [--kills 20] [--count 6]
"""

from __future__ import annotations

import argparse
import json
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CONFIG = """
seed = 5
[render]
resolution = [64, 64]
samples = 1
[people]
count = [1, 2]
"""
LABELS = ("depth.exr", "normals.exr", "parts.png", "instances.png", "meta.json")


def run(config: Path, out: Path, count: int, kill_after: float | None = None) -> int:
    cmd = [sys.executable, "-m", "avatar.cli", "dataset", "run", str(config), "-o", str(out),
           "-n", str(count)]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)  # fmt: skip
    if kill_after is None:
        return proc.wait()
    try:
        proc.wait(timeout=kill_after)
        return proc.returncode
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        return -9


def labels(out: Path, count: int) -> dict[str, bytes]:
    return {f"{i}/{name}": (out / "samples" / f"{i:08d}" / name).read_bytes()
            for i in range(count) for name in LABELS}  # fmt: skip


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kills", type=int, default=20)
    parser.add_argument("--count", type=int, default=16)
    parser.add_argument("--seed", type=int, default=0, help="of the kill moments")
    args = parser.parse_args()
    rng = random.Random(args.seed)
    with tempfile.TemporaryDirectory() as tmp:
        config = Path(tmp) / "ds.toml"
        config.write_text(CONFIG)
        start = time.perf_counter()
        assert run(config, Path(tmp) / "clean", args.count) == 0
        per_run = time.perf_counter() - start
        print(f"clean run: {args.count} samples in {per_run:.0f} s")
        out = Path(tmp) / "killed"
        kills = 0
        while kills < args.kills:
            code = run(config, out, args.count, kill_after=rng.uniform(1.0, 12.0))
            if code != -9:
                break  # it finished before the kill
            kills += 1
            manifest = out / "manifest.jsonl"
            done = manifest.read_text().count("\n") if manifest.exists() else 0
            print(f"kill {kills}: {done} samples finished so far")
        assert run(config, out, args.count) == 0
        lines = [json.loads(x) for x in (out / "manifest.jsonl").read_text().splitlines()]
        ids = sorted(e["id"] for e in lines)
        same = labels(out, args.count) == labels(Path(tmp) / "clean", args.count)
        print(f"{kills} kills; manifest ids {ids}; label bytes equal to the clean run: {same}")
        return 0 if same and ids == list(range(args.count)) else 1


if __name__ == "__main__":
    sys.exit(main())
