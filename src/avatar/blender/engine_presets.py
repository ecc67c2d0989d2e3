"""What each game engine (and Blender itself) wants in a character file: one record per
engine, read by ``avatar.blender.export.export_character``.

Pure data (no bpy), so it can be listed and documented anywhere. Every setting says why; the
engine documentation behind it:

- Unity: ``ModelImporter.skinWeights`` (docs.unity3d.com/ScriptReference/
  ModelImporter-skinWeights.html): Unity skins with 4 bone weights per vertex unless a
  project opts into more, so weights past the 4th are dropped at import without
  renormalising; Avatar keeps the 4 largest and renormalises instead. Unity is Y-up, +Z
  forward, 1 unit = 1 m.
- Unreal: ``FbxSkeletalMeshImportData.convert_scene_unit`` (dev.epicgames.com, Python API
  5.7): Unreal's unit is the centimetre and converting the file's unit is an opt-in, so the
  file itself is written in centimetres. Unreal builds root motion from a bone at the
  origin above the pelvis (its mannequin's ``root``), and turns an FBX armature node that is
  not named "Armature" into an extra bone, so the armature object is named so in the file.
- Godot: "Available 3D formats" (docs.godotengine.org, 4.x): glTF 2.0 is the recommended
  format (FBX goes through ufbx); glTF is Y-up, metres, +Z forward by its spec. Godot node
  and bone paths use ``.`` and ``:`` as separators, so bone names become identifiers.
"""

from __future__ import annotations

from dataclasses import dataclass

FORMATS = {"GLB": ".glb", "FBX": ".fbx", "USD": ".usdz"}  # format -> default suffix
SUFFIXES = {".glb": "GLB", ".gltf": "GLB", ".fbx": "FBX", ".usd": "USD", ".usda": "USD",
            ".usdc": "USD", ".usdz": "USD"}  # fmt: skip


@dataclass(frozen=True)
class EnginePreset:
    """How a character is written for one engine.

    name: the operator's enum value ("UNITY"); label, description: for the UI.
    format: the default file format ("GLB", "FBX", "USD") when the path names none.
    unit_scale: file units per metre (100: centimetres). Geometry, bones and animation
        translations are scaled by it and the file declares that unit.
    fbx_axis_forward, fbx_axis_up: Blender's FBX exporter axes (the file's forward and up).
    usd_y_up: write the USD stage Y-up (else Blender's Z-up).
    root_bone: a bone of this name at the origin parents every top bone ("" for none).
    armature_name: the armature object's name in the file ("" keeps the character's).
    bone_names: "keep", or "identifier" (every character outside [A-Za-z0-9_] becomes _).
    shape_keys: "KEEP" (shape keys and their animation) or "BAKE" (the current mix becomes
        the mesh, no keys).
    max_influences: bone weights per vertex (the largest kept, renormalised); 0 = all.
    at_origin: write the character with its root at the origin (else where it stands).
    """

    name: str
    label: str
    description: str
    format: str
    unit_scale: float = 1.0
    fbx_axis_forward: str = "-Z"
    fbx_axis_up: str = "Y"
    usd_y_up: bool = False
    root_bone: str = ""
    armature_name: str = ""
    bone_names: str = "keep"
    shape_keys: str = "KEEP"
    max_influences: int = 0
    at_origin: bool = True


PRESETS: dict[str, EnginePreset] = {
    "BLENDER": EnginePreset(
        "BLENDER",
        "Blender / generic",
        "Everything as it is in Blender: metres, every bone "
        "weight, names kept, the character where it stands",
        format="GLB",
        # glTF (Y-up by spec) and FBX's customary Y-up; Blender's importers convert back.
        at_origin=False,
    ),
    "UNITY": EnginePreset(
        "UNITY",
        "Unity",
        "FBX in metres, Y-up, 4 bone weights per vertex",
        format="FBX",
        # FBX -Z forward / Y up: a character facing Blender's -Y faces Unity's +Z (forward).
        fbx_axis_forward="-Z",
        fbx_axis_up="Y",
        usd_y_up=True,
        # Unity's default skin quality reads 4 weights (ModelImporter.skinWeights).
        max_influences=4,
    ),
    "UNREAL": EnginePreset(
        "UNREAL",
        "Unreal Engine",
        "FBX in centimetres with a root bone at the origin, 4 bone weights per vertex",
        format="FBX",
        # Centimetres in the file itself: Unreal's "Convert Scene Unit" is off by default.
        unit_scale=100.0,
        # Unreal converts FBX's Y-up into its Z-up; Blender's -Y front arrives as Unreal's
        # +Y, the way its mannequin faces.
        fbx_axis_forward="-Z",
        fbx_axis_up="Y",
        root_bone="root",  # root motion and the mannequin's hierarchy start at the origin
        armature_name="Armature",  # any other name becomes an extra bone above the root
        bone_names="identifier",  # FNames: '.' and '-' are awkward in Blueprints/Python
        max_influences=4,  # the engine's default skin cache / mobile limit
    ),
    "GODOT": EnginePreset(
        "GODOT",
        "Godot",
        "glTF binary (Godot's recommended format), identifier bone names, "
        "4 bone weights per vertex",
        format="GLB",
        usd_y_up=True,
        bone_names="identifier",  # '.' and ':' separate node paths in Godot's animations
        max_influences=4,  # Godot's Skeleton3D skins with 4 weights (8 is an opt-in)
    ),
}


def preset(name: str) -> EnginePreset:
    """The preset called ``name`` (case-insensitive); KeyError lists the known ones."""
    try:
        return PRESETS[name.upper()]
    except KeyError:
        raise KeyError(f"no engine preset {name!r}; there are {', '.join(PRESETS)}") from None
