"""avatar.io.atomic, and every io writer through it: an interrupted write leaves the old file
untouched and nothing partial beside it."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest
from gltf_fixtures import scene

from avatar.io import atomic, bvh, gltf, mhclo, mhm, mhmat, mhw, obj, png
from avatar.mesh import Mesh

IO = Path(atomic.__file__).resolve().parent
ALLOWED = ("avatar.errors", "avatar.mesh", "avatar.material", "avatar.part", "avatar.rig",
           "avatar.io")  # fmt: skip


class Boom(Exception):
    pass


def _files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


# ----------------------------------------------------------------------------- the helper


def test_replacing_writes_the_file_and_leaves_no_temporary(tmp_path):
    dest = tmp_path / "a.txt"
    with atomic.replacing(dest) as tmp:
        assert tmp.parent == dest.parent and tmp != dest
        tmp.write_text("new")
        assert not dest.exists()  # nothing visible until the block ends
    assert _files(tmp_path) == {"a.txt": b"new"}


def test_a_writer_raising_midway_keeps_the_old_file_and_no_temporary(tmp_path):
    dest = tmp_path / "a.txt"
    dest.write_text("old")
    with pytest.raises(Boom), atomic.replacing(dest) as tmp:
        tmp.write_text("half of the ne")
        raise Boom
    assert _files(tmp_path) == {"a.txt": b"old"}


def test_keyboard_interrupt_cleans_up_too(tmp_path):
    dest = tmp_path / "a.txt"
    dest.write_text("old")

    def write(tmp: Path) -> None:
        tmp.write_text("partial")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic.write_all({dest: write})
    assert _files(tmp_path) == {"a.txt": b"old"}


def test_write_all_replaces_every_file(tmp_path):
    (tmp_path / "x.gltf").write_text("old json")
    (tmp_path / "x.bin").write_bytes(b"old")
    gltf_path = str(tmp_path / "x.gltf")  # str or Path
    atomic.write_all({tmp_path / "x.bin": lambda tmp: tmp.write_bytes(b"new blob"),
                      gltf_path: lambda tmp: tmp.write_text("new json")})  # fmt: skip
    assert _files(tmp_path) == {"x.bin": b"new blob", "x.gltf": b"new json"}


def test_write_all_replaces_nothing_unless_every_file_was_written(tmp_path):
    (tmp_path / "x.gltf").write_text("old json")
    (tmp_path / "x.bin").write_bytes(b"old")

    def fail(tmp: Path) -> None:
        tmp.write_text("{ half")
        raise Boom

    with pytest.raises(Boom):
        atomic.write_all({tmp_path / "x.bin": lambda tmp: tmp.write_bytes(b"new blob"),
                          tmp_path / "x.gltf": fail})  # fmt: skip
    assert _files(tmp_path) == {"x.bin": b"old", "x.gltf": b"old json"}


def test_a_writer_that_writes_nothing_fails_without_touching_the_file(tmp_path):
    dest = tmp_path / "a.txt"
    dest.write_text("old")
    with pytest.raises(FileNotFoundError):
        atomic.write_all({dest: lambda tmp: None})
    assert _files(tmp_path) == {"a.txt": b"old"}


def test_write_text_and_bytes_match_pathlib(tmp_path):
    text = "ünïcode\nlines\n"
    atomic.write_text(tmp_path / "a", text)
    (tmp_path / "b").write_text(text, encoding="utf-8")
    atomic.write_bytes(tmp_path / "c", b"\x00\xff")
    assert (tmp_path / "a").read_bytes() == (tmp_path / "b").read_bytes()
    assert (tmp_path / "c").read_bytes() == b"\x00\xff"


def test_a_missing_folder_raises_and_creates_nothing(tmp_path):
    with pytest.raises(FileNotFoundError):
        atomic.write_text(tmp_path / "no" / "a.txt", "x")
    assert _files(tmp_path) == {}


# ----------------------------------------------------------------------- every io writer

MESH = Mesh(
    vertices=np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float32),
    faces=np.array([[0, 1, 2, 3]], np.int32),
)
MHCLO = """name tiny
obj_file tiny.obj
x_scale 5399 11998 1.4340
verts 0
17090 17384 17383 0.16911 0.65529 0.17560 0.02236 0.02127 -0.06878
4
"""
BVH = """HIERARCHY
ROOT Hips
{
\tOFFSET 0 90 0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\tEnd Site
\t{
\t\tOFFSET 0 50 0
\t}
}
MOTION
Frames: 1
Frame Time: .0333333
1 90 2 10 20 30
"""

# name -> (file name, write(path)): each writes a non-trivial file.
WRITERS = {
    "obj": ("m.obj", lambda p: obj.write(p, MESH)),
    "mhm": ("c.mhm", lambda p: mhm.write(p, mhm.CharacterFile("me", modifiers={"a": 0.5}))),
    "mhmat": ("m.mhmat", lambda p: mhmat.write(p, mhmat.loads("name m\ndiffuseColor 1 0 0\n"))),
    "mhclo": ("g.mhclo", lambda p: mhclo.write(p, mhclo.loads(MHCLO))),
    "mhw": ("w.mhw", lambda p: mhw.write(p, mhw.loads('{"weights": {"a": [[0, 1.0]]}}'))),
    "bvh": ("a.bvh", lambda p: bvh.write(p, bvh.loads(BVH))),
    "png": ("t.png", lambda p: png.write(p, np.full((4, 4, 3), 200, np.uint8))),
}


def _half_then_fail(monkeypatch) -> None:
    """Make every pathlib text/bytes write put half its data on disk, then fail (a full
    disk, a crash): the file a writer leaves behind is then partial."""

    def text(self, data, *args, **kwargs):
        with open(self, "w", encoding="utf-8") as f:
            f.write(data[: len(data) // 2])
        raise Boom

    def raw(self, data):
        with open(self, "wb") as f:
            f.write(data[: len(data) // 2])
        raise Boom

    monkeypatch.setattr(Path, "write_text", text)
    monkeypatch.setattr(Path, "write_bytes", raw)


@pytest.mark.parametrize("kind", sorted(WRITERS))
def test_an_interrupted_write_keeps_the_old_file(tmp_path, monkeypatch, kind):
    name, write = WRITERS[kind]
    (tmp_path / name).write_bytes(b"the old file")
    write(tmp_path / name)
    written = (tmp_path / name).read_bytes()
    assert written != b"the old file" and _files(tmp_path) == {name: written}
    _half_then_fail(monkeypatch)
    with pytest.raises(Boom):
        write(tmp_path / name)
    assert _files(tmp_path) == {name: written}


@pytest.mark.parametrize("kind", sorted(WRITERS))
def test_an_interrupted_first_write_leaves_no_file(tmp_path, monkeypatch, kind):
    name, write = WRITERS[kind]
    _half_then_fail(monkeypatch)
    with pytest.raises(Boom):
        write(tmp_path / name)
    assert _files(tmp_path) == {}


@pytest.mark.parametrize("name", ["t.glb", "t.gltf", "embedded.gltf"])
def test_an_interrupted_gltf_write_keeps_the_old_files(tmp_path, monkeypatch, name):
    parts, sk, anim = scene()
    path = tmp_path / name
    gltf.write(path, parts, sk, {"bend": anim}, embed=name.startswith("embedded"))
    before = _files(tmp_path)
    assert len(before) == (2 if name == "t.gltf" else 1)

    def half(self, fname):  # the .glb container, half written
        with open(fname, "wb") as f:
            f.write(b"glTF half")
        raise Boom

    monkeypatch.setattr(gltf.g.GLTF2, "save_binary", half)
    _half_then_fail(monkeypatch)  # .gltf: the .bin half written first, then the JSON fails
    with pytest.raises(Boom):
        gltf.write(path, parts[1:], sk, {"bend": anim}, embed=name.startswith("embedded"))
    assert _files(tmp_path) == before


def test_io_imports_only_formats():
    """io reads and writes arrays and records: it may import errors, mesh, material, part,
    rig and itself, never body, clothes, motion, geometry, looks, human or export."""
    bad = []
    for path in sorted(IO.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                assert node.level == 0, f"{path.name}:{node.lineno}: relative import"
                mod = node.module or ""
                names = [f"{mod}.{a.name}" for a in node.names] if mod == "avatar" else [mod]
            else:
                continue
            bad += [f"{path.name}:{node.lineno} {n}" for n in names
                    if (n == "avatar" or n.startswith("avatar."))
                    and not any(n == a or n.startswith(a + ".") for a in ALLOWED)]  # fmt: skip
    assert bad == []
