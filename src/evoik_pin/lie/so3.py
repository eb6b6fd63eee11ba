"""SO(3) maths in NumPy, vectorized over a batch of rotations (leading axis N): Pinocchio's closed forms (``pin.log3``,
``pin.exp3``), ``1 - cos`` as ``2 sin^2(theta / 2)`` (no digits lost at small angles)."""

from __future__ import annotations

import numpy as np

__all__ = ["angle", "exp3", "is_rotation", "log3", "relative_angle", "rotation_to_z", "rpy", "skew",
           "wrap_angle", "yaw"]

#: Pinocchio's series thresholds (TaylorSeriesExpansion precision<3> and <2>: eps^(1/3), eps^(1/2)).
PREC3, PREC2 = np.finfo(np.float64).eps ** (1.0 / 3.0), np.finfo(np.float64).eps ** 0.5
#: Angles (rad) above pi - NEAR_PI take the axis from the symmetric part of R (the antisymmetric part vanishes).
NEAR_PI = 1e-3


def wrap_angle(a):
    """Angles (any shape, rad) wrapped into [-pi, pi)."""
    return (np.asarray(a) + np.pi) % (2.0 * np.pi) - np.pi


def is_rotation(R: np.ndarray, tol: float = 1e-6):
    """Whether each (3, 3) matrix of R (..., 3, 3) is a rotation: every entry of R^T R - I within ``tol`` and
    det R >= 0 (False for NaN or inf). Shape (...,) bool."""
    R = np.asarray(R, dtype=float)
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        ortho = np.abs(np.swapaxes(R, -1, -2) @ R - np.eye(3)).max(axis=(-2, -1))
        return (ortho <= tol) & (np.linalg.det(np.nan_to_num(R, nan=0.0, posinf=0.0, neginf=0.0)) >= 0)


def is_rotation_entries(a: float, b: float, c: float, d: float, e: float, f: float, g: float, h: float,
                        i: float) -> bool:
    """Whether the 9 numbers (a 3 x 3 matrix, row-major) are a rotation's: |R^T R - I|_F <= 1e-6 and det R >= 0
    (False for NaN or inf): a target's test (:class:`evoik_pin.Target`), compiled in :mod:`.compiled` for kernels."""
    # a rotation's squared Frobenius norm is 3: past the screen at 4 no product below overflows (inf or NaN: refused)
    if not a * a + b * b + c * c + d * d + e * e + f * f + g * g + h * h + i * i <= 4.0:
        return False
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    n0, n1, n2 = a * a + d * d + g * g - 1.0, b * b + e * e + h * h - 1.0, c * c + f * f + i * i - 1.0
    m01, m02, m12 = a * b + d * e + g * h, a * c + d * f + g * i, b * c + e * f + h * i
    return not (n0 * n0 + n1 * n1 + n2 * n2 + 2.0 * (m01 * m01 + m02 * m02 + m12 * m12) > 1e-12 or det < 0)


def skew(v: np.ndarray) -> np.ndarray:
    """Skew matrices (..., 3, 3) of vectors v (..., 3): ``skew(v) @ x = v x x``."""
    v = np.asarray(v, dtype=float)
    K = np.zeros(v.shape[:-1] + (3, 3))
    K[..., 0, 1], K[..., 0, 2] = -v[..., 2], v[..., 1]
    K[..., 1, 0], K[..., 1, 2] = v[..., 2], -v[..., 0]
    K[..., 2, 0], K[..., 2, 1] = -v[..., 1], v[..., 0]
    return K


def _axis_and_cos(R: np.ndarray):
    """Twice the antisymmetric part's vector (N, 3), its half-norm sin(theta) (N,) and cos(theta) (N,)."""
    ax = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], axis=1)
    s = 0.5 * np.sqrt((ax * ax).sum(axis=1))
    c = 0.5 * (R[:, 0, 0] + R[:, 1, 1] + R[:, 2, 2] - 1.0)
    return ax, s, c


def angle(R: np.ndarray) -> np.ndarray:
    """Rotation angles (N,) in [0, pi] rad of rotations R (N, 3, 3): ``|log3(R)|``, as ``atan2(|sin|, cos)`` (full
    precision near 0, where ``acos`` of the trace loses half the digits, and near pi)."""
    _, s, c = _axis_and_cos(np.asarray(R, dtype=float).reshape(-1, 3, 3))
    return np.arctan2(s, c)


