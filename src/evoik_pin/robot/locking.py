"""Locking joints: :meth:`Robot.locked`, and the helpers mapping ``q`` between a robot and its locked copy (the
solvers' ``locked=`` option)."""

from __future__ import annotations

import weakref

import numpy as np

from ..errors import BoundsError, ConfigurationError, FrameError, OptionError
from .frames import closest_hint

__all__ = ["expand_q", "expand_result", "expand_rows", "kept_columns", "locked_note", "locked_robot", "shrink_q"]

_CACHE: dict = {}


def _checked(robot, values) -> dict[str, float]:
    if not isinstance(values, dict):
        raise OptionError(f"locked takes a dict {{joint name: value (rad or m)}}, got {type(values).__name__}")
    out = {}
    for name, value in values.items():
        if name not in robot.joint_names:
            raise FrameError(f"cannot lock {name!r}: no joint of {robot.name}'s q has that name"
                             f"{closest_hint(name, robot.joint_names)}; its joints: {', '.join(robot.joint_names)}")
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
    """:meth:`Robot.locked`, cached per robot (weakly) and values."""
    values = _checked(robot, values)
    if not values:
        return robot
    key = (id(robot), tuple(sorted(values.items())))
    hit = _CACHE.get(key)
    if hit is not None and hit[0]() is robot:
        return hit[1]
    keep = [j for j in robot.joint_names if j not in values]
    args = {**robot._init_args, "joints": keep, "base_box": None}  # the bounds are copied below
    out = type(robot)(**args, rest={**robot.locked_values, **values})
    out.srdf = robot.srdf
    idx = [robot.joint_names.index(j) for j in keep]
    out.set_bounds(robot.lower[idx], robot.upper[idx])
    if len(_CACHE) > 32:
        _CACHE.clear()
    _CACHE[key] = (weakref.ref(robot), out)
    return out


def kept_columns(robot, sub) -> np.ndarray:
    """The indices (sub.n,) in ``robot``'s q of ``sub``'s joints (``sub = robot.locked(...)``), in ``sub``'s order."""
    return np.array([robot.joint_names.index(name) for name in sub.joint_names], dtype=np.intp)


def expand_rows(robot, sub, values: dict[str, float], Q) -> np.ndarray:
    """``robot``'s q (N, robot.n) of ``sub``'s ``Q`` (N, sub.n), the locked joints at their ``values``."""
    Q = np.asarray(Q, dtype=float)
    out = np.empty((Q.shape[0], robot.n))
    for name, value in values.items():
        out[:, robot.joint_names.index(name)] = value
    out[:, kept_columns(robot, sub)] = Q
    return out


def expand_q(robot, sub, values: dict[str, float], q) -> np.ndarray:
    """``robot``'s q (n,) of ``sub``'s ``q`` (a robot ``robot.locked(values)``): the locked joints at their values."""
    return expand_rows(robot, sub, values, np.asarray(q, dtype=float)[None])[0]


def locked_note(values: dict[str, float]) -> str:
    """What a result's message says of the joints a call locked (rad or m)."""
    return f"; joints locked: {', '.join(f'{k}={v:g}' for k, v in values.items())}"


def expand_result(robot, sub, values: dict[str, float], result):
    """A Result of ``sub`` (``robot.locked(values)``) put in ``robot``'s layout in place; returns it."""
    result.q = expand_q(robot, sub, values, result.q)
    for s in result.solutions or ():
        s.q = expand_q(robot, sub, values, s.q)
    result.message += locked_note(values)
    return result


def shrink_q(robot, sub, q) -> np.ndarray:
    """``sub``'s entries of ``robot``'s ``q`` (n,)."""
    return robot.check_q(q)[kept_columns(robot, sub)]
