"""The extension zip builds, validates, installs into Blender, and its operators and live
properties work on real characters (MakeHuman assets; skipped without them)."""

from __future__ import annotations

import json
import os
import resource
import tomllib
import zipfile
from pathlib import Path

import numpy as np
import pytest

from avatar.body.shaped import PART_GROUPS

ROOT = Path(__file__).resolve().parents[2]
FIXTURES = Path(os.environ.get("AVATAR_FIXTURES", ROOT.parent / "shared" / "fixtures"))
WALK = FIXTURES / "bvh" / "cmu_motionbuilder" / "02_01_walk.bvh"


from extension_fixtures import load_build_script  # noqa: E402,F401 - the envs tests use it


def _state(root):
    """Everything a failed operator must leave alone: objects, vertices, recipe."""
    from avatar.blender import live, mesh

    parts = live.part_objects(root)
    return (root["avatar_recipe"], sorted(parts),
            {n: mesh.read_vertices(o).copy() for n, o in parts.items()})  # fmt: skip


def _assert_same_state(before, after):
    assert before[0] == after[0] and before[1] == after[1]
    for name in before[1]:
        np.testing.assert_array_equal(before[2][name], after[2][name])


def _assert_matches_fresh_human(root, tolerance=1e-4):
    """Body, skeleton and garments equal those of a Human realised from the stored recipe."""
    from avatar.blender import armature, live, mesh
    from avatar.human import Human

    fresh = Human.from_recipe(json.loads(root["avatar_recipe"]))
    parts = live.part_objects(root)
    np.testing.assert_allclose(mesh.read_vertices(parts["body"]), fresh.mesh.vertices,
                               atol=tolerance)  # fmt: skip
    for part in PART_GROUPS:  # eyes (teeth, tongue, ...): helpers that follow the body
        if part != "body":
            want = fresh.part(part).vertices  # as a Human renders it (teeth in their bite)
            np.testing.assert_allclose(mesh.read_vertices(parts[part]), want, atol=tolerance)
    if root.type == "ARMATURE":
        rest = armature.rest_matrices(root, fresh.skeleton.names)
        np.testing.assert_allclose(rest, fresh.skeleton.rest, atol=tolerance)
    for garment in fresh.outfit.garments if fresh.recipe.clothes else ():
        np.testing.assert_allclose(mesh.read_vertices(parts[garment.name]),
                                   garment.mesh.vertices, atol=tolerance)  # fmt: skip


def test_zip_manifest_is_stamped_from_pyproject(extension_zip):
    with open(ROOT / "pyproject.toml", "rb") as f:
        version = tomllib.load(f)["project"]["version"]
    with zipfile.ZipFile(extension_zip) as z:
        manifest = tomllib.loads(z.read("blender_manifest.toml").decode())
        names = set(z.namelist())
    assert {"__init__.py", "operators.py", "panels.py", "live.py", "thumbnails.py"} <= names
    assert manifest["version"] == version
    assert manifest["id"] == "avatar_addon"


def test_panels_operators_and_properties_register(installed):
    import bpy

    for panel in ("AVATAR_PT_body", "AVATAR_PT_dress", "AVATAR_PT_motion"):
        assert hasattr(bpy.types, panel)
    for op in ("create_human", "wear", "take_off", "toggle_garment", "apply_motion", "settle",
               "randomise", "apply_preset", "save_preset", "fit_measurements", "import_mhm",
               "export_mhm", "reset_body", "bind_garment"):  # fmt: skip
        assert hasattr(bpy.ops.avatar, op), op
    props = bpy.types.Object.bl_rna.properties["avatar"].fixed_type.bl_rna.properties
    names = ("gender", "age", "muscle", "weight", "height", "proportions", "cupsize",
             "firmness", "african", "asian", "caucasian", "pca_belly", "pca_breast")  # fmt: skip
    for name in names:
        assert props[name].type == "FLOAT", name


def test_a_new_human_is_active_rigged_with_hair_brows_and_lashes(human):
    from avatar.blender import live

    assert human.type == "ARMATURE" and human.select_get()
    assert set(live.part_objects(human)) == {*PART_GROUPS, "hair-short", "eyebrows", "eyelashes"}
    assert human.avatar.gender == pytest.approx(0.5)
    assert human.avatar.measured_height > 150  # cm, refreshed by the settle
    assert len(human.avatar.modifiers) > 250  # every local modifier and face unit
    _assert_matches_fresh_human(human)


