"""Fuzzing the ``avatar`` command: random bad arguments and bad or garbage files (BVH, .mhm,
.mhclo, OBJ, random bytes) for create, retarget, poses, clothes and info never raise out of
``avatar.cli.main`` (what a user would see as a traceback), exit with 0, 1 or 2, print
errors as one ``avatar: error:`` line, and leave nothing half-written."""

from __future__ import annotations

import contextlib
import io
import shutil
import tempfile
from datetime import timedelta
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from avatar import cli

FIXTURES = Path(__file__).resolve().parents[1].parent / "shared" / "fixtures"
WALK = FIXTURES / "bvh" / "cmu_motionbuilder" / "pfnn_hierarchy_30fps.bvh"

GOOD_BVH = """HIERARCHY
ROOT Hips
{
\tOFFSET 0 90 0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\tJOINT Spine
\t{
\t\tOFFSET 0 10 0
\t\tCHANNELS 3 Zrotation Xrotation Yrotation
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0 50 0
\t\t}
\t}
}
MOTION
Frames: 2
Frame Time: .0333333
0 90 0 0 0 0 0 0 0
0 91 0 5 0 0 0 3 0
"""
GOOD_MHM = (
    "version v1.1.1\nname fuzz\nmodifier macrodetails/Gender 0.300000\n"
    "skeleton game_engine.mhskel\n"
)
GOOD_MHCLO = "name fuzz\nuuid 1234\nobj_file fuzz.obj\nverts 0\n0 1 2 0.3 0.3 0.4 0 0 0\n"
GOOD_OBJ = "v 0 -0.2 1\nv 0.1 -0.2 1\nv 0 -0.2 1.1\nf 1 2 3\n"

_JUNK_LINES = ["", "nan", "Frames: -1", "Frames: 0", "Frame Time: 0", "MOTION", "{", "}",
               "ROOT", "JOINT x", "CHANNELS 9 Xrotation", "OFFSET 1 2", "modifier", "modifier a",
               "modifier macrodetails/Gender nan", "modifier nope/nope 1", "skeleton nope.mhskel",
               "clothes missing 00", "verts 0", "verts", "0 1", "v 1 2", "v nan 0 0", "f 1 2 99",
               "f 0 0 0", "f", "obj_file ../../etc/passwd", "x_scale 1 2", "1e999", "\x00",
               "delete_verts 5 - 2", "eyebrows eyebrow001 00", "subdivide maybe"]  # fmt: skip


@st.composite
def _text(draw, good: str) -> bytes:
    """A file's bytes: the good text cut, spliced with junk lines, or random bytes."""
    kind = draw(st.sampled_from(["cut", "junk", "bytes", "empty", "good"]))
    if kind == "bytes":
        return draw(st.binary(max_size=300))
    if kind == "empty":
        return b""
    lines = good.splitlines()
    if kind == "cut":
        lines = lines[: draw(st.integers(0, len(lines)))]
    if kind == "junk":
        for _ in range(draw(st.integers(1, 4))):
            at = draw(st.integers(0, len(lines)))
            lines.insert(at, draw(st.sampled_from(_JUNK_LINES)))
    return ("\n".join(lines) + "\n").encode("utf-8")


_NUMBERS = st.sampled_from(["-5", "0", "nan", "inf", "1e999", "abc", "", "30", "400", "-0"])
_NAMES = st.sampled_from(["gender", "nope", "pca/belly", "height", "waist", "", "=", "age=1"])


