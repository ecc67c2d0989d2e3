"""The `avatar` command end to end (in-process)."""

import os
import re

import numpy as np
import pytest

from avatar import cli
from avatar.io import mhm, obj


def test_help_lists_every_command(capsys):
    with pytest.raises(SystemExit):
        cli.main(["--help"])
    out = capsys.readouterr().out
    for command in ("create", "info"):
        assert command in out


def test_create_obj_and_mhm(tmp_path, model):
    assert cli.main(["create", "--set", "gender=1", "--set", "pca/belly=1", "-o",
                     str(tmp_path / "h.mhm")]) == 0  # fmt: skip
    assert cli.main(["create", str(tmp_path / "h.mhm"), "--pose", "t-pose", "-o",
                     str(tmp_path / "h.obj")]) == 0  # fmt: skip
    assert mhm.read(tmp_path / "h.mhm").modifiers["macrodetails/Gender"] == 1.0
    mesh = obj.read(tmp_path / "h.obj")
    # the skin (13,380 vertices) and, since OBJ writes every part, the eyes
    assert mesh.vertices.shape[0] >= 13380 and np.isfinite(mesh.vertices).all()


def test_create_with_measurements(tmp_path, model, caplog):
    assert cli.main(["create", "--measure", "height=185", "-o", str(tmp_path / "t.obj")]) == 0
    z = obj.read(tmp_path / "t.obj").vertices[:, 2]
    assert z.max() - z.min() == pytest.approx(1.85, abs=0.01)


def test_errors_are_reported_not_raised(tmp_path, capsys, model):
    assert cli.main(["create", "--set", "gendr=1", "-o", str(tmp_path / "x.obj")]) == 1
    assert "did you mean" in capsys.readouterr().err
    assert cli.main(["create", "-o", str(tmp_path / "x.xyz")]) == 1
    assert cli.main(["create", "--rig", "nope", "-o", str(tmp_path / "x.obj")]) == 1
    assert cli.main(["create", "--set", "age", "-o", str(tmp_path / "x.obj")]) == 1


def test_info_lists_parameters(capsys, model):
    assert cli.main(["info", "--search", "pca/"]) == 0
    out = capsys.readouterr().out
    assert out.count("pca/") == 7


@pytest.mark.parametrize(("flags", "resolve", "segment"), [
    ([], True, 300), (["--no-resolve-garments"], False, 300), (["--bake-segment", "120"], True, 120)
])  # fmt: skip
def test_create_resolves_garments_in_animations_unless_told_not_to(
    tmp_path, model, monkeypatch, flags, resolve, segment
):
    """Dressed + animated glTF bakes the garment resolve by default, with a progress bar, in
    segments of at most 300 frames unless told otherwise."""
    import avatar.export

    calls = []
    monkeypatch.setattr(avatar.export, "save", lambda *a, **k: calls.append((a, k)) or a[1])
    argv = ["create", "--wear", "tshirt", "--motion", "walk", "--fps", "4",
            "-o", str(tmp_path / "w.glb"), *flags]  # fmt: skip
    assert cli.main(argv) == 0
    ((args, kwargs),) = calls
    assert kwargs["resolve_garments"] is resolve and kwargs["progress"] is True
    assert kwargs["bake_segment"] == segment
    assert args[0].recipe.clothes == ("tshirt",) and args[2].frames == 8


def _one_line_error(capsys) -> str:
    """The command's stderr: exactly one ``avatar: error: ...`` line, no traceback."""
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("avatar: error: "), err
    assert "Traceback" not in err[0]
    return err[0]


@pytest.mark.parametrize("segment", ["0", "-2", "1.5", "many"])
def test_create_refuses_a_bake_segment_under_one_frame_as_a_usage_error(tmp_path, capsys,
                                                                        segment):  # fmt: skip
    with pytest.raises(SystemExit) as exit_:
        cli.main(["create", "--wear", "tshirt", "--motion", "walk", "--bake-segment", segment,
                  "-o", str(tmp_path / "w.glb")])  # fmt: skip
    assert exit_.value.code == 2
    assert "--bake-segment" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("fps", ["-5", "0", "nan", "inf", "fast"])
