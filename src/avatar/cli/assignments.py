"""``NAME=VALUE`` options (``--set``, ``--measure``) into plain mappings."""

from __future__ import annotations

import math
from collections.abc import Sequence

from avatar.errors import ParameterError


def parse_assignments(items: Sequence[str], flag: str = "--set") -> dict[str, float]:
    """["gender=1", "pca/belly=1.5"] -> {"gender": 1.0, "pca/belly": 1.5}."""
    out: dict[str, float] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise ParameterError(f"{flag} expects NAME=VALUE, got {item!r}")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            raise ParameterError(f"{flag} {name}: {value!r} is not a number") from None
    return out


def parse_measurements(items: Sequence[str]) -> dict[str, float]:
    """``--measure`` options ["height=180", "waist=85"] (cm) -> {"height": 1.8, ...} in
    metres; a measurement that is not a positive finite length is a ParameterError."""
    out = {}
    for name, cm in parse_assignments(items, "--measure").items():
        if not math.isfinite(cm) or cm <= 0:
            raise ParameterError(f"--measure {name}: a measurement is a positive length in cm, "
                                 f"got {cm:g}")  # fmt: skip
        out[name] = cm / 100.0
    return out
