"""A robot's speed limits per entry of ``q`` (rad/s or m/s), and the ``velocity_limits=`` / ``dt=`` options. Where
the URDF gives none (0 or inf; a floating base), the defaults below stand in; a floating base's limits bound each of
x, y, z and each Euler rate (yaw, pitch, roll)."""

from __future__ import annotations

import math

import numpy as np

from ..errors import OptionError

__all__ = ["DEFAULT_BASE_ANGULAR_SPEED", "DEFAULT_BASE_LINEAR_SPEED", "DEFAULT_JOINT_SPEED", "check_dt",
           "urdf_velocity_limits", "velocity_limits", "without_urdf_speed"]

#: Speed (rad/s, m/s for prismatic joints) of a joint whose URDF gives no velocity limit.
DEFAULT_JOINT_SPEED = 3.0
#: A floating base's x, y, z speed (m/s) by default: a running human's, so a retargeted motion is not held back.
DEFAULT_BASE_LINEAR_SPEED = 5.0
#: A floating base's yaw, pitch, roll rates (rad/s) by default (a turn per second).
DEFAULT_BASE_ANGULAR_SPEED = 2.0 * math.pi


def urdf_velocity_limits(robot) -> np.ndarray:
    """(n,) speed limits (rad/s or m/s) of ``robot``'s ``q``: the URDF's, the defaults where it has none."""
    limits = _urdf_limits(robot)
    limits[~np.isfinite(limits) | (limits <= 0.0)] = DEFAULT_JOINT_SPEED
    if robot.floating_base:  # x, y, z (m/s), yaw, pitch, roll (rad/s): a free flyer has no URDF limit
        limits[:6] = [DEFAULT_BASE_LINEAR_SPEED] * 3 + [DEFAULT_BASE_ANGULAR_SPEED] * 3
    return limits


def without_urdf_speed(robot) -> np.ndarray:
    """(n,) bool: the entries of ``robot``'s ``q`` whose URDF gives no speed limit, the floating base's excepted."""
    limits = _urdf_limits(robot)
    out = ~np.isfinite(limits) | (limits <= 0.0)
    if robot.floating_base:
        out[:6] = False
    return out


def _urdf_limits(robot) -> np.ndarray:
    """The URDF's limits (n,) per entry of q (the smallest ``v_j / |m|`` of the physical joints following it; 0 or
    inf where it gives none). The model has one velocity limit per physical joint (all 1-DOF)."""
    v, (index, scale) = robot.model.velocityLimit, robot.tree_constants()[4:6]
    limits = np.full(robot.n, np.inf)
    for j, k in enumerate(index):
        if scale[j] != 0.0:
            limits[k] = min(limits[k], v[j] / abs(scale[j]))
    return limits


def velocity_limits(robot, spec) -> np.ndarray:
    """(n,) speed limits (rad/s, m/s) of ``velocity_limits=spec``: ``True`` the URDF's (:func:`urdf_velocity_limits`),
    a factor > 0 times those, or an array (n,) of positive finite speeds; OptionError otherwise."""
    accepted = (f"velocity_limits must be True (the URDF's limits), a factor > 0 of them, or an array of {robot.n} "
                "speeds > 0 (rad/s for revolute joints, m/s for prismatic ones and a floating base's x, y, z)")
    if spec is True:
        return urdf_velocity_limits(robot)
    if isinstance(spec, bool) or spec is None:
        raise OptionError(f"{accepted}; got {spec!r}")
    if isinstance(spec, (int, float, np.integer, np.floating)):
        if not (math.isfinite(spec) and spec > 0.0):
            raise OptionError(f"{accepted}; got the factor {spec!r}")
        return float(spec) * urdf_velocity_limits(robot)
    try:
        arr = np.asarray(spec, dtype=float)
    except (TypeError, ValueError):
        raise OptionError(f"{accepted}; got {type(spec).__name__}") from None
    if arr.shape != (robot.n,):
        raise OptionError(f"{accepted}; got an array of shape {arr.shape}")
    if not (np.isfinite(arr).all() and (arr > 0.0).all()):
        raise OptionError(f"{accepted}; got entries {arr[~(np.isfinite(arr) & (arr > 0.0))].tolist()}")
    return arr.copy()


def check_dt(dt) -> float:
    """``dt`` (s) between two points of a trajectory or control steps: a finite number > 0, else OptionError."""
    if isinstance(dt, bool) or not isinstance(dt, (int, float, np.integer, np.floating)) or not (
            math.isfinite(float(dt)) and float(dt) > 0.0):
        raise OptionError(f"dt must be the time step in s, a finite number > 0; got {dt!r}")
    return float(dt)
