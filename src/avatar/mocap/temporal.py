"""Zero-lag smoothing of a whole keypoint clip over time (offline: video files).

A live stream can only filter causally (``filters.OneEuro``: smoothing costs lag). A video
file is known from its first frame to its last, so each frame's keypoints can be averaged
with the frames on both sides: a Gaussian over time, which removes frame-to-frame jitter
without delaying anything (a joint moving at constant speed is left where it is).

Missing keypoints (NaN, or confidence below the threshold) take no part: each output is the
weighted mean of the seen samples within three sigmas (normalised convolution), and a
keypoint seen in none of them stays missing. Near the clip's ends the window shrinks to
what both sides have (the first and last frames are kept as they are). Confidence is left
as it was.

Measured on rendered ground truth (``bench/mocap_video.py``, 30 fps), MediaPipe's landmarks,
already One-Euro-filtered by its graph, against the clip (mean joint acceleration, jitter;
MPJPE / PA-MPJPE in mm):

    clip                          sigma   acceleration mm/frame^2   MPJPE   PA-MPJPE
    forward jumps, 360 frames     0       25.6 (clip 9.0)           118.0   54.4
                                  33 ms   12.4                      117.3   54.1
                                  50 ms    9.0                      116.9   53.9
    walk 02_01, 60 frames         0       17.2 (clip 9.0)            72.1   58.3
                                  33 ms    9.1                       71.6   58.7
                                  50 ms    7.5                       71.3   59.0

A causal One Euro pass (default strength) on the jumps left 13.6 mm/frame^2 and raised both
errors (its lag). One frame at 30 fps (33 ms) is the default: it brings the walk to the
clip's own smoothness, where 50 ms smooths it more than the clip moves (its price there:
0.4 mm of PA-MPJPE).
"""

from __future__ import annotations

import numpy as np

from avatar.errors import ParameterError

SIGMA = 1.0 / 30.0  # seconds: one frame of a 30 fps video


def smooth(points: np.ndarray, confidence: np.ndarray | None, fps: float,
           sigma: float = SIGMA, threshold: float = 0.5) -> np.ndarray:  # fmt: skip
    """points (T, K, 3) (NaN: missing), confidence (T, K) or None, fps frames/s, sigma
    seconds (0: unchanged) -> (T, K, 3) smoothed over time, missing where nothing was
    seen within three sigmas."""
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 3 or points.shape[2] != 3:
        raise ParameterError(f"expected (frames, keypoints, 3) points, got {points.shape}")
    if not (np.isfinite(sigma) and sigma >= 0 and np.isfinite(fps) and fps > 0):
        raise ParameterError(f"sigma must be >= 0 s and fps > 0, got {sigma!r}, {fps!r}")
    step = sigma * fps  # sigma in frames
    if step < 1e-3 or len(points) < 2:
        return points.copy()
    seen = np.isfinite(points).all(axis=2)
    if confidence is not None:
        seen &= np.asarray(confidence, dtype=np.float64) >= threshold
    radius = max(1, int(np.ceil(3.0 * step)))
    kernel = np.exp(-0.5 * (np.arange(-radius, radius + 1) / step) ** 2)
    weight = seen.astype(np.float64)
    values = np.where(seen[..., None], points, 0.0) * weight[..., None]
    total = np.zeros_like(weight)
    summed = np.zeros_like(values)
    count = len(points)
    for offset, k in zip(range(-radius, radius + 1), kernel, strict=True):
        # frame t takes k * sample (t + offset) where its window reaches as far on the
        # other side: near the ends the window shrinks symmetrically (a one-sided one would
        # pull the first frames towards the later ones: a T-pose start lost its arms)
        lo, hi = abs(offset), count - abs(offset)
        if lo >= hi:
            continue
        total[lo:hi] += k * weight[lo + offset : hi + offset]
        summed[lo:hi] += k * values[lo + offset : hi + offset]
    with np.errstate(invalid="ignore", divide="ignore"):
        out = summed / total[..., None]
    out[total <= 0.0] = np.nan
    return out
