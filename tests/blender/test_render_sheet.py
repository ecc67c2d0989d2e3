"""bench/render_sheet.py: every built-in is worn on the sheet, and a tiny sheet (two bodies,
64 px, 1 sample) shows a person in the Avatar row and, with the shared fixtures, in the
MakeHuman row next to it."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
BENCH = ROOT / "bench"
FIXTURES = ROOT.parent / "shared" / "fixtures"


@pytest.fixture(scope="module")
def sheet_module():
    sys.path.insert(0, str(BENCH))
    try:
        spec = importlib.util.spec_from_file_location("render_sheet", BENCH / "render_sheet.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules["render_sheet"] = module  # dataclasses look their module up
        spec.loader.exec_module(module)
        return module
    finally:
        sys.path.remove(str(BENCH))


def test_every_builtin_is_worn_and_every_body_has_a_makehuman_outfit(sheet_module):
    from avatar.clothes import library

    bodies = sheet_module.outfits()
    assert len(bodies) == len(sheet_module.NAMES) == len(sheet_module.MAKEHUMAN) == 8
    worn = {name for _, names in bodies for name in names}
    assert {e.name for e in library.builtin_entries()} <= worn
    if FIXTURES.is_dir():
        for i in range(8):
            for path in sheet_module.makehuman_outfit(i, FIXTURES):
                assert Path(path).is_file(), path


def test_a_tiny_sheet_shows_a_person_in_each_row(sheet_module, tmp_path):
    from PIL import Image

    indices = [0, 3]  # child, man: both poses' code paths
    bodies = [sheet_module.outfits()[i] for i in indices]
    fixtures = FIXTURES if (FIXTURES / "makehuman").is_dir() else None
    rows = sheet_module.rows_for(bodies, indices, fixtures)
    assert len(rows) == (2 if fixtures else 1)  # the MakeHuman row only with the fixtures
    sheet = sheet_module.make_sheet(rows, "front", "walk", tmp_path / "sheet_front_walk.png",
                                    tmp_path / "raw", indices, width=64, samples=1)  # fmt: skip
    pixels = np.asarray(Image.open(sheet.path).convert("RGB"), dtype=np.float32) / 255
    assert pixels.shape[1] == 64
    assert pixels.std() > 0.05  # not a flat image
    backdrop = np.asarray(sheet_module.BACKDROP, np.float32) / 255
    assert len(sheet.boxes) == len(rows)
    for (top, bottom), raw in zip(sheet.boxes, sheet.rows, strict=True):
        band = pixels[top:bottom]
        person = np.abs(band - backdrop).max(axis=-1) > 0.08
        assert person.mean() > 0.04, person.mean()  # two bodies take >4% of their row
        # Opaque pixels of the row's own render (transparent film): the people, both halves.
        alpha = np.asarray(Image.open(raw))[..., 3] > 128
        half = alpha.shape[1] // 2
        assert alpha[:, :half].mean() > 0.02 and alpha[:, half:].mean() > 0.02
