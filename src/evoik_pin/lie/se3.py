"""SE(3) maths over a batch of poses (R (N, 3, 3), t (N, 3) m; twists (N, 6) = (v m, w rad)): Pinocchio's closed
forms of ``pin.log6`` and ``pin.Jlog6`` in NumPy (their numba twins are in :mod:`.compiled`), ``pin.exp6``."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from .so3 import PREC2, PREC3, jlog3, log3, skew

__all__ = ["exp6", "jlog6", "log6"]


def _as_batch(R, t):
    return np.asarray(R, dtype=float).reshape(-1, 3, 3), np.asarray(t, dtype=float).reshape(-1, 3)


def log6(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Twists (N, 6) = (v, w) of poses (R (N, 3, 3), t (N, 3)): ``pin.log6`` row by row, ``w = log3(R)``."""
    R, t = _as_batch(R, t)
    w = log3(R)
    theta = np.sqrt((w * w).sum(axis=1))
    trace = R[:, 0, 0] + R[:, 1, 1] + R[:, 2, 2]
    series = trace >= 3.0 - PREC2
    # Pinocchio's series variable: sin^2(theta), the squared norm of the antisymmetric part
    a = 0.5 * np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], axis=1)
    t2 = (a * a).sum(axis=1)
    th = np.where(series, 1.0, theta)
    st, omc = np.sin(th), 2.0 * np.sin(0.5 * th) ** 2
    alpha = np.where(series, 1.0 - t2 / 12.0 - t2 * t2 / 720.0, th * st / (2.0 * omc))
    beta = np.where(series, 1.0 / 12.0 + t2 / 720.0, 1.0 / (th * th) - st / (2.0 * th * omc))
    wp = beta * (w * t).sum(axis=1)
    v = alpha[:, None] * t - 0.5 * np.cross(w, t) + wp[:, None] * w
    return np.concatenate([v, w], axis=1)


def exp6(xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Poses (R (N, 3, 3), t (N, 3)) of twists xi (N, 6) = (v, w): ``pin.exp6`` row by row."""
    M = [pin.exp6(x).homogeneous for x in np.asarray(xi, dtype=float).reshape(-1, 6)]
    H = np.array(M).reshape(-1, 4, 4)
    return H[:, :3, :3].copy(), H[:, :3, 3].copy()


def jlog6(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``pin.Jlog6`` (N, 6, 6) of poses (R (N, 3, 3), t (N, 3)): ``[[A, B], [0, A]]`` with ``A = Jlog3``."""
    R, t = _as_batch(R, t)
    w = log3(R)
    A = jlog3(w)
    theta = np.sqrt((w * w).sum(axis=1))
    t2 = theta * theta
    small = theta < PREC3
    th = np.where(small, 1.0, theta)
    tinv = 1.0 / th
    t2inv = tinv * tinv
    sh = np.sin(0.5 * th)
    st, inv_2_2ct = np.sin(th), 1.0 / (4.0 * sh * sh)  # 1 / (2 (1 - cos))
    beta = np.where(small, 1.0 / 12.0 + t2 / 720.0, t2inv - st * tinv * inv_2_2ct)
    # (the same order of operations as the numba form: the terms cancel for small theta)
    bdot = np.where(small, 1.0 / 360.0, -2.0 * t2inv * t2inv + (1.0 + st * tinv) * t2inv * inv_2_2ct)
    wTp = (w * t).sum(axis=1)
    vi = (bdot * wTp)[:, None] * w - (t2 * bdot + 2.0 * beta)[:, None] * t
    C = (vi[:, :, None] * w[:, None, :] + beta[:, None, None] * w[:, :, None] * t[:, None, :]
         + (wTp * beta)[:, None, None] * np.eye(3) + 0.5 * skew(t))
    out = np.zeros((R.shape[0], 6, 6))
    out[:, :3, :3] = A
    out[:, 3:, 3:] = A
    out[:, :3, 3:] = C @ A
    return out
