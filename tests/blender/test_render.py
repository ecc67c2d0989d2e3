"""Workbench and Cycles renders of a staged character produce real pictures."""

from __future__ import annotations

import numpy as np
import pytest
from bridge_fixtures import figure


@pytest.mark.parametrize(("engine", "samples"), [("WORKBENCH", 1), ("CYCLES", 4)])
def test_render_writes_a_picture(empty_scene, rng, tmp_path, engine, samples):
    from avatar.blender import render

    render.stage_characters([figure(rng)], resolution=(128, 192))
    path = render.render(tmp_path / f"{engine}.png", engine=engine, samples=samples,
                         resolution=(128, 192))  # fmt: skip
    pixels = render.read_png(path)
    assert pixels.shape == (192, 128, 4)
    # Something other than the background is in the middle of the frame.
    assert pixels[..., :3].std() > 0.02
    centre = pixels[80:112, 56:72, :3].mean(axis=(0, 1))
    corner = pixels[:16, :16, :3].mean(axis=(0, 1))
    assert np.abs(centre - corner).max() > 0.02


def test_grid_and_strip(empty_scene, rng, tmp_path):
    from bridge_fixtures import random_animation

    from avatar.blender import render

    chars = [figure(rng, f"f{i}") for i in range(3)]
    grid = render.render_grid(chars, tmp_path / "grid.png", engine="WORKBENCH",
                              resolution=(240, 160))  # fmt: skip
    assert render.read_png(grid).shape == (160, 240, 4)
    walker = chars[0]
    from dataclasses import replace

    walker = replace(walker, animation=random_animation(walker.skeleton, rng, frames=7))
    strip = render.render_strip(walker, tmp_path / "strip.png", every=3, panel=(64, 96),
                                engine="WORKBENCH")  # fmt: skip
    assert render.read_png(strip).shape == (96, 64 * 3, 4)
