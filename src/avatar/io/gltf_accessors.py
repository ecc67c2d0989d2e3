"""numpy arrays <-> glTF 2.0 buffer views and accessors (glTF 2.0 spec, section 3.6).

``Packer`` appends arrays to one binary buffer (4-byte aligned views, min/max where the spec
asks for them, sparse accessors for mostly-zero morph targets). ``unpack`` reads any accessor
back, strided or sparse, from a loaded ``pygltflib.GLTF2``.
"""

from __future__ import annotations

import base64
from pathlib import Path

import numpy as np
import pygltflib as g

ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
COMPONENT: dict[int, np.dtype] = {  # glTF componentType -> numpy dtype (little-endian)
    5120: np.dtype("<i1"), 5121: np.dtype("<u1"), 5122: np.dtype("<i2"),
    5123: np.dtype("<u2"), 5125: np.dtype("<u4"), 5126: np.dtype("<f4"),
}  # fmt: skip
COMPONENT_OF = {v: k for k, v in COMPONENT.items()}
WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
TYPE_OF = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4", 16: "MAT4"}


class Packer:
    """Accumulates buffer views and accessors into ``gltf`` and one binary blob."""

    def __init__(self, gltf: g.GLTF2):
        self.gltf = gltf
        self.blob = bytearray()

    def view(self, data: bytes, target: int | None = None) -> int:
        """Append raw bytes as a new buffer view (4-byte aligned); return its index."""
        self.blob.extend(b"\x00" * (-len(self.blob) % 4))
        view = g.BufferView(buffer=0, byteOffset=len(self.blob), byteLength=len(data))
        if target is not None:
            view.target = target
        self.blob.extend(data)
        self.gltf.bufferViews.append(view)
        return len(self.gltf.bufferViews) - 1

    def accessor(self, array: np.ndarray, target: int | None = None, bounds: bool = False) -> int:
        """Append (N,) or (N, C) (or (N, 4, 4) as MAT4) array as an accessor; return its index.

        The dtype must be one of glTF's component types; ``bounds`` writes min/max (required
        for POSITION and animation inputs).
        """
        array = np.ascontiguousarray(array)
        flat = array.reshape(len(array), -1)
        accessor = g.Accessor(
            bufferView=self.view(flat.astype(array.dtype.newbyteorder("<")).tobytes(), target),
            componentType=COMPONENT_OF[array.dtype.newbyteorder("<")],
            count=len(array),
            type=TYPE_OF[flat.shape[1]],
        )
        if bounds:
            accessor.min = flat.min(axis=0).tolist()
            accessor.max = flat.max(axis=0).tolist()
        return self._add(accessor)

    def sparse_accessor(self, values: np.ndarray, target: int | None = ARRAY_BUFFER) -> int:
        """(N,) or (N, C) float32 mostly-zero values -> a sparse accessor over implicit zeros.

        Used for morph target deltas (N, 3) and for morph weight animation outputs (one
        weight set per key, flattened). Falls back to a dense accessor (bound to ``target``)
        when more than a third of the rows are non-zero (sparse storage would be larger).
        min/max always cover all N rows.
        """
        values = np.ascontiguousarray(values, dtype=np.float32)
        rows = values.reshape(len(values), -1)
        nonzero = np.flatnonzero(np.any(rows != 0, axis=1))
        if len(nonzero) * 3 > len(values):
            return self.accessor(values, target, bounds=True)
        accessor = g.Accessor(
            componentType=5126, count=len(values), type=TYPE_OF[rows.shape[1]], byteOffset=None
        )
        accessor.min = np.minimum(rows.min(axis=0, initial=0), 0).tolist()
        accessor.max = np.maximum(rows.max(axis=0, initial=0), 0).tolist()
        if len(nonzero):
            index_type = np.dtype("<u2") if len(values) <= 65536 else np.dtype("<u4")
            accessor.sparse = g.Sparse(
                count=len(nonzero),
                indices=g.AccessorSparseIndices(
                    bufferView=self.view(nonzero.astype(index_type).tobytes()),
                    componentType=COMPONENT_OF[index_type],
                ),
                values=g.AccessorSparseValues(bufferView=self.view(rows[nonzero].tobytes())),
            )
        return self._add(accessor)

    def image(self, png: bytes, name: str) -> int:
        """Append PNG bytes as an image in a buffer view; return the image index."""
        self.gltf.images.append(g.Image(bufferView=self.view(png), mimeType="image/png", name=name))
        return len(self.gltf.images) - 1

    def _add(self, accessor: g.Accessor) -> int:
        self.gltf.accessors.append(accessor)
        return len(self.gltf.accessors) - 1


def buffer_bytes(gltf: g.GLTF2, index: int, folder: Path) -> bytes:
    """The bytes of buffer ``index``: the GLB chunk, a data URI, or a side-car file."""
    uri = gltf.buffers[index].uri
    if uri is None:
        return bytes(gltf.binary_blob() or b"")
    if uri.startswith("data:"):
        return base64.b64decode(uri.split(",", 1)[1])
    return (folder / uri).read_bytes()


def view_bytes(gltf: g.GLTF2, buffers: list[bytes], index: int) -> bytes:
    """The bytes of buffer view ``index``."""
    view = gltf.bufferViews[index]
    start = view.byteOffset or 0
    return buffers[view.buffer][start : start + view.byteLength]


def unpack(gltf: g.GLTF2, buffers: list[bytes], index: int) -> np.ndarray:
    """Accessor ``index`` -> (N,) or (N, C) array ((N, 4, 4) row-major for MAT4).

    Handles byte offsets, strides, sparse substitution and accessors without a view (zeros).
    Normalised integers are returned as stored (not scaled).
    """
    acc = gltf.accessors[index]
    dtype, width = COMPONENT[acc.componentType], WIDTH[acc.type]
    out = np.zeros((acc.count, width), dtype=dtype)
    if acc.bufferView is not None:
        out[:] = _strided(
            gltf, buffers, acc.bufferView, acc.byteOffset or 0, dtype, width, acc.count
        )
    if acc.sparse is not None and acc.sparse.count:
        sp = acc.sparse
        idx_dtype = COMPONENT[sp.indices.componentType]
        rows = _strided(
            gltf, buffers, sp.indices.bufferView, sp.indices.byteOffset or 0, idx_dtype, 1, sp.count
        )[:, 0]
        out[rows] = _strided(
            gltf, buffers, sp.values.bufferView, sp.values.byteOffset or 0, dtype, width, sp.count
        )
    if acc.type == "MAT4":  # column-major in the file
        return out.reshape(-1, 4, 4).transpose(0, 2, 1)
    return out[:, 0] if width == 1 else out


def _strided(gltf, buffers, view_index, offset, dtype, width, count) -> np.ndarray:
    """(count, width) elements of a (possibly interleaved) buffer view."""
    view = gltf.bufferViews[view_index]
    data = view_bytes(gltf, buffers, view_index)
    item = dtype.itemsize * width
    stride = view.byteStride or item
    if stride == item:
        return np.frombuffer(data, dtype=dtype, count=count * width, offset=offset).reshape(
            count, width
        )
    raw = np.frombuffer(data, dtype=np.uint8)
    rows = np.lib.stride_tricks.as_strided(raw[offset:], shape=(count, item), strides=(stride, 1))
    return np.ascontiguousarray(rows).view(dtype).reshape(count, width)
