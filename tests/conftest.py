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
def fixtures() -> Path:
    """../shared/fixtures (real MakeHuman/CMU data for tests only); skips when absent."""
    if not FIXTURES.is_dir():
        pytest.skip(f"shared fixtures not found at {FIXTURES}")
    return FIXTURES
