"""SHA-256 of the files `avatar create` writes for six fixed recipes (dressed, posed,
animated, every rig), through the CLI so the same script runs on any commit.

A refactor that must not change results runs this before and after and compares:

    python bench/recipe_hashes.py > before.txt   # on the old commit
    python bench/recipe_hashes.py | diff before.txt -
"""

from __future__ import annotations

import hashlib
import logging
import sys
import tempfile
from pathlib import Path

from avatar.cli import main as avatar

RECIPES = {
    "dressed-walk-default.glb": "--set gender=0.3 --set age=0.45 --set muscle=0.6 --wear tshirt "
    "--wear jeans --wear shoes --wear hair-short --wear eyebrows --wear eyelashes --motion walk "
    "--fps 10",
    "posed-game_engine.glb": "--set gender=1 --set pca/belly=1.5 --rig game_engine --wear hoodie "
    "--wear trousers --pose t-pose",
    "rest-mixamo.glb": "--set age=0.9 --set weight=0.8 --rig mixamo --wear dress --wear hair-long",
    "posed-cmu_mb.obj": "--set gender=0 --set height=0.8 --rig cmu_mb --pose a-pose",
    "walk-game_engine_with_breast.glb": "--set cupsize=0.9 --set gender=0 "
    "--rig game_engine_with_breast --wear tanktop --wear shorts --motion walk --fps 10",
    "measured-default_no_toes.obj": "--measure height=172 --rig default_no_toes",
}


def main() -> int:
    logging.disable(logging.INFO)
    with tempfile.TemporaryDirectory() as tmp:
        for name, args in RECIPES.items():
            path = Path(tmp) / name
            if avatar(["create", *args.split(), "-o", str(path)]) != 0:
                return 1
            print(f"{hashlib.sha256(path.read_bytes()).hexdigest()}  {name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
