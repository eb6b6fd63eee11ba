"""The robot: :class:`Robot`, the active joints of a URDF (the others locked), their kinematics for one ``q``
(Pinocchio) or a population (NumPy), and the folded constants of compiled kernels. ``q``: one entry per independent
degree of freedom (rad or m) in Pinocchio's order. Poses are in the base frame (the world frame when none is chosen).
"""

from __future__ import annotations

from functools import cached_property
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import ConfigurationError, FrameError, RobotLoadError
from .active_joints import MAX_CHAIN_JOINTS, choose_joints
from .frames import closest_hint, find_frame, frame_names, reduced_model
from .geometry_models import RobotGeometry
from .joints import NEAR_UNBOUNDED, JointBounds, couplings, joint_motions, joint_value, set_joint_value
from .tree import (
    ChainView,
    KinematicTree,
    chain_forward,
    chain_jacobians,
    chain_positions,
    free_flyer_model,
    mass_constants,
    with_floating_base,
)

__all__ = ["MAX_CHAIN_JOINTS", "NEAR_UNBOUNDED", "Robot"]

_MANIPULABILITY_ROWS = {"translation": [0, 1, 2], "rotation": [3, 4, 5], "full": [0, 1, 2, 3, 4, 5],
                        "planar": [0, 1, 5]}


def yoshikawa(J: np.ndarray):
    """Yoshikawa's manipulability (...,) of Jacobians J (..., r, n): the product of J's singular values
    (sqrt(det(J J^T)) when r <= n); 0 at a singularity."""
    if J.shape[-2] > J.shape[-1]:  # the singular values themselves: det(J^T J) of a rank-deficient J is noise
        return np.prod(np.linalg.svd(J, compute_uv=False), axis=-1)
    return np.sqrt(np.maximum(np.linalg.det(J @ np.swapaxes(J, -1, -2)), 0.0))


