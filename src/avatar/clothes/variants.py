"""Fabric and colour variants of the built-in garments.

A variant is a built-in worn in another colour or fabric: ``{"colour": "navy"}``,
``{"colour": "#3a5f8c", "fabric": "linen"}``. The geometry is the built-in's own; only
the material changes (``builtin.look`` on the spec with the variant's fabric and colour).
A recipe keeps each garment's options under ``garment_options`` ({entry: options}).

colour: a name of ``looks.fabrics.COLOURS`` or a custom sRGB ``"#rrggbb"`` (what a colour
picker gives). fabric: one of the garment's ``FABRIC_CHOICES`` (a T-shirt can be linen,
not leather). ``SWATCHES`` are the few colours a panel offers per category.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import replace

from avatar.clothes import builtin
from avatar.errors import ParameterError, unknown_name
from avatar.looks import fabrics

KEYS = ("colour", "fabric")
_HEX = re.compile(r"#[0-9a-fA-F]{6}")

SWATCHES: dict[str, tuple[str, ...]] = {
    "tops": ("white", "black", "grey", "navy", "red", "green", "sky", "burgundy"),
    "bottoms": ("indigo", "light indigo", "dark indigo", "black", "charcoal", "khaki",
                "beige", "navy"),  # fmt: skip
    "dresses": ("teal", "red", "navy", "black", "white", "pink", "burgundy", "yellow"),
    "swimwear": ("sky", "black", "red", "navy", "teal", "yellow"),
    "legwear": ("white", "black", "grey", "navy", "red"),
    "headwear": ("red", "navy", "black", "white", "khaki", "green"),
    "hair": ("dark brown hair", "black hair", "blond hair", "auburn hair", "grey hair"),
    "face": ("dark brown hair", "black hair", "blond hair", "auburn hair", "grey hair"),
    "beard": ("dark brown", "black hair", "blond hair", "auburn hair", "grey hair"),
}

# The fabrics that make sense per garment (its own first). Unlisted built-ins: their own.
FABRIC_CHOICES: dict[str, tuple[str, ...]] = {
    "tshirt": ("cotton", "jersey", "linen"),
    "longsleeve": ("jersey", "cotton", "linen"),
    "tanktop": ("jersey", "cotton", "linen"),
    "jacket": ("leather", "denim", "canvas", "wool"),
    "cardigan": ("knit", "wool"),
    "hoodie": ("knit", "jersey", "wool"),
    "shorts": ("canvas", "cotton", "denim", "linen"),
    "trousers": ("wool", "cotton", "linen", "cord"),
    "jeans": ("denim", "cord"),
    "sweatpants": ("jersey", "knit"),
    "skirt": ("cotton", "denim", "linen", "wool"),
    "dress": ("cotton", "linen", "jersey"),
    "socks": ("knit", "cotton"),
    "cap": ("canvas", "denim", "wool"),
}


def colours(name: str) -> tuple[str, ...]:
    """The swatch names offered for built-in ``name`` (empty: it has no colour variants,
    e.g. shoes, whose atlas of leather, sole and laces has colours of its own)."""
    spec = builtin.BY_NAME.get(name)
    return SWATCHES.get(spec.category, ()) if spec is not None else ()


def fabric_choices(name: str) -> tuple[str, ...]:
    """The fabrics built-in ``name`` may be made of (its own first)."""
    spec = builtin.BY_NAME.get(name)
    if spec is None or not colours(name):
        return ()
    return FABRIC_CHOICES.get(name, (spec.fabric,))


def check(name: str, options: Mapping[str, object] | None) -> dict[str, str]:
    """``options`` of garment ``name`` checked and normalised (hex colours lower case);
    {} for none. Raises ParameterError naming the problem: a garment that is not a
    variant-able built-in, an unknown key, colour or fabric."""
    if not options:
        return {}
    if not isinstance(options, Mapping):
        raise ParameterError(f"{name}: garment options must be a mapping, not {options!r}")
    if not colours(name):
        raise ParameterError(f"{name!r} has no colour or fabric variants (only the built-in "
                             "clothes, hair and face items have)")  # fmt: skip
    out: dict[str, str] = {}
    for key, value in options.items():
        if key not in KEYS:
            raise ParameterError(f"{name}: unknown garment option {key!r} (use colour, fabric)")
        if not isinstance(value, str):
            raise ParameterError(f"{name}: {key} must be a text, not {value!r}")
        if key == "colour":
            if _HEX.fullmatch(value):
                out[key] = value.lower()
            elif value in fabrics.COLOURS:
                out[key] = value
            else:
                raise unknown_name("colour (or #rrggbb)", value, fabrics.COLOURS)
        else:
            allowed = fabric_choices(name)
            if value not in allowed:
                raise ParameterError(f"{name} cannot be made of {value!r}: choose "
                                     f"{', '.join(allowed)}")  # fmt: skip
            out[key] = value
    return out


def is_default(name: str, options: Mapping[str, str]) -> bool:
    """True when ``options`` change nothing of built-in ``name``'s look."""
    spec = builtin.BY_NAME[name]
    return options.get("colour", spec.colour) == spec.colour and \
        options.get("fabric", spec.fabric) == spec.fabric  # fmt: skip


def spec(name: str, options: Mapping[str, str]) -> builtin.Spec:
    """Built-in ``name``'s spec in the (checked) variant ``options``."""
    base = builtin.BY_NAME[name]
    return replace(base, colour=options.get("colour", base.colour),
                   fabric=options.get("fabric", base.fabric))  # fmt: skip