def test_setting_a_property_updates_the_character_in_place(human):
    import bpy

    from avatar.blender import live

    parts = live.part_objects(human)
    pointers = {n: (o.as_pointer(), o.data.as_pointer()) for n, o in parts.items()}
    counts = (len(bpy.data.objects), len(bpy.data.meshes), len(bpy.data.materials),
              len(bpy.data.images))  # fmt: skip
    human.avatar.weight = 0.9  # as a slider does: the body moves at once
    human.avatar.pca_belly = 1.5
    human.avatar.modifiers["torso/torso-scale-depth-decr|incr"].value = 0.4
    bpy.ops.avatar.settle()
    recipe = json.loads(human["avatar_recipe"])
    assert recipe["params"]["weight"] == pytest.approx(0.9)
    assert recipe["params"]["torso/torso-scale-depth-decr|incr"] == pytest.approx(0.4)
    _assert_matches_fresh_human(human)
    after = {n: (o.as_pointer(), o.data.as_pointer()) for n, o in live.part_objects(human).items()}
    assert after == pointers  # the same objects and meshes: written, not re-created
    assert counts == (len(bpy.data.objects), len(bpy.data.meshes), len(bpy.data.materials),
                      len(bpy.data.images))  # fmt: skip


def test_the_real_time_fit_is_close_to_the_exact_one(human):
    from avatar.blender import live, mesh
    from avatar.human import Human

    human.avatar.weight = 1.0  # no settle: the garments as a drag shows them
    fresh = Human.from_recipe(json.loads(human["avatar_recipe"]))
    parts = live.part_objects(human)
    for garment in fresh.outfit.garments:
        got = mesh.read_vertices(parts[garment.name])
        assert np.abs(got - garment.mesh.vertices).max() < 0.005  # within 5 mm before settling


def test_ethnicity_is_a_normalised_mix(human):
    props = human.avatar
    props.african = 0.6
    assert props.african + props.asian + props.caucasian == pytest.approx(1.0)
    assert props.asian == pytest.approx(0.2) and props.caucasian == pytest.approx(0.2)
    props.asian = 0.0
    assert props.african + props.caucasian == pytest.approx(1.0)
    assert props.african / props.caucasian == pytest.approx(0.6 / 0.2)


def test_skin_follows_ethnicity_once_settled_and_old_material_goes(human):
    import bpy

    from avatar.blender import live

    body = live.part_objects(human)["body"]
    before = body.data.materials[0].name
    images = len(bpy.data.images)
    human.avatar.african = 0.9
    bpy.ops.avatar.settle()
    assert body.data.materials[0].name != before
    assert before not in bpy.data.materials  # nothing used it any more
    assert len(bpy.data.images) == images


def _user_skin(folder: Path, name: str, rgb, texture: bool = True) -> Path:
    """A MakeHuman skin in ``folder``/skins/``name``: a one-colour diffuse texture and a
    ``.thumb``, as MakeHuman ships them (``texture=False``: the texture line only)."""
    from avatar.io import png

    skin = folder / "skins" / name
    skin.mkdir(parents=True)
    image = np.zeros((64, 64, 3), np.uint8) + np.array(rgb, np.uint8)
    if texture:
        png.write(skin / f"{name}_diffuse.png", image)
    png.write(skin / f"{name}.thumb", image)
    (skin / f"{name}.mhmat").write_text(f"name {name}\ndiffuseColor 1 1 1\n"
                                        f"diffuseTexture {name}_diffuse.png\n")  # fmt: skip
    return skin / f"{name}.mhmat"


def _texels(obj) -> np.ndarray:
    """(N, 3) the colours (0..1) of the image in ``obj``'s material (its first)."""
    image = next(n.image for n in obj.data.materials[0].node_tree.nodes
                 if n.type == "TEX_IMAGE" and n.image is not None)  # fmt: skip
    pixels = np.empty(len(image.pixels), np.float32)
    image.pixels.foreach_get(pixels)
    return pixels.reshape(-1, image.channels)[:, :3]


