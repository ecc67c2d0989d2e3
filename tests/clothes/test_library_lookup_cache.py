"""find_garment remembers what it found (a live slider step validates every worn garment),
and forgets it when the file goes or the folders change."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from avatar.clothes import library
from avatar.errors import AvatarError, ParameterError

FIXTURES = Path(__file__).resolve().parents[3] / "shared" / "fixtures" / "makehuman"
SHOES = FIXTURES / "clothes" / "shoes01"


@pytest.fixture
def asset(tmp_path, monkeypatch):
    if not (SHOES / "shoes01.mhclo").is_file():
        pytest.skip("MakeHuman clothes fixtures not found")
    folder = tmp_path / "assets"
    shutil.copytree(SHOES, folder / "shoes01")
    monkeypatch.delenv(library.ENV_PATH, raising=False)
    return folder


def test_a_name_found_by_scanning_is_not_scanned_again(asset, monkeypatch):
    found = library.find_garment("shoes01", [asset])
    assert found == str(asset / "shoes01" / "shoes01.mhclo")
    scans = []
    real = library.list_garments
    monkeypatch.setattr(library, "list_garments",
                        lambda *a, **k: scans.append(1) or real(*a, **k))  # fmt: skip
    for _ in range(5):
        assert library.find_garment("shoes01", [asset]) == found
        assert library.find_garment(found) == found
    assert scans == []


def test_a_removed_file_is_an_error_again(asset):
    path = asset / "shoes01" / "shoes01.mhclo"
    assert library.find_garment(str(path)) == str(path)
    assert library.find_garment("shoes01", [asset]) == str(path)
    path.unlink()
    with pytest.raises(AvatarError, match="no such garment file"):
        library.find_garment(str(path))
    with pytest.raises(ParameterError):
        library.find_garment("shoes01", [asset])


def test_other_folders_are_another_question(asset, tmp_path):
    assert library.find_garment("shoes01", [asset])
    with pytest.raises(ParameterError):
        library.find_garment("shoes01", [tmp_path / "elsewhere"])
    assert library.find_garment("tshirt") == "tshirt"  # built-ins: no file, no memo needed
