"""Animated morph target weights for glTF 2.0 (spec section 3.11, ``weights`` path).

A ``weights`` channel targets a mesh node; its sampler's output holds one weight per morph
target of that mesh for every key (``frames x targets`` floats, frame after frame). Avatar
writes them with STEP interpolation, into the same animation as the skeleton and on the
same key times, e.g. to switch on one garment correction per frame (``avatar.clothes.bake``).
Outputs that are mostly zero are stored as sparse accessors.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pygltflib as g

from avatar.io import gltf_accessors as acc


def add_channels(
    gltf: g.GLTF2,
    packer: acc.Packer,
    clips: list[str],
    nodes: dict[str, int],
    keyed: Mapping[str, Mapping[str, np.ndarray]],
) -> None:
    """``weights`` channels for the parts named in ``keyed`` (clip -> part -> (T, targets)).

    clips: the file's animation names in order; nodes: part name -> its mesh node.
    """
    for clip, by_part in keyed.items():
        if clip not in clips:
            raise ValueError(f"morph weights for unknown animation {clip!r}")
        for name, weights in by_part.items():
            if name not in nodes:
                raise ValueError(f"morph weights for unknown part {name!r}")
            add_weights_channel(gltf, packer, clips.index(clip), nodes[name], weights)


def add_weights_channel(
    gltf: g.GLTF2, packer: acc.Packer, animation: int, node: int, weights: np.ndarray
) -> None:
    """Key the morph weights (T, targets) of mesh node ``node`` in animation ``animation``.

    T must equal the animation's key count: the channel reuses its time accessor.
    """
    anim = gltf.animations[animation]
    times = anim.samplers[0].input if anim.samplers else None
    weights = np.asarray(weights, dtype=np.float32)
    targets = len(gltf.meshes[gltf.nodes[node].mesh].primitives[0].targets or [])
    if times is None or weights.shape != (gltf.accessors[times].count, targets):
        raise ValueError(
            f"morph weights of node {gltf.nodes[node].name!r} must be (frames, targets) = "
            f"({None if times is None else gltf.accessors[times].count}, {targets}), "
            f"got {weights.shape}"
        )
    output = packer.sparse_accessor(weights.reshape(-1), target=None)
    anim.samplers.append(g.AnimationSampler(input=times, output=output, interpolation="STEP"))
    anim.channels.append(
        g.AnimationChannel(
            sampler=len(anim.samplers) - 1,
            target=g.AnimationChannelTarget(node=node, path="weights"),
        )
    )


def read_weights(gltf: g.GLTF2, buffers: list[bytes]) -> dict[str, dict[int, np.ndarray]]:
    """Animation name -> mesh node -> (T, targets) float32 keyed morph weights.

    Interpolation is not applied: these are the values at the sampler's key times.
    """
    out: dict[str, dict[int, np.ndarray]] = {}
    for i, anim in enumerate(gltf.animations):
        keyed: dict[int, np.ndarray] = {}
        for ch in anim.channels:
            node = ch.target.node
            if ch.target.path != "weights" or node is None:
                continue
            mesh = gltf.nodes[node].mesh
            targets = len(gltf.meshes[mesh].primitives[0].targets or []) if mesh is not None else 0
            sampler = anim.samplers[ch.sampler]
            values = acc.unpack(gltf, buffers, sampler.output).astype(np.float32)
            if sampler.interpolation == "CUBICSPLINE":
                raise ValueError("CUBICSPLINE morph weights are not supported")
            if not targets or len(values) % targets:
                raise ValueError(f"weights channel of node {node}: {len(values)} values "
                                 f"for {targets} targets")  # fmt: skip
            keyed[node] = values.reshape(-1, targets)
        if keyed:
            out[anim.name or f"animation_{i}"] = keyed
    return out
