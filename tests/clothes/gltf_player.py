"""What a glTF viewer shows at a key frame, computed from the file alone (pygltflib + numpy).

Per the glTF 2.0 spec: node TRS from the animation's key ``t`` (or the node's own), world
matrices down the node tree, morph targets blended with the keyed weights, then linear
blend skinning with joint world @ inverse bind matrix. Only Avatar's reader helpers for
decoding accessors are shared with the code under test.
"""

from __future__ import annotations

import numpy as np
import pygltflib

from avatar.io import gltf_accessors as acc
from avatar.rig import quaternion


class Player:
    """A loaded file that can evaluate its mesh nodes at key frames of one animation."""

    def __init__(self, path, animation: int = 0):
        self.gltf = pygltflib.GLTF2().load(str(path))
        self.buffers = [acc.buffer_bytes(self.gltf, 0, path.parent)]
        self.keys: dict[tuple[int, str], np.ndarray] = {}
        anim = self.gltf.animations[animation]
        for ch in anim.channels:
            out = self.unpack(anim.samplers[ch.sampler].output).astype(np.float64)
            if ch.target.path == "weights":
                out = out.reshape(-1, len(self._targets(ch.target.node)))
            self.keys[(ch.target.node, ch.target.path)] = out

    def unpack(self, index: int) -> np.ndarray:
        return acc.unpack(self.gltf, self.buffers, index)

    def mesh_nodes(self) -> dict[str, int]:
        return {n.name: i for i, n in enumerate(self.gltf.nodes) if n.mesh is not None}

    def positions(self, name: str, t: int) -> np.ndarray:
        """(V, 3) float64 Avatar-frame positions of part ``name``'s source vertices at key t."""
        n = self.mesh_nodes()[name]
        node, prim = self.gltf.nodes[n], self._primitive(n)
        p = self.unpack(prim.attributes.POSITION).astype(np.float64)
        weights = self.keys.get((n, "weights"))
        for k, target in enumerate(prim.targets or []):
            w = weights[t, k] if weights is not None else 0.0
            if w:
                p = p + w * self.unpack(target["POSITION"])
        if node.skin is not None:
            p = self._skin(node.skin, prim, p, t)
        source = self.unpack(prim.attributes._AVATAR_VERTEX).astype(np.int64)
        out = np.zeros((source.max() + 1, 3))
        out[source] = np.stack([p[:, 0], -p[:, 2], p[:, 1]], axis=1)  # glTF Y-up -> Z-up
        return out

    def morph_count(self, name: str) -> int:
        return len(self._targets(self.mesh_nodes()[name]))

    def _primitive(self, n: int):
        return self.gltf.meshes[self.gltf.nodes[n].mesh].primitives[0]

    def _targets(self, n: int) -> list:
        return self._primitive(n).targets or []

    def _skin(self, skin_index: int, prim, p: np.ndarray, t: int) -> np.ndarray:
        skin = self.gltf.skins[skin_index]
        world = self._world(t)
        inverse_bind = self.unpack(skin.inverseBindMatrices).astype(np.float64)
        joint = np.stack([world[j] for j in skin.joints]) @ inverse_bind  # (J, 4, 4)
        homo = np.concatenate([p, np.ones((len(p), 1))], axis=1)
        out = np.zeros_like(homo)
        for s in range(2):
            if getattr(prim.attributes, f"JOINTS_{s}", None) is None:
                continue
            j = self.unpack(getattr(prim.attributes, f"JOINTS_{s}")).astype(np.int64)
            w = self.unpack(getattr(prim.attributes, f"WEIGHTS_{s}")).astype(np.float64)
            for k in range(4):
                out += w[:, k, None] * np.einsum("vab,vb->va", joint[j[:, k]], homo)
        return out[:, :3]

    def _local(self, n: int, t: int) -> np.ndarray:
        node = self.gltf.nodes[n]
        r = self._key(n, "rotation", t, node.rotation or [0.0, 0.0, 0.0, 1.0])
        m = np.eye(4)
        m[:3, :3] = quaternion.to_matrix(np.roll(r, 1))  # glTF xyzw -> wxyz
        m[:3, 3] = self._key(n, "translation", t, node.translation or [0.0, 0.0, 0.0])
        return m

    def _key(self, n: int, path: str, t: int, default) -> np.ndarray:
        keyed = self.keys.get((n, path))
        return np.asarray(default if keyed is None else keyed[t], dtype=np.float64)

    def _world(self, t: int) -> dict[int, np.ndarray]:
        world: dict[int, np.ndarray] = {}
        stack = [(n, np.eye(4)) for n in self.gltf.scenes[0].nodes]
        while stack:
            n, parent = stack.pop()
            world[n] = parent @ self._local(n, t)
            stack += [(c, world[n]) for c in self.gltf.nodes[n].children or []]
        return world