def _texture_mean(obj) -> np.ndarray:
    return _texels(obj).mean(axis=0)


def test_a_users_makehuman_skin_is_listed_and_worn_and_a_broken_one_changes_nothing(
        human, tmp_path, monkeypatch):  # fmt: skip
    """The Body panel lists the user's textured MakeHuman skins (from their asset folders,
    with their ``.thumb``); a click puts one on, it stays through a settle (ethnicity no
    longer repaints it), "Avatar" gives the procedural skin back; a skin whose texture is
    missing is an error report that leaves the skin as it was."""
    import importlib

    import bpy
    from extension_fixtures import ADDON

    from avatar.blender import live

    catalogue = importlib.import_module(f"{ADDON}.catalogue")
    tanned = _user_skin(tmp_path, "tanned", (150, 90, 60))
    broken = _user_skin(tmp_path / "broken", "broken", (0, 0, 0), texture=False)
    monkeypatch.setenv("AVATAR_CLOTHES_PATH", str(tmp_path))  # finds skins/ below, too
    catalogue.skins.cache_clear()
    try:
        assert [s[:2] for s in catalogue.skins()] == [("tanned", str(tanned))]  # not broken
        assert catalogue.skins()[0][2].endswith("tanned.thumb")
        body = live.part_objects(human)["body"]
        own = body.data.materials[0].name
        assert bpy.ops.avatar.set_skin(path=str(tanned)) == {"FINISHED"}
        assert np.allclose(_texture_mean(body), np.array([150, 90, 60]) / 255, atol=0.02)
        assert json.loads(human["avatar_recipe"])["skin_material"] == str(tanned)
        human.avatar.african = 0.8
        bpy.ops.avatar.settle()
        assert np.allclose(_texture_mean(body), np.array([150, 90, 60]) / 255, atol=0.02)
        worn = body.data.materials[0].name
        with pytest.raises(RuntimeError, match="diffuse"):
            bpy.ops.avatar.set_skin(path=str(broken))
        assert body.data.materials[0].name == worn
        assert json.loads(human["avatar_recipe"])["skin_material"] == str(tanned)
        assert bpy.ops.avatar.set_skin(path="") == {"FINISHED"}
        assert body.data.materials[0].name != worn and not json.loads(
            human["avatar_recipe"]).get("skin_material")  # fmt: skip
        assert own  # (the procedural skin's name changes with ethnicity)
    finally:
        catalogue.skins.cache_clear()


def test_eye_colour_changes_only_the_eyes(human):
    """Eyes: a menu of iris colours; picking one changes the eyes' material at once (the
    body and garments are not rebuilt) and the recipe names MakeHuman's eye material."""
    from avatar.blender import live

    parts = live.part_objects(human)
    eyes, body = parts["eyes"], parts["body"]
    before = _texels(eyes)
    skin, vertices = body.data.materials[0], body.data.vertices[0].co.copy()
    human.avatar.eyes = "blue"
    after = _texels(eyes)
    iris = np.abs(after - before).max(axis=1) > 0.05  # the texels that changed
    assert iris.sum() > 1000, iris.sum()
    was, now = before[iris].mean(axis=0), after[iris].mean(axis=0)
    assert now[2] > now[0] + 0.1 and was[2] < was[0], (was, now)  # brown to blue
    assert body.data.materials[0] == skin and body.data.vertices[0].co == vertices
    assert json.loads(human["avatar_recipe"])["eye_material"] == "eyes/materials/blue.mhmat"
    human.avatar.eyes = "brown"


def test_several_humans_coexist(installed, assets, empty_scene):
    import bpy

    from avatar.blender import mesh
    from avatar.blender.live import part_objects

    bpy.ops.avatar.create_human()
    first = bpy.context.view_layer.objects.active
    bpy.context.scene.cursor.location = (1.5, 0, 0)
    bpy.ops.avatar.create_human(default_look=False, rigged=False)
    second = bpy.context.view_layer.objects.active
    assert second is not first and second.type == "MESH"
    untouched = mesh.read_vertices(part_objects(first)["body"]).copy()
    second.avatar.height = 1.0
    second.avatar.gender = 1.0
    np.testing.assert_array_equal(mesh.read_vertices(part_objects(first)["body"]), untouched)
    assert first.avatar.height == pytest.approx(0.5) and second.avatar.height == 1.0
    bpy.ops.avatar.settle()
    _assert_matches_fresh_human(second)


