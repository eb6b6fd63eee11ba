"""The kinematic tree of a robot's active joints: folded constants, masses, frames, a floating base, and the
kinematics of populations (physical joint values X (N, m), a few NumPy calls per joint whatever N is).

The m physical joints of a reduced model are its joints 1..m in topological order; joint k has ``parent[k]`` (-1 at
the root) and placement ``(FR[k], Fp[k])`` in its parent's *folded* frame: a constant rotation ``B_k``
(:func:`~evoik_pin.lie.rotation_to_z`) turns each axis onto z, ``F_k = B_parent^T M_k B_k``, so ``(R_k, p_k) =
(R_parent, p_parent) F_k Z(x_k)`` with ``Z(x)`` about or along z. A frame on joint j_f (-1: the base) sits at
``B_j^T M_f``. A floating base is six 1-DOF joints before the root: x, y, z (m), yaw, pitch, roll (rad).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import pinocchio as pin

from ..lie import rotation_to_z
from .frames import restore_frame_names, unique_frame_names
from .joints import joint_motions

__all__ = ["FLOATING_BASE_BOUNDS", "FLOATING_BASE_JOINTS", "ChainView", "KinematicTree", "MassConstants",
           "chain_forward", "chain_jacobians", "chain_positions", "free_flyer_model", "mass_constants",
           "with_floating_base"]

#: Names of the six joints a floating base adds at the front of q (rotation Rz(yaw) Ry(pitch) Rx(roll)).
FLOATING_BASE_JOINTS = ("floating_base_x", "floating_base_y", "floating_base_z", "floating_base_yaw",
                        "floating_base_pitch", "floating_base_roll")
#: Default bounds of the floating base's six entries: a 1 m box, yaw and roll a full turn, pitch [-pi/2, pi/2].
FLOATING_BASE_BOUNDS = (np.array([-1.0, -1.0, -1.0, -np.pi, -np.pi / 2, -np.pi]),
                        np.array([1.0, 1.0, 1.0, np.pi, np.pi / 2, np.pi]))


def with_floating_base(model: pin.Model) -> pin.Model:
    """``model`` (fixed-base) behind the six joints :data:`FLOATING_BASE_JOINTS` (limits
    :data:`FLOATING_BASE_BOUNDS`, each with its JOINT frame); the root link hangs from the roll joint's frame."""
    base, parent = pin.Model(), 0
    kinds = (pin.JointModelPX, pin.JointModelPY, pin.JointModelPZ, pin.JointModelRZ, pin.JointModelRY, pin.JointModelRX)
    for name, joint, lo, hi in zip(FLOATING_BASE_JOINTS, kinds, *FLOATING_BASE_BOUNDS, strict=True):
        parent = base.addJoint(parent, joint(), pin.SE3.Identity(), name, np.array([np.inf]), np.array([np.inf]),
                               np.array([lo]), np.array([hi]))
        base.appendBodyToJoint(parent, pin.Inertia.Zero(), pin.SE3.Identity())
        frame = base.addFrame(pin.Frame(name, parent, pin.SE3.Identity(), pin.FrameType.JOINT))
    return _appended(base, model, frame)


def _appended(base: pin.Model, model: pin.Model, frame: int) -> pin.Model:
    """``pin.appendModel(base, model, frame, identity)`` safe for shared frame names."""
    work, renamed = unique_frame_names(model)
    out = pin.appendModel(base, work, frame, pin.SE3.Identity())
    restore_frame_names(out, renamed)
    return out


def free_flyer_model(model: pin.Model) -> pin.Model:
    """``model`` behind Pinocchio's free-flyer ``root_joint`` (``pin.buildModelFromUrdf(path, free_flyer)``'s)."""
    base = pin.Model()
    joint = base.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root_joint")
    frame = base.addFrame(pin.Frame("root_joint", joint, pin.SE3.Identity(), pin.FrameType.JOINT))
    return _appended(base, model, frame)


