"""Material records become node trees with the right pixels; exporters write files."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from bridge_fixtures import figure


@dataclass(frozen=True)
class FakeMaterial:
    """The fields of avatar.material.Material the bridge reads."""

    name: str
    base_color: tuple = (0.8, 0.5, 0.4)
    roughness: float = 0.45
    base_color_texture: np.ndarray | None = None
    normal_texture: np.ndarray | None = None
    roughness_texture: np.ndarray | None = None


def test_material_node_tree_and_texture_pixels(empty_scene, rng):
    from avatar.blender import materials

    colour = rng.integers(0, 256, size=(8, 4, 3), dtype=np.uint8)
    normal = np.full((4, 4, 3), 128, np.uint8)
    rough = rng.random((4, 4)).astype(np.float32)
    record = FakeMaterial(
        "skin", base_color_texture=colour, normal_texture=normal, roughness_texture=rough
    )
    mat = materials.material(record)
    nodes = mat.node_tree.nodes
    bsdf = nodes["Principled BSDF"]
    assert bsdf.inputs["Base Color"].links[0].from_node.image.name == "skin colour"
    assert bsdf.inputs["Normal"].links[0].from_node.type == "NORMAL_MAP"
    assert bsdf.inputs["Roughness"].is_linked
    image = bsdf.inputs["Base Color"].links[0].from_node.image
    assert tuple(image.size) == (4, 8)
    pixels = np.empty(8 * 4 * 4, np.float32)
    image.pixels.foreach_get(pixels)
    top_row_first = pixels.reshape(8, 4, 4)[::-1, :, :3]
    np.testing.assert_allclose(top_row_first, colour / 255.0, atol=1 / 255)
    assert image.packed_file is not None
    roughness_image = bsdf.inputs["Roughness"].links[0].from_node.image
    assert roughness_image.colorspace_settings.name == "Non-Color"


def test_scalar_material_and_none(empty_scene):
    from avatar.blender import materials

    mat = materials.material(FakeMaterial("cloth"))
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    assert bsdf.inputs["Roughness"].default_value == pytest.approx(0.45)
    assert tuple(bsdf.inputs["Base Color"].default_value)[:3] == pytest.approx((0.8, 0.5, 0.4))
    assert materials.material(None, "grey").name == "grey"


@pytest.mark.parametrize("suffix", [".fbx", ".usdc", ".blend"])
def test_export_writes_a_file(empty_scene, rng, tmp_path, suffix):
    from avatar.blender import export
    from avatar.blender.scene import build_character

    built = build_character(figure(rng))
    path = export.export(tmp_path / f"figure{suffix}", [built.root])
    assert path.stat().st_size > 1000


def test_export_rejects_unknown_suffix(empty_scene, tmp_path):
    from avatar.blender import export
    from avatar.errors import AvatarError

    with pytest.raises(AvatarError, match="cannot export"):
        export.export(tmp_path / "x.dae")