def test_wear_and_take_off_by_name(human):
    import bpy

    from avatar.blender import live

    assert bpy.ops.avatar.wear(name="tshirt") == {"FINISHED"}
    assert bpy.ops.avatar.wear(name="jeans") == {"FINISHED"}
    assert {"tshirt", "jeans"} <= set(live.part_objects(human))
    _assert_matches_fresh_human(human)
    assert bpy.ops.avatar.wear(name="shoes") == {"FINISHED"}  # the body rises onto the soles
    _assert_matches_fresh_human(human)
    human.avatar.weight = 0.8  # the new garments follow the body too
    bpy.ops.avatar.settle()
    _assert_matches_fresh_human(human)
    assert bpy.ops.avatar.take_off(name="tshirt") == {"FINISHED"}
    assert "tshirt" not in live.part_objects(human)
    assert "tshirt" not in bpy.data.objects and "tshirt" not in bpy.data.meshes
    _assert_matches_fresh_human(human)


def test_errors_are_reports_and_change_nothing(human, tmp_path):
    import bpy

    before = _state(human)
    with pytest.raises(RuntimeError, match="tshrt.*tshirt"):  # an error report: close matches
        bpy.ops.avatar.wear(name="tshrt")
    with pytest.raises(RuntimeError, match="no such garment file"):
        bpy.ops.avatar.wear(name=str(tmp_path / "missing.mhclo"))
    settings = bpy.context.scene.avatar_motion
    settings.bvh_path = str(tmp_path / "missing.bvh")
    with pytest.raises(RuntimeError, match="no such BVH file"):
        bpy.ops.avatar.apply_motion()
    empty = tmp_path / "empty.bvh"
    empty.write_text(WALK.read_text().split("MOTION")[0] + "MOTION\nFrames: 0\n"
                     "Frame Time: 0.033333\n") if WALK.is_file() else None  # fmt: skip
    if WALK.is_file():
        settings.bvh_path = str(empty)
        with pytest.raises(RuntimeError, match="no motion|no frames"):
            bpy.ops.avatar.apply_motion()
    settings.bvh_path = str(tmp_path)  # a folder is not a clip
    with pytest.raises(RuntimeError):
        bpy.ops.avatar.apply_motion()
    with pytest.raises(RuntimeError, match="no preset"):
        bpy.ops.avatar.apply_preset(name="nobody")
    with pytest.raises(RuntimeError, match="no such file"):
        bpy.ops.avatar.import_mhm(filepath=str(tmp_path / "none.mhm"))
    assert human.name in bpy.data.objects
    _assert_same_state(before, _state(human))


@pytest.mark.skipif(not WALK.is_file(), reason="needs the CMU BVH fixtures")
def test_apply_motion_on_a_dressed_human_keeps_a_report(human):
    import bpy

    from avatar.blender import action, live

    bpy.ops.avatar.wear(name="tshirt")
    name = human.name
    settings = bpy.context.scene.avatar_motion
    settings.bvh_path, settings.frame_end = str(WALK), 12
    assert bpy.ops.avatar.apply_motion() == {"FINISHED"}
    root = bpy.context.view_layer.objects.active
    assert root.name == name  # rebuilt under its own name
    curves = action.action_curves(root.animation_data.action)
    frames = {int(p.co[0]) for c in curves for p in c.keyframe_points}
    assert len(frames) == 12
    report = root["avatar_motion_report"]
    assert "frames" in report.lower() and len(report.splitlines()) >= 3
    tshirt = live.part_objects(root)["tshirt"]
    assert tshirt.data.shape_keys is not None  # the baked per-frame corrections
    root.avatar.weight = 0.7  # still live after a motion: basis moves, corrections kept
    assert json.loads(root["avatar_recipe"])["params"]["weight"] == pytest.approx(0.7)


