"""The extension zip builds, validates, installs into Blender and its operators work."""

from __future__ import annotations

import importlib.util
import tomllib
import zipfile
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def load_build_script():
    spec = importlib.util.spec_from_file_location("avatar_addon_build", ROOT / "addon/build.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def extension_zip(tmp_path_factory):
    # --no-wheel: the tests import `avatar` from this checkout; the wheel step is pip's job.
    out = tmp_path_factory.mktemp("dist")
    return load_build_script().main(["--output", str(out), "--no-wheel"])


@pytest.fixture(scope="module")
def installed(extension_zip):
    import bpy

    result = bpy.ops.extensions.package_install_files(
        filepath=str(extension_zip), repo="user_default", enable_on_install=True
    )
    assert result == {"FINISHED"}
    yield
    bpy.ops.preferences.addon_disable(module="bl_ext.user_default.avatar_addon")


def test_zip_manifest_is_stamped_from_pyproject(extension_zip):
    with open(ROOT / "pyproject.toml", "rb") as f:
        version = tomllib.load(f)["project"]["version"]
    with zipfile.ZipFile(extension_zip) as z:
        manifest = tomllib.loads(z.read("blender_manifest.toml").decode())
        assert {"__init__.py", "operators.py", "panels.py"} <= set(z.namelist())
    assert manifest["version"] == version
    assert manifest["id"] == "avatar_addon"


def test_panels_and_operators_register(installed):
    import bpy

    for panel in ("AVATAR_PT_body", "AVATAR_PT_dress", "AVATAR_PT_motion"):
        assert hasattr(bpy.types, panel)
    for op in ("create_human", "update_human", "wear", "take_off", "apply_motion"):
        assert hasattr(bpy.ops.avatar, op)


def test_create_and_update_through_operators(installed, empty_scene, monkeypatch):
    import bpy
    from bridge_fixtures import box_mesh, skeleton

    from avatar.blender import character
    from avatar.errors import ParameterError

    def fake_realise(recipe):
        if recipe["params"]["height"] > 0.9:
            raise ParameterError("height too tall for this test")
        mesh = box_mesh((0, 0, 0), (0.4, 0.3, 1 + recipe["params"]["height"]))
        return _Fake(mesh, skeleton(np.random.default_rng(0)), recipe)

    monkeypatch.setattr(character, "realise", fake_realise)
    settings = bpy.context.scene.avatar
    settings.height = 0.25
    assert bpy.ops.avatar.create_human() == {"FINISHED"}
    root = bpy.context.view_layer.objects.active
    assert character.recipe_of(root)["params"]["height"] == pytest.approx(0.25)
    settings.height = 0.75
    assert bpy.ops.avatar.update_human() == {"FINISHED"}
    root = bpy.context.view_layer.objects.active
    assert character.recipe_of(root)["params"]["height"] == pytest.approx(0.75)
    settings.height = 0.95
    with pytest.raises(RuntimeError, match="too tall"):  # AvatarError -> an error report
        bpy.ops.avatar.update_human()


class _Fake:
    def __init__(self, mesh, skel, recipe):
        self.mesh, self.skeleton, self._recipe = mesh, skel, recipe
        self.weights = (np.zeros((8, 1), np.int32), np.ones((8, 1)))

    def to_recipe(self):
        return self._recipe

    def parts(self):
        from avatar.part import MeshPart

        return [MeshPart("body", self.mesh, None, self.weights)]


def test_dress_library_lists_the_builtin_garments(installed):
    import bpy

    assert bpy.ops.avatar.refresh_library() == {"FINISHED"}
    garments = bpy.context.scene.avatar.garments
    assert len(garments) >= 14
    assert all(g.entry for g in garments)


@pytest.fixture
def character_and_vest(installed, empty_scene):
    """A real character away from the origin, and a vest modelled on it: its torso skin
    pushed out 1 cm along the normals, as an unparented mesh object in world space."""
    import bpy

    from avatar.blender import character, mesh
    from avatar.errors import AssetError
    from avatar.mesh import vertex_normals

    bpy.context.scene.cursor.location = (0.5, 0.2, 0.0)
    try:
        assert bpy.ops.avatar.create_human() == {"FINISHED"}
    except RuntimeError as exc:
        pytest.skip(f"no character without the MakeHuman assets: {exc}")
    root = bpy.context.view_layer.objects.active
    try:
        human = character.realise(character.recipe_of(root))
    except AssetError as exc:
        pytest.skip(f"MakeHuman assets not installed: {exc}")
    base = human.model.base
    body = base.faces[base.face_groups["body"]]
    v = human.vertices
    normals = vertex_normals(v, body)
    torso = np.all((v[body, 2] > 1.0) & (v[body, 2] < 1.3) & (np.abs(v[body, 0]) < 0.15), axis=1)
    vest = base.with_vertices(v + 0.01 * normals).subset(np.flatnonzero(torso))
    obj = mesh.new_mesh_object("Vest", vest.with_vertices(vest.vertices + root.location))
    for o in bpy.context.view_layer.objects:
        o.select_set(o is obj)
    bpy.context.view_layer.objects.active = obj
    return human, vest, obj


def test_bind_selected_as_garment(character_and_vest, tmp_path, monkeypatch):
    import bpy

    from avatar.clothes.binding import fit
    from avatar.clothes.library import load_garment

    monkeypatch.setenv("AVATAR_CLOTHES_PATH", "")  # the operator adds the folder it saved in
    human, vest, obj = character_and_vest
    body = next(o for o in bpy.data.objects if o.parent is not None and o.type == "MESH")
    body.select_set(True)  # the user picks the body too, last (the far test finds it alone)
    bpy.context.view_layer.objects.active = body
    folder = tmp_path / "mine"
    result = bpy.ops.avatar.bind_garment(name="vest", folder=str(folder), tags="top")
    assert result == {"FINISHED"}
    assert {p.name for p in folder.iterdir()} == {"vest.mhclo", "vest.obj", "vest.mhmat"}
    garment = load_garment(folder / "vest.mhclo")
    assert garment.mesh.uvs is not None and len(garment.mesh.vertices) == len(vest.vertices)
    error = np.abs(fit(garment.binding, human.vertices) - vest.vertices).max()
    assert error < 1e-3  # the authoring body gives the garment back (before collisions)
    settings = bpy.context.scene.avatar
    listed = settings.garments[settings.garment_index]
    assert (listed.name, listed.entry) == ("vest", str(folder / "vest.mhclo"))
    root = next(o for o in bpy.data.objects if "avatar_recipe" in o.keys())
    bpy.context.view_layer.objects.active = root
    assert bpy.ops.avatar.wear() == {"FINISHED"}  # worn on the body right away
    assert "vest" in bpy.data.objects


def test_a_garment_far_from_the_body_is_refused(character_and_vest, tmp_path):
    import bpy

    _, _, obj = character_and_vest
    obj.location.x += 2.0  # modelled nowhere near the character (the nearest one)
    folder = tmp_path / "far"
    with pytest.raises(RuntimeError, match="from the body"):
        bpy.ops.avatar.bind_garment(name="vest", folder=str(folder))
    assert not folder.exists()
