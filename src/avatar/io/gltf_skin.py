"""Skeleton, skin weights and animation for glTF 2.0 (spec sections 3.7.3 skins, 3.11 animations).

Frames, as Blender's own exporter writes them: a bone keeps its own local axes (Y from head
to tail, rolled X/Z); only the world around it turns Y-up. So a joint's glTF world matrix is
``AXES @ rest``, a root joint's local matrix is ``AXES @ rest`` and every other joint's local
matrix is Avatar's (parent-relative) rest matrix unchanged. Blender's importer undoes exactly
this, giving back Avatar's bone rolls and pose quaternions. A bone pose (pose-bone
quaternion ``q``, location ``t``, both in the bone's rest frame) becomes the node's animated
local transform ``local_rest @ T(t) R(q)``; reading inverts it, keeping the quaternion's sign.
"""

from __future__ import annotations

import numpy as np
import pygltflib as g

from avatar.io import gltf_accessors as acc
from avatar.rig import quaternion as quat
from avatar.rig.skeleton import Animation, Skeleton

# Avatar (Z-up) -> glTF (Y-up): (x, y, z) -> (x, z, -y); a proper rotation (-90 deg about X).
AXES = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])


def _axes4() -> np.ndarray:
    a = np.eye(4)
    a[:3, :3] = AXES
    return a


def gltf_local_rest(skeleton: Skeleton) -> np.ndarray:
    """(J, 4, 4) joint node rest matrices: Avatar's local rest, roots turned Y-up."""
    local = skeleton.local_rest()
    roots = skeleton.parents < 0
    local[roots] = _axes4() @ local[roots]
    return local


def _xyzw(q: np.ndarray) -> np.ndarray:
    return np.roll(q, -1, axis=-1)


def _wxyz(q) -> np.ndarray:
    return np.roll(np.asarray(q, dtype=np.float64), 1, axis=-1)


# ---------------------------------------------------------------------------- writing


def add_skeleton(gltf: g.GLTF2, packer: acc.Packer, skeleton: Skeleton) -> int:
    """Add an armature node, one node per joint and the skin; return the skin index."""
    local = gltf_local_rest(skeleton)
    rotations = _xyzw(quat.from_matrix(local[:, :3, :3]))
    translations = local[:, :3, 3]
    tails = skeleton.tails @ AXES.T
    first = len(gltf.nodes) + 1  # node index of joint 0 (the armature node comes first)
    armature = g.Node(name=str(skeleton.extra.get("name", "Armature")), children=[])
    gltf.nodes.append(armature)
    for j, name in enumerate(skeleton.names):
        gltf.nodes.append(
            g.Node(
                name=name,
                translation=translations[j].tolist(),
                rotation=rotations[j].tolist(),
                children=[],
                extras={"avatar_tail": tails[j].tolist()},
            )
        )
    for j, p in enumerate(skeleton.parents):
        parent = armature if p < 0 else gltf.nodes[first + p]
        parent.children.append(first + j)
    for node in gltf.nodes[first - 1 :]:
        node.children = node.children or None
    gltf.scenes[0].nodes.append(first - 1)
    inverse_bind = np.linalg.inv(_axes4() @ skeleton.rest)
    gltf.skins.append(
        g.Skin(
            name=armature.name,
            joints=list(range(first, first + len(skeleton.names))),
            skeleton=first - 1,
            # MAT4 accessors are column-major: store the transposes row by row.
            inverseBindMatrices=packer.accessor(inverse_bind.transpose(0, 2, 1).astype(np.float32)),
        )
    )
    return len(gltf.skins) - 1


def joint_count(gltf: g.GLTF2) -> int:
    return len(gltf.skins[0].joints) if gltf.skins else 0


