"""The kinematic tree of a robot's active joints: topology, folded constants, frames on joints, a floating base.

The m physical joints of a (reduced) Pinocchio model are its joints 1..m, in Pinocchio's topological order (a
joint comes after its parent). :class:`KinematicTree` holds, for physical joint k:

* ``parent[k]``: the index of its parent physical joint, -1 for a joint at the root (below the base frame);
* ``FR[k]`` (3, 3), ``Fp[k]`` (3,) (m): the joint's placement in its parent's *folded* frame (in the base frame
  for a root joint). Folded: every joint axis a_k is turned onto z by a constant rotation ``B_k``
  (:func:`~evoik_pin.lie.rotation_to_z`) folded into the placements, ``F_k = B_parent^T M_k B_k``, so that a
  joint's motion ``Z(x)`` is a rotation by x about z (revolute) or a translation by x along z (prismatic);
* the joint poses follow in one pass: ``(R_k, p_k) = (R_parent, p_parent) F_k Z(x_k)``.

A frame f (a link, a joint frame or a fixed frame of the URDF) sits on one physical joint j_f (or on the base,
j_f = -1) at a constant placement, folded as ``B_j^T M_f``: its pose is ``(R_j R_f, p_j + R_j p_f)``; the
joints that move it are j_f and its ancestors. A serial chain is the tree with ``parent[k] = k - 1``; the chain
from the base to one frame (:meth:`KinematicTree.chain_to`) is what the population kinematics
(:mod:`.population`) evaluate.

A floating base (:func:`with_floating_base`) is six 1-DOF joints in front of the URDF's root link, so nothing
downstream needs a special case: prismatic along the world x, y, z axes (m), then revolute about z (yaw), the
new y (pitch) and the new x (roll) (rad), so that the root link's pose is ``(Rz(yaw) Ry(pitch) Rx(roll),
(x, y, z))``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import pinocchio as pin

from ..lie import rotation_to_z
from .frames import restore_frame_names, unique_frame_names
from .joints import joint_motions

__all__ = ["FLOATING_BASE_BOUNDS", "FLOATING_BASE_JOINTS", "ChainView", "KinematicTree",
           "free_flyer_model", "rpy_to_quaternion", "with_floating_base"]

#: Names of the six joints a floating base adds at the front of q: x, y, z (m, along the world axes), then yaw,
#: pitch, roll (rad; the root link's rotation is Rz(yaw) Ry(pitch) Rx(roll)).
FLOATING_BASE_JOINTS = ("floating_base_x", "floating_base_y", "floating_base_z", "floating_base_yaw",
                        "floating_base_pitch", "floating_base_roll")
#: Default bounds of the floating base's six entries: a 1 m box around the origin, yaw and roll a full turn
#: (they wrap), pitch [-pi/2, pi/2] (every rotation has such roll-pitch-yaw angles).
FLOATING_BASE_BOUNDS = (np.array([-1.0, -1.0, -1.0, -np.pi, -np.pi / 2, -np.pi]),
                        np.array([1.0, 1.0, 1.0, np.pi, np.pi / 2, np.pi]))


def with_floating_base(model: pin.Model) -> pin.Model:
    """``model`` (a fixed-base model of a URDF) behind six 1-DOF joints (:data:`FLOATING_BASE_JOINTS`) whose
    limits are :data:`FLOATING_BASE_BOUNDS`, each with its JOINT frame as a URDF joint has: the model's joints keep
    their order after them, and its frames their names; the root link hangs from the roll joint's frame."""
    base = pin.Model()
    parent = 0
    kinds = (pin.JointModelPX(), pin.JointModelPY(), pin.JointModelPZ(), pin.JointModelRZ(), pin.JointModelRY(),
             pin.JointModelRX())
    lo, hi = FLOATING_BASE_BOUNDS
    for k, (name, joint) in enumerate(zip(FLOATING_BASE_JOINTS, kinds, strict=True)):
        parent = base.addJoint(parent, joint, pin.SE3.Identity(), name, np.array([np.inf]), np.array([np.inf]),
                               np.array([lo[k]]), np.array([hi[k]]))
        base.appendBodyToJoint(parent, pin.Inertia.Zero(), pin.SE3.Identity())
        frame = base.addFrame(pin.Frame(name, parent, pin.SE3.Identity(), pin.FrameType.JOINT))
    return _appended(base, model, frame)


def _appended(base: pin.Model, model: pin.Model, frame: int) -> pin.Model:
    """``pin.appendModel(base, model, frame, identity)`` for models whose frames share names (appendModel looks
    frames up by name: see :func:`.frames.unique_frame_names`)."""
    work, renamed = unique_frame_names(model)
    out = pin.appendModel(base, work, frame, pin.SE3.Identity())
    restore_frame_names(out, renamed)
    return out


