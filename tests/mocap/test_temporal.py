"""Zero-lag smoothing of keypoint clips (``temporal.smooth``): less jitter, no lag, missing
samples neither used nor spread, bad arguments a clear error."""

from __future__ import annotations

import numpy as np
import pytest

from avatar.errors import ParameterError
from avatar.mocap import temporal


def _jerk(points: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(points, 2, axis=0), axis=-1).mean())


def test_jitter_goes_and_steady_motion_keeps_its_place():
    fps, t = 30.0, np.arange(120) / 30.0
    clean = np.zeros((120, 2, 3))
    clean[:, 0, 0] = 0.8 * t  # a joint moving steadily at 0.8 m/s
    clean[:, 1, 2] = 0.1 * np.sin(2 * np.pi * 0.5 * t)  # a slow swing
    noisy = clean + np.random.default_rng(0).normal(0.0, 0.01, clean.shape)
    got = temporal.smooth(noisy, None, fps)
    assert _jerk(got) < 0.25 * _jerk(noisy)
    inner = slice(5, -5)  # away from the clip's ends (the window shrinks there)
    assert np.abs(got[inner] - clean[inner]).mean() < 0.6 * np.abs(noisy - clean).mean()
    steady = temporal.smooth(clean, None, fps)
    np.testing.assert_allclose(steady[:, 0], clean[:, 0], atol=1e-12)  # no lag, ends too
    np.testing.assert_allclose(steady[inner, 1], clean[inner, 1], atol=2e-3)  # 0.1 m swing


def test_missing_samples_take_no_part_and_do_not_spread():
    points = np.zeros((40, 3, 3))
    points[:, :, 0] = 1.0
    points[10, 0] = np.nan  # missing: filled from its neighbours, not NaN around it
    points[20, 1] = 50.0  # an outlier with no confidence: ignored
    confidence = np.ones((40, 3))
    confidence[20, 1] = 0.1
    points[:, 2] = np.nan  # never seen: stays missing
    got = temporal.smooth(points, confidence, 30.0)
    np.testing.assert_allclose(got[:, :2, 0], 1.0, atol=1e-12)
    assert np.isnan(got[:, 2]).all()


def test_zero_sigma_and_bad_arguments():
    points = np.random.default_rng(1).normal(size=(10, 4, 3))
    np.testing.assert_array_equal(temporal.smooth(points, None, 30.0, sigma=0.0), points)
    with pytest.raises(ParameterError, match="frames, keypoints, 3"):
        temporal.smooth(points[..., :2], None, 30.0)
    for sigma, fps in ((-1.0, 30.0), (float("nan"), 30.0), (0.05, 0.0)):
        with pytest.raises(ParameterError, match="sigma"):
            temporal.smooth(points, None, fps, sigma=sigma)


def test_a_sudden_start_is_not_pulled_towards_later_frames():
    """The first frame keeps its pose (a clip starting in a T-pose whose arms drop at once:
    a one-sided window moved the first frame's arms half-way down)."""
    points = np.zeros((30, 1, 3))
    points[0, 0, 2] = 1.0  # frame 0 up, every later frame down
    got = temporal.smooth(points, None, 30.0)
    assert got[0, 0, 2] == 1.0
    assert got[1:, 0, 2].max() < 0.5
