"""The people of a sample, posed in world space: meshes for the renderer, joints and
COCO-17 keypoints for the labels, a body-part id per skin face. numpy only (no Blender).

Body parts (``PARTS``, ids 1..15; 0 = not skin) come from MakeHuman's vertex groups: each
skin vertex takes the part of its dominant bone in the default rig's weights, each face the
part of most of its corners. COCO-17 keypoints: shoulders, elbows, wrists, hips, knees and
ankles are the rig's joints (found by role, any rig); eyes are the eyeballs' centres; nose
and ears are skin vertices picked on the model's default body (nose tip: the most forward
midline vertex below the eyes; ears: the outermost head vertices at eye height).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from avatar.body.model import BODY_VERTICES, BodyModel
from avatar.body.shaped import PART_GROUPS, default_body, part_vertices
from avatar.clothes.library import garment_normals
from avatar.dataset.sampling import WALK_FPS, WALK_SECONDS, Person
from avatar.human import Human, Recipe
from avatar.io import bvh
from avatar.mesh import Mesh
from avatar.motion import bonemap
from avatar.part import MeshPart
from avatar.rig import kinematics, skinning
from avatar.rig.skeleton import Animation

PARTS = ("head", "neck", "torso", "upper_arm_l", "lower_arm_l", "hand_l", "upper_arm_r",
         "lower_arm_r", "hand_r", "upper_leg_l", "lower_leg_l", "foot_l", "upper_leg_r",
         "lower_leg_r", "foot_r")  # fmt: skip
"""Body part names by id - 1 (``parts.png`` stores id 1..15; 0 is anything else)."""

COCO_KEYPOINTS = ("nose", "left_eye", "right_eye", "left_ear", "right_ear", "left_shoulder",
                  "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist",
                  "left_hip", "right_hip", "left_knee", "right_knee", "left_ankle",
                  "right_ankle")  # fmt: skip
COCO_SKELETON = [[16, 14], [14, 12], [17, 15], [15, 13], [12, 13], [6, 12], [7, 13], [6, 7],
                 [6, 8], [7, 9], [8, 10], [9, 11], [2, 3], [1, 2], [1, 3], [2, 4], [3, 5],
                 [4, 6], [5, 7]]  # fmt: skip
# COCO joint -> canonical bone role whose head it is (person's left = Avatar's .L, +x).
_JOINT_ROLES = {"left_shoulder": "upperarm.L", "right_shoulder": "upperarm.R",
                "left_elbow": "forearm.L", "right_elbow": "forearm.R", "left_wrist": "hand.L",
                "right_wrist": "hand.R", "left_hip": "thigh.L", "right_hip": "thigh.R",
                "left_knee": "shin.L", "right_knee": "shin.R", "left_ankle": "foot.L",
                "right_ankle": "foot.R"}  # fmt: skip
_PART_OF_BONE = (  # (bone name prefix, part without side); checked in order
    ("neck", "neck"), ("head", "head"), ("jaw", "head"), ("eye", "head"), ("tongue", "head"),
    ("special", "head"), ("levator", "head"), ("oris", "head"), ("temporalis", "head"),
    ("risorius", "head"), ("orbicularis", "head"), ("oculi", "head"), ("clavicle", "torso"),
    ("shoulder", "upper_arm"), ("upperarm", "upper_arm"), ("lowerarm", "lower_arm"),
    ("wrist", "hand"), ("finger", "hand"), ("metacarpal", "hand"), ("upperleg", "upper_leg"),
    ("lowerleg", "lower_leg"), ("foot", "foot"), ("toe", "foot"),
)  # fmt: skip
_SIDED = ("upper_arm", "lower_arm", "hand", "upper_leg", "lower_leg", "foot")


@dataclass(frozen=True, eq=False)
class PosedPerson:
    """One person at one frame, in world space (metres, Z up).

    parts: MeshParts for the renderer: body (skin) first, eyes, then garments.
    face_parts: per part, (F_i,) int32 body-part id (1..15) of each face: the skin's own,
        the head for the eyes, for a garment the part of the skin nearest each face (so
        part segmentation covers clothes as the body under them).
    joints: (J, 3) world joint (bone head) positions of the rig; joint_names: (J,).
    keypoints: (17, 3) COCO-17 points; keypoint_depth: (17,) metres each point lies under
        the skin (0 for surface points), for the visibility test.
    """

    person: Person
    recipe: dict
    parts: list[MeshPart]
    face_parts: list[np.ndarray]
    joints: np.ndarray
    joint_names: tuple[str, ...]
    keypoints: np.ndarray
    keypoint_depth: np.ndarray


def pose_person(person: Person, model: BodyModel | None = None) -> PosedPerson:
    """Build, pose and place one person (garments resolved exactly: none inside the body)."""
    recipe = Recipe(params=dict(person.params), rig=person.rig, clothes=tuple(person.clothes))
    human = Human.from_recipe(recipe, model)
    animation = _animation(human, person)
    frame = min(person.frame, animation.frames - 1) if person.motion == "walk" else 0
    rot, trans = animation.rotations[frame : frame + 1], animation.translations[frame : frame + 1]
    world = kinematics.forward(human.skeleton, rot, trans)
    matrices = kinematics.skinning_matrices(human.skeleton, world)[0]
    posed = skinning.linear_blend(human.vertices, human.weights, matrices)
    garments = human.outfit.frame(posed, matrices, exact=True) if human.recipe.clothes else []
    # In place: the root's horizontal travel is removed, so the person stands at its
    # ``position`` whatever frame of a walk or clip is shown.
    root = int(np.flatnonzero(human.skeleton.parents < 0)[0])
    travel = np.zeros(3, np.float32)
    travel[:2] = world[0][root, :2, 3]
    posed = posed - travel
    garments = [g - travel for g in garments]
    world = world.copy()
    world[..., :3, 3] -= travel
    place = _placement(person)
    rest_parts = human.parts()
    parts = []
    body_parts = len(PART_GROUPS)  # body, eyes, teeth, tongue: posed base-mesh vertices
    for part in rest_parts[:body_parts]:
        index = human.part_vertices(part.name)
        parts.append(_moved(part, posed[index], place))
    for part, fitted, vertices in zip(rest_parts[body_parts:], human.outfit.garments,
                                      garments, strict=True):  # fmt: skip
        moved = _moved(part, vertices, place)  # shading as Blender and exports have it:
        parts.append(replace(moved, normals=garment_normals(fitted, moved.mesh.vertices)))
    joints = _apply(place, world[0][:, :3, 3])
    keypoints, depth = _keypoints(human, posed, world[0][:, :3, 3])
    return PosedPerson(person, human.to_recipe(), parts, _face_parts(human, posed, garments),
                       joints, tuple(human.skeleton.names), _apply(place, keypoints),
                       depth)  # fmt: skip


def _face_parts(human: Human, posed: np.ndarray, garments: list[np.ndarray]) -> list:
    """Body-part id per face of the skin, the eyes and each garment (see PosedPerson)."""
    from scipy.spatial import cKDTree

    model = human.model
    skin = posed[:BODY_VERTICES]
    labels = vertex_parts(model)
    out = [body_face_parts(model)]
    for name in list(PART_GROUPS)[1:]:  # eyes, teeth, tongue: the head
        out.append(np.full(len(human.part(name).faces), PARTS.index("head") + 1, np.int32))
    if garments:
        tree = cKDTree(skin)
        for fitted, vertices in zip(human.outfit.garments, garments, strict=True):
            _, nearest = tree.query(vertices)
            corner = labels[nearest][fitted.mesh.faces]  # (F, N) part of each corner
            out.append(corner[:, 0].astype(np.int32))  # a face's first corner decides
    return out


def _animation(human: Human, person: Person) -> Animation:
    if person.motion == "walk":
        return human.walk(WALK_SECONDS, WALK_FPS)
    if person.motion.lower().endswith(".bvh"):
        source, clip = _clip(person.motion)
        start = max(0, person.frame - 30)  # a window: contacts and the floor need context
        window = slice(start, person.frame + 31)
        animation, _ = human.retarget(source, clip, frames=window)
        index = person.frame - start
        return Animation(animation.rotations[index : index + 1],
                         animation.translations[index : index + 1], animation.fps,
                         animation.bone_names)  # fmt: skip
    return human.pose(person.motion)


@lru_cache(maxsize=8)
def _clip(path: str):
    return bvh.load(path)


def _placement(person: Person) -> np.ndarray:
    """(4, 4) turn by ``yaw_deg`` about Z, then move to ``position`` on the floor."""
    a = np.radians(person.yaw_deg)
    out = np.eye(4)
    out[:2, :2] = [[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]
    out[:2, 3] = person.position
    return out


def _apply(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    return (np.asarray(points, dtype=np.float64) @ matrix[:3, :3].T + matrix[:3, 3]).astype(
        np.float32
    )


def _moved(part: MeshPart, vertices: np.ndarray, place: np.ndarray) -> MeshPart:
    """The part with its vertices posed and placed; static (no skin, no morphs)."""
    mesh: Mesh = part.mesh.with_vertices(_apply(place, vertices))
    return replace(part, mesh=mesh, skin=None, morphs={}, normals=None)


def _keypoints(human: Human, posed: np.ndarray, joints: np.ndarray):
    """(17, 3) COCO-17 points (unplaced) and (17,) their depth under the skin (metres)."""
    faces = face_landmarks(human.model)
    roles = bonemap.detect(human.skeleton).bones
    out = np.zeros((17, 3), np.float32)
    depth = np.zeros(17, np.float32)
    base = human.model.base
    for k, name in enumerate(COCO_KEYPOINTS):
        if name in _JOINT_ROLES:
            out[k] = joints[roles[_JOINT_ROLES[name]]]
        elif name.endswith("_eye"):
            group = "helper-l-eye" if name.startswith("left") else "helper-r-eye"
            out[k] = posed[base.groups[group]].mean(axis=0)
        else:
            out[k] = posed[faces[name]]
    # joints and eye centres lie under the skin: how far, measured on this body at rest
    skin = human.vertices[:BODY_VERTICES]
    rest_joints = human.skeleton.heads
    for k, name in enumerate(COCO_KEYPOINTS):
        if name in _JOINT_ROLES:
            point = rest_joints[roles[_JOINT_ROLES[name]]]
        elif name.endswith("_eye"):
            group = "helper-l-eye" if name.startswith("left") else "helper-r-eye"
            point = human.vertices[base.groups[group]].mean(axis=0)
        else:
            continue
        depth[k] = float(np.sqrt(((skin - point) ** 2).sum(axis=1)).min())
    return out, depth


@lru_cache(maxsize=4)
def face_landmarks(model: BodyModel) -> dict[str, int]:
    """Skin vertex index of the nose tip and the ears, picked on the default body."""
    body = default_body(model)
    v = body.vertices[:BODY_VERTICES]
    part = vertex_parts(model)[:BODY_VERTICES]
    head = np.flatnonzero(part == PARTS.index("head") + 1)
    eyes = body.vertices[model.base.groups["helper-l-eye"]].mean(axis=0)
    near_mid = head[(np.abs(v[head, 0]) < 0.004) & (v[head, 2] < eyes[2])
                    & (v[head, 2] > eyes[2] - 0.08)]  # fmt: skip
    nose = int(near_mid[np.argmin(v[near_mid, 1])])
    level = head[np.abs(v[head, 2] - eyes[2]) < 0.025]
    return {"nose": nose, "left_ear": int(level[np.argmax(v[level, 0])]),
            "right_ear": int(level[np.argmin(v[level, 0])])}  # fmt: skip


@lru_cache(maxsize=4)
def vertex_parts(model: BodyModel) -> np.ndarray:
    """(19158,) int32 part id (1..15) of each base-mesh vertex from the default rig's
    dominant bone (see ``PARTS``)."""
    body = default_body(model)
    names = body.skeleton.names
    table = np.zeros(len(names), np.int32)
    for j, name in enumerate(names):
        low = name.lower()
        part = next((p for prefix, p in _PART_OF_BONE if low.startswith(prefix)), "torso")
        if part in _SIDED:
            part += "_l" if name.endswith(".L") else "_r"
        table[j] = PARTS.index(part) + 1
    dominant = body.weights.indices[np.arange(len(body.weights.indices)),
                                    np.argmax(body.weights.weights, axis=1)]  # fmt: skip
    return table[dominant]


@lru_cache(maxsize=4)
def body_face_parts(model: BodyModel) -> np.ndarray:
    """(F,) int32 part id of each face of the skin part mesh (``Human.part("body")``): the
    part of most of its corners."""
    base = model.base
    faces = np.sort(base.face_groups["body"])
    labels = vertex_parts(model)[base.faces[faces]]  # (F, 4)
    counts = np.stack([(labels == p).sum(axis=1) for p in range(1, len(PARTS) + 1)], axis=1)
    out = (np.argmax(counts, axis=1) + 1).astype(np.int32)
    out.setflags(write=False)
    return out


def skin_index(model: BodyModel) -> np.ndarray:
    """Base-mesh indices of the skin part's vertices (its mesh's vertex order)."""
    return part_vertices(model, "body")
