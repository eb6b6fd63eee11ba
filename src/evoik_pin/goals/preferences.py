"""Preferences: members of a goal list that are not goals (``solve(robot, [Pose(...), Posture(q_rest, 0.1)])``):
costs over configurations (lower is better) a solve lowers once the goals are met, never at their expense, and ranks
its answers by (:func:`evoik_pin.solvers.search.prefer.refine`). Differences on joints whose range spans a full turn
are taken to the nearest turn."""

from __future__ import annotations

import copy

import numpy as np

from ..errors import ConfigurationError, FrameError, OptionError, TargetError
from ..lie import wrap_angle
from ..robot.robot import yoshikawa
from .goal import Goal, number

__all__ = ["JointLimitMargin", "Manipulability", "MinimalDisplacement", "Posture", "Preference", "check_preferences",
           "holds_preferences", "split_preferences"]

def _weight(value, what: str) -> float:
    return number(value, f"weight of {what}", "a finite number > 0", 0.0, strict=True)


def turn_difference(q: np.ndarray, ref: np.ndarray, wrap: np.ndarray) -> np.ndarray:
    """``q - ref`` (n,), on the ``wrap`` joints (bool (n,)) taken to the nearest turn, in [-pi, pi)."""
    d = q - ref
    return np.where(wrap, wrap_angle(d), d)


class Preference:
    """A cost over configurations met as well as the goals allow (abstract; see the module docstring)."""

    weight: float = 1.0
    #: d^2 cost / dq^2 along any direction (quadratic terms: their weight; 0: none known)
    curvature: float = 0.0

    def bind(self, robot, q0, lower, upper, wrap) -> Preference:
        """This preference checked against ``robot`` for one solve (q0 (n,) or None, the box, its wrapping
        joints): the bound copy :meth:`cost` and :meth:`gradient` read."""
        raise NotImplementedError  # pragma: no cover

    def cost(self, q: np.ndarray) -> float:  # pragma: no cover - abstract
        raise NotImplementedError

    def gradient(self, q: np.ndarray) -> np.ndarray | None:
        """d cost / dq (n,), or None when it is taken by finite differences."""
        return None

    def costs(self, Q: np.ndarray) -> np.ndarray:
        """:meth:`cost` of each row of ``Q`` (N, n), shape (N,)."""
        return np.array([self.cost(q) for q in Q])


class Posture(Preference):
    """Stay near ``q_ref``: a joint vector like ``Result.q`` (n,), or a dict {joint name: value} (rad or m) for
    some joints; cost ``weight / 2 * |q - q_ref|^2`` over those joints."""

    def __init__(self, q_ref, weight: float = 1.0) -> None:
        self.weight = self.curvature = _weight(weight, "Posture")
        if isinstance(q_ref, dict):
            if not q_ref:
                raise OptionError("Posture: the dict of joint values is empty; give {joint name: value (rad or m)}")
            self.q_ref = {str(k): number(v, f"Posture value of joint {k!r}", "a finite number (rad or m)")
                          for k, v in q_ref.items()}
        else:
            try:
                ref = np.asarray(q_ref, dtype=float)
            except (TypeError, ValueError):
                raise ConfigurationError(f"Posture takes a joint vector (n,) or a dict {{joint: value}}, got "
                                         f"{q_ref!r}") from None
            if ref.ndim != 1 or not np.isfinite(ref).all():
                raise ConfigurationError(f"Posture takes a finite joint vector (n,) or a dict {{joint: value}}, got "
                                         f"shape {ref.shape}")
            self.q_ref = ref
        self._ref = self._mask = self._wrap = None

    def bind(self, robot, q0, lower, upper, wrap) -> Posture:
        out = copy.copy(self)
        out._wrap = wrap
        if isinstance(self.q_ref, dict):
            unknown = [k for k in self.q_ref if k not in robot.joint_names]
            if unknown:
                raise FrameError(f"Posture names joints {unknown} that {robot.name} does not move; its joints: "
                                 f"{', '.join(robot.joint_names)}")
            out._ref = np.zeros(robot.n)
            out._mask = np.zeros(robot.n, dtype=bool)
            for k, v in self.q_ref.items():
                i = robot.joint_names.index(k)
                out._ref[i], out._mask[i] = v, True
        else:
            try:
                out._ref = robot.check_q(self.q_ref)
            except ConfigurationError as exc:
                raise ConfigurationError(f"Posture: {exc}") from None
            out._mask = np.ones(robot.n, dtype=bool)
        return out

    def cost(self, q):
        return float(self.costs(q))

    def gradient(self, q):
        return self.weight * np.where(self._mask, turn_difference(q, self._ref, self._wrap), 0.0)

    def costs(self, Q):
        d = np.where(self._mask, turn_difference(Q, self._ref, self._wrap), 0.0)
        return 0.5 * self.weight * (d * d).sum(axis=-1)

    def __repr__(self) -> str:
        ref = self.q_ref if isinstance(self.q_ref, dict) else np.round(self.q_ref, 6).tolist()
        return f"Posture({ref}, weight={self.weight:g})"