def test_rig_choice_rebuilds_with_the_new_armature(human):
    import bpy

    from avatar.blender import live

    human.avatar.weight = 0.7
    bpy.ops.avatar.settle()
    name = human.name
    human.avatar.rig = "game_engine"
    root = bpy.data.objects[name]
    assert json.loads(root["avatar_recipe"])["rig"] == "game_engine"
    assert len(root.data.bones) < 100  # game_engine has 53 bones, default 163
    assert root.avatar.weight == pytest.approx(0.7)  # the body kept
    assert set(live.part_objects(root)) >= {"body", "hair-short"}
    _assert_matches_fresh_human(root)


def test_randomise_presets_and_mhm_round_trip(human, tmp_path, monkeypatch):
    import bpy

    settings = bpy.context.scene.avatar
    settings.seed = 11
    bpy.ops.avatar.randomise()
    first = json.loads(human["avatar_recipe"])["params"]
    settings.seed = 11
    bpy.ops.avatar.randomise()
    assert json.loads(human["avatar_recipe"])["params"] == first  # one seed, one body
    assert first != {}
    _assert_matches_fresh_human(human)
    assert bpy.ops.avatar.apply_preset(name="old_man") == {"FINISHED"}
    assert human.avatar.age == pytest.approx(0.95)
    assert bpy.ops.avatar.save_preset(name="Mine") == {"FINISHED"}
    assert bpy.ops.avatar.reset_body() == {"FINISHED"}
    assert bpy.ops.avatar.apply_preset(name="mine") == {"FINISHED"}
    assert human.avatar.age == pytest.approx(0.95)
    path = tmp_path / "me.mhm"
    assert bpy.ops.avatar.export_mhm(filepath=str(path)) == {"FINISHED"}
    assert bpy.ops.avatar.import_mhm(filepath=str(path)) == {"FINISHED"}
    again = bpy.context.view_layer.objects.active
    assert again is not human and again.avatar.age == pytest.approx(0.95, abs=1e-4)


def test_fit_measurements(human):
    import bpy

    settings = bpy.context.scene.avatar
    settings.target_height = 182.0
    assert bpy.ops.avatar.fit_measurements() == {"FINISHED"}
    assert human.avatar.measured_height == pytest.approx(182.0, abs=1.0)
    settings.target_height = settings.target_chest = 0
    with pytest.raises(RuntimeError, match="target"):
        bpy.ops.avatar.fit_measurements()


