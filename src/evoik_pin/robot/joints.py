"""1-DOF joint helpers on a Pinocchio model: values (rad or m; a continuous joint stores (cos, sin)), motions,
limits, mimic couplings; one joint at a time (a model-wide ``Data`` is large for big models)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

__all__ = ["DEFAULT_PRISMATIC_RANGE", "UNBOUNDED", "couplings", "joint_limits", "joint_motions", "joint_value",
           "set_joint_value"]

#: Search interval (m) used for prismatic joints whose URDF gives no finite limits.
DEFAULT_PRISMATIC_RANGE = 1.0
#: Limits at or beyond this magnitude are treated as "no limit" (URDF readers use 1e308-style sentinels).
UNBOUNDED = 1e10


def couplings(model: pin.Model, mimic: dict | None) -> dict[int, tuple[int, float, float]]:
    """``{mimic joint id: (followed joint id, multiplier, offset)}`` of the ``mimic`` entries (``{joint: (followed,
    multiplier, offset)}`` or objects with those attributes) whose two joints are 1-DOF joints of ``model``."""
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
    """(revolute (k,) bool, unit axes (k, 3) in each joint's own frame) of 1-DOF joints, from their motion
    subspace at the neutral configuration."""
    q, S = pin.neutral(model), []
    for j in joint_ids:
        jd = model.joints[j].createData()
        model.joints[j].calc(jd, q)
        S.append(np.asarray(jd.S).reshape(6))
    S = np.array(S, dtype=float).reshape(-1, 6)  # rows (linear, angular)
    revolute = np.linalg.norm(S[:, 3:], axis=1) > 0.5
    return revolute, np.where(revolute[:, None], S[:, 3:], S[:, :3])


def joint_limits(model: pin.Model, j: int) -> tuple[float, float, bool]:
    """(lower, upper, limited) of 1-DOF joint j: not limited when continuous, or limits absent (lower == upper),
    inverted or beyond :data:`UNBOUNDED`."""
    jm = model.joints[j]
    if jm.nq != 1:
        return -np.pi, np.pi, False
    lo, hi = float(model.lowerPositionLimit[jm.idx_q]), float(model.upperPositionLimit[jm.idx_q])
    limited = abs(lo) < UNBOUNDED and abs(hi) < UNBOUNDED and lo < hi
    return lo, hi, limited
