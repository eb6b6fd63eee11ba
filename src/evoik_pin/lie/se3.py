"""SE(3) maths in NumPy, vectorized over a batch of poses (R (N, 3, 3), t (N, 3) m; twists (N, 6) = (v m, w rad)):
Pinocchio's closed forms (``pin.log6``, ``pin.exp6``, ``pin.Jlog6``); the numba twins are in :mod:`.compiled`."""

from __future__ import annotations

import numpy as np

from .so3 import PREC2, PREC3, exp3, jlog3, log3, skew

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
    xi = np.asarray(xi, dtype=float).reshape(-1, 6)
    v, w = xi[:, :3], xi[:, 3:]
    t2 = (w * w).sum(axis=1)
    theta = np.sqrt(t2)
    small = theta < PREC3
    th = np.where(small, 1.0, theta)
    # V = I + b [w]x + c [w]x^2 with b = (1 - cos) / theta^2, c = (theta - sin) / theta^3
    b = np.where(small, 0.5 - t2 / 24.0, 2.0 * np.sin(0.5 * th) ** 2 / (th * th))
    c = np.where(small, 1.0 / 6.0 - t2 / 120.0, (th - np.sin(th)) / (th * th * th))
    K = skew(w)
    V = np.eye(3) + b[:, None, None] * K + c[:, None, None] * (K @ K)
    return exp3(w), (V @ v[:, :, None])[:, :, 0]


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
