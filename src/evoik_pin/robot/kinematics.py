"""The robot's kinematics: :class:`Robot`, one serial chain of a URDF as Pinocchio sees it.

This module is the only code in evoik_pin that runs Pinocchio's kinematics on a ``Model``/``Data``. A
:class:`Robot` picks the chain from a base frame to a tip frame, locks every other joint
(``pin.buildReducedModel``) and offers forward kinematics, Jacobians and manipulability, one configuration
at a time (through Pinocchio) or a whole population at once (a NumPy recursion built from the same
Pinocchio model, checked against it in the tests), the folded chain constants compiled kernels evaluate,
and the placements the viewer draws. Loading a URDF is :mod:`.loading`'s job.

The joint vector ``q`` users and solvers see has one entry per independent degree of freedom (rad for
revolute joints, m for prismatic ones). Pinocchio stores a continuous (unbounded revolute) joint as two numbers
(cos, sin); :meth:`Robot.to_pinocchio` and :meth:`Robot.from_pinocchio` map between the two.

Mimic joints (URDF ``<mimic joint="k" multiplier="m" offset="c"/>``: ``q_j = m q_k + c``) are not entries of
``q``: the reduced Pinocchio model holds the chain's *physical* joints (mimic joints included), and every
physical joint's value is ``scale * q[index] + offset`` (1, its own entry, 0 for the others; see
:meth:`Robot.chain_coupling`). The joint a chain mimic follows is an entry of ``q`` even when it lies off the
base->tip chain (a gripper finger driven by the other finger), and Jacobians get the chain rule: column k
gathers ``m`` times the column of each physical joint that follows q_k.

Poses are those of the tip frame expressed in the base frame (the world frame when no base is chosen).
"""

from __future__ import annotations

import re
from functools import cached_property
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import BoundsError, ConfigurationError, FrameError, RobotLoadError
from ..lie import rotation_to_z
from .frames import body_frame_names, deepest_body, find_frame, reduced_model, root_link

__all__ = ["DEFAULT_PRISMATIC_RANGE", "MAX_CHAIN_JOINTS", "Robot"]

#: Search interval (m) used for prismatic joints whose URDF gives no finite limits.
DEFAULT_PRISMATIC_RANGE = 1.0
#: A ``package://pkg/rel`` URI (its package name and relative path) in URDF text.
_MESH_URI = re.compile(r"package://([^/\"'<>\s]+)/([^\"'<>]+)")
#: Limits at or beyond this magnitude are treated as "no limit" (URDF readers use 1e308-style sentinels).
_UNBOUNDED = 1e10
#: Longest chain (physical joints) a Robot accepts: Pinocchio's ``Data`` of an n-joint chain takes O(n^3) memory
#: (about 0.45 GB at 200 joints, 3.5 GB at 400), so a runaway URDF would exhaust the machine.
MAX_CHAIN_JOINTS = 200

_MANIPULABILITY_ROWS = {"translation": [0, 1, 2], "rotation": [3, 4, 5], "full": [0, 1, 2, 3, 4, 5],
                        "planar": [0, 1, 5]}