def relative_angle(R_ref: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Angles (N,) rad of ``R_ref^T R`` for one reference rotation R_ref (3, 3) and rotations R (N, 3, 3):
    the orientation error of a population against a target orientation."""
    return angle(np.einsum("ji,njk->nik", R_ref, np.asarray(R, dtype=float).reshape(-1, 3, 3)))


def yaw(R: np.ndarray) -> np.ndarray:
    """Heading (N,) rad of rotations R (N, 3, 3) about the base z axis: ``atan2(R[1, 0], R[0, 0])``
    (the yaw of roll-pitch-yaw; a planar arm's orientation)."""
    R = np.asarray(R, dtype=float).reshape(-1, 3, 3)
    return np.arctan2(R[:, 1, 0], R[:, 0, 0])


def rpy(R: np.ndarray) -> np.ndarray:
    """Roll-pitch-yaw (N, 3) rad of rotations R (N, 3, 3), ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (URDF's and
    ``pin.rpy.matrixToRpy``'s convention). At gimbal lock (pitch = +-pi/2) the whole heading goes to roll."""
    R = np.asarray(R, dtype=float).reshape(-1, 3, 3)
    cp = np.hypot(R[:, 0, 0], R[:, 1, 0])
    pitch, roll = np.arctan2(-R[:, 2, 0], cp), np.arctan2(R[:, 2, 1], R[:, 2, 2])
    yw = np.arctan2(R[:, 1, 0], R[:, 0, 0])
    lock = cp < 1e-12
    if lock.any():
        roll = np.where(lock, np.arctan2(-R[:, 1, 2], R[:, 1, 1]), roll)
        yw = np.where(lock, 0.0, yw)
    return np.stack([roll, pitch, yw], axis=1)


def log3(R: np.ndarray) -> np.ndarray:
    """Rotation vectors (N, 3) rad of rotations R (N, 3, 3), ``pin.log3`` row by row, stable near 0 and pi (there
    the axis comes from the symmetric part, ``a a^T = ((R + R^T)/2 - cos I) / (1 - cos)``, as in :mod:`.compiled`)."""
    R = np.asarray(R, dtype=float).reshape(-1, 3, 3)
    ax, s, c = _axis_and_cos(R)
    theta = np.arctan2(s, c)
    small = s < 1e-8
    coef = np.where(small, 0.5 + theta * theta / 12.0, theta / (2.0 * np.where(small, 1.0, s)))
    phi = coef[:, None] * ax
    near = theta >= np.pi - NEAR_PI
    if near.any():
        i = np.nonzero(near)[0]
        Rn, cn = R[i], c[i]
        omc = (1.0 - cn)[:, None]
        d = (np.stack([Rn[:, 0, 0], Rn[:, 1, 1], Rn[:, 2, 2]], axis=1) - cn[:, None]) / omc
        sym = (Rn + Rn.transpose(0, 2, 1)) / (2.0 * omc[:, :, None])  # off-diagonal: a_i a_j
        big = d.argmax(axis=1)
        rows = np.arange(i.size)
        a_big = np.sqrt(np.maximum(d[rows, big], 0.0))
        a = sym[rows, big, :] / a_big[:, None]
        a[rows, big] = a_big
        a /= np.sqrt((a * a).sum(axis=1))[:, None]
        sign = np.where((a * ax[i]).sum(axis=1) < 0.0, -1.0, 1.0)
        phi[i] = (sign * theta[i])[:, None] * a
    return phi


def exp3(phi: np.ndarray) -> np.ndarray:
    """Rotations (N, 3, 3) of rotation vectors phi (N, 3) rad (Rodrigues; ``pin.exp3`` row by row)."""
    phi = np.asarray(phi, dtype=float).reshape(-1, 3)
    t2 = (phi * phi).sum(axis=1)
    theta = np.sqrt(t2)
    small = theta < PREC3
    th = np.where(small, 1.0, theta)
    a = np.where(small, 1.0 - t2 / 6.0, np.sin(th) / th)  # sin / theta
    b = np.where(small, 0.5 - t2 / 24.0, 2.0 * np.sin(0.5 * th) ** 2 / (th * th))  # (1 - cos) / theta^2
    K = skew(phi)
    return np.eye(3) + a[:, None, None] * K + b[:, None, None] * (K @ K)


def rotation_to_z(axis) -> np.ndarray:
    """A rotation B (3, 3) whose third column is the unit vector of ``axis`` (3,) (identity when it is +z):
    turns a joint axis, or a cylinder's axis, onto z."""
    z = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    if np.allclose(z, [0.0, 0.0, 1.0], atol=1e-15):
        return np.eye(3)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])