@st.composite
def _command(draw, folder: Path) -> tuple[list[str], list[Path]]:
    """(argv, the output paths it may write) with bad arguments and bad files in ``folder``."""
    files = {
        "bvh": draw(_text(GOOD_BVH)),
        "mhm": draw(_text(GOOD_MHM)),
        "mhclo": draw(_text(GOOD_MHCLO)),
        "obj": draw(_text(GOOD_OBJ)),
    }
    for suffix, data in files.items():
        (folder / f"in.{suffix}").write_bytes(data)
    (folder / "in.obj.bin").write_bytes(draw(st.binary(max_size=64)))
    out_dir = folder / "out"
    outputs = draw(
        st.sampled_from(
            [
                out_dir / "h.mhm",
                out_dir / "h.bvh",
                out_dir / "h.xyz",
                folder / "missing" / "h.mhm",
                folder / "in.bvh" / "h.mhm",  # under a file
                out_dir,  # a folder
            ]
        )
    )
    out_dir.mkdir(exist_ok=True)
    pick = st.sampled_from
    command = draw(pick(["create", "retarget", "poses", "clothes-bind", "clothes-list",
                         "clothes-thumbnails", "info"]))  # fmt: skip
    argv: list[str]
    if command == "create":
        argv = ["create"]
        if draw(st.booleans()):
            argv.append(str(folder / draw(pick(["in.mhm", "in.bvh", "none.mhm", "in.obj.bin"]))))
        for flag, values in (
            ("--set", st.builds(lambda n, v: f"{n}={v}", _NAMES, _NUMBERS)),
            ("--measure", st.builds(lambda n, v: f"{n}={v}", _NAMES, _NUMBERS)),
            ("--fps", _NUMBERS),
            ("--bake-segment", pick(["0", "-3", "x", "2.5", "1"])),
            ("--frames", pick(["0:2", "5:1", "x", "::", "-3:"])),
            ("--motion", pick([str(folder / "in.bvh"), "missing.bvh", "walk", "run"])),
            ("--pose", pick([str(folder / "in.bvh"), "nope", str(folder / "in.mhm")])),
            ("--wear", pick([str(folder / "in.mhclo"), "nope", str(folder / "none.mhclo")])),
            ("--rig", pick(["nope", "default", ""])),
            ("--skin", pick(["avatar", "nope", str(folder / "in.mhmat"), str(folder / "in.mhm")])),
            ("--eyes", pick(["blue", "purple", ""])),
        ):
            if draw(st.integers(0, 3)) == 0:
                argv += [flag, draw(values)]
        argv += ["-o", str(outputs)]
        writes = [outputs]
    elif command == "retarget":
        clip = draw(pick([folder / "in.bvh", folder, folder / "out", folder / "none.bvh"]))
        frames, rig = draw(pick(["0:2", "x", "3:1"])), draw(pick(["game_engine", "nope"]))
        argv = ["retarget", str(clip), "--out", str(outputs.parent / "clips"), "--frames",
                frames, "--rig", rig]  # fmt: skip
        if draw(st.booleans()):
            argv += ["--fps", draw(_NUMBERS)]
        if draw(st.booleans()):
            argv += ["--report", str(outputs.parent / "report.json")]
        writes = [outputs.parent / "clips", outputs.parent / "report.json"]
    elif command == "poses":
        argv = ["poses", "list", "--folder", str(draw(pick([folder, folder / "none"])))]
        writes = []
    elif command == "clothes-bind":
        argv = ["clothes", "bind", str(folder / draw(pick(["in.obj", "in.bvh", "none.obj"]))),
                "-o", str(outputs.parent / "garment")]  # fmt: skip
        if draw(st.booleans()):
            argv += ["--frame", draw(pick(["auto", "avatar", "nope"]))]
        if draw(st.booleans()):
            argv += ["--set", draw(st.builds(lambda n, v: f"{n}={v}", _NAMES, _NUMBERS))]
        writes = [outputs.parent / "garment"]
    elif command == "clothes-thumbnails":
        names = draw(st.lists(pick(["cap", "socks", "nope", str(folder / "in.mhclo")]),
                              min_size=1, max_size=2))  # fmt: skip
        out = draw(pick([outputs.parent / "pictures", folder / "in.bvh" / "pictures"]))
        argv = ["clothes", "thumbnails", *names, "--out", str(out),
                "--size", draw(pick(["24", "4", "x", "2000"]))]  # fmt: skip
        writes = [out]
    elif command == "clothes-list":
        argv = ["clothes", "list", "--folder", str(folder), "--search", draw(_NAMES)]
        writes = []
    else:
        argv = ["info", *draw(pick([["--params"], ["--search", "zzz"], ["--nope"], []]))]
        writes = []
    return argv, writes


def _run(argv: list[str]) -> tuple[int, str]:
    """(exit status, stderr) of ``avatar.cli.main`` in this process."""
    err, out = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
        try:
            code = cli.main(argv)
        except SystemExit as exc:  # argparse: usage errors and --help
            code = exc.code if isinstance(exc.code, int) else 2
    return code, err.getvalue()


@pytest.mark.usefixtures("model")
@settings(max_examples=150, deadline=timedelta(seconds=60), derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])  # fmt: skip
@given(st.data())
def test_bad_arguments_and_files_never_raise_out_of_the_cli(data):
    folder = Path(tempfile.mkdtemp(prefix="avatar-fuzz-"))
    try:
        argv, writes = data.draw(_command(folder))
        code, err = _run(argv)
        assert code in (0, 1, 2), (argv, code, err)
        assert "Traceback" not in err, (argv, err)
        if code == 1:
            errors = [line for line in err.splitlines() if line.startswith("avatar: error: ")]
            assert errors, (argv, err)
        # nothing half-written: no temporary files anywhere; a failed create wrote nothing
        leftovers = [p for p in folder.rglob("*") if p.name.endswith(".part")]
        assert not leftovers, (argv, leftovers)
        if code != 0 and argv[0] == "create":
            assert not any(p.is_file() for p in writes), (argv, err)
        if code != 0 and argv[:2] in (["clothes", "bind"], ["clothes", "thumbnails"]):
            assert not any(p.exists() for p in writes), (argv, err)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


@pytest.mark.skipif(not WALK.exists(), reason="../shared/fixtures is absent")
def test_fuzz_helpers_accept_a_good_run(tmp_path, model):
    """The harness itself: a good command exits 0 with nothing on stderr but logging."""
    code, err = _run(["retarget", str(WALK), "--frames", "0:4", "--rig", "game_engine",
                      "--out", str(tmp_path / "o")])  # fmt: skip
    assert code == 0 and "error" not in err
    assert (tmp_path / "o" / WALK.name).is_file()
