"""Motion: BVH clips onto any Avatar rig (bone maps, rest alignment, retargeting, contacts,
quality metrics).

    skeleton, clip = load_bvh("walk.bvh")
    animation, report = retarget(skeleton, clip, human.skeleton)  # onto the rig
    animation, report = retarget(skeleton, clip, human.skeleton, body=human.body)  # settled
    print(report.summary())
"""

from __future__ import annotations

from avatar.io.bvh import load as load_bvh
from avatar.io.bvh import save as save_bvh
from avatar.motion.metrics import Quality
from avatar.motion.retarget import RetargetReport, retarget

__all__ = ["Quality", "RetargetReport", "load_bvh", "retarget", "save_bvh"]
