"""Render the tenth look pass's shoe pictures (docs/images/looks10_shoes_*.png): the sets and
framings of ``render_looks9`` (one body a picture), plus single-shoe close-ups aimed with
``--at`` (the man's left toe cap from in front and from its outer side, the woman's boot
lacing and bow) and the man's pair 80 cm across (2 mm a pixel: the vamp's creases from
afar).

    python bench/render_looks10_shoes.py OUT_DIR [NAME ...]   # all of SHOTS if no NAME
    python bench/render_looks9.py sheet BEFORE_DIR AFTER_DIR OUT.png one_s9-shoes_toe ...

Needs the pip ``bpy`` module (Cycles on the CPU); each shot is its own process.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

LOOKS9 = str(Path(__file__).resolve().parent / "render_looks9.py")
SMALL = ["--size", "360", "--samples", "12"]
SHOTS = {  # name: render_looks9 arguments (the file is NAME_SET_VIEW.png, or closeup_...)
    "pair": ["s9-shoes", "--views", "profile,toe,side", *SMALL],
    "boots": ["s9-boots", "--views", "side,toe", *SMALL],
    "sneakers": ["s9-sneakers", "--views", "profile", *SMALL],
    "one": ["s9-shoes", "--views", "toe", "--at", "0.21,-0.17,0.15,0.035", "--name", "one",
            *SMALL],  # fmt: skip
    "oneside": ["s9-shoes", "--views", "side", "--at", "0.21,-0.16,0.13,0.03", "--name",
                "oneside", *SMALL],  # fmt: skip
    "lacing": ["s9-boots", "--views", "toe", "--at", "0.173,-0.15,0.15,0.08", "--name", "one",
               *SMALL],  # fmt: skip
    "bow": ["s9-boots", "--views", "toe", "--at", "0.165,-0.1,0.12,0.175", "--name", "bow",
            *SMALL],  # fmt: skip
    "far": ["s9-shoes", "--views", "profile", "--at", "0.12,-0.12,0.8,0.25", "--name", "far",
            "--size", "400", "--samples", "16"],  # fmt: skip
}


def main() -> None:
    out, names = sys.argv[1], sys.argv[2:] or list(SHOTS)
    for name in names:
        subprocess.run([sys.executable, LOOKS9, *SHOTS[name], "--out", out], check=True)


if __name__ == "__main__":
    main()