def _rss_mb() -> float:
    """The process's current resident memory (MB; Linux), else its peak."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20
    except OSError:
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def test_no_leaks_over_100_changes(human):
    import gc

    import bpy

    bpy.ops.avatar.wear(name="tshirt")

    def counts():
        return {name: len(getattr(bpy.data, name)) for name in
                ("objects", "meshes", "materials", "images", "armatures", "actions")}  # fmt: skip

    def hundred_changes():
        for i in range(100):
            human.avatar.weight = 0.3 + 0.004 * i
            if i % 10 == 0:  # a new skin each settle: the old material and images go
                human.avatar.african = (0.2, 0.6)[(i // 10) % 2]
                bpy.ops.avatar.settle()
        bpy.ops.avatar.settle()
        gc.collect()

    hundred_changes()  # warms every cache (skin textures, fits, templates, allocator)
    hundred_changes()
    before, rss = counts(), _rss_mb()
    hundred_changes()
    assert counts() == before
    grown = _rss_mb() - rss
    assert grown < 25, f"RSS grew {grown:.0f} MB over 100 changes"


def test_undo_restores_the_previous_body(human):
    import bpy

    from avatar.blender import live, mesh

    if not bpy.ops.ed.undo.poll():
        pytest.skip("no undo context headless (tests/ui checks undo in a real window)")
    body = live.part_objects(human)["body"]
    before = mesh.read_vertices(body).copy()
    bpy.ops.ed.undo_push(message="before")
    human.avatar.weight = 1.0
    bpy.ops.ed.undo_push(message="weight")
    bpy.ops.ed.undo()
    np.testing.assert_allclose(mesh.read_vertices(live.part_objects(human)["body"]), before)


def test_dress_library_lists_the_builtin_garments(installed):
    import bpy

    assert bpy.ops.avatar.refresh_library() == {"FINISHED"}
    garments = bpy.context.scene.avatar.garments
    assert len(garments) >= 22
    assert all(g.entry for g in garments)


@pytest.fixture
def character_and_vest(installed, assets, empty_scene):
    """A real character away from the origin, and a vest modelled on it: its torso skin
    pushed out 1 cm along the normals, as an unparented mesh object in world space."""
    import bpy

    from avatar.blender import character, mesh
    from avatar.mesh import vertex_normals

    bpy.context.scene.cursor.location = (0.5, 0.2, 0.0)
    assert bpy.ops.avatar.create_human(default_look=False) == {"FINISHED"}
    root = bpy.context.view_layer.objects.active
    human = character.realise(character.recipe_of(root))
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
    assert "vest" in {o.get("avatar_part") for o in bpy.data.objects}


def test_a_garment_far_from_the_body_is_refused(character_and_vest, tmp_path):
    import bpy

    _, _, obj = character_and_vest
    obj.location.x += 2.0  # modelled nowhere near the character (the nearest one)
    folder = tmp_path / "far"
    with pytest.raises(RuntimeError, match="from the body"):
        bpy.ops.avatar.bind_garment(name="vest", folder=str(folder))
    assert not folder.exists()


def test_the_dress_grid_swaps_swatches_for_pictures_drawn_outside_blender(installed):
    """A built-in with no cached picture shows its swatch at once; a separate Python process
    draws the picture (``python -m avatar.clothes.thumbnail``) and the grid's timer swaps
    it in; unregistering stops the process."""
    from avatar.clothes import thumbnail

    thumbnails = _thumbnails_module()
    picture = thumbnail.picture_path("tshirt")
    picture.unlink(missing_ok=True)
    try:
        thumbnails.icon("tshirt", "")  # (icon ids are 0 headless: no GPU to draw them)
        assert "tshirt" in thumbnails._DRESS.get()  # the swatch, at once
        assert "tshirt" in thumbnails._WAITING and not thumbnails._DRAWER
        thumbnails.draw_queued()  # what the grid does after its items
        process = _wait_for(thumbnails, picture)
        thumbnails._swap_pictures()  # what the timer does (timers do not run headless)
        assert "tshirt" not in thumbnails._WAITING
        assert "tshirt" not in thumbnails._DRESS.get()  # reloaded on the next draw...
        thumbnails.icon("tshirt", "")
        assert "tshirt" in thumbnails._DRESS.get() and "tshirt" not in thumbnails._WAITING
    finally:
        thumbnails.release()
    assert process.wait(timeout=30) is not None and not thumbnails._DRAWER


def test_a_user_garment_without_a_thumb_gets_a_drawn_picture(installed, fixtures, tmp_path):
    """A user's garment with no ``.thumb`` showed a plain button for good; the grid now
    queues it with the built-ins' missing pictures, one process draws them all, and the
    picture replaces the button."""
    import shutil

    from avatar.clothes import thumbnail

    source = fixtures / "makehuman" / "clothes" / "shoes02"
    shutil.copytree(source, tmp_path / "shoes02", ignore=shutil.ignore_patterns("*.thumb"))
    entry = str(tmp_path / "shoes02" / "shoes02.mhclo")
    thumbnails = _thumbnails_module()
    picture = thumbnail.picture_path(entry)
    try:
        assert thumbnails.icon(entry, "") == 0  # a plain button while it is drawn
        assert entry in thumbnails._WAITING and entry not in thumbnails._DRESS.get()
        thumbnails.draw_queued()
        assert len(thumbnails._DRAWER) == 1
        process = _wait_for(thumbnails, picture)
        thumbnails._swap_pictures()
        thumbnails.icon(entry, "")
        assert entry in thumbnails._DRESS.get() and not thumbnails._WAITING
    finally:
        thumbnails.release()
    assert process.wait(timeout=30) is not None
    picture.unlink()


def _thumbnails_module():
    import importlib

    from extension_fixtures import ADDON

    thumbnails = importlib.import_module(f"{ADDON}.thumbnails")
    thumbnails.release()
    return thumbnails


def _wait_for(thumbnails, picture):
    """The drawing process, once ``picture`` has landed (or it has exited)."""
    import time

    process = thumbnails._DRAWER[0]
    deadline = time.monotonic() + 300
    while not picture.is_file() and process.poll() is None:
        assert time.monotonic() < deadline, "no picture drawn in 5 minutes"
        time.sleep(0.5)
    assert picture.is_file(), f"drawer exited {process.returncode}"
    return process