@dataclass(eq=False)
class ChainView:
    """The folded serial chain from the base to one frame, ``T = F_0 Z(x_a0) F_1 ... Z(x_ac) F_c+1``: ``joints``
    (c,), base to frame; ``FR`` (c+1, 3, 3), ``Fp`` (c+1, 3) m, the last the frame's; ``revolute`` (c,) bool."""

    joints: np.ndarray
    FR: np.ndarray
    Fp: np.ndarray
    revolute: np.ndarray

    def __post_init__(self) -> None:
        self.all_revolute = bool(self.revolute.all())

    @cached_property
    def positions_operator(self) -> tuple[list[np.ndarray], np.ndarray]:
        """(S3, y_tip) of :func:`chain_positions`: joint k's homogeneous map is ``H_k(x) = a A_k + b B_k + C_k``
        (a, b = cos x, sin x; or x, 0 if prismatic), so ``H_k p = [A_k B_k C_k] [a p; b p; p]``. S3: that (4, 12)
        block stacked thrice per joint (12, 12); y_tip (12, 1): the frame's origin, thrice."""
        c = self.joints.size
        S = np.zeros((c, 4, 12))
        for k in range(c):
            R, t = self.FR[k], self.Fp[k]
            if self.revolute[k]:
                S[k, 0:3, 0], S[k, 0:3, 1] = R[:, 0], R[:, 1]
                S[k, 0:3, 4], S[k, 0:3, 5] = R[:, 1], -R[:, 0]
                S[k, 0:3, 10] = R[:, 2]
            else:
                S[k, 0:3, 3] = R[:, 2]
                S[k, 0:3, 8:11] = R
            S[k, 0:3, 11], S[k, 3, 11] = t, 1.0
        S3 = [np.ascontiguousarray(np.vstack([S[k]] * 3)) for k in range(c)]
        return S3, np.tile(np.append(self.Fp[-1], 1.0), 3)[:, None]


@dataclass(frozen=True)
class KinematicTree:
    """The folded constants of a model's m physical joints (the module docstring): parent (m,) int64, FR (m, 3, 3),
    Fp (m, 3) m, revolute (m,) bool, axes (m, 3) unfolded unit axes, B (m, 3, 3) folding rotations, and base_R,
    base_p: ``baseMo``, for frames no joint moves."""

    parent: np.ndarray
    FR: np.ndarray
    Fp: np.ndarray
    revolute: np.ndarray
    axes: np.ndarray
    B: np.ndarray
    base_R: np.ndarray
    base_p: np.ndarray

    @classmethod
    def of(cls, model: pin.Model, baseMo: pin.SE3) -> KinematicTree:
        """The tree of every joint of ``model`` (all 1-DOF), poses in the frame ``baseMo`` maps the world to."""
        m = model.njoints - 1
        revolute, axes = joint_motions(model, range(1, m + 1))
        B = np.array([rotation_to_z(a) for a in axes]).reshape(m, 3, 3)
        parent = np.array([model.parents[k + 1] - 1 for k in range(m)], dtype=np.int64)
        FR, Fp = np.empty((m, 3, 3)), np.empty((m, 3))
        for k in range(m):
            M = model.jointPlacements[k + 1]
            a = parent[k]
            if a < 0:
                M = baseMo * M
                FR[k], Fp[k] = M.rotation @ B[k], M.translation
            else:
                FR[k], Fp[k] = B[a].T @ M.rotation @ B[k], B[a].T @ M.translation
        return cls(parent, np.ascontiguousarray(FR), np.ascontiguousarray(Fp), revolute, axes, B,
                   np.array(baseMo.rotation), np.array(baseMo.translation))

    @property
    def m(self) -> int:
        return int(self.parent.size)

    @cached_property
    def is_chain(self) -> bool:
        """True when every joint's parent is the joint before it (a serial chain)."""
        return bool(np.array_equal(self.parent, np.arange(-1, self.m - 1)))

    def frame(self, model: pin.Model, frame_id: int) -> tuple[int, np.ndarray, np.ndarray]:
        """(j_f, R_f, p_f) of frame ``frame_id`` of the tree's ``model`` (:meth:`Robot.frame_constants`)."""
        f = model.frames[frame_id]
        j, M = int(f.parentJoint) - 1, f.placement
        if j < 0:
            return -1, self.base_R @ M.rotation, self.base_R @ M.translation + self.base_p
        Bt = self.B[j].T
        return j, Bt @ M.rotation, Bt @ M.translation

    def ancestors(self, j: int) -> np.ndarray:
        """(c,) int64: the physical joints that move a frame on joint j (its ancestors and j), root first."""
        parent, out = self.parent.tolist(), []
        while j >= 0:
            out.append(j)
            j = parent[j]
        return np.array(out[::-1], dtype=np.int64)

    def chain_to(self, j: int, R: np.ndarray, p: np.ndarray) -> ChainView:
        """The :class:`ChainView` from the base to a frame on joint j at folded placement (R (3, 3), p (3,))."""
        joints = self.ancestors(j)
        FR = np.ascontiguousarray(np.concatenate([self.FR[joints], R[None]]), dtype=float)
        Fp = np.ascontiguousarray(np.concatenate([self.Fp[joints], p[None]]), dtype=float)
        return ChainView(joints, FR, Fp, self.revolute[joints])

    def support_mask(self, joints_of_frames) -> np.ndarray:
        """(G, m) bool: row g marks the joints that move frame g (``joints_of_frames``: (G,) frame joints)."""
        mask = np.zeros((len(joints_of_frames), self.m), dtype=bool)
        for g, j in enumerate(joints_of_frames):
            mask[g, self.ancestors(int(j))] = True
        return mask