def test_create_refuses_a_non_positive_fps_as_a_usage_error(tmp_path, capsys, fps):
    with pytest.raises(SystemExit) as exit_:
        cli.main(["create", "--motion", "walk", "--fps", fps, "-o", str(tmp_path / "w.glb")])
    assert exit_.value.code == 2
    assert "--fps" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    ("where", "words"),
    [
        (lambda tmp: tmp / "missing" / "h.glb", "does not exist"),  # a folder that is not there
        (lambda tmp: tmp / "file.txt" / "h.glb", "is a file"),  # a path under a file
        (lambda tmp: tmp, "is a folder"),  # a folder, not a file
    ],
)
def test_create_refuses_outputs_it_cannot_write_before_any_work(tmp_path, capsys, monkeypatch,
                                                                where, words):  # fmt: skip
    import avatar.cli.create

    (tmp_path / "file.txt").write_text("x")
    built = []
    monkeypatch.setattr(avatar.cli.create, "BodyModel", lambda *a: built.append(a))
    assert cli.main(["create", "-o", str(where(tmp_path))]) == 1
    line = _one_line_error(capsys)
    assert words in line and str(where(tmp_path)) in line
    assert not built  # refused before the body model was even loaded
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.txt"]


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root writes anywhere")
def test_create_refuses_a_read_only_folder(tmp_path, capsys):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        assert cli.main(["create", "-o", str(folder / "h.glb")]) == 1
        assert "not writable" in _one_line_error(capsys)
    finally:
        folder.chmod(0o700)


def test_a_write_that_fails_anyway_is_one_line(tmp_path, capsys, monkeypatch, model):
    """An OSError at write time (disk full, a folder removed meanwhile) is one line too."""
    import avatar.export

    def full(*args, **kwargs):
        raise OSError(28, "No space left on device", str(tmp_path / "h.obj"))

    monkeypatch.setattr(avatar.export, "save", full)
    assert cli.main(["create", "-o", str(tmp_path / "h.obj")]) == 1
    assert "No space left on device" in _one_line_error(capsys)


def test_create_refuses_a_missing_motion_or_character_file(tmp_path, capsys):
    out = tmp_path / "h.glb"
    assert cli.main(["create", "--motion", str(tmp_path / "missing.bvh"), "-o", str(out)]) == 1
    line = _one_line_error(capsys)
    assert "missing.bvh" in line and "no such file" in line and "walk" in line
    assert cli.main(["create", str(tmp_path / "me.mhm"), "-o", str(out)]) == 1
    assert "me.mhm" in _one_line_error(capsys)
    assert not list(tmp_path.iterdir())


def test_unreachable_measurements_name_the_reachable_range(tmp_path, capsys, model):
    out = tmp_path / "t.obj"
    assert cli.main(["create", "--measure", "height=400", "-o", str(out)]) == 1
    line = _one_line_error(capsys)
    low, high = (float(v) for v in re.search(r"ranges ([\d.]+)-([\d.]+) cm", line).groups())
    assert "height 400 cm is out of reach" in line and 100 < low < 160 < 200 < high < 260
    assert not out.exists()


@pytest.mark.parametrize("value", ["-5", "0", "nan"])
def test_non_positive_measurements_are_errors(tmp_path, capsys, value):
    assert cli.main(["create", "--measure", f"waist={value}", "-o", str(tmp_path / "t.obj")]) == 1
    assert "--measure waist: a measurement is a positive length in cm" in _one_line_error(capsys)
    assert not list(tmp_path.iterdir())


def _cube_obj(path, corner, size):
    """A closed cube OBJ (metres, Avatar's frame) with one corner at ``corner``."""
    lines = [f"v {corner[0] + x} {corner[1] + y} {corner[2] + z}"
             for x in (0, size) for y in (0, size) for z in (0, size)]  # fmt: skip
    lines += ["f 1 2 4 3", "f 5 7 8 6", "f 1 5 6 2", "f 3 4 8 7", "f 1 3 7 5", "f 2 6 8 4"]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("frame", [[], ["--frame", "avatar"], ["--frame", "makehuman"]])
def test_binding_a_mesh_far_from_the_body_is_an_error_naming_the_limit(tmp_path, capsys,
                                                                       model, frame):  # fmt: skip
    far = _cube_obj(tmp_path / "far.obj", (10.0, 0.0, 1.0), 0.5)  # 10 m beside the body
    out = tmp_path / "garments"
    assert cli.main(["clothes", "bind", str(far), "-o", str(out), *frame]) == 1
    line = _one_line_error(capsys)
    assert "far.obj" in line and "limit 0.5 m" in line
    assert not out.exists()
    near = _cube_obj(tmp_path / "near.obj", (-0.15, -0.2, 1.0), 0.3)  # around the chest
    assert cli.main(["clothes", "bind", str(near), "-o", str(out)]) == 0
    assert (out / "near.mhclo").is_file()
