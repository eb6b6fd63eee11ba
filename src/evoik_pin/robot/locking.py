"""Locking joints: :meth:`Robot.locked` makes a robot whose ``q`` omits some joints, fixed at given values; the
solvers' ``locked=`` option (:func:`evoik_pin.solve`) does it for one call and maps ``q`` back.

The locked robot is built like the original (the same URDF model, tips, base, mimic couplings), with the locked
joints left out of ``q`` and Pinocchio's reduced model built at their values, so every kinematic quantity
(frames, Jacobians, the compiled kernel's tree) is that of the arm with those joints fixed.
"""

from __future__ import annotations

import numpy as np

from ..errors import BoundsError, ConfigurationError, FrameError, OptionError
from .frames import closest_names

__all__ = ["expand_q", "locked_robot", "shrink_q"]

_CACHE: dict = {}


def _checked(robot, values) -> dict[str, float]:
    if not isinstance(values, dict):
        raise OptionError(f"locked takes a dict {{joint name: value (rad or m)}}, got {type(values).__name__}")
    out = {}
    for name, value in values.items():
        if name not in robot.joint_names:
            near = closest_names(str(name), robot.joint_names)
            hint = f" (did you mean {', '.join(map(repr, near))}?)" if near else ""
            raise FrameError(f"cannot lock {name!r}: no joint of {robot.name}'s q has that name{hint}; its joints: "
                             f"{', '.join(robot.joint_names)}")
        k = robot.joint_names.index(name)
        try:
            x = float(value)
        except (TypeError, ValueError):
            raise OptionError(f"locked value of joint {name!r} must be a number (rad or m), got {value!r}") from None
        lo, hi = robot.lower[k], robot.upper[k]
        if not np.isfinite(x) or x < lo or x > hi:
            unit = "rad" if robot.revolute[k] else "m"
            raise BoundsError(f"cannot lock joint {name!r} at {value!r}: outside its limits [{lo:.6g}, {hi:.6g}] "
                              f"{unit}")
        out[name] = x
    if len(out) >= robot.n:
        raise ConfigurationError(f"locking {len(out)} joints leaves none of {robot.name}'s {robot.n} free")
    return out


def locked_robot(robot, values):
    """:meth:`Robot.locked` (see there); the robots made are cached per robot and values (weakly)."""
    import weakref

    from .robot import Robot

    values = _checked(robot, values)
    if not values:
        return robot
    key = (id(robot), tuple(sorted(values.items())))
    hit = _CACHE.get(key)
    if hit is not None and hit[0]() is robot:
        return hit[1]
    args = dict(robot._init_args)
    keep = [j for j in robot.joint_names if j not in values]
    args["joints"] = keep
    args["base_box"] = None  # the bounds are copied below
    out = Robot(**args, rest={**robot.locked_values, **values})
    out.srdf = robot.srdf
    idx = [robot.joint_names.index(j) for j in keep]
    out.set_bounds(robot.lower[idx], robot.upper[idx])
    out.parent_robot = robot  # the robot whose q ``expand_q`` gives back
    if len(_CACHE) > 32:
        _CACHE.clear()
    _CACHE[key] = (weakref.ref(robot), out)
    return out


def expand_q(robot, sub, values: dict[str, float], q) -> np.ndarray:
    """``robot``'s q (n,) of ``sub``'s ``q`` (a robot ``robot.locked(values)``): the locked joints at their values."""
    out = np.empty(robot.n)
    for k, name in enumerate(robot.joint_names):
        out[k] = values[name] if name in values else q[sub.joint_names.index(name)]
    return out


def shrink_q(robot, sub, q) -> np.ndarray:
    """``sub``'s entries of ``robot``'s ``q`` (n,)."""
    q = robot.check_q(q)
    return np.array([q[robot.joint_names.index(name)] for name in sub.joint_names])
