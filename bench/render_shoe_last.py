"""Render shoes close (docs/images/looks7_shoes_*.png): Avatar's built-in shoes, black
shoes, sneakers and boots on four feet, bare legs, and MakeHuman's CC0 shoes01/shoes02 on
the same bodies for comparison, with ``render_closeups``' cameras.

    python bench/render_shoe_last.py avatar --views side,front,profile --samples 16
    python bench/render_shoe_last.py makehuman --views side   # needs ../shared/fixtures

Needs the pip ``bpy`` module (Cycles on the CPU).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import render_closeups as closeups  # noqa: E402

FIXTURES = Path(__file__).resolve().parents[2] / "shared" / "fixtures" / "makehuman" / "clothes"
BODIES = [{"gender": 1.0, "age": 0.5}, {"gender": 0.0, "age": 0.45},
          {"gender": 0.3, "age": 0.12}, {"gender": 1.0, "age": 0.9, "weight": 0.9}]  # fmt: skip


def _mhclo(name: str) -> str:
    return str(FIXTURES / name / f"{name}.mhclo")


SETS = {
    "avatar": list(zip(BODIES, [("socks", "shoes"), ("shoes-black",), ("sneakers",),
                                ("boots",)], strict=True)),  # fmt: skip
    "makehuman": list(zip(BODIES, [(_mhclo("shoes01"),), (_mhclo("shoes01"),),
                                   (_mhclo("shoes02"),), (_mhclo("shoes01"),)], strict=True)),
}  # fmt: skip
# One body each, framed close: python bench/render_shoe_last.py one-sneakers --views side
for _body, _names in SETS["avatar"]:
    SETS[f"one-{_names[-1]}"] = [(_body, _names)]
    SETS[f"mh-{_names[-1]}"] = SETS["makehuman"][SETS["avatar"].index((_body, _names)):][:1]
# The eighth look pass: a man in shoes, a woman in boots, a child in sneakers.
SETS["s8"] = [({"gender": 1.0, "age": 0.5}, ("socks", "shoes")),
              ({"gender": 0.0, "age": 0.45}, ("boots",)),
              ({"gender": 0.3, "age": 0.12}, ("sneakers",))]  # fmt: skip
for _body, _names in SETS["s8"]:
    SETS[f"s8-{_names[-1]}"] = [(_body, _names)]
FRAMING = {name: (0.42 if len(s) > 1 else 0.6, 0.6, 0.06) for name, s in SETS.items()}
VIEWS = {"profile": (0.6, -1.0, 0.12), "side": (1.0, 0.0, 0.08)}


def main() -> None:
    closeups.SETS.update(SETS)
    closeups.FRAMING.update(FRAMING)
    closeups.VIEWS.update(VIEWS)
    closeups.main()


if __name__ == "__main__":
    main()