def add_animation(
    gltf: g.GLTF2, packer: acc.Packer, skeleton: Skeleton, animation: Animation, name: str
) -> None:
    """One glTF animation: a rotation channel per bone, translation where it moves; LINEAR."""
    cols = [skeleton.index(n) for n in animation.bone_names]
    local = gltf_local_rest(skeleton)[cols]
    rotation = quat.multiply(quat.from_matrix(local[:, :3, :3])[None], animation.rotations)
    rotation = rotation / np.linalg.norm(rotation, axis=-1, keepdims=True)
    translation = np.einsum("jab,tjb->tja", local[:, :3, :3], animation.translations)
    translation = translation + local[None, :, :3, 3]
    times = (np.arange(animation.frames) / float(animation.fps)).astype(np.float32)
    out = g.Animation(name=name, channels=[], samplers=[], extras={"fps": float(animation.fps)})
    time_accessor = packer.accessor(times, bounds=True)
    joint_nodes = gltf.skins[0].joints
    moving = np.any(animation.translations != 0, axis=(0, 2))
    for k, j in enumerate(cols):
        node = joint_nodes[j]
        keys = {"rotation": _xyzw(rotation[:, k])}
        if moving[k]:
            keys["translation"] = translation[:, k]
        for path, values in keys.items():
            out.samplers.append(
                g.AnimationSampler(
                    input=time_accessor,
                    output=packer.accessor(values.astype(np.float32)),
                    interpolation="LINEAR",
                )
            )
            out.channels.append(
                g.AnimationChannel(
                    sampler=len(out.samplers) - 1,
                    target=g.AnimationChannelTarget(node=node, path=path),
                )
            )
    gltf.animations.append(out)


# ---------------------------------------------------------------------------- reading


def read_skeleton(gltf: g.GLTF2, buffers: list[bytes]) -> tuple[Skeleton | None, list[int]]:
    """The joints of every skin as one Skeleton (parents first) and their node indices."""
    joint_nodes: list[int] = []
    for skin in gltf.skins:
        joint_nodes += [n for n in skin.joints if n not in joint_nodes]
    if not joint_nodes:
        return None, []
    parent_node = {c: i for i, n in enumerate(gltf.nodes) for c in (n.children or [])}
    world = {n: world_matrix(gltf, parent_node, n) for n in joint_nodes}
    joint_nodes = _parents_first(joint_nodes, parent_node)
    parents = np.array([_joint_parent(n, parent_node, joint_nodes) for n in joint_nodes])
    rest = _axes4().T @ np.stack([world[n] for n in joint_nodes])
    tails = _tails(gltf, joint_nodes, rest, parents)
    root = parent_node.get(joint_nodes[0])
    extra = {"name": gltf.nodes[root].name} if root is not None and gltf.nodes[root].name else {}
    names = tuple(gltf.nodes[n].name or f"joint_{n}" for n in joint_nodes)
    return Skeleton(names, parents.astype(np.int32), rest, tails, extra), joint_nodes


def node_local(node: g.Node) -> np.ndarray:
    """(4, 4) float64 local transform of a node (matrix or TRS)."""
    if node.matrix is not None and len(node.matrix) == 16:
        return np.array(node.matrix, dtype=np.float64).reshape(4, 4).T
    m = np.eye(4)
    if node.rotation is not None:
        m[:3, :3] = quat.to_matrix(_wxyz(node.rotation))
    if node.scale is not None:
        m[:3, :3] = m[:3, :3] * np.array(node.scale)
    if node.translation is not None:
        m[:3, 3] = node.translation
    return m


def world_matrix(gltf: g.GLTF2, parent_node: dict[int, int], n: int) -> np.ndarray:
    m = node_local(gltf.nodes[n])
    while n in parent_node:
        n = parent_node[n]
        m = node_local(gltf.nodes[n]) @ m
    return m


def _parents_first(nodes: list[int], parent_node: dict[int, int]) -> list[int]:
    """Keep the given order when every parent joint precedes its children, else sort by depth."""
    if all(_joint_parent(n, parent_node, nodes) < i for i, n in enumerate(nodes)):
        return nodes

    def depth(n: int) -> int:
        d = 0
        while n in parent_node:
            n, d = parent_node[n], d + 1
        return d

    return sorted(nodes, key=depth)