def free_flyer_model(model: pin.Model) -> pin.Model:
    """``model`` behind a free-flyer root joint (Pinocchio's ``root_joint``): the model
    ``pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer())`` builds, whose configuration starts with the root
    link's position (3) and unit quaternion (x, y, z, w) (4)."""
    base = pin.Model()
    joint = base.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root_joint")
    frame = base.addFrame(pin.Frame("root_joint", joint, pin.SE3.Identity(), pin.FrameType.JOINT))
    return _appended(base, model, frame)


def rpy_to_quaternion(yaw: float, pitch: float, roll: float) -> np.ndarray:
    """Unit quaternion (x, y, z, w) of ``Rz(yaw) Ry(pitch) Rx(roll)`` (rad), with w >= 0."""
    R = pin.rpy.rpyToMatrix(roll, pitch, yaw)
    quat = pin.Quaternion(R).coeffs()  # (x, y, z, w)
    return np.array(quat) * (1.0 if quat[3] >= 0 else -1.0)


class ChainView:
    """The serial chain from the base to one frame, in the folded form ``T = F_0 Z(x_a0) F_1 ... Z(x_ac) F_c+1``.

    Attributes:
        joints: (c,) indices of the physical joints on the chain, base to frame (the frame's joint's ancestors
            and itself).
        FR: (c+1, 3, 3), Fp: (c+1, 3) (m): the placements; the last one is the frame's (its only one when c = 0:
            a frame no joint moves).
        revolute: (c,) bool.
    """

    def __init__(self, joints: np.ndarray, FR: np.ndarray, Fp: np.ndarray, revolute: np.ndarray) -> None:
        self.joints = joints
        self.FR = FR
        self.Fp = Fp
        self.revolute = revolute
        self.all_revolute = bool(revolute.all())

    @cached_property
    def positions_operator(self) -> tuple[list[np.ndarray], np.ndarray]:
        """(S3, y_tip) for the positions-only recursion of :func:`.population.chain_positions`.

        The homogeneous map of joint k is ``H_k(x) = a(x) A_k + b(x) B_k + C_k`` (4 x 4) with a = cos x, b = sin x
        (revolute) or a = x, b = 0 (prismatic). With ``Y = [a p; b p; p]`` (12, N) for the homogeneous points p
        (4, N), ``H_k p = [A_k B_k C_k] Y``; stacking that (4, 12) block three times makes one BLAS product
        return p' already copied into all three slots of the next Y. S3: one (12, 12) matrix per joint; y_tip
        (12, 1): the frame's origin, three times.
        """
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
    """The folded constants of a model's m physical joints (see the module docstring).

    Attributes:
        parent: (m,) int64, the parent physical joint of each (-1 at the root).
        FR: (m, 3, 3), Fp: (m, 3) (m): each joint's placement in its parent's folded frame (base frame at the
            root). revolute: (m,) bool. axes: (m, 3) unit joint axes in each joint's own (unfolded) frame.
        B: (m, 3, 3) the rotations folding each axis onto z. base_R, base_p: the base frame's inverse
            placement in the model's world frame (``baseMo``), for frames no joint moves.
    """

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
        """The tree of every joint of ``model`` (all 1-DOF), with poses expressed in the frame whose inverse
        placement in the model's world frame is ``baseMo``."""
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
        """Number of physical joints."""
        return int(self.parent.size)

    @cached_property
    def is_chain(self) -> bool:
        """True when every joint's parent is the joint before it (a serial chain)."""
        return bool(np.array_equal(self.parent, np.arange(-1, self.m - 1)))

    def frame(self, model: pin.Model, frame_id: int) -> tuple[int, np.ndarray, np.ndarray]:
        """(physical joint j_f or -1, R_f (3, 3), p_f (3,) m) of frame ``frame_id`` of ``model`` (the model the tree
        was made of): its folded placement on its joint, or its constant pose in the base frame when j_f = -1."""
        f = model.frames[frame_id]
        j = int(f.parentJoint) - 1
        M = f.placement
        if j < 0:
            R = self.base_R @ M.rotation
            p = self.base_R @ M.translation + self.base_p
            return -1, R, p
        Bt = self.B[j].T
        return j, Bt @ M.rotation, Bt @ M.translation

    def ancestors(self, j: int) -> np.ndarray:
        """(c,) int64: the physical joints that move a frame on joint j (its ancestors and j), root first."""
        parent = self.parent.tolist()  # Python ints: cheaper than indexing the array joint by joint
        out = []
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
