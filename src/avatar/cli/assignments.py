"""``NAME=VALUE`` options (``--set``, ``--measure``) into plain mappings."""

from __future__ import annotations

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