def _ancestor_joint(n: int, parent_node: dict[int, int], joints: list[int]) -> int | None:
    while n in parent_node:
        n = parent_node[n]
        if n in joints:
            return n
    return None


def _joint_parent(n: int, parent_node: dict[int, int], joints: list[int]) -> int:
    a = _ancestor_joint(n, parent_node, joints)
    return -1 if a is None else joints.index(a)


def _tails(gltf, joint_nodes, rest, parents) -> np.ndarray:
    """Tails from Avatar's ``avatar_tail`` extras, else along the bone's Y axis."""
    tails = np.empty((len(joint_nodes), 3))
    for j, n in enumerate(joint_nodes):
        stored = (gltf.nodes[n].extras or {}).get("avatar_tail")
        if stored is not None:
            tails[j] = AXES.T @ np.asarray(stored, dtype=np.float64)
            continue
        children = np.flatnonzero(parents == j)
        length = np.linalg.norm(rest[children[0], :3, 3] - rest[j, :3, 3]) if len(children) else 0.1
        tails[j] = rest[j, :3, 3] + rest[j, :3, 1] * max(length, 1e-3)
    return tails


def read_animations(
    gltf: g.GLTF2, buffers: list[bytes], skeleton: Skeleton | None, joint_nodes: list[int]
) -> dict[str, Animation]:
    """Every glTF animation that moves joints -> name -> Animation over all skeleton bones."""
    out: dict[str, Animation] = {}
    if skeleton is None:
        return out
    for i, anim in enumerate(gltf.animations):
        keyed = _joint_channels(gltf, buffers, anim, joint_nodes)
        if not keyed:
            continue
        times = next(iter(keyed.values()))[0]
        if any(len(t) != len(times) for t, _ in keyed.values()):
            raise ValueError(f"animation {anim.name or i}: channels with different key counts")
        fps = (anim.extras or {}).get("fps") or (
            1.0 / float(np.median(np.diff(times))) if len(times) > 1 else 24.0
        )
        rotations, translations = _decode_pose(gltf, keyed, joint_nodes, len(times))
        out[anim.name or f"animation_{i}"] = Animation(
            rotations, translations, float(fps), skeleton.names
        )
    return out


def _joint_channels(gltf, buffers, anim, joint_nodes):
    """(node, path) -> (times (T,), values (T, C)) for rotation/translation joint channels."""
    keyed = {}
    for ch in anim.channels:
        node, path = ch.target.node, ch.target.path
        if node in joint_nodes and path in ("rotation", "translation"):
            sampler = anim.samplers[ch.sampler]
            if sampler.interpolation == "CUBICSPLINE":
                raise ValueError("CUBICSPLINE animation is not supported")
            keyed[(node, path)] = (
                acc.unpack(gltf, buffers, sampler.input).astype(np.float64),
                acc.unpack(gltf, buffers, sampler.output).astype(np.float64),
            )
    return keyed


def _decode_pose(gltf, keyed, joint_nodes, frames: int):
    """Keyed node TRS -> pose-bone quaternions and locations in each bone's rest frame."""
    count = len(joint_nodes)
    rotations = np.zeros((frames, count, 4))
    rotations[..., 0] = 1.0
    translations = np.zeros((frames, count, 3))
    for j, n in enumerate(joint_nodes):
        rest = node_local(gltf.nodes[n])
        rest_q = quat.from_matrix(rest[:3, :3])
        if gltf.nodes[n].rotation is not None:  # keep the stored sign, not from_matrix's
            rest_q = _wxyz(gltf.nodes[n].rotation)
        if (n, "rotation") in keyed:
            q = _wxyz(keyed[(n, "rotation")][1])
            rotations[:, j] = quat.multiply(quat.conjugate(rest_q)[None], q)
        if (n, "translation") in keyed:
            translations[:, j] = (keyed[(n, "translation")][1] - rest[:3, 3]) @ rest[:3, :3]
    return rotations, translations