class Robot(JointBounds, RobotGeometry):
    """The active joints of a URDF (a serial chain or a tree): kinematics, Jacobians, manipulability of any frame.

    Attributes:
        name: robot name. n: entries of ``q`` (mimic joints folded in; a floating base counts 6).
        joint_names: the joints of ``q`` (n,), in Pinocchio's order (a floating base's first six:
            :data:`~evoik_pin.robot.tree.FLOATING_BASE_JOINTS`).
        lower, upper: search bounds (n,) in rad or m, finite (:meth:`set_bounds`).
        tip: default goal frame; tips: the frames the active joints were chosen for. base: frame poses are
            expressed in (the URDF root, or the world with a floating base). floating_base: bool.
        model: reduced Pinocchio model of the active physical joints (:meth:`to_pinocchio` maps ``q`` to it);
            full_model: the whole URDF's (:meth:`full_configuration`). urdf_path, urdf_xml: the file and its text.
        revolute, continuous: (n,) bool (revolute: rad, else m; continuous: stored as (cos, sin)).
        joint_axes: (n, 3) unit axis of each joint in its own frame.
        mimic_joints: ``{physical joint: (joint it follows, multiplier, offset)}`` of the active mimic joints.
    """

    def __init__(self, full_model: pin.Model, tip: str | None = None, base: str | None = None,
                 joints: list[str] | None = None, name: str = "robot", urdf_path: Path | None = None,
                 urdf_xml: str | None = None, package_dirs: list[str] | None = None, mimic: dict | None = None,
                 tips: list[str] | str | None = None, floating_base: bool = False, base_box=None,
                 packages: dict[str, str] | None = None, missing_packages: dict[str, str] | None = None,
                 rest: dict[str, float] | None = None) -> None:
        """``full_model``: the URDF's fixed-base model. ``mimic``: ``{joint: (followed joint, multiplier, offset)}``
        (or :class:`~evoik_pin.robot.urdf_checks.Mimic`). ``packages``: ``{pkg: folder}`` of mesh URIs,
        ``missing_packages``: ``{pkg: error}``. ``rest``: ``{joint: value}`` of joints locked off rest
        (:meth:`locked`). The other arguments: :func:`~evoik_pin.robot.load_robot`'s."""
        self._init_args = {k: v for k, v in locals().items() if k not in ("self", "rest")}  # for Robot.locked
        self.locked_values: dict[str, float] = dict(rest or {})
        self.name, self.urdf_path, self.urdf_xml = name, urdf_path, urdf_xml
        self.package_dirs, self.packages = list(package_dirs or []), dict(packages or {})
        self.missing_packages = dict(missing_packages or {})
        self.srdf: str | None = None  # set by load_robot
        self.floating_base = bool(floating_base)
        kin = self.full_model = full_model  # kin: the model the reduced one is cut from (six joints + full_model)
        if self.floating_base:
            moving = [j for j in range(1, kin.njoints) if kin.parents[j] == 0 and kin.joints[j].nv > 1]
            if moving:  # the URDF's root already moves: a floating base would move it twice
                raise RobotLoadError(f"{name}'s root already moves (joint {kin.names[moving[0]]!r} is a "
                                     f"{kin.joints[moving[0]].shortname()} of {kin.joints[moving[0]].nv} DOF): load "
                                     "it without floating_base=True")
            if base is not None:
                raise FrameError(f"a floating base moves the root link of {name}: poses are in the world frame, so "
                                 f"no base frame can be chosen (got base={base!r})")
            kin, self.full_model = with_floating_base(full_model), free_flyer_model(full_model)
        self._kin_model = kin
        self._full_couplings = coupling = couplings(kin, mimic)

        chosen = choose_joints(kin, full_model, name, tip, tips, base, joints, coupling)
        physical, dofs = chosen.physical, chosen.dofs
        q_ref = pin.neutral(kin)  # locked joints at rest, inside their limits
        idx = np.array([kin.joints[j].idx_q for j in range(1, kin.njoints) if kin.joints[j].nq == 1], dtype=np.intp)
        lo, hi = kin.lowerPositionLimit[idx], kin.upperPositionLimit[idx]
        q_ref[idx] = np.where(lo <= hi, np.clip(q_ref[idx], lo, hi), q_ref[idx])
        for jname, value in (rest or {}).items():  # joints locked elsewhere than at rest (Robot.locked)
            set_joint_value(kin, q_ref, kin.getJointId(jname), value)
        for j, (d, m, off) in coupling.items():  # locked mimic joints sit where their driver's rest puts them
            set_joint_value(kin, q_ref, j, m * joint_value(kin, q_ref, d) + off)
        self._q_ref_full, self._locked = q_ref, [j for j in range(1, kin.njoints) if j not in physical]
        self._above_base = chosen.above_base  # kinematic-model joints that stay put whatever q is
        self.model = reduced_model(kin, self._locked, q_ref) if self._locked else pin.Model(kin)
        self.data = self.model.createData()
        self._pin_q_key, self._pin_q_value = None, None
        self.tip, self.tips, self.base = chosen.tip, chosen.tips, chosen.base
        self._tip_id = find_frame(self.model, self.tip)
        self._base_id = 0 if base is None else find_frame(self.model, base)
        self.n, self.joint_names = len(dofs), [kin.names[d] for d in dofs]
        self._dof_ids = dofs  # kinematic-model joint ids of the entries of q

        pin.framesForwardKinematics(self.model, self.data, pin.neutral(self.model))
        self._oMbase = self.data.oMf[self._base_id].copy() if base is not None else pin.SE3.Identity()
        self._baseMo = self._oMbase.inverse()

        # The physical joints: the reduced model's joints 1..m in topological order, and how each follows q.
        m_phys = self.model.njoints - 1
        self._phys_idx_q = np.array([self.model.joints[k].idx_q for k in range(1, m_phys + 1)], dtype=np.intp)
        self._phys_continuous = np.array([self.model.joints[k].nq == 2 for k in range(1, m_phys + 1)])
        self._has_continuous = bool(self._phys_continuous.any())
        self.tree = KinematicTree.of(self.model, self._baseMo)
        follow = chosen.follow
        self.mimic_joints = {kin.names[j]: (kin.names[d], m, off) for j, (d, m, off) in zip(physical, follow,
                                                                                          strict=True) if d != j}
        self._phys_index = np.array([dofs.index(d) for d, _, _ in follow], dtype=np.int64)
        _, scale, offset = zip(*follow, strict=True)
        self._phys_scale, self._phys_offset = np.array(scale, dtype=float), np.array(offset, dtype=float)
        self._coupled = bool(self.mimic_joints)
        self._G = np.zeros((m_phys, self.n))  # d(physical values)/dq
        self._G[np.arange(m_phys), self._phys_index] = self._phys_scale
        self._views: dict[int, tuple[int, np.ndarray, np.ndarray, ChainView]] = {}
        self._frame_ids: dict[str, int] = {}
        self._moving: dict[int, list[str]] = {}  # frame id -> moving_joints
        self._tip_view = self._frame_view(self._tip_id)[3]

        self.revolute, self.joint_axes = joint_motions(kin, dofs)
        self.continuous = np.array([kin.joints[d].nq == 2 for d in dofs])
        self._set_default_bounds(coupling)
        if base_box is not None:
            self._set_base_box(base_box)

    def locked(self, values: dict[str, float]) -> Robot:
        """A new Robot whose ``q`` omits the joints ``values`` names, fixed at those values (rad or m), this robot's
        bounds on the others. FrameError for no joint of ``q``, BoundsError outside its bounds, ConfigurationError
        when none is left free."""
        from .locking import locked_robot

        return locked_robot(self, values)

    # ------------------------------------------------------------------ frames
    @cached_property
    def frames(self) -> list[str]:
        """Names of every frame a goal or :meth:`fk` can name (links, joint and fixed frames), in model order."""
        return frame_names(self.model)

    def frame_id(self, frame: str | None) -> int:
        """Pinocchio id in :attr:`model` of frame ``frame`` (None: the tip); a FrameError naming the closest frames
        when there is no such frame."""
        if frame is None:
            return self._tip_id
        fid = self._frame_ids.get(frame) if isinstance(frame, str) else None
        if fid is None:
            if not isinstance(frame, str):
                raise FrameError(f"a frame is named by a string, got {type(frame).__name__} {frame!r}")
            fid = find_frame(self.model, frame)
            if fid < 0:
                raise FrameError(f"{self.name} has no frame {frame!r}{closest_hint(frame, self.frames)} (robot.frames "
                                 f"lists its {len(self.frames)} frames)")
            self._frame_ids[frame] = fid
        return fid

    def _frame_view(self, fid: int) -> tuple[int, np.ndarray, np.ndarray, ChainView]:
        """(physical joint or -1, folded placement R (3, 3), p (3,), the chain from the base) of frame ``fid``."""
        hit = self._views.get(fid)
        if hit is None:
            j, R, p = self.tree.frame(self.model, fid)
            hit = self._views[fid] = (j, R, p, self.tree.chain_to(j, R, p))
        return hit

    def frame_constants(self, frame: str | None = None) -> tuple[int, np.ndarray, np.ndarray]:
        """(physical joint j_f, R_f (3, 3), p_f (3,) m) of a frame (None: the tip) for compiled kernels: its folded
        placement on joint j_f of :meth:`tree_constants`, or its base-frame pose when j_f = -1. Read-only."""
        j, R, p, _ = self._frame_view(self.frame_id(frame))
        return j, R, p

    def moving_joints(self, frame: str | None = None) -> list[str]:
        """Names of the entries of ``q`` that move a frame (None: the tip); empty when no active joint moves it."""
        fid = self.frame_id(frame)
        names = self._moving.get(fid)
        if names is None:
            phys = self.tree.ancestors(self._frame_view(fid)[0])
            ks = sorted({int(self._phys_index[k]) for k in phys if self._phys_scale[k] != 0.0})
            names = self._moving[fid] = [self.joint_names[k] for k in ks]
        return list(names)

    def locked_joints(self, frame: str | None = None) -> list[str]:
        """Names of the joints between the base and a frame (None: the tip) that ``q`` does not move; a mimic joint
        is named by the joint it follows."""
        kin, locked = self._kin_model, set(self._locked) - self._above_base
        path = kin.supports[kin.frames[find_frame(kin, self.model.frames[self.frame_id(frame)].name)].parentJoint]
        drivers = [self._full_couplings.get(j, (j,))[0] for j in path if j in locked]
        return list(dict.fromkeys(kin.names[d] for d in drivers if d not in self._above_base))

    # ------------------------------------------------------------------ constants of compiled kernels
    def tree_constants(self) -> tuple[np.ndarray, ...]:
        """The folded tree of the m physical joints for compiled kernels (:mod:`.tree`): parent (m,) int64, FR (m, 3,
        3), Fp (m, 3) m, revolute (m,) bool, index (m,) int64, scale (m,), offset (m,): joint k's value is
        ``scale[k] * q[index[k]] + offset[k]``. C-contiguous, read-only."""
        t = self.tree
        return (t.parent, t.FR, t.Fp, t.revolute, self._phys_index, self._phys_scale, self._phys_offset)

    def chain_constants(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The folded chain ``T = F_0 Z(x_1) F_1 ... Z(x_c) F_c`` from the base to the tip (:class:`.tree.ChainView`):
        F_R (c+1, 3, 3), F_p (c+1, 3) m, revolute (c,) bool; x from q by :meth:`chain_coupling`. Read-only."""
        view = self._tip_view
        return view.FR, view.Fp, view.revolute

    def chain_coupling(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """index (c,) int64, scale (c,), offset (c,): ``x_k = scale[k] * q[index[k]] + offset[k]``."""
        joints = self._tip_view.joints
        if joints.size == self.tree.m:  # the chain holds every physical joint (then 0..m-1 in order)
            return self._phys_index, self._phys_scale, self._phys_offset
        return self._phys_index[joints], self._phys_scale[joints], self._phys_offset[joints]

    def chain_joints(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Revolute mask (m,), unit axes (m, 3) and the lower and upper values (m,) (rad or m) of the m physical
        joints when q spans its bounds."""
        a, b = self._physical(self.lower), self._physical(self.upper)
        return self.tree.revolute, self.tree.axes, np.minimum(a, b), np.maximum(a, b)

    def _physical(self, Q: np.ndarray) -> np.ndarray:
        """Physical joint values (..., m) of joint vectors Q (..., n): ``scale * Q[..., index] + offset``."""
        if not self._coupled:
            return Q
        return Q[..., self._phys_index] * self._phys_scale + self._phys_offset

    # ------------------------------------------------------------------ Pinocchio mapping
    def to_pinocchio(self, q) -> np.ndarray:
        """Configuration (model.nq,) of :attr:`model` at ``q`` (n,): mimic joints coupled, continuous as (cos, sin)."""
        x = self._physical(np.asarray(q, dtype=float))
        if not self._has_continuous:
            return np.array(x)  # a copy: the caller owns it
        return np.concatenate((x, np.cos(x), np.sin(x)))[self._pin_gather]

    def from_pinocchio(self, q_pin) -> np.ndarray:
        """Joint vector (n,) of a configuration (model.nq,) of :attr:`model` (the inverse of :meth:`to_pinocchio`)."""
        q_pin = np.asarray(q_pin, dtype=float)
        out = np.full(self.n, np.nan)
        for k, i in enumerate(self._phys_idx_q):
            d, m = self._phys_index[k], self._phys_scale[k]
            if np.isnan(out[d]) and m != 0.0:
                x = np.arctan2(q_pin[i + 1], q_pin[i]) if self._phys_continuous[k] else q_pin[i]
                out[d] = (x - self._phys_offset[k]) / m
        return out

    def full_configuration(self, q) -> np.ndarray:
        """Configuration (full_model.nq,) of the whole URDF: ``q`` on its joints, mimic joints coupled, the others at
        rest. A floating base comes first as position (m) and unit quaternion (x, y, z, w), w >= 0."""
        q, out, fm = self.check_q(q), self._q_ref_full.copy(), self._kin_model
        for k, d in enumerate(self._dof_ids):
            set_joint_value(fm, out, d, q[k])
        for j, (d, m, off) in self._full_couplings.items():
            if d in self._dof_ids:
                set_joint_value(fm, out, j, m * q[self._dof_ids.index(d)] + off)
        if self.floating_base:
            quat = np.array(pin.Quaternion(pin.rpy.rpyToMatrix(out[5], out[4], out[3])).coeffs())  # (x, y, z, w)
            out = np.concatenate([out[:3], quat if quat[3] >= 0 else -quat, out[6:]])
        return out

    # ------------------------------------------------------------------ kinematics, one configuration
    def fk(self, q, frame: str | None = None) -> pin.SE3:
        """Pose (``pin.SE3``, m) in the base frame of a frame (None: the tip) at ``q`` (n,)."""
        q = self.check_q(q)
        return self.frame_poses_unchecked(q, [self.frame_id(frame)])[0]

    def jacobian(self, q, frame: str = "world", of: str | None = None) -> np.ndarray:
        """Jacobian (6, n) of a frame (``of``; None: the tip), rows (vx, vy, vz, wx, wy, wz), columns the entries of q.
        ``frame="world"``: in the base frame's axes (``J[:3]`` is the derivative of :meth:`fk`'s translation);
        ``"local"``: in the frame itself."""
        q = self.check_q(q)
        if frame not in ("world", "local"):
            raise ConfigurationError(f"jacobian frame must be 'world' or 'local', got {frame!r} (name the frame "
                                     "whose Jacobian you want with of=...)")
        fid = self.frame_id(of)
        J = self.jacobian_world_unchecked(q, fid) if frame == "world" else self.jacobian_local_unchecked(q, fid)
        return np.array(J)

    # ------------------------------------------------------------------ hot path of local solvers
    @cached_property
    def _pin_gather(self) -> np.ndarray:
        """(nq,) indices into ``[x, cos x, sin x]`` (3m,) that give Pinocchio's configuration vector."""
        m_phys = self._phys_idx_q.size
        gather = np.empty(self.model.nq, dtype=np.intp)
        for k, i in enumerate(self._phys_idx_q):
            if self._phys_continuous[k]:
                gather[i], gather[i + 1] = m_phys + k, 2 * m_phys + k
            else:
                gather[i] = k
        return gather

    def _pin_q(self, q: np.ndarray) -> np.ndarray:
        """:meth:`to_pinocchio`, or ``q`` itself when no conversion is needed; the last one memoized."""
        if not (self._has_continuous or self._coupled):
            return q
        key = q.tobytes()
        if key == self._pin_q_key:
            return self._pin_q_value
        out = self.to_pinocchio(q)
        self._pin_q_key, self._pin_q_value = key, out
        return out

    def fk_unchecked(self, q: np.ndarray) -> pin.SE3:
        """:meth:`fk` of the tip without validation (``q`` a finite float array (n,))."""
        return self.frame_poses_unchecked(q, [self._tip_id])[0]

    def tip_pose_seen_from_unchecked(self, q: np.ndarray, M: pin.SE3) -> pin.SE3:
        """``M * fk(q)`` (e.g. ``M = T_target^-1``: the tip seen from the target), unchecked, a new ``pin.SE3``."""
        return M * self.frame_poses_unchecked(q, [self._tip_id])[0]

    def frame_poses_unchecked(self, q: np.ndarray, frame_ids) -> list[pin.SE3]:
        """Base-frame poses (new ``pin.SE3``) of the frames ``frame_ids`` (:meth:`frame_id`) at ``q``, unchecked."""
        pin.framesForwardKinematics(self.model, self.data, self._pin_q(q))
        oMf = self.data.oMf
        if self._base_id == 0:
            return [oMf[f].copy() for f in frame_ids]
        return [self._baseMo * oMf[f] for f in frame_ids]

    def jacobian_local_unchecked(self, q: np.ndarray, frame_id: int | None = None) -> np.ndarray:
        """``jacobian(q, "local")`` (6, n) of the tip (or frame id ``frame_id``), unchecked."""
        return self._frame_jacobian(q, frame_id, pin.ReferenceFrame.LOCAL)

    def _frame_jacobian(self, q: np.ndarray, frame_id: int | None, reference) -> np.ndarray:
        fid = self._tip_id if frame_id is None else frame_id
        J = pin.computeFrameJacobian(self.model, self.data, self._pin_q(q), fid, reference)
        J = J.reshape(6, -1)  # (6,) for a one-joint model
        return J @ self._G if self._coupled else J

    def jacobian_world_unchecked(self, q: np.ndarray, frame_id: int | None = None) -> np.ndarray:
        """``jacobian(q, "world")`` (6, n) of the tip (or frame id ``frame_id``), unchecked."""
        J = self._frame_jacobian(q, frame_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        if self._base_id != 0:
            Rt = self._oMbase.rotation.T
            J = np.vstack([Rt @ J[:3], Rt @ J[3:]])
        return J

    @staticmethod
    def task_rows(rows) -> list[int]:
        """Jacobian row indices of a row selection: "translation", "rotation", "full", "planar" or a list."""
        if isinstance(rows, str):
            if rows not in _MANIPULABILITY_ROWS:
                raise ConfigurationError(f"manipulability rows {rows!r} unknown; use one of "
                                         f"{list(_MANIPULABILITY_ROWS)} or a list of row indices 0-5 (vx, vy, vz, wx, "
                                         "wy, wz)")
            return _MANIPULABILITY_ROWS[rows]
        out = [int(r) for r in rows]
        if not out or any(r < 0 or r > 5 for r in out) or len(set(out)) != len(out):
            raise ConfigurationError(f"manipulability rows must be distinct indices 0-5, got {rows!r}")
        return out

    def manipulability(self, q, rows="translation") -> float:
        """:func:`yoshikawa` of the rows :meth:`task_rows` picks of the tip's world Jacobian."""
        return float(yoshikawa(self.jacobian(q, "world")[self.task_rows(rows)]))

    # ------------------------------------------------------------------ kinematics, whole populations
    def _view(self, frame: str | None) -> ChainView:
        return self._tip_view if frame is None else self._frame_view(self.frame_id(frame))[3]

    def fk_batch(self, Q, validate: bool = True, frames=None):
        """Positions (N, 3) m and rotations (N, 3, 3) of the tip (or one frame) for ``Q`` (N, n); for a list of G
        frames (N, G, 3) and (N, G, 3, 3)."""
        if validate:
            Q = self.check_population(Q)
        X = self._physical(Q)
        if frames is None or isinstance(frames, str):
            R, p, _, _ = chain_forward(self._view(frames), X, want_joints=False)
            return p, R
        out = [chain_forward(self._view(f), X, want_joints=False) for f in frames]
        N = Q.shape[0]
        P = np.stack([o[1] for o in out], axis=1) if out else np.zeros((N, 0, 3))
        R = np.stack([o[0] for o in out], axis=1) if out else np.zeros((N, 0, 3, 3))
        return P, R

    def positions_batch(self, Q, frame: str | None = None) -> np.ndarray:
        """Positions (N, 3) m of the tip (or ``frame``) for ``Q`` (N, n), unchecked; cheaper than :meth:`fk_batch`."""
        return chain_positions(self._view(frame), self._physical(Q))

    def jacobian_batch(self, Q, validate: bool = True, frame: str | None = None) -> np.ndarray:
        """World-frame Jacobians (N, 6, n) of the tip (or ``frame``)."""
        return self.fk_jacobian_batch(Q, validate, frame)[2]

    def fk_jacobian_batch(self, Q, validate: bool = True, frame: str | None = None):
        """Positions (N, 3), rotations (N, 3, 3) and world Jacobians (N, 6, n) of the tip (or ``frame``), one pass."""
        if validate:
            Q = self.check_population(Q)
        p, R, J = chain_jacobians(self._view(frame), self._physical(Q), self.tree.m)
        return p, R, (J @ self._G if self._coupled else J)

    def manipulability_batch(self, Q, rows="translation") -> np.ndarray:
        """:meth:`manipulability` of every row of ``Q`` (N, n), shape (N,)."""
        return yoshikawa(self.jacobian_batch(Q)[:, self.task_rows(rows)])

    @cached_property
    def mass_constants(self):
        """:class:`~evoik_pin.robot.tree.MassConstants` for compiled kernels. Read-only."""
        return mass_constants(self)

    def __repr__(self) -> str:
        tips = f"tip={self.tip!r}" if len(self.tips) == 1 else f"tips={list(self.tips)}"
        floating = ", floating_base=True" if self.floating_base else ""
        return f"Robot({self.name!r}, n={self.n}, base={self.base!r}, {tips}{floating})"
