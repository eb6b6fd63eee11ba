"""SE(3) maths over a batch of poses (R (N, 3, 3), t (N, 3) m; twists (N, 6) = (v m, w rad)): ``pin.exp6``, and
Pinocchio's ``log6``, ``Jlog3`` and ``Jlog6`` in their numba forms (:mod:`.compiled`), one compiled loop over the
rows each."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numba import njit

from . import compiled

__all__ = ["exp6", "jlog3", "jlog6", "log6"]


def _as_batch(R, t):
    return np.ascontiguousarray(R, dtype=float).reshape(-1, 3, 3), np.ascontiguousarray(t, dtype=float).reshape(-1, 3)


def log6(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Twists (N, 6) = (v, w) of poses (R (N, 3, 3), t (N, 3)): ``pin.log6`` row by row, ``w = log3(R)``."""
    R, t = _as_batch(R, t)
    out = np.empty((R.shape[0], 6))
    _log6_rows(R, t, out)
    return out


def exp6(xi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Poses (R (N, 3, 3), t (N, 3)) of twists xi (N, 6) = (v, w): ``pin.exp6`` row by row."""
    M = [pin.exp6(x).homogeneous for x in np.asarray(xi, dtype=float).reshape(-1, 6)]
    H = np.array(M).reshape(-1, 4, 4)
    return H[:, :3, :3].copy(), H[:, :3, 3].copy()


def jlog3(phi: np.ndarray) -> np.ndarray:
    """``pin.Jlog3`` (N, 3, 3) from rotation vectors phi (N, 3) = ``log3(R)``: the derivative of
    ``log3(R exp(dw))`` at dw = 0."""
    w = np.ascontiguousarray(phi, dtype=float).reshape(-1, 3)
    out = np.empty((w.shape[0], 3, 3))
    _jlog3_rows(w, out)
    return out


def jlog6(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``pin.Jlog6`` (N, 6, 6) of poses (R (N, 3, 3), t (N, 3)): ``[[A, B], [0, A]]`` with ``A = Jlog3``."""
    R, t = _as_batch(R, t)
    out = np.zeros((R.shape[0], 6, 6))
    _jlog6_rows(R, t, out)
    return out


@njit(cache=True, nogil=True)
def _log6_rows(R, t, out):  # pragma: no cover - compiled
    for k in range(R.shape[0]):
        compiled.log6(R[k], t[k], out[k])


@njit(cache=True, nogil=True)
def _jlog3_rows(w, out):  # pragma: no cover - compiled
    for k in range(w.shape[0]):
        compiled.jlog3(np.sqrt(w[k, 0] * w[k, 0] + w[k, 1] * w[k, 1] + w[k, 2] * w[k, 2]), w[k], out[k])


@njit(cache=True, nogil=True)
def _jlog6_rows(R, t, out):  # pragma: no cover - compiled
    w, A, B = np.empty(3), np.empty((3, 3)), np.empty((3, 3))
    for k in range(R.shape[0]):
        compiled.jlog6(compiled.log3(R[k], w), w, t[k], A, B)
        out[k, :3, :3] = A
        out[k, 3:, 3:] = A
        out[k, :3, 3:] = B
