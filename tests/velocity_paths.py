"""Smooth joint paths for the velocity-limit tests (test_trajectory_velocity.py, test_tracker.py): sums of sines
whose speed stays a chosen fraction of the robot's limits, inside its bounds, and the goals their FK gives."""

import numpy as np

from evoik_pin.goals import Pose
from evoik_pin.robot.velocity_limits import velocity_limits

#: Talos's four pose goals: both soles and both grippers.
TALOS_FRAMES = ("left_sole_link", "right_sole_link", "gripper_left_base_link", "gripper_right_base_link")


def smooth_path(robot, steps: int, dt: float, seed: int, fraction: float = 0.5) -> np.ndarray:
    """(steps, n) configurations q(t) = c + A sin(2 pi f t + phase), t = k dt (s), every entry's speed at most
    ``fraction`` of its limit (rad/s, m/s) and every row inside the robot's bounds (amplitude <= 0.3 of the half
    range, at most 0.3 rad or m)."""
    rng = np.random.default_rng(seed)
    lo, hi = robot.lower, robot.upper
    f = rng.uniform(0.2, 0.5, robot.n)
    A = np.minimum(np.minimum((hi - lo) / 2, 1.0) * 0.3, fraction * velocity_limits(robot, True) / (2 * np.pi * f))
    c = np.clip(0.0, lo + 1.01 * A, hi - 1.01 * A)
    t = np.arange(steps)[:, None] * dt
    return c + A * np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi, robot.n))


def pose_goals(robot, Q: np.ndarray, frames=TALOS_FRAMES) -> list[list[Pose]]:
    """One goal list per row of ``Q``: a Pose of each frame at its FK."""
    return [[Pose(frame, robot.fk(q, frame=frame)) for frame in frames] for q in Q]


def steps_within(Q: np.ndarray, max_step: np.ndarray, q0: np.ndarray) -> np.ndarray:
    """(N,) whether each row of ``Q`` (N, n) is within ``max_step`` (n,) of the row before (``q0`` before the first),
    with 1e-12 for rounding."""
    moves = np.abs(np.diff(np.vstack([q0, Q]), axis=0))
    return (moves <= max_step + 1e-12).all(axis=1)