class MinimalDisplacement(Posture):
    """Move as little as possible from the solve's ``q0``: cost ``weight / 2 * |q - q0|^2`` (rad^2, m^2)."""

    def __init__(self, weight: float = 1.0) -> None:  # noqa: D107 - no q_ref: it is q0
        self.weight = self.curvature = _weight(weight, "MinimalDisplacement")
        self.q_ref = None

    def bind(self, robot, q0, lower, upper, wrap) -> Posture:
        if q0 is None:
            raise OptionError("MinimalDisplacement is measured from q0: give q0 (the current joints) to solve")
        return Posture(q0, self.weight).bind(robot, q0, lower, upper, wrap)

    def __repr__(self) -> str:
        return f"MinimalDisplacement(weight={self.weight:g})"


class JointLimitMargin(Preference):
    """Keep ``margin`` (rad or m, >= 0) from every joint limit (of the search box): cost ``weight / 2 * sum over
    the joints of max(0, margin - (q - lower))^2 + max(0, margin - (upper - q))^2``; joints whose range spans a
    full turn wrap and have no limit to keep off."""

    def __init__(self, margin: float, weight: float = 1.0) -> None:
        self.margin = number(margin, "JointLimitMargin's margin (rad or m)", "a finite number >= 0", 0.0)
        self.weight = self.curvature = _weight(weight, "JointLimitMargin")

    def bind(self, robot, q0, lower, upper, wrap) -> JointLimitMargin:
        out = JointLimitMargin(self.margin, self.weight)
        out._lo, out._hi, out._free = lower, upper, ~wrap
        return out

    def _shortfalls(self, q):
        a = np.where(self._free, np.maximum(0.0, self.margin - (q - self._lo)), 0.0)
        b = np.where(self._free, np.maximum(0.0, self.margin - (self._hi - q)), 0.0)
        return a, b

    def cost(self, q):
        a, b = self._shortfalls(q)
        return 0.5 * self.weight * float(a @ a + b @ b)

    def gradient(self, q):
        a, b = self._shortfalls(q)
        return self.weight * (b - a)

    def __repr__(self) -> str:
        return f"JointLimitMargin({self.margin:g}, weight={self.weight:g})"


#: Manipulability.costs computes up to this many rows one by one (faster than its batched Jacobians).
SMALL_BATCH = 24


class Manipulability(Preference):
    """Stay dexterous: cost ``-weight * log(w)``, ``w`` Yoshikawa's manipulability (the product of the singular
    values: :func:`~evoik_pin.robot.robot.yoshikawa`) of ``frame``'s 6 x n Jacobian in LOCAL_WORLD_ALIGNED (None:
    the first goal's frame, the tip for a single target)."""

    def __init__(self, frame: str | None = None, weight: float = 1.0) -> None:
        if frame is not None and (not isinstance(frame, str) or not frame):
            raise FrameError(f"Manipulability's frame is a frame name (a non-empty string) or None, got {frame!r}")
        self.frame = frame
        self.weight = _weight(weight, "Manipulability")

    def bind(self, robot, q0, lower, upper, wrap, frame: str | None = None) -> Manipulability:
        out = Manipulability(self.frame or frame, self.weight)
        out._fid = robot.frame_id(out.frame)  # FrameError with the closest names
        out._robot = robot
        return out

    def cost(self, q):
        J = self._robot.jacobian_world_unchecked(np.asarray(q, dtype=float), self._fid)
        return -self.weight * float(np.log(max(float(yoshikawa(J)), 1e-300)))

    def costs(self, Q):
        if Q.shape[0] <= SMALL_BATCH:
            return super().costs(Q)
        w = yoshikawa(self._robot.jacobian_batch(Q, validate=False, frame=self.frame))
        return -self.weight * np.log(np.maximum(w, 1e-300))

    def __repr__(self) -> str:
        return f"Manipulability({self.frame!r}, weight={self.weight:g})"


def holds_preferences(value) -> bool:
    """True for a list or tuple of goals and preferences holding at least one preference."""
    return (isinstance(value, (list, tuple)) and any(isinstance(x, Preference) for x in value)
            and all(isinstance(x, (Goal, Preference)) for x in value))


def check_preferences(robot, preferences, frame: str | None, with_q0: bool) -> None:
    """Each preference bound to ``robot`` once, for its errors before any work (without ``with_q0``: a
    MinimalDisplacement's); ``frame``: the goal frame a Manipulability without one measures."""
    wrap = np.zeros(robot.n, dtype=bool)
    q0 = np.clip(np.zeros(robot.n), robot.lower, robot.upper) if with_q0 else None
    for p in preferences:
        p.bind(robot, q0, robot.lower, robot.upper, wrap, *([frame] if isinstance(p, Manipulability) else []))


def split_preferences(target):
    """(the goals, the preferences) of a goal list holding preferences; ``(target, [])`` for anything else.
    TargetError for preferences alone."""

    if not isinstance(target, (list, tuple)) or not any(isinstance(x, Preference) for x in target):
        return target, []
    goals = [x for x in target if not isinstance(x, Preference)]
    prefs = [x for x in target if isinstance(x, Preference)]
    if not goals:
        raise TargetError("the goal list holds preferences only: give at least one goal (Pose(frame, T), "
                          "Position(frame, p)) for them to rank the answers of")
    return goals, prefs
