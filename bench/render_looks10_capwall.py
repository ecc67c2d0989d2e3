"""Render the toe cap's side wall close up (docs/images/looks10_capwall_*.png): the man's
left shoe and sneaker and the woman's left boot from their outer side, aimed with
``render_looks9``'s ``--at`` (one shoe close).

    python bench/render_looks10_capwall.py OUT_DIR [NAME ...]   # all of SHOTS if no NAME
    python bench/render_looks9.py sheet BEFORE_DIR AFTER_DIR OUT.png capwall_s9-shoes_side ...

Needs the pip ``bpy`` module (Cycles on the CPU); each shot is its own process.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

LOOKS9 = str(Path(__file__).resolve().parent / "render_looks9.py")
SMALL = ["--size", "360", "--samples", "12"]
SHOTS = {  # name: render_looks9 arguments (the file is closeup_capwall_SET_VIEW.png)
    "man": ["s9-shoes", "--views", "side", "--at", "0.21,-0.16,0.11,0.03", "--name", "capwall",
            *SMALL],  # fmt: skip
    "boot": ["s9-boots", "--views", "side", "--at", "0.175,-0.15,0.11,0.03", "--name",
             "capwall", *SMALL],  # fmt: skip
    "sneaker": ["s9-sneakers", "--views", "side", "--at", "0.13,-0.08,0.1,0.03", "--name",
                "capwall", *SMALL],  # fmt: skip
}


def main() -> None:
    out, names = sys.argv[1], sys.argv[2:] or list(SHOTS)
    for name in names:
        subprocess.run([sys.executable, LOOKS9, *SHOTS[name], "--out", out], check=True)


if __name__ == "__main__":
    main()
