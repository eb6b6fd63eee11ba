"""Foot contacts of a motion: when each foot stands on the ground, from its height and speed.

A retargeter holds a robot foot where it landed while the source foot is in contact. A foot keypoint is in contact
in a frame when it is near the clip's floor (within ``height`` m of :func:`ground_height`) and slow (its speed,
by central differences over frames, below ``speed`` m/s). The defaults were set on the bundled CMU clips
(``motions/cmu``), whose foot keypoints are ankles: a stance ankle stays within a few cm of its lowest height and
moves at a few cm/s, a swing ankle rises 0.1 m or more and moves at 1 m/s or more.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import MotionError
from .motion import Motion, positive_number

__all__ = ["CONTACT_HEIGHT_M", "CONTACT_SPEED_MPS", "DEFAULT_FEET", "detect_contacts", "ground_height"]

#: A foot keypoint within this height (m) of the floor can be in contact.
CONTACT_HEIGHT_M = 0.05
#: A foot keypoint slower than this (m/s) can be in contact.
CONTACT_SPEED_MPS = 0.7
#: Foot keypoint names tried in turn when none are given: CMU/LAFAN BVH ankles, then SMPL's ankles.
DEFAULT_FEET: tuple[tuple[str, str], ...] = (("LeftFoot", "RightFoot"), ("left_ankle", "right_ankle"))
#: Percentile (%) of the feet's heights taken as the floor: low, but above a few glitched frames.
FLOOR_PERCENTILE = 5.0


def _feet(motion: Motion, feet: Sequence[str] | None) -> tuple[str, ...]:
    if feet is None:
        for pair in DEFAULT_FEET:
            if all(name in motion.names for name in pair):
                return pair
        raise MotionError(f"no default foot keypoints in this motion (tried {[list(p) for p in DEFAULT_FEET]}); "
                          f"pass feet=(left_foot_name, right_foot_name) among its names")
    if isinstance(feet, str):
        feet = (feet,)
    feet = tuple(feet)
    if not feet:
        raise MotionError("feet must name at least one foot keypoint of the motion")
    for name in feet:
        motion.index(name)  # raises MotionError with the closest names
    return feet


def _threshold(value, default: float, what: str, unit: str) -> float:
    if value is None:
        return default
    return positive_number(value, f"contact {what} threshold must be a finite number > 0 ({unit}); got {value!r}")


def ground_height(motion: Motion, feet: Sequence[str] | None = None) -> float:
    """The floor's height (m, z) under the motion: the 5th percentile of the foot keypoints' heights over all
    frames (``feet``: their names; by default CMU's ``LeftFoot``/``RightFoot`` or SMPL's ankles)."""
    names = _feet(motion, feet)
    z = motion.positions[:, [motion.index(n) for n in names], 2]
    return float(np.percentile(z, FLOOR_PERCENTILE))


def detect_contacts(motion: Motion, feet: Sequence[str] | None = None, height: float | None = None,
                    speed: float | None = None) -> dict[str, np.ndarray]:
    """``{foot name: (N,) bool}``, True in the frames where that foot keypoint is in contact with the ground:
    within ``height`` m (default :data:`CONTACT_HEIGHT_M`) of :func:`ground_height` and slower than ``speed`` m/s
    (default :data:`CONTACT_SPEED_MPS`). ``feet``: foot keypoint names (default: the motion's CMU ankles
    ``LeftFoot``, ``RightFoot`` or SMPL's ``left_ankle``, ``right_ankle``). A one-frame motion has speed 0."""
    names = _feet(motion, feet)
    h = _threshold(height, CONTACT_HEIGHT_M, "height", "m")
    v = _threshold(speed, CONTACT_SPEED_MPS, "speed", "m/s")
    floor = ground_height(motion, names)
    contacts = {}
    for name in names:
        p = motion.trajectory(name)
        if motion.frames > 1:
            velocity = np.gradient(p, axis=0) * motion.fps  # central differences inside, one-sided at the ends
            slow = np.linalg.norm(velocity, axis=1) < v
        else:
            slow = np.ones(1, dtype=bool)
        contacts[name] = (p[:, 2] - floor < h) & slow
    return contacts