@dataclass(frozen=True)
class MassConstants:
    """The masses of a robot's m physical joints: ``masses`` (m,) kg, ``moments`` (m, 3) kg m (``m_k c_k`` in the
    joint's folded frame), ``subtree`` (m,) kg (a joint's body and all below), ``fixed_mass`` kg and ``fixed_moment``
    (3,) kg m (base frame) of the bodies no active joint moves, ``total`` kg."""

    masses: np.ndarray
    moments: np.ndarray
    subtree: np.ndarray
    fixed_mass: float
    fixed_moment: np.ndarray
    total: float


def mass_constants(robot) -> MassConstants:
    """The :class:`MassConstants` of ``robot``, from its reduced model's inertias; bodies welded to the world in
    ``full_model`` are left out, as ``pin.centerOfMass(full_model, ...)`` does."""
    model, tree = robot.model, robot.tree
    inertias = [model.inertias[k + 1] for k in range(tree.m)]
    masses = np.array([i.mass for i in inertias], dtype=float)
    moments = np.array([B.T @ (i.mass * np.asarray(i.lever)) for B, i in zip(tree.B, inertias, strict=True)])
    subtree = masses.copy()
    for k in range(tree.m - 1, -1, -1):  # a joint comes after its parent
        if tree.parent[k] >= 0:
            subtree[tree.parent[k]] += subtree[k]
    held, welded = model.inertias[0], robot.full_model.inertias[0]
    fixed_mass = float(held.mass - welded.mass)
    first = held.mass * np.asarray(held.lever) - welded.mass * np.asarray(welded.lever)  # world frame
    fixed_moment = tree.base_R @ first + fixed_mass * tree.base_p
    if abs(fixed_mass) < 1e-12:  # no round-off left over
        fixed_mass, fixed_moment = 0.0, np.zeros(3)
    return MassConstants(masses, moments, subtree, fixed_mass, fixed_moment, float(masses.sum() + fixed_mass))


def _on_chain(view: ChainView, X: np.ndarray) -> np.ndarray:
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
    z_axes, origins = (np.empty((N, c, 3)), np.empty((N, c, 3))) if want_joints else (None, None)
    for k in range(c):
        if want_joints:
            z_axes[:, k], origins[:, k] = R[:, :, 2], p
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
    (:attr:`ChainView.positions_operator`)."""
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
    Y, Z = np.empty((12, N)), np.empty((12, N))
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
    J, cols, rev = np.zeros((X.shape[0], 6, m)), view.joints, view.revolute
    lever = p[:, None, :] - origins  # (N, c, 3)
    J[:, :3, cols[rev]] = np.cross(z_axes[:, rev], lever[:, rev]).transpose(0, 2, 1)
    J[:, 3:, cols[rev]] = z_axes[:, rev].transpose(0, 2, 1)
    J[:, :3, cols[~rev]] = z_axes[:, ~rev].transpose(0, 2, 1)
    return p, R, J
