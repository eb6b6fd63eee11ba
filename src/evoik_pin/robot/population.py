"""Kinematics of whole populations (NumPy): poses, positions and Jacobians of one frame for physical joint values
X (N, m), walking its :class:`~.tree.ChainView` with a few NumPy calls per joint whatever N is.
"""

from __future__ import annotations

import numpy as np

from .tree import ChainView

__all__ = ["chain_forward", "chain_jacobians", "chain_positions"]


def _on_chain(view: ChainView, X: np.ndarray) -> np.ndarray:
    """The columns of X (N, m) of the chain's joints."""
    return X if view.joints.size == X.shape[1] else X[:, view.joints]


def chain_forward(view: ChainView, X: np.ndarray, want_joints: bool):
    """Base-to-frame recursion over physical joint values X (N, m): the frame's rotations (N, 3, 3) and positions
    (N, 3) m, and with ``want_joints`` the chain joints' z axes and origins (N, c, 3) (else None)."""
    N = X.shape[0]
    X = _on_chain(view, X)
    c = X.shape[1]
    FR, Fp = view.FR, view.Fp
    R = np.broadcast_to(FR[0], (N, 3, 3)).copy()
    p = np.broadcast_to(Fp[0], (N, 3)).copy()
    cos, sin = np.cos(X), np.sin(X)
    z_axes = np.empty((N, c, 3)) if want_joints else None
    origins = np.empty((N, c, 3)) if want_joints else None
    for k in range(c):
        if want_joints:
            z_axes[:, k] = R[:, :, 2]
            origins[:, k] = p
        if view.revolute[k]:
            cs, sn = cos[:, k, None], sin[:, k, None]
            c0, c1 = R[:, :, 0].copy(), R[:, :, 1]
            R[:, :, 0] = cs * c0 + sn * c1
            R[:, :, 1] = cs * c1 - sn * c0
        else:
            p = p + X[:, k, None] * R[:, :, 2]
        p = p + (R.reshape(N * 3, 3) @ Fp[k + 1]).reshape(N, 3)
        R = (R.reshape(N * 3, 3) @ FR[k + 1]).reshape(N, 3, 3)
    return R, p, z_axes, origins


def chain_positions(view: ChainView, X: np.ndarray) -> np.ndarray:
    """The frame's positions (N, 3) m for X (N, m), walking back from the frame with two NumPy calls per joint
    (:attr:`~.tree.ChainView.positions_operator`); cheaper than :func:`chain_forward`."""
    N = X.shape[0]
    XT = _on_chain(view, X).T
    c = XT.shape[0]
    S3, y_tip = view.positions_operator
    AB = np.empty((c, 8, N))  # rows 0-3: a = cos x (or x), rows 4-7: b = sin x (or 0)
    AB[:, 0:4] = np.cos(XT)[:, None, :]
    AB[:, 4:8] = np.sin(XT)[:, None, :]
    if not view.all_revolute:
        prismatic = ~view.revolute
        AB[prismatic, 0:4] = XT[prismatic][:, None, :]
    Y = np.empty((12, N))
    Z = np.empty((12, N))
    Y[:] = y_tip
    for k in range(c - 1, -1, -1):
        Y[0:8] *= AB[k]
        np.matmul(S3[k], Y, out=Z)
        Y, Z = Z, Y
    return Y[8:11].T.copy()


def chain_jacobians(view: ChainView, X: np.ndarray, m: int):
    """The frame's positions (N, 3), rotations (N, 3, 3) and base-frame Jacobians (N, 6, m) with respect to the
    m physical joint values (rows vx, vy, vz, wx, wy, wz; zero columns for joints that do not move the frame)."""
    R, p, z_axes, origins = chain_forward(view, X, want_joints=True)
    J = np.zeros((X.shape[0], 6, m))
    cols = view.joints
    rev = view.revolute
    lever = p[:, None, :] - origins  # (N, c, 3)
    J[:, :3, cols[rev]] = np.cross(z_axes[:, rev], lever[:, rev]).transpose(0, 2, 1)
    J[:, 3:, cols[rev]] = z_axes[:, rev].transpose(0, 2, 1)
    J[:, :3, cols[~rev]] = z_axes[:, ~rev].transpose(0, 2, 1)
    return p, R, J