class Robot:
    """A serial chain of a URDF: forward kinematics, Jacobians and manipulability of its tip frame.

    Attributes:
        name: robot name (bundled or example name, or the URDF file's stem).
        n: number of independent degrees of freedom of the chain (mimic joints are folded in).
        joint_names: the joints of ``q``, base to tip (length n); a joint that chain mimic joints follow is
            listed where the first of them sits when it is not on the chain itself.
        lower, upper: search bounds (n,) in rad or m; finite; see :meth:`set_bounds`. A joint that mimic joints
            follow is also bounded so that every such joint stays inside its own URDF limits.
        tip, base: frame names; ``base`` is the URDF root when none was chosen.
        model: the reduced Pinocchio model holding the chain's physical joints (``model.nv == n`` unless mimic
            joints are on the chain); map ``q`` to its configuration with :meth:`to_pinocchio`.
        full_model: the Pinocchio model of the whole URDF (every joint independent).
        urdf_path: the URDF file (None when loaded from an XML string); ``urdf_xml`` holds its text (the expanded
            URDF for a xacro file).
        revolute: (n,) bool, True for revolute joints (rad), False for prismatic ones (m).
        continuous: (n,) bool, True for joints Pinocchio stores as (cos, sin).
        joint_axes: (n, 3) unit axis of each joint in its own frame: the rotation axis of a revolute joint,
            the sliding direction of a prismatic one.
        mimic_joints: ``{physical chain joint: (joint it follows, multiplier, offset)}`` for the chain's mimic
            joints: ``q_joint = multiplier * q_followed + offset``.
    """

    def __init__(
        self,
        full_model: pin.Model,
        tip: str | None = None,
        base: str | None = None,
        joints: list[str] | None = None,
        name: str = "robot",
        urdf_path: Path | None = None,
        urdf_xml: str | None = None,
        package_dirs: list[str] | None = None,
        mimic: dict | None = None,
        packages: dict[str, str] | None = None,
        missing_packages: dict[str, str] | None = None,
    ) -> None:
        """``mimic``: ``{joint: (followed joint, multiplier, offset)}`` (objects with ``joint``, ``multiplier``,
        ``offset`` attributes also do), the URDF's mimic couplings resolved to joints no mimic drives
        (:func:`~evoik_pin.robot.urdf_checks.check_urdf` returns them); entries naming no 1-DOF joint of
        ``full_model`` are ignored. ``packages``: ``{pkg: folder}`` that ``package://pkg/...`` mesh URIs resolve
        to (before ``package_dirs``); ``missing_packages``: ``{pkg: error message}`` of those nothing found."""
        self.full_model = full_model
        self.name = name
        self.urdf_path = urdf_path
        self.urdf_xml = urdf_xml
        self.package_dirs = list(package_dirs or [])
        self.packages = dict(packages or {})
        self.missing_packages = dict(missing_packages or {})
        self.srdf: str | None = None  # an SRDF file (disabled collision pairs); load_robot sets it
        frames = body_frame_names(full_model)
        couplings = _couplings(full_model, mimic)
        self._full_couplings = couplings

        if tip is None:
            tip = deepest_body(full_model)
        tip_id = find_frame(full_model, tip)
        if tip_id < 0:
            raise FrameError(f"unknown tip frame {tip!r}; frames of {name}: {', '.join(frames)}")
        root_name = root_link(full_model) if base is None else base
        base_id = 0 if base is None else find_frame(full_model, base)
        if base_id < 0:
            raise FrameError(f"unknown base frame {base!r}; frames of {name}: {', '.join(frames)}")

        support = list(full_model.supports[full_model.frames[tip_id].parentJoint])
        base_joint = full_model.frames[base_id].parentJoint
        if base_joint not in support:
            raise FrameError(
                f"tip frame {tip!r} is not downstream of base frame {root_name!r}: no kinematic chain joins "
                "them from base to tip"
            )
        chain = support[support.index(base_joint) + 1:]
        bad = [full_model.names[j] for j in chain if full_model.joints[j].nv != 1]
        if bad:
            raise RobotLoadError(
                f"joints {bad} of the chain are not 1-DOF revolute or prismatic joints; only those are "
                "supported (lock them with joints=[...])"
            )
        above_base = set(full_model.supports[base_joint])

        def follows(j: int) -> tuple[int | None, float, float]:
            """(joint whose q moves chain joint j, multiplier, offset); None when j is constant (it follows a
            joint above the base, which stays locked, or has multiplier 0)."""
            c = couplings.get(j)
            if c is None:
                return j, 1.0, 0.0
            driver, m, off = c
            return (None if driver in above_base or m == 0.0 else driver), m, off

        dofs: list[int] = []
        for j in chain:
            d = follows(j)[0]
            if d is not None and d not in dofs:
                dofs.append(d)
        dof_names = [full_model.names[d] for d in dofs]
        if joints is not None:
            unknown = [j for j in joints if j not in dof_names]
            if unknown:
                coupled = [f"{u!r} mimics {full_model.names[couplings[full_model.getJointId(u)][0]]!r}"
                           for u in unknown if full_model.existJointName(u) and full_model.getJointId(u) in couplings]
                hint = f" ({'; '.join(coupled)}: name the joint it follows)" if coupled else ""
                raise FrameError(
                    f"joints {unknown} are not on the chain {root_name!r} -> {tip!r}; its joints are "
                    f"{', '.join(dof_names) or '(none)'}{hint}"
                )
            dofs = [d for d in dofs if full_model.names[d] in joints]
        physical = [j for j in chain if follows(j)[0] in dofs]
        if not physical:
            raise RobotLoadError(
                f"the chain {root_name!r} -> {tip!r} of {name} has no movable joint; pick another tip or base"
            )
        if len(physical) > MAX_CHAIN_JOINTS:
            raise RobotLoadError(
                f"the chain {root_name!r} -> {tip!r} of {name} has {len(physical)} joints; at most "
                f"{MAX_CHAIN_JOINTS} are supported (Pinocchio's data for an n-joint chain takes O(n^3) memory): pick "
                "a nearer tip, a farther base, or keep fewer joints free with joints=[...]"
            )

        q_ref = pin.neutral(full_model)
        for j in range(1, full_model.njoints):
            jm = full_model.joints[j]
            if jm.nq == 1:  # keep locked joints inside their limits
                lo, hi = full_model.lowerPositionLimit[jm.idx_q], full_model.upperPositionLimit[jm.idx_q]
                if lo <= hi:
                    q_ref[jm.idx_q] = np.clip(q_ref[jm.idx_q], lo, hi)
        for j, (d, m, off) in couplings.items():  # locked mimic joints sit where their driver's rest puts them
            _set_joint_value(full_model, q_ref, j, m * _joint_value(full_model, q_ref, d) + off)
        to_lock = [j for j in range(1, full_model.njoints) if j not in physical]
        self._q_ref_full = q_ref
        self._locked = to_lock
        self.model = reduced_model(full_model, to_lock, q_ref) if to_lock else pin.Model(full_model)
        self.data = self.model.createData()
        self._pin_q_key, self._pin_q_value = None, None  # memo of _pin_q
        self.tip = tip
        self.base = root_name
        self._tip_id = find_frame(self.model, tip)
        self._base_id = 0 if base is None else find_frame(self.model, base)
        self.n = len(dofs)
        self.joint_names = [full_model.names[d] for d in dofs]
        self._dof_ids = dofs  # full-model joint ids of the entries of q

        # Base placement is constant: every free joint is downstream of the base frame.
        q0 = pin.neutral(self.model)
        pin.framesForwardKinematics(self.model, self.data, q0)
        self._oMbase = self.data.oMf[self._base_id].copy() if base is not None else pin.SE3.Identity()
        self._baseMo = self._oMbase.inverse()
        self._identity = pin.SE3.Identity()

        # The physical chain: the reduced model's joints 1..m, base to tip, and how each follows q.
        m_phys = self.model.njoints - 1
        self._chain_idx_q = np.array([self.model.joints[k].idx_q for k in range(1, m_phys + 1)], dtype=np.intp)
        self._chain_continuous = np.array([self.model.joints[k].nq == 2 for k in range(1, m_phys + 1)])
        self._chain_revolute, self._chain_axes = _joint_motions(self.model, range(1, m_phys + 1))
        index, scale, offset = [], [], []
        self.mimic_joints: dict[str, tuple[str, float, float]] = {}
        for j in physical:
            d, m, off = follows(j)
            index.append(dofs.index(d))
            scale.append(m)
            offset.append(off)
            if d != j:
                self.mimic_joints[full_model.names[j]] = (full_model.names[d], m, off)
        self._chain_index = np.ascontiguousarray(index, dtype=np.int64)
        self._chain_scale = np.ascontiguousarray(scale, dtype=float)
        self._chain_offset = np.ascontiguousarray(offset, dtype=float)
        self._coupled = bool(self.mimic_joints)
        self._G = np.zeros((m_phys, self.n))  # d(physical values)/dq
        self._G[np.arange(m_phys), self._chain_index] = self._chain_scale

        # The entries of q: their own joint's motion (on the chain, or the off-chain joint mimics follow).
        revolute, axes = _joint_motions(full_model, dofs)
        self.revolute = revolute
        self.joint_axes = axes
        self.continuous = np.array([full_model.joints[d].nq == 2 for d in dofs])
        self._set_default_bounds(couplings)
        self._build_batch_chain()

    # ------------------------------------------------------------------ construction helpers
    def _set_default_bounds(self, couplings: dict[int, tuple[int, float, float]]) -> None:
        """URDF limits of each entry of q ([-pi, pi] or +-DEFAULT_PRISMATIC_RANGE when it has none), narrowed
        so that every mimic joint following it stays inside its own limits."""
        fm = self.full_model
        lower = np.empty(self.n)
        upper = np.empty(self.n)
        for k, d in enumerate(self._dof_ids):
            lo, hi, limited = _joint_limits(fm, d)
            if not limited:
                half = np.pi if self.revolute[k] else DEFAULT_PRISMATIC_RANGE
                lo, hi = -half, half
            for j, (driver, m, off) in couplings.items():
                jlo, jhi, jlimited = _joint_limits(fm, j)
                if driver != d or not jlimited or m == 0.0:
                    continue
                a, b = sorted(((jlo - off) / m, (jhi - off) / m))
                if max(lo, a) > min(hi, b):
                    raise RobotLoadError(
                        f"joint {fm.names[j]!r} of {self.name} mimics {fm.names[d]!r} ({fm.names[j]} = {m:g} "
                        f"{fm.names[d]} + {off:g}) but no value of {fm.names[d]!r} in [{lo:g}, {hi:g}] keeps it in "
                        f"its limits [{jlo:g}, {jhi:g}]"
                    )
                lo, hi = max(lo, a), min(hi, b)
            lower[k], upper[k] = lo, hi
        self.lower, self.upper = lower, upper

    def _build_batch_chain(self) -> None:
        """Precompute the fixed transforms F_0..F_m of ``T(q) = F_0 Z(x_1) F_1 ... Z(x_m) F_m`` over the m
        physical chain joints (x_k = scale_k q[index_k] + offset_k).

        Z(x) is a rotation about (or translation along) the local z axis: every joint axis a_k is turned
        into z by a constant rotation B_k folded into the neighbouring fixed transforms, so the batched
        recursion needs only cheap column updates per joint.
        """
        m_phys = self._chain_index.size
        B = [rotation_to_z(a) for a in self._chain_axes]
        Rs, ps = [], []
        prev_B = np.eye(3)
        for k in range(m_phys):
            M = self.model.jointPlacements[k + 1]
            if k == 0:
                M = self._baseMo * M
            Rs.append(prev_B.T @ M.rotation @ B[k])
            ps.append(prev_B.T @ M.translation)
            prev_B = B[k]
        tip_frame = self.model.frames[self._tip_id]
        if tip_frame.parentJoint != m_phys:  # pragma: no cover - guaranteed by the reduction
            raise RobotLoadError(f"tip frame {self.tip!r} is not attached to the last chain joint")
        Rs.append(prev_B.T @ tip_frame.placement.rotation)
        ps.append(prev_B.T @ tip_frame.placement.translation)
        self._F_R = np.ascontiguousarray(Rs, dtype=float)  # (m+1, 3, 3)
        self._F_p = np.ascontiguousarray(ps, dtype=float)  # (m+1, 3)
        # positions_batch: the homogeneous map of joint k is H_k(x) = a(x) A_k + b(x) B_k + C_k (4 x 4) with
        # a = cos x, b = sin x (revolute) or a = x, b = 0 (prismatic). With Y = [a p; b p; p] (12, N) for the
        # homogeneous points p (4, N), H_k p = [A_k B_k C_k] Y; stacking that (4, 12) block three times
        # makes one BLAS product return p' already copied into all three slots of the next Y.
        S = np.zeros((m_phys, 4, 12))
        for k in range(m_phys):
            R, t = self._F_R[k], self._F_p[k]
            if self._chain_revolute[k]:
                S[k, 0:3, 0], S[k, 0:3, 1] = R[:, 0], R[:, 1]
                S[k, 0:3, 4], S[k, 0:3, 5] = R[:, 1], -R[:, 0]
                S[k, 0:3, 10] = R[:, 2]
            else:
                S[k, 0:3, 3] = R[:, 2]
                S[k, 0:3, 8:11] = R
            S[k, 0:3, 11], S[k, 3, 11] = t, 1.0
        self._S3 = [np.ascontiguousarray(np.vstack([S[k]] * 3)) for k in range(m_phys)]  # (12, 12) each
        self._p_tip = np.tile(np.append(self._F_p[-1], 1.0), 3)[:, None]  # (12, 1)
        self._all_revolute = bool(self._chain_revolute.all())

    def _physical(self, Q: np.ndarray) -> np.ndarray:
        """Physical joint values (..., m) of joint vectors Q (..., n): ``scale * Q[..., index] + offset``."""
        if not self._coupled:
            return Q
        return Q[..., self._chain_index] * self._chain_scale + self._chain_offset

    def chain_constants(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The folded chain ``T = F_0 Z(x_1) F_1 ... Z(x_m) F_m`` (tip pose in the base frame) over the m
        physical chain joints, for compiled kernels that evaluate it without Pinocchio: rotations F_R
        (m+1, 3, 3), translations F_p (m+1, 3) (m) and the (m,) bool mask of revolute joints. Z(x) is a rotation
        by x about z (revolute) or a translation by x along z (prismatic); the joint values x come from q by
        :meth:`chain_coupling` (m == n and x == q unless mimic joints are on the chain). C-contiguous float64 /
        bool arrays, owned by the robot: do not modify them.
        """
        return self._F_R, self._F_p, self._chain_revolute

    def chain_coupling(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """How the physical chain joints of :meth:`chain_constants` follow q (n,): ``x_k = scale[k] *
        q[index[k]] + offset[k]``. Returns index (m,) int64, scale (m,) and offset (m,) float64 (identity,
        ones and zeros without mimic joints on the chain). The Jacobian with respect to q adds ``scale[k]``
        times physical column k into column ``index[k]``. Owned by the robot: do not modify them.
        """
        return self._chain_index, self._chain_scale, self._chain_offset

    def chain_joints(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The m physical joints of the chain (``model``'s joints: q's joints and the mimic joints on the chain):
        revolute mask (m,), unit axes (m, 3) in each joint's frame, and the lower and upper values (m,) (rad or
        m) they take when q spans its bounds. Equal to (revolute, joint_axes, lower, upper) without mimic joints."""
        a = self._chain_scale * self.lower[self._chain_index] + self._chain_offset
        b = self._chain_scale * self.upper[self._chain_index] + self._chain_offset
        return self._chain_revolute, self._chain_axes, np.minimum(a, b), np.maximum(a, b)

    # ------------------------------------------------------------------ bounds and validation
    def set_bounds(self, lower, upper) -> None:
        """Replace the search bounds (rad or m), each of length ``n``; finite, lower <= upper."""
        lower = np.asarray(lower, dtype=float).reshape(-1)
        upper = np.asarray(upper, dtype=float).reshape(-1)
        if lower.shape != (self.n,) or upper.shape != (self.n,):
            raise BoundsError(
                f"bounds of {self.name} need {self.n} values each (one per joint), got {lower.size} and "
                f"{upper.size}"
            )
        if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper))):
            raise BoundsError("bounds must be finite numbers (rad or m); got NaN or inf")
        bad = np.nonzero(lower > upper)[0]
        if bad.size:
            k = int(bad[0])
            raise BoundsError(
                f"inverted bounds for joint {self.joint_names[k]!r}: lower {lower[k]:.6g} > upper {upper[k]:.6g}"
            )
        self.lower, self.upper = lower, upper

    def check_q(self, q) -> np.ndarray:
        """``q`` as a float array of shape (n,), or a ConfigurationError naming the problem."""
        arr = np.asarray(q, dtype=float)
        if arr.ndim != 1 or arr.shape[0] != self.n:
            raise ConfigurationError(
                f"{self.name} has {self.n} joints ({', '.join(self.joint_names)}); got a joint vector of "
                f"shape {arr.shape}, expected ({self.n},)"
            )
        if not np.all(np.isfinite(arr)):
            raise ConfigurationError(f"joint vector contains NaN or inf: {arr}")
        return arr

    def check_population(self, Q) -> np.ndarray:
        """``Q`` as a float array of shape (N, n), or a ConfigurationError naming the problem."""
        arr = np.asarray(Q, dtype=float)
        if arr.ndim == 1 and arr.shape[0] == self.n:
            arr = arr[None, :]
        if arr.ndim != 2 or arr.shape[1] != self.n:
            raise ConfigurationError(
                f"{self.name} needs configurations of shape (N, {self.n}); got shape {arr.shape}"
            )
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
        """``count`` configurations drawn uniformly inside the search bounds, shape (count, n)."""
        return rng.uniform(self.lower, self.upper, size=(count, self.n))

    # ------------------------------------------------------------------ Pinocchio mapping
    def to_pinocchio(self, q) -> np.ndarray:
        """Configuration (model.nq,) of :attr:`model` at joint vector ``q`` (n,): mimic joints at their coupled
        values, continuous joints as (cos, sin)."""
        x = self._physical(np.asarray(q, dtype=float))
        if not self._has_continuous:
            return np.array(x)  # a copy: the caller owns it
        return np.concatenate((x, np.cos(x), np.sin(x)))[self._pin_gather]

    def from_pinocchio(self, q_pin) -> np.ndarray:
        """Joint vector (n,) of a configuration (model.nq,) of :attr:`model`; continuous joints via
        atan2(sin, cos), an entry that only mimic joints show through the first of them (``(x - offset) /
        scale``)."""
        q_pin = np.asarray(q_pin, dtype=float)
        out = np.full(self.n, np.nan)
        for k, i in enumerate(self._chain_idx_q):
            d, m = self._chain_index[k], self._chain_scale[k]
            if np.isnan(out[d]) and m != 0.0:
                x = np.arctan2(q_pin[i + 1], q_pin[i]) if self._chain_continuous[k] else q_pin[i]
                out[d] = (x - self._chain_offset[k]) / m
        return out

    def full_configuration(self, q) -> np.ndarray:
        """Configuration (full_model.nq,) of the whole URDF: the entries of ``q`` on their joints, every mimic
        joint of them at its coupled value, the other joints at rest (where the model locked them)."""
        q = self.check_q(q)
        out = self._q_ref_full.copy()
        fm = self.full_model
        for k, d in enumerate(self._dof_ids):
            _set_joint_value(fm, out, d, q[k])
        for j, (d, m, off) in self._full_couplings.items():
            if d in self._dof_ids:
                _set_joint_value(fm, out, j, m * q[self._dof_ids.index(d)] + off)
        return out

    # ------------------------------------------------------------------ kinematics, one configuration
    def fk(self, q) -> pin.SE3:
        """Pose of the tip frame in the base frame at joint vector ``q`` (n,), as a ``pin.SE3`` (m)."""
        q = self.check_q(q)
        pin.framesForwardKinematics(self.model, self.data, self.to_pinocchio(q))
        return self._baseMo * self.data.oMf[self._tip_id]

    def jacobian(self, q, frame: str = "world") -> np.ndarray:
        """Frame Jacobian (6, n) of the tip: rows (vx, vy, vz, wx, wy, wz), columns joints.

        ``frame="world"``: linear velocity of the tip origin and angular velocity, both in the base
        frame's axes (the derivative of :meth:`fk`'s translation is ``J[:3]``).
        ``frame="local"``: both expressed in the tip frame.
        """
        q = self.check_q(q)
        if frame not in ("world", "local"):
            raise ConfigurationError(f"jacobian frame must be 'world' or 'local', got {frame!r}")
        ref = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED if frame == "world" else pin.ReferenceFrame.LOCAL
        # reshape: eigenpy returns a (6,) array for a one-joint chain
        J = pin.computeFrameJacobian(self.model, self.data, self.to_pinocchio(q), self._tip_id, ref).reshape(6, -1)
        if self._coupled:
            J = J @ self._G  # chain rule: dx/dq
        if frame == "world" and self._base_id != 0:
            Rt = self._oMbase.rotation.T
            J = np.vstack([Rt @ J[:3], Rt @ J[3:]])
        return np.array(J)

    # ------------------------------------------------------------------ hot path of local solvers
    @cached_property
    def _pin_gather(self) -> np.ndarray:
        """(nq,) indices into ``[x, cos x, sin x]`` (3m,) of the physical values x (m,) that give Pinocchio's
        configuration vector."""
        m_phys = self._chain_idx_q.size
        gather = np.empty(self.model.nq, dtype=np.intp)
        for k, i in enumerate(self._chain_idx_q):
            if self._chain_continuous[k]:
                gather[i], gather[i + 1] = m_phys + k, 2 * m_phys + k
            else:
                gather[i] = k
        return gather

    @cached_property
    def _has_continuous(self) -> bool:
        return bool(self._chain_continuous.any())

    def _pin_q(self, q: np.ndarray) -> np.ndarray:
        """:meth:`to_pinocchio` for the hot path: ``q`` itself when nothing is continuous and no mimic joint is
        on the chain, else the conversion.

        The last conversion is memoized by the bytes of ``q``: local solvers ask for the pose and then the
        Jacobian of one configuration, and the (cos, sin) conversion costs more than the kinematics.
        """
        if not (self._has_continuous or self._coupled):
            return q
        key = q.tobytes()
        if key == self._pin_q_key:
            return self._pin_q_value
        out = self.to_pinocchio(q)
        self._pin_q_key, self._pin_q_value = key, out
        return out

    def fk_unchecked(self, q: np.ndarray) -> pin.SE3:
        """:meth:`fk` without validation, for local solvers' inner loops.

        ``q`` must already be a finite float array of shape (n,). Returns the tip pose in the base frame
        (a ``pin.SE3`` owned by the caller).
        """
        return self.tip_pose_seen_from_unchecked(q, self._identity)

    def tip_pose_seen_from_unchecked(self, q: np.ndarray, M: pin.SE3) -> pin.SE3:
        """``M * fk(q)``: the tip pose expressed in a frame whose inverse placement in the base frame is
        ``M`` (e.g. ``M = T_target^-1`` gives the tip seen from the target), without validation and
        without the copy :meth:`fk_unchecked` makes. ``q`` as in :meth:`fk_unchecked`; a new ``pin.SE3``."""
        pin.framesForwardKinematics(self.model, self.data, self._pin_q(q))
        if self._base_id == 0:
            return M * self.data.oMf[self._tip_id]
        return M * (self._baseMo * self.data.oMf[self._tip_id])

    def jacobian_local_unchecked(self, q: np.ndarray) -> np.ndarray:
        """``jacobian(q, "local")`` without validation: the tip Jacobian (6, n) in the tip frame.

        Rows (vx, vy, vz, wx, wy, wz): ``T(q + dq) ~ T(q) exp(J dq)`` for small dq. ``q`` as in
        :meth:`fk_unchecked`.
        """
        J = pin.computeFrameJacobian(self.model, self.data, self._pin_q(q), self._tip_id, pin.ReferenceFrame.LOCAL)
        J = J.reshape(6, -1)  # eigenpy returns a (6,) array for a one-joint chain
        return J @ self._G if self._coupled else J

    @staticmethod
    def task_rows(rows) -> list[int]:
        """Jacobian row indices of a row selection: "translation", "rotation", "full", "planar" or a list."""
        if isinstance(rows, str):
            if rows not in _MANIPULABILITY_ROWS:
                raise ConfigurationError(
                    f"manipulability rows {rows!r} unknown; use one of {list(_MANIPULABILITY_ROWS)} or a list of "
                    "row indices 0-5 (vx, vy, vz, wx, wy, wz)"
                )
            return _MANIPULABILITY_ROWS[rows]
        out = [int(r) for r in rows]
        if not out or any(r < 0 or r > 5 for r in out) or len(set(out)) != len(out):
            raise ConfigurationError(f"manipulability rows must be distinct indices 0-5, got {rows!r}")
        return out

    def manipulability(self, q, rows="translation") -> float:
        """Yoshikawa manipulability sqrt(det(J J^T)) of the chosen rows of the world-frame Jacobian.

        ``rows``: ``"translation"`` (vx, vy, vz), ``"rotation"``, ``"full"`` (all six), ``"planar"``
        (vx, vy, wz: paper 003's x, y, yaw) or an explicit list of row indices.
        """
        J = self.jacobian(q, "world")[self.task_rows(rows)]
        return float(np.sqrt(max(np.linalg.det(J @ J.T), 0.0)))

    # ------------------------------------------------------------------ kinematics, whole populations
    def fk_batch(self, Q, validate: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Tip poses of a population ``Q`` (N, n): positions (N, 3) in m and rotations (N, 3, 3).

        ``validate=False`` skips the shape/finiteness check, for solvers' inner loops on populations
        they built themselves.
        """
        if validate:
            Q = self.check_population(Q)
        R, p, _, _ = self._forward(Q, want_joints=False)
        return p, R

    def positions_batch(self, Q) -> np.ndarray:
        """Tip positions (N, 3) in m of a population ``Q`` (N, n); cheaper than :meth:`fk_batch`.

        Walks the chain from the tip back to the base carrying homogeneous points in a (12, N) buffer
        ``Y = [a p; b p; p]``: per joint one in-place product with the joint's (cos, sin) rows and one BLAS
        product with a constant (12, 12) matrix (see ``_build_batch_chain``), so a joint costs two NumPy
        calls whatever N is. Not validated: solvers call it in their inner loop with populations they
        built themselves.
        """
        N = Q.shape[0]
        XT = self._physical(Q).T
        m_phys = XT.shape[0]
        AB = np.empty((m_phys, 8, N))  # rows 0-3: a = cos x (or x), rows 4-7: b = sin x (or 0)
        AB[:, 0:4] = np.cos(XT)[:, None, :]
        AB[:, 4:8] = np.sin(XT)[:, None, :]
        if not self._all_revolute:
            prismatic = ~self._chain_revolute
            AB[prismatic, 0:4] = XT[prismatic][:, None, :]
        Y = np.empty((12, N))
        Z = np.empty((12, N))
        Y[:] = self._p_tip
        S3 = self._S3
        for k in range(m_phys - 1, -1, -1):
            Y[0:8] *= AB[k]
            np.matmul(S3[k], Y, out=Z)
            Y, Z = Z, Y
        return Y[8:11].T.copy()

    def jacobian_batch(self, Q, validate: bool = True) -> np.ndarray:
        """World-frame Jacobians (N, 6, n) of a population, equal to :meth:`jacobian` row by row."""
        return self.fk_jacobian_batch(Q, validate)[2]

    def fk_jacobian_batch(self, Q, validate: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Tip positions (N, 3), rotations (N, 3, 3) and world-frame Jacobians (N, 6, n) from one pass.

        What :meth:`fk_batch` and :meth:`jacobian_batch` return, for batched Newton-type solvers that need
        both at every iteration.
        """
        if validate:
            Q = self.check_population(Q)
        R_tip, p_tip, z_axes, origins = self._forward(Q, want_joints=True)
        J = np.zeros((Q.shape[0], 6, self._chain_index.size))
        rev = self._chain_revolute
        lever = p_tip[:, None, :] - origins  # (N, m, 3)
        J[:, :3, rev] = np.cross(z_axes[:, rev], lever[:, rev]).transpose(0, 2, 1)
        J[:, 3:, rev] = z_axes[:, rev].transpose(0, 2, 1)
        J[:, :3, ~rev] = z_axes[:, ~rev].transpose(0, 2, 1)
        return p_tip, R_tip, (J @ self._G if self._coupled else J)

    def manipulability_batch(self, Q, rows="translation") -> np.ndarray:
        """:meth:`manipulability` of every row of ``Q`` (N, n), shape (N,)."""
        J = self.jacobian_batch(Q)[:, self.task_rows(rows)]
        det = np.linalg.det(J @ J.transpose(0, 2, 1))
        return np.sqrt(np.maximum(det, 0.0))

    def _forward(self, Q: np.ndarray, want_joints: bool):
        """Base-to-tip recursion over a population Q (N, n); optionally the physical joints' axes and origins
        (N, m, 3)."""
        N = Q.shape[0]
        X = self._physical(Q)
        m_phys = X.shape[1]
        FR, Fp = self._F_R, self._F_p
        R = np.broadcast_to(FR[0], (N, 3, 3)).copy()
        p = np.broadcast_to(Fp[0], (N, 3)).copy()
        cos, sin = np.cos(X), np.sin(X)
        z_axes = np.empty((N, m_phys, 3)) if want_joints else None
        origins = np.empty((N, m_phys, 3)) if want_joints else None
        for k in range(m_phys):
            if want_joints:
                z_axes[:, k] = R[:, :, 2]
                origins[:, k] = p
            if self._chain_revolute[k]:
                c, s = cos[:, k, None], sin[:, k, None]
                c0, c1 = R[:, :, 0].copy(), R[:, :, 1]
                R[:, :, 0] = c * c0 + s * c1
                R[:, :, 1] = c * c1 - s * c0
            else:
                p = p + X[:, k, None] * R[:, :, 2]
            p = p + (R.reshape(N * 3, 3) @ Fp[k + 1]).reshape(N, 3)
            R = (R.reshape(N * 3, 3) @ FR[k + 1]).reshape(N, 3, 3)
        return R, p, z_axes, origins

    # ------------------------------------------------------------------ geometry for display
    @property
    def base_placement(self) -> pin.SE3:
        """Placement (m) of the base frame in the world frame of :attr:`model` (the URDF's root), a new
        ``pin.SE3``; the identity when no base was chosen. Constant: every free joint lies downstream of the
        base, so it is taken at the neutral configuration."""
        return self._oMbase.copy()

    def geometry_placements(self, geometry_model: pin.GeometryModel, q) -> list[pin.SE3]:
        """Placements (m) of every object of ``geometry_model`` at joint vector ``q`` (n,) in rad/m.

        ``geometry_model`` must be attached to :attr:`model`'s joints (e.g. :attr:`visual_model`, or a
        skeleton built on :attr:`model`). Returns one new ``pin.SE3`` per geometry object, in its order,
        expressed in :attr:`model`'s world frame (compose with ``base_placement.inverse()`` for the base
        frame).
        """
        q = self.check_q(q)
        gdata = pin.GeometryData(geometry_model)
        pin.forwardKinematics(self.model, self.data, self.to_pinocchio(q))
        pin.updateGeometryPlacements(self.model, self.data, geometry_model, gdata)
        return [M.copy() for M in gdata.oMg]

    @cached_property
    def visual_model(self) -> pin.GeometryModel:
        """Visual geometry of the chain (meshes resolved through ``package_dirs``), for viz.py."""
        return self._geometry_model(pin.GeometryType.VISUAL)

    @cached_property
    def collision_model(self) -> pin.GeometryModel:
        """Collision geometry of the chain (the URDF's ``<collision>`` elements), attached to :attr:`model`'s
        joints (locked parts fixed where they rest), for :class:`~evoik_pin.scene.Scene`."""
        return self._geometry_model(pin.GeometryType.COLLISION)

    def _geometry_model(self, kind) -> pin.GeometryModel:
        """The URDF's geometry of one kind, reduced onto the chain's model like the model itself."""
        if self.urdf_xml is None:  # pragma: no cover
            raise RobotLoadError("this robot has no URDF text to read geometry from")
        xml = _MESH_URI.sub(self._mesh_file, self.urdf_xml) if self.packages else self.urdf_xml
        try:
            geom = pin.buildGeomFromUrdfString(self.full_model, xml, kind, package_dirs=self.package_dirs)
        except (ValueError, RuntimeError) as exc:  # a mesh Pinocchio could not find or read
            said = str(exc).strip()
            why = [m for pkg, m in self.missing_packages.items() if f"package://{pkg}/" in said]
            raise RobotLoadError(f"{self.name}: {why[0] if why else said}") from None
        if self._locked:
            _, geoms = reduced_model(self.full_model, self._locked, self._q_ref_full, (geom,))
            geom = geoms[0]
        return geom

    def _mesh_file(self, m: re.Match) -> str:
        """The absolute file of one ``package://pkg/rel`` URI whose package was found and holds ``rel``; the URI
        unchanged otherwise (Pinocchio then tries ``package_dirs``)."""
        folder = self.packages.get(m.group(1))
        if folder is not None and (Path(folder) / m.group(2)).is_file():
            return (Path(folder) / m.group(2)).as_posix()
        return m.group(0)

    def __repr__(self) -> str:
        return f"Robot({self.name!r}, n={self.n}, base={self.base!r}, tip={self.tip!r})"


# ---------------------------------------------------------------------- joint helpers (full or reduced model)
def _couplings(model: pin.Model, mimic: dict | None) -> dict[int, tuple[int, float, float]]:
    """``{mimic joint id: (followed joint id, multiplier, offset)}`` of ``mimic`` entries whose two joints are
    1-DOF joints of ``model``."""
    out: dict[int, tuple[int, float, float]] = {}
    for name, spec in (mimic or {}).items():
        driver, m, off = (spec.joint, spec.multiplier, spec.offset) if hasattr(spec, "joint") else spec
        if not (model.existJointName(name) and model.existJointName(driver)):
            continue
        j, d = model.getJointId(name), model.getJointId(driver)
        if j != d and model.joints[j].nv == 1 and model.joints[d].nv == 1:
            out[j] = (d, float(m), float(off))
    return out


def _joint_value(model: pin.Model, q: np.ndarray, j: int) -> float:
    """Value (rad or m) of 1-DOF joint j in configuration q (model.nq,)."""
    jm = model.joints[j]
    return float(np.arctan2(q[jm.idx_q + 1], q[jm.idx_q])) if jm.nq == 2 else float(q[jm.idx_q])


def _set_joint_value(model: pin.Model, q: np.ndarray, j: int, value: float) -> None:
    """Write value (rad or m) of 1-DOF joint j into configuration q (model.nq,), as (cos, sin) if continuous."""
    jm = model.joints[j]
    if jm.nq == 2:
        q[jm.idx_q], q[jm.idx_q + 1] = np.cos(value), np.sin(value)
    else:
        q[jm.idx_q] = value


def _joint_motions(model: pin.Model, joint_ids) -> tuple[np.ndarray, np.ndarray]:
    """(revolute (k,) bool, unit axes (k, 3) in each joint's own frame) of 1-DOF joints, from their motion
    subspace at the neutral configuration (joint by joint: no model-wide ``Data``, which is large)."""
    ids = list(joint_ids)
    q = pin.neutral(model)
    revolute = np.zeros(len(ids), dtype=bool)
    axes = np.zeros((len(ids), 3))
    for k, j in enumerate(ids):
        jm = model.joints[j]
        jd = jm.createData()
        jm.calc(jd, q)
        S = np.asarray(jd.S).reshape(6)
        lin, ang = S[:3], S[3:]
        revolute[k] = np.linalg.norm(ang) > 0.5
        axes[k] = ang if revolute[k] else lin
    return revolute, axes


def _joint_limits(model: pin.Model, j: int) -> tuple[float, float, bool]:
    """(lower, upper, limited) of 1-DOF joint j: limited is False for continuous joints and for limits that
    are absent (lower == upper, as urdfdom reads a <limit> without them), inverted or beyond 1e10."""
    jm = model.joints[j]
    if jm.nq != 1:
        return -np.pi, np.pi, False
    lo = float(model.lowerPositionLimit[jm.idx_q])
    hi = float(model.upperPositionLimit[jm.idx_q])
    limited = abs(lo) < _UNBOUNDED and abs(hi) < _UNBOUNDED and lo < hi
    return lo, hi, limited
