"""1-DOF joint helpers on a Pinocchio model (values in rad or m, a continuous joint storing (cos, sin); motions,
limits, mimic couplings), and a robot's bounds and checks of joint vectors (:class:`JointBounds`, a base of
:class:`~evoik_pin.robot.Robot`)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..errors import BoundsError, ConfigurationError, RobotLoadError
from .frames import listed

__all__ = ["DEFAULT_PRISMATIC_RANGE", "NEAR_UNBOUNDED", "UNBOUNDED", "JointBounds", "couplings", "joint_limits",
           "joint_motions", "joint_value", "set_joint_value"]

#: Search interval (m) used for prismatic joints whose URDF gives no finite limits.
DEFAULT_PRISMATIC_RANGE = 1.0
#: Limits at or beyond this magnitude are treated as "no limit" (URDF readers use 1e308-style sentinels).
UNBOUNDED = 1e10


def couplings(model: pin.Model, mimic: dict | None) -> dict[int, tuple[int, float, float]]:
    """``{mimic joint id: (followed joint id, multiplier, offset)}`` of the ``mimic`` entries (as for
    :class:`~evoik_pin.robot.Robot`) whose two joints are 1-DOF joints of ``model``."""
    out: dict[int, tuple[int, float, float]] = {}
    for name, spec in (mimic or {}).items():
        driver, m, off = (spec.joint, spec.multiplier, spec.offset) if hasattr(spec, "joint") else spec
        if not (model.existJointName(name) and model.existJointName(driver)):
            continue
        j, d = model.getJointId(name), model.getJointId(driver)
        if j != d and model.joints[j].nv == 1 and model.joints[d].nv == 1:
            out[j] = (d, float(m), float(off))
    return out


def joint_value(model: pin.Model, q: np.ndarray, j: int) -> float:
    """Value (rad or m) of 1-DOF joint j in configuration q (model.nq,)."""
    jm = model.joints[j]
    return float(np.arctan2(q[jm.idx_q + 1], q[jm.idx_q])) if jm.nq == 2 else float(q[jm.idx_q])


def set_joint_value(model: pin.Model, q: np.ndarray, j: int, value: float) -> None:
    """Write value (rad or m) of 1-DOF joint j into configuration q (model.nq,), as (cos, sin) if continuous."""
    jm = model.joints[j]
    if jm.nq == 2:
        q[jm.idx_q], q[jm.idx_q + 1] = np.cos(value), np.sin(value)
    else:
        q[jm.idx_q] = value


def joint_motions(model: pin.Model, joint_ids) -> tuple[np.ndarray, np.ndarray]:
    """(revolute (k,) bool, unit axes (k, 3) in each joint's own frame) of 1-DOF joints (their motion subspace)."""
    q, S = pin.neutral(model), []
    for j in joint_ids:
        jd = model.joints[j].createData()
        model.joints[j].calc(jd, q)
        S.append(np.asarray(jd.S).reshape(6))
    S = np.array(S, dtype=float).reshape(-1, 6)  # rows (linear, angular)
    revolute = np.linalg.norm(S[:, 3:], axis=1) > 0.5
    return revolute, np.where(revolute[:, None], S[:, 3:], S[:, :3])


def joint_limits(model: pin.Model, j: int) -> tuple[float, float, bool]:
    """(lower, upper, limited) of 1-DOF joint j: not limited when continuous, or its limits are equal, inverted or
    beyond :data:`UNBOUNDED`."""
    jm = model.joints[j]
    if jm.nq != 1:
        return -np.pi, np.pi, False
    lo, hi = float(model.lowerPositionLimit[jm.idx_q]), float(model.upperPositionLimit[jm.idx_q])
    limited = abs(lo) < UNBOUNDED and abs(hi) < UNBOUNDED and lo < hi
    return lo, hi, limited


#: A joint whose bound reaches this far (m or rad) is near-unbounded: URDFs give mobile bases' virtual joints limits
#: like +-999999 to mean "none"; no real arm joint travels 1 km or 160 turns.
NEAR_UNBOUNDED = 1e3


class JointBounds:
    """The search bounds ``lower``, ``upper`` (n,) (rad or m) and the checks of joint vectors."""

    lower: np.ndarray
    upper: np.ndarray

    def _set_default_bounds(self, coupling: dict[int, tuple[int, float, float]]) -> None:
        """URDF limits of each entry of q ([-pi, pi] or +-DEFAULT_PRISMATIC_RANGE without), narrowed to keep every
        mimic joint following it inside its own."""
        fm, lower, upper = self._kin_model, np.empty(self.n), np.empty(self.n)
        for k, d in enumerate(self._dof_ids):
            lo, hi, limited = joint_limits(fm, d)
            if not limited:
                half = np.pi if self.revolute[k] else DEFAULT_PRISMATIC_RANGE
                lo, hi = -half, half
            for j, (driver, m, off) in coupling.items():
                jlo, jhi, jlimited = joint_limits(fm, j)
                if driver != d or not jlimited or m == 0.0:
                    continue
                a, b = sorted(((jlo - off) / m, (jhi - off) / m))
                if max(lo, a) > min(hi, b):
                    raise RobotLoadError(f"joint {fm.names[j]!r} of {self.name} mimics {fm.names[d]!r} ({fm.names[j]} "
                                         f"= {m:g} {fm.names[d]} + {off:g}) but no value of {fm.names[d]!r} in "
                                         f"[{lo:g}, {hi:g}] keeps it in its limits [{jlo:g}, {jhi:g}]")
                lo, hi = max(lo, a), min(hi, b)
            lower[k], upper[k] = lo + 0.0, hi + 0.0  # + 0.0: no -0.0 bound (NumPy's uniform refuses [0, -0])
        self.lower, self.upper = lower, upper

    def _set_base_box(self, base_box) -> None:
        """The floating base's position bounds: a half-width h (m) or (lower (3,), upper (3,)) in m."""
        if not self.floating_base:
            raise BoundsError("base_box bounds the floating base's position: give it with floating_base=True")
        try:
            if np.ndim(base_box) == 0:
                lo, hi = np.full(3, -float(base_box)), np.full(3, float(base_box))
            else:
                lo, hi = (np.asarray(b, dtype=float).reshape(3) for b in base_box)
        except (TypeError, ValueError) as exc:
            raise BoundsError(f"base_box must be a half-width (m) or a pair (lower (3,), upper (3,)) in m, got "
                              f"{base_box!r}") from exc
        lower, upper = self.lower.copy(), self.upper.copy()
        lower[:3], upper[:3] = lo, hi
        self.set_bounds(lower, upper)

    def set_bounds(self, lower, upper) -> None:
        """Replace the search bounds (rad or m), each (n,), finite, lower <= upper."""
        self.lower, self.upper = self.checked_bounds(lower, upper)

    def checked_bounds(self, lower, upper) -> tuple[np.ndarray, np.ndarray]:
        """``lower`` and ``upper`` as new float arrays (n,) (rad or m); BoundsError for a count other than n, NaN or
        inf, lower > upper."""
        lower, upper = np.array(lower, dtype=float).reshape(-1), np.array(upper, dtype=float).reshape(-1)
        if lower.shape != (self.n,) or upper.shape != (self.n,):
            raise BoundsError(f"bounds need {self.n} values each (one per joint of {self.name}), got {lower.size} "
                              f"and {upper.size}")
        if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper))):
            raise BoundsError("bounds must be finite numbers (rad or m); got NaN or inf")
        bad = np.nonzero(lower > upper)[0]
        if bad.size:
            k = int(bad[0])
            raise BoundsError(f"inverted bounds for joint {self.joint_names[k]!r}: lower {lower[k]:.6g} > upper "
                              f"{upper[k]:.6g}")
        return lower, upper

    def check_q(self, q) -> np.ndarray:
        """``q`` as a float array of shape (n,), or a ConfigurationError naming the problem."""
        arr = np.asarray(q, dtype=float)
        if arr.ndim != 1 or arr.shape[0] != self.n:
            raise ConfigurationError(f"{self.name} has {self.n} joints ({listed(self.joint_names, 12)}); got a joint "
                                     f"vector of shape {arr.shape}, expected ({self.n},)")
        if not np.isfinite(arr).all():  # the method, not np.all: hot path
            raise ConfigurationError(f"joint vector contains NaN or inf: {arr}")
        return arr

    def check_population(self, Q) -> np.ndarray:
        """``Q`` as a float array of shape (N, n), or a ConfigurationError naming the problem."""
        arr = np.asarray(Q, dtype=float)
        if arr.ndim == 1 and arr.shape[0] == self.n:
            arr = arr[None, :]
        if arr.ndim != 2 or arr.shape[1] != self.n:
            raise ConfigurationError(f"{self.name} needs configurations of shape (N, {self.n}); got shape {arr.shape}")
        if not np.all(np.isfinite(arr)):
            raise ConfigurationError("configurations contain NaN or inf")
        return arr

    def within_bounds(self, q, tol: float = 0.0) -> bool:
        """True when every joint value lies inside [lower - tol, upper + tol]."""
        q = np.asarray(q, dtype=float)
        return bool(np.all(q >= self.lower - tol) and np.all(q <= self.upper + tol))

    def clip(self, Q) -> np.ndarray:
        """``Q`` (..., n) clipped into the search bounds."""
        return np.clip(Q, self.lower, self.upper)

    def random_configurations(self, count: int, rng: np.random.Generator) -> np.ndarray:
        """``count`` configurations (count, n) drawn uniformly inside :meth:`sampling_box`."""
        lower, upper = self.sampling_box()
        return rng.uniform(lower, upper, size=(count, self.n))

    def sampling_box(self) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper), each (n,): the search bounds with every near-unbounded entry (:data:`NEAR_UNBOUNDED`)
        narrowed to where answers lie near the base: a revolute one to one turn around 0, a prismatic one to
        +-(2 R + max(0.1, 0.1 R)) m, R the robot's reach (joint offsets and bounded prismatic travel, summed)."""
        lower, upper = self.lower.copy(), self.upper.copy()
        far = (np.abs(lower) >= NEAR_UNBOUNDED) | (np.abs(upper) >= NEAR_UNBOUNDED)
        if not far.any():
            return lower, upper
        prismatic_travel = np.where(~self.revolute & ~far, np.maximum(np.abs(lower), np.abs(upper)), 0.0)
        reach = float(np.linalg.norm(self.tree.Fp, axis=1).sum() + prismatic_travel.sum())
        half = 2.0 * reach + max(0.1, 0.1 * reach)
        centre = np.where(self.revolute, np.clip(0.0, lower + np.pi, upper - np.pi), 0.0)
        width = np.where(self.revolute, np.pi, half)
        lower[far] = np.clip(centre - width, self.lower, self.upper)[far]
        upper[far] = np.clip(centre + width, self.lower, self.upper)[far]
        return lower, upper
