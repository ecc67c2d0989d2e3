"""The built-in walk asked for as an animator does: a speed and a number of steps.

``procedural.walk`` takes a cadence (strides a second) and a duration; its stride (two
steps) is 1.1 leg lengths, so a speed in m/s sets the cadence for each body: a long-legged
body takes fewer, longer steps at the same speed.
"""

from __future__ import annotations

from avatar.body.shaped import Body
from avatar.errors import ParameterError
from avatar.motion import bonemap, procedural
from avatar.rig.skeleton import Animation, Skeleton

STRIDE_LEGS = 1.1  # stride (two steps) in leg lengths, as procedural.walk moves the root
SPEED_RANGE = (0.2, 3.0)  # m/s: a slow stroll to a fast walk
MAX_STEPS = 200


def leg_length(skeleton: Skeleton) -> float:
    """Hip joint height above the floor (metres), the leg length the walk scales by."""
    thigh = bonemap.detect(skeleton).bones.get("thigh.L")
    if thigh is None:
        raise ParameterError("the walk needs a rig with legs (no left thigh found)")
    return float(skeleton.heads[thigh, 2])


def cadence(skeleton: Skeleton, speed: float) -> float:
    """Strides a second that walk ``speed`` m/s on this skeleton."""
    return speed / (STRIDE_LEGS * leg_length(skeleton))


def walk(
    skeleton: Skeleton,
    speed: float = 1.3,
    steps: int = 8,
    fps: float = 30.0,
    body: Body | None = None,
) -> Animation:
    """``steps`` steps of the procedural walk at ``speed`` m/s along -Y, at ``fps``.

    Returns a (T, J) Animation, T = the frames those steps take (at least 2).
    Raises ParameterError for a speed outside SPEED_RANGE, steps outside 1..MAX_STEPS or a
    non-positive fps."""
    if not SPEED_RANGE[0] <= speed <= SPEED_RANGE[1]:
        raise ParameterError(f"walk speed {speed:g} m/s is outside {SPEED_RANGE[0]:g}.."
                             f"{SPEED_RANGE[1]:g}")  # fmt: skip
    if not 1 <= int(steps) <= MAX_STEPS:
        raise ParameterError(f"walk steps {steps} is outside 1..{MAX_STEPS}")
    if not fps > 0:
        raise ParameterError(f"walk fps {fps:g} must be positive")
    rate = cadence(skeleton, speed)
    seconds = max(int(steps) / (2.0 * rate), 2.0 / fps)
    return procedural.walk(skeleton, seconds=seconds, fps=fps, cadence=rate, body=body)
