"""The extension ages a character's brows, facial hair and built-in hair as ``Human``
does (``library.dress(age=)``): when it is created, when its age is settled after a slider
change, and when the hair's colour variant changes (the brows follow). Skipped without the
MakeHuman assets."""

from __future__ import annotations

import numpy as np

LUMA = np.array([0.2126, 0.7152, 0.0722])
WORN = ["hair-short", "eyebrows", "moustache"]
# How much lighter an old wearer's items render than a young one's: facial hair less, as
# its dark shades are lifted (``looks.facial_hair.facial_lift``: x1.7 for dark hair) and
# its grey held at ``FACIAL_GREY`` of the scalp's (a white beard read as cotton wool).
# An item that did not grey at all stays near 1.
GREYING = {"hair-short": 2.5, "eyebrows": 2.5, "moustache": 2.0}


def _shown_luma(obj) -> float:
    """Mean luminance of the texels a part's material shows (alpha above a half)."""
    mat = obj.data.materials[0]
    bsdf = next(n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    image = bsdf.inputs["Base Color"].links[0].from_node.image  # wired straight in
    w, h = image.size
    px = np.empty(w * h * 4, np.float32)
    image.pixels.foreach_get(px)
    px = px.reshape(-1, 4)
    return float((px[px[:, 3] > 0.5, :3] @ LUMA).mean())


def _lumas(root) -> dict[str, float]:
    from avatar.blender import live

    parts = live.part_objects(root)
    return {name: _shown_luma(parts[name]) for name in WORN}


def test_created_characters_grey_with_age(empty_scene, assets):
    from avatar.blender import character

    young = character.create({"params": {"age": 0.4}, "clothes": WORN}, name="Young")
    old = character.create({"params": {"age": 0.95}, "clothes": WORN}, name="Old",
                           location=(1, 0, 0))  # fmt: skip
    a, b = _lumas(young.root), _lumas(old.root)
    for name in WORN:
        assert b[name] > GREYING[name] * a[name], (name, a[name], b[name])


def test_settling_an_age_change_greys_the_hair(empty_scene, assets):
    from avatar.blender import character, live

    built = character.create({"params": {"age": 0.4}, "clothes": WORN})
    before = _lumas(built.root)
    live.set_params(built.root, {"age": 0.95}, drag=True)
    live.settle(built.root)
    after = _lumas(built.root)
    for name in WORN:
        assert after[name] > GREYING[name] * before[name], (name, before[name], after[name])


def test_a_hair_colour_variant_carries_to_the_brows(empty_scene, assets):
    from avatar.blender import character, garment_looks

    built = character.create({"params": {"age": 0.4}, "clothes": WORN})
    dark = _lumas(built.root)
    garment_looks.set_options(built.root, "hair-short", {"colour": "blond hair"})
    blond = _lumas(built.root)
    assert blond["hair-short"] > 3 * dark["hair-short"]
    assert blond["eyebrows"] > 2 * dark["eyebrows"]
