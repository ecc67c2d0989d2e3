"""The `avatar` command end to end (in-process)."""

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
    assert mesh.vertices.shape == (13380, 3) and np.isfinite(mesh.vertices).all()


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


@pytest.mark.parametrize(("flags", "resolve"), [([], True), (["--no-resolve-garments"], False)])
def test_create_resolves_garments_in_animations_unless_told_not_to(tmp_path, model, monkeypatch,
                                                                   flags, resolve):  # fmt: skip
    """Dressed + animated glTF bakes the garment resolve by default, with a progress bar."""
    import avatar.export

    calls = []
    monkeypatch.setattr(avatar.export, "save", lambda *a, **k: calls.append((a, k)) or a[1])
    argv = ["create", "--wear", "tshirt", "--motion", "walk", "--fps", "4",
            "-o", str(tmp_path / "w.glb"), *flags]  # fmt: skip
    assert cli.main(argv) == 0
    ((args, kwargs),) = calls
    assert kwargs["resolve_garments"] is resolve and kwargs["progress"] is True
    assert args[0].recipe.clothes == ("tshirt",) and args[2].frames == 8
