"""Retargeting: a human motion (:class:`~evoik_pin.motion.Motion`) onto a floating-base humanoid, one warm-started
goal-list solve per frame through the public :func:`evoik_pin.solve`.

The method (:func:`retarget`):

1. **Scale** (``scale="auto"``): the robot's leg length (hip -> knee -> ankle frames at the neutral pose, q = 0)
   over the source's (the same keypoints, median over frames, both legs averaged). The source is scaled about the
   ground point under its first frame's root (x, y of the pelvis keypoint, z of the floor), so the clip stays in
   the source's world: the robot faces where the source faces and moves where it moves (scaled), no global turn.
   Two corrections for the robot's body: the whole source moves up or down so that a standing ankle keypoint sits
   at the robot's sole height (:meth:`_Plan._vertical_shift`), and knees and ankles closer together than the
   robot's leg links can be are moved apart along the hips' line (:meth:`_Plan._widen_stance`: people walk with
   their feet almost on one line and cross them dancing). Limb angles in the report are measured against the
   source before that widening.
2. **Goals per frame** (targets from the scaled source):

   * the root frame (mapped to the pelvis keypoint): a :class:`~evoik_pin.goals.Position` at the scaled source hip
     centre less the robot's own hip-centre offset (turned by the source pelvis's axes), and a
     :class:`~evoik_pin.goals.Direction` laying the robot's left axis (its hips' left-right line at neutral) along
     the source's (heading and roll from the source hips);
   * limb **directions**: a :class:`~evoik_pin.goals.RelativePosition` per limb (parent mapped frame -> child mapped
     frame, :data:`~evoik_pin.motion.mapping.LIMBS`), target the source limb's unit vector times the robot's own
     limb length at neutral, in the world's axes, weighted by 1 / length^2 so that each limb's residual reads as an
     angle (the trunk's limbs ten times an arm's or a leg's: :data:`WEIGHTS`): limbs follow the source's directions
     whatever the proportions. A child frame no joint moves relative to
     its parent (G1's head on its torso) gets a Direction on the parent's axis towards it instead;
   * feet (the frames mapped to the ankle keypoints): while the source foot is in contact, a Position at the point
     where it landed, held for the whole stance: x, y where the robot's foot was at touchdown (then where that
     frame's answer put it), z the floor plus the robot's sole height at neutral (ankle frame over the lowest
     corner of its collision boxes), the foot level within ``LEVEL_BAND["stance"]`` (an Orientation band on roll
     and pitch, yaw free); otherwise a one-sided band (a Position with per-axis tolerance, x, y free) keeping the
     frame at least its clearance above the floor, the foot level within ``LEVEL_BAND["swing"]``. The clearance
     is the height of the ankle frame over the lowest corner of the foot's collision boxes at the previous frame's
     tilt (at least the sole's height), so a toe-off tilt lifts the frame instead of pushing the toe into the
     floor; an answer that still puts a corner under the floor is solved again from itself with the clearance of
     its own tilt (:data:`FLOOR_RETRIES`);
   * any other mapped frame: a Position at its scaled keypoint.

   Each goal has a tolerance: what "met" means for that goal (:data:`TOLERANCES`); weights rank them when they
   cannot all be met (a held foot first, then the root, then the limbs); a frame whose held foot still ends more
   than :data:`HOLD_SLIP` from its point is solved once more from that answer with the feet weighing
   :data:`FIRM_CONTACT_WEIGHT`. No posture preference: the warm start
   from the previous frame (LM moves as little as the goals need) plays its part, at no cost.
3. **Warm start and velocity box**: each frame is solved from the previous answer (``q0``) within
   ``bounds = [q_prev - v_max dt, q_prev + v_max dt]`` clipped to the robot's joint bounds, ``dt = 1 / fps``:
   no flip, no jump. ``v_max``: the URDF's joint velocity limits (an entry of 0 or none: no limit); the floating
   base :data:`BASE_LINEAR_SPEED` m/s on x, y, z and :data:`BASE_ANGULAR_SPEED` rad/s on yaw, pitch, roll. A frame
   that cannot meet every goal gets the solver's best inside that box (``success=False`` recorded), never a jump.
   The per-frame solve is one LM run from q0 (no seed table, no DE restarts: :data:`FRAME_OPTIONS`), so the clip
   does not depend on the machine's speed. It runs on goal stacks bound once per clip (:mod:`.frame_stacks`: one per
   structure of the goal list, its targets written per frame; those that do not depend on the previous frame
   computed for every frame at the clip's set-up), not through a solver set up per frame.
4. **Self-collision**: each answer is checked on the collision meshes (:class:`~evoik_pin.Scene`, adjacent and
   SRDF-disabled pairs ignored; its verdict through a broad phase, :mod:`.self_collision_check`: boxes, hulls, then
   meshes, ~0.3-0.6 ms a check). A colliding answer steps back towards the previous, collision-free frame
   (:mod:`.collision_step`: the joints moving one link of the colliding pair, never those placing a foot), so it
   stays in the velocity box and free (a relaxed solve with ``scene=`` first, as the first frame gets, freed ~5 % of
   the colliding frames of the ten benchmark clips, at one more solve and check each);
   when only the whole previous frame is free (a leg moved into where an arm was), it steps back from a
   collision-free configuration drawn near the answer inside the box instead (:func:`.collision_step.free_nearby`),
   so the robot does not stand still.
   A scene passed to the first solve would not do it: a frame's goals usually conflict a little, its answer meets
   them only within their weights, and the solvers judge collisions on answers meeting every goal.

The first frame has no previous answer: it starts from the neutral pose with the base at its target and is
solved within the robot's bounds (the base's translation box widened to the clip's extent), with
:data:`FIRST_FRAME_RESTARTS` DE restarts; if it collides, it steps back from a collision-free configuration drawn
near it (:func:`.collision_step.free_nearby`).
"""

from __future__ import annotations

import functools
import time
from collections.abc import Mapping

import numpy as np

from ..errors import MappingError, OptionError
from ..goals import Direction, Orientation, Position, RelativePosition
from ..robot.velocity_limits import without_urdf_speed
from .clip import Clip
from .collision_step import free_nearby, step_back_free
from .contacts import DEFAULT_FEET, detect_contacts, ground_height
from .frame_stacks import FrameSolve, FrameStacks
from .mapping import LIMBS, SKELETON_JOINTS, resolve_mapping
from .motion import Motion

__all__ = ["BASE_ANGULAR_SPEED", "BASE_LINEAR_SPEED", "TOLERANCES", "WEIGHTS", "retarget", "self_collision_check",
           "self_collision_scene", "velocity_limits_of"]

#: Floating base speed limits used with ``velocity_limits=True``: m/s on x, y, z (a sprinter's pelvis moves
#: at ~10 m/s, a humanoid robot's at ~2) and rad/s on yaw, pitch, roll (a full turn in a second).
BASE_LINEAR_SPEED = 2.0
BASE_ANGULAR_SPEED = 2.0 * np.pi
#: What "met" means per goal family: m for positions, rad for the heading and a limb's direction (a limb's
#: RelativePosition gets this angle times its length in m); a held foot's 1 mm keeps skating far below the 2 mm per
#: frame a judge accepts.
TOLERANCES = {"contact": 1e-3, "floor": 1e-3, "root": 0.01, "heading": 0.03, "limb": 0.035, "point": 0.02}
#: The tolerances of a colliding first frame's second solve, with the scene: a scene judges the answers that meet
#: every goal, so the limbs and the root get room (0.25 rad, 5 cm) for the search to find a collision-free one; a
#: held foot keeps its 1 mm.
RELAXED_TOLERANCES = {**TOLERANCES, "root": 0.05, "heading": 0.25, "limb": 0.25, "point": 0.1}
#: Clearance (m) between the two legs' knee and ankle links kept by the stance widening.
STANCE_CLEARANCE = 0.01
#: A held foot farther than this (m) from its hold point gets its frame solved again with the feet weighing
#: FIRM_CONTACT_WEIGHT (the goal's tolerance is 1 mm; a judge accepts 2 mm of skating per frame).
HOLD_SLIP = 1.5e-3
FIRM_CONTACT_WEIGHT = 3e4
#: Length (m) at which a limb's weight is WEIGHTS["limb"]: a thigh's.
LIMB_REFERENCE_LENGTH = 0.3
#: Weights ranking the goals when they cannot all be met (the rows of a goal scale by sqrt(weight)). The trunk's
#: limbs (pelvis -> torso -> head) weigh "trunk" instead of "limb": they place the head and both shoulders, and a
#: robot trunk with fewer joints than a spine (Talos: yaw and pitch, no roll) otherwise gives their direction up
#: to the arms' (measured over five clips on G1 and Talos: docs/BENCHMARKS.md, "The trunk's weight").
WEIGHTS = {"contact": 300.0, "floor": 300.0, "level": 30.0, "root": 10.0, "heading": 3.0, "trunk": 10.0, "limb": 1.0,
           "point": 1.0}
#: Budget (s) of each frame's solve (its LM run from q0 is made whatever the clock says: see FRAME_OPTIONS).
FRAME_TIMEOUT = 0.005
#: memetic's options per frame: the previous answer is the start (LM from q0); no seed table (a global search
#: over the whole robot, ~60 ms of set-up per new goal list, for starts far outside the velocity box) and at most
#: :data:`FRAME_RESTARTS` DE populations inside the box when LM from q0 does not meet every goal.
FRAME_RESTARTS = 0
#: DE populations of the first frame (no previous answer; LM from the neutral pose placed on the root first). Counts,
#: not a time budget, so that a loaded machine gives the same clip.
FIRST_FRAME_RESTARTS = 1
FRAME_OPTIONS = {"table_size": 0, "max_restarts": FRAME_RESTARTS}
FIRST_FRAME_OPTIONS = {"table_size": 0, "max_restarts": FIRST_FRAME_RESTARTS}
#: A colliding first frame's second solve (relaxed tolerances, with the scene), with DE restarts (once a clip): a
#: first frame left colliding is stepped back from a random free configuration, where the limb may then stay caught
#: behind the body for many frames.
FIRST_COLLISION_RETRY_OPTIONS = {"table_size": 0, "max_restarts": 8}
#: Half-height (m) of the above-floor band of a swing foot: its sole anywhere from the floor to twice this above.
FLOOR_BAND = 2.0
#: Roll and pitch (rad) a foot may take from level: a held foot stays flat (its toe or heel less than a centimetre
#: from the floor); a swing foot tilted further would have to be lifted far to keep its toe or heel out of it.
LEVEL_BAND = {"stance": 0.05, "swing": 0.3}
#: Solves more of a frame whose swing foot's lowest corner ends more than FLOOR_SLACK (m) under the floor.
FLOOR_RETRIES = 4
FLOOR_SLACK = 5e-4
#: Slack (m) around the clip's extent for the floating base's translation bounds.
BASE_BOX_SLACK = 2.0


def _roles(pairs: list[tuple[str, str]]) -> dict[str, str]:
    """``{role: robot frame}`` of the mapping's frames whose keypoint is a joint of a known skeleton (cmu, smpl):
    role names are :data:`~evoik_pin.motion.mapping.SKELETON_JOINTS`' (``pelvis``, ``left_hip``, ...)."""
    by_keypoint = {}
    for names in SKELETON_JOINTS.values():
        for role, keypoint in names.items():
            by_keypoint.setdefault(keypoint, role)
    roles = {}
    for frame, keypoint in pairs:
        role = by_keypoint.get(keypoint)
        if role is not None and role not in roles:
            roles[role] = frame
    return roles


def velocity_limits_of(robot, velocity_limits=True) -> np.ndarray:
    """``v_max`` (n,) (rad/s, m/s; inf: none) of ``robot`` for ``velocity_limits``: True (the URDF's joint limits,
    an entry of 0 or inf read as none; the floating base :data:`BASE_LINEAR_SPEED`, :data:`BASE_ANGULAR_SPEED`),
    False (no limit), a number > 0 (that factor times True's), or an array (n,) of limits > 0."""
    if velocity_limits is False or velocity_limits is None:
        return np.full(robot.n, np.inf)
    if velocity_limits is True or np.ndim(velocity_limits) == 0:
        factor = 1.0
        if velocity_limits is not True:
            try:
                factor = float(velocity_limits)
            except (TypeError, ValueError):
                factor = np.nan
            if not (np.isfinite(factor) and factor > 0):
                raise OptionError(f"velocity_limits must be True, False, a factor > 0 of the URDF's limits or an "
                                  f"array ({robot.n},) of limits > 0 (rad/s, m/s); got {velocity_limits!r}")
        model = robot.model
        v = np.full(robot.n, np.inf)
        for k, name in enumerate(robot.joint_names):
            if model.existJointName(name):
                joint = model.joints[model.getJointId(name)]
                limit = float(model.velocityLimit[joint.idx_v])
                if np.isfinite(limit) and limit > 0:
                    v[k] = limit
        if robot.floating_base:
            v[:3], v[3:6] = BASE_LINEAR_SPEED, BASE_ANGULAR_SPEED
        return v * factor
    try:
        v = np.asarray(velocity_limits, dtype=float)
    except (TypeError, ValueError):
        v = None
    if v is None or v.shape != (robot.n,) or not (v > 0).all() or np.isnan(v).any():
        raise OptionError(f"velocity_limits must be True, False, a factor > 0 of the URDF's limits or an array "
                          f"({robot.n},) of limits > 0 (rad/s, m/s); got {velocity_limits!r}")
    return v


def _choice(value, name: str, accepted: str):
    raise OptionError(f"retarget: {name} must be {accepted}; got {value!r}")


def _unit(v: np.ndarray) -> np.ndarray:
    """Rows of ``v`` (..., 3) normalised (a zero row stays zero)."""
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.divide(v, n, out=np.zeros_like(v), where=n > 1e-12)


def _foot_corners(robot, frame: str) -> np.ndarray:
    """(K, 3) corners (m, in ``frame``'s axes, from its origin) of the collision boxes its joint carries, or (0, 3)
    without collision geometry."""
    q = np.zeros(robot.n)
    joint = robot.model.frames[robot.frame_id(frame)].parentJoint
    model = robot.collision_model
    corners = [_box_corners(obj.geometry) @ placement.rotation.T + placement.translation
               for obj, placement in zip(model.geometryObjects, robot.geometry_placements(model, q), strict=True)
               if obj.parentJoint == joint]
    if not corners:
        return np.zeros((0, 3))
    pose = robot.fk(q, frame)
    return (np.concatenate(corners) - pose.translation) @ pose.rotation


def _sole_height(robot, frame: str, corners: np.ndarray, q: np.ndarray) -> float:
    """Height (m) of ``frame``'s origin over the lowest of its foot's ``corners`` (:func:`_foot_corners`) at q: the
    sole's height under an ankle frame at that tilt (0 without collision geometry)."""
    return _sole_height_at(corners, robot.fk(q, frame).rotation) if len(corners) else 0.0


def _sole_height_at(corners: np.ndarray, rotation: np.ndarray) -> float:
    """:func:`_sole_height` of a foot frame whose rotation (3, 3) is ``rotation``."""
    if not len(corners):
        return 0.0
    return -float((corners @ rotation[2]).min())


def _half_width(robot, frame: str, axis: np.ndarray) -> float:
    """Largest distance (m) along unit ``axis`` (world) from ``frame``'s origin to a corner of the collision boxes
    its joint carries, at the neutral pose (0 without collision geometry)."""
    q = np.zeros(robot.n)
    joint = robot.model.frames[robot.frame_id(frame)].parentJoint
    model = robot.collision_model
    origin = robot.fk(q, frame).translation
    widest = 0.0
    for obj, placement in zip(model.geometryObjects, robot.geometry_placements(model, q), strict=True):
        if obj.parentJoint == joint:
            corners = _box_corners(obj.geometry) @ placement.rotation.T + placement.translation
            widest = max(widest, float(np.abs((corners - origin) @ axis).max()))
    return widest


def _box_corners(geometry) -> np.ndarray:
    """(8, 3) corners of a coal geometry's local axis-aligned bounding box (m, in its own frame)."""
    geometry.computeLocalAABB()
    lo, hi = np.asarray(geometry.aabb_local.min_), np.asarray(geometry.aabb_local.max_)
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])


class _Plan:
    """Everything fixed over a clip: roles, scale, the source in the robot's world, contacts, floor, robot sizes."""

    def __init__(self, robot, motion: Motion, mapping, scale, contacts, ground):
        self.pairs = resolve_mapping(robot, motion, mapping)
        self.roles = _roles(self.pairs)
        if "pelvis" not in self.roles:
            raise MappingError("retarget needs the root: map the robot's root frame to the motion's pelvis keypoint "
                               f"(one of {sorted({s['pelvis'] for s in SKELETON_JOINTS.values()})})")
        self.keypoint_of = dict(self.pairs)
        q_neutral = np.zeros(robot.n)
        self.neutral = {f: robot.fk(q_neutral, f) for f, _ in self.pairs}
        src = motion.positions
        self.src_index = {f: motion.index(k) for f, k in self.pairs}
        self.limbs = {group: [(self.roles[a], self.roles[b]) for a, b in limbs
                              if a in self.roles and b in self.roles]
                      for group, limbs in LIMBS.items()}
        #: limbs whose child no active joint moves relative to the parent (a head fixed on the torso)
        #: (the child's direction in the parent's frame at neutral, the axis a Direction goal turns)
        self.rigid = {(a, b): _unit(self.neutral[a].rotation.T
                                    @ (self.neutral[b].translation - self.neutral[a].translation))
                      for limbs in self.limbs.values() for a, b in limbs
                      if not set(robot.moving_joints(b)) - set(robot.moving_joints(a))}
        self.scale = self._scale(robot, motion, scale)
        feet_keys = self._foot_keypoints(motion)
        self.ground = self._ground(motion, ground, feet_keys)
        origin = np.array([*src[0, self.src_index[self.roles["pelvis"]], :2],
                           self.ground if self.ground is not None else ground_height(motion, feet_keys or None)])
        self.origin = origin
        self.points = origin + self.scale * (src - origin)  # (N, K, 3) the source in the robot's world, m
        self.contacts = self._contacts(robot, motion, contacts, feet_keys)
        #: each foot's collision-box corners in its frame, and the sole's height under it at neutral
        self.corners = {f: _foot_corners(robot, f) for f in self.contacts}
        self.sole = {f: _sole_height(robot, f, self.corners[f], q_neutral) for f in self.contacts}
        #: bool (n,): the joints placing a foot frame (the floating base included), kept when a collision steps back
        self.foot_joints = np.array([any(name in robot.moving_joints(f) for f in self.contacts)
                                     for name in robot.joint_names])
        self.shift = self._vertical_shift()
        self.points[..., 2] += self.shift
        #: (N, K, 3) the scaled source before the stance widening: what limb angles are measured against
        self.source_points = self.points.copy()
        self._widen_stance(robot)
        # the robot's own hip centre and left axis in its root frame at neutral
        root = self.roles["pelvis"]
        root_pose = self.neutral[root]
        if "left_hip" in self.roles and "right_hip" in self.roles:
            lh, rh = self.neutral[self.roles["left_hip"]].translation, self.neutral[self.roles["right_hip"]].translation
            self.hip_offset = root_pose.rotation.T @ ((lh + rh) / 2 - root_pose.translation)
            self.left_axis = _unit(root_pose.rotation.T @ (lh - rh))
        else:
            self.hip_offset, self.left_axis = np.zeros(3), None

    def _scale(self, robot, motion: Motion, scale) -> float:
        if isinstance(scale, str):
            if scale != "auto":
                _choice(scale, "scale", '"auto" or a number > 0')
            legs = [(s + "_hip", s + "_knee", s + "_ankle") for s in ("left", "right")]
            legs = [leg for leg in legs if all(j in self.roles for j in leg)]
            if not legs:
                raise MappingError('scale="auto" compares leg lengths: map the hip, knee and ankle keypoints of a '
                                   "leg, or give scale= a number > 0")
            robot_len, source_len = [], []
            for leg in legs:
                frames = [self.roles[j] for j in leg]
                robot_len.append(sum(np.linalg.norm(self.neutral[b].translation - self.neutral[a].translation)
                                     for a, b in zip(frames, frames[1:], strict=False)))
                p = [motion.positions[:, self.src_index[f]] for f in frames]
                source_len.append(float(np.median(np.linalg.norm(p[1] - p[0], axis=1)
                                                  + np.linalg.norm(p[2] - p[1], axis=1))))
            return float(np.mean(robot_len) / np.mean(source_len))
        try:
            value = float(scale)
        except (TypeError, ValueError):
            value = np.nan
        if not (np.isfinite(value) and value > 0):
            _choice(scale, "scale", '"auto" or a finite number > 0')
        return value

    def _foot_keypoints(self, motion: Motion) -> tuple[str, ...]:
        """The motion's foot keypoints that the mapping follows (ankles), for the floor and contacts."""
        mapped = {k for _, k in self.pairs}
        for pair in DEFAULT_FEET:
            if all(n in mapped for n in pair):
                return pair
        ankles = tuple(self.keypoint_of[self.roles[r]] for r in ("left_ankle", "right_ankle") if r in self.roles)
        return ankles

    def _ground(self, motion: Motion, ground, feet_keys) -> float | None:
        if ground is None:
            return None
        if isinstance(ground, str):
            if ground != "auto":
                _choice(ground, "ground", '"auto", a height in m or None')
            if not feet_keys:
                raise MappingError('ground="auto" reads the feet: map the ankle keypoints, or give ground= a '
                                   "height in m or None")
            return ground_height(motion, feet_keys)
        try:
            value = float(ground)
        except (TypeError, ValueError):
            value = np.nan
        if not np.isfinite(value):
            _choice(ground, "ground", '"auto", a finite height in m or None')
        return value

    def _contacts(self, robot, motion: Motion, contacts, feet_keys) -> dict[str, np.ndarray]:
        """``{robot foot frame: (N,) bool}``."""
        if contacts is None:
            return {}
        if isinstance(contacts, str):
            if contacts != "auto":
                _choice(contacts, "contacts", '"auto", a dict {robot frame: (N,) bool} or None')
            if not feet_keys:
                return {}
            by_key = detect_contacts(motion, feet_keys)
            frame_of = {k: f for f, k in self.pairs}
            return {frame_of[k]: v for k, v in by_key.items()}
        if not isinstance(contacts, Mapping):
            _choice(contacts, "contacts", '"auto", a dict {robot frame: (N,) bool} or None')
        out = {}
        frames = set(robot.frames) if hasattr(robot, "frames") else set()
        for frame, flags in contacts.items():
            if frames and frame not in frames:
                raise MappingError(f"contacts entry {frame!r}: robot {robot.name!r} has no frame {frame!r}")
            v = np.asarray(flags)
            if v.shape != (motion.frames,) or v.dtype != bool:
                raise OptionError(f"contacts[{frame!r}] must be a bool array of shape ({motion.frames},) (one flag "
                                  f"per frame); got {v.dtype} {v.shape}")
            out[frame] = v
        return out

    def _widen_stance(self, robot) -> None:
        """Move the knee and ankle keypoints of the two legs apart, along the source hips' horizontal left-right
        line, where they are closer than the robot's legs can be: the two links' lateral half-widths (their collision
        boxes at neutral) plus :data:`STANCE_CLEARANCE`, at most their neutral distance, the largest over knees and
        ankles (each side moves half the gap). A person walks with the feet almost on one line and crosses them when
        dancing; a robot's legs are thicker and would collide."""
        if not all(r in self.roles for r in ("left_hip", "right_hip")):
            return
        lh, rh = (self.points[:, self.src_index[self.roles[r]]] for r in ("left_hip", "right_hip"))
        lateral = lh - rh
        lateral[:, 2] = 0.0
        lateral = _unit(lateral)  # (N, 3)
        robot_left = (self.neutral[self.roles["left_hip"]].translation
                      - self.neutral[self.roles["right_hip"]].translation)
        robot_left = _unit(robot_left)
        pairs = [(self.roles["left_" + j], self.roles["right_" + j]) for j in ("knee", "ankle")
                 if "left_" + j in self.roles and "right_" + j in self.roles]
        # one width for the whole leg (the widest link's need): a knee kept apart above ankles that are not would
        # only tilt the shanks into each other
        wanted = max((min(float((self.neutral[a].translation - self.neutral[b].translation) @ robot_left),
                          _half_width(robot, a, robot_left) + _half_width(robot, b, robot_left) + STANCE_CLEARANCE)
                      for a, b in pairs), default=0.0)
        for left, right in pairs:
            kl, kr = self.src_index[left], self.src_index[right]
            gap = np.einsum("ij,ij->i", self.points[:, kl] - self.points[:, kr], lateral)
            push = np.maximum(wanted - gap, 0.0)[:, None] / 2 * lateral
            self.points[:, kl] += push
            self.points[:, kr] -= push

    def _vertical_shift(self) -> float:
        """Height (m) the scaled source is moved up so that a standing ankle keypoint sits at the robot's sole
        height over the floor (a person's ankle joint stands ~8 cm up, a scaled one lower or higher than the
        robot's ankle frame): without it the held feet and the limb directions would disagree by that much."""
        if self.ground is None:
            return 0.0
        gaps = []
        for frame, flags in self.contacts.items():
            if frame in self.src_index and flags.any():
                z = self.points[flags, self.src_index[frame], 2]
                gaps.append(self.sole[frame] - float(np.median(z - self.ground)))
        return float(np.mean(gaps)) if gaps else 0.0

    # ------------------------------------------------------------------ per-frame targets
    def src(self, frame: str, i: int) -> np.ndarray:
        """The scaled source keypoint (3,) (m) robot ``frame`` follows at frame i."""
        return self.points[i, self.src_index[frame]]

    def pelvis_axes(self, i: int) -> np.ndarray | None:
        """The source pelvis's axes (3, 3) at frame i (columns forward, left, up), or None without both hips."""
        if "left_hip" not in self.roles or "right_hip" not in self.roles:
            return None
        left = _unit(self.src(self.roles["left_hip"], i) - self.src(self.roles["right_hip"], i))
        up_hint = np.array([0.0, 0.0, 1.0])
        if "torso" in self.roles:
            centre = (self.src(self.roles["left_hip"], i) + self.src(self.roles["right_hip"], i)) / 2
            up_hint = _unit(self.src(self.roles["torso"], i) - centre)
        up = _unit(up_hint - (up_hint @ left) * left)
        return np.column_stack([np.cross(left, up), left, up])

    def root_target(self, i: int) -> np.ndarray:
        """Where the root frame goes at frame i (m): the source hip centre less the robot's hip offset."""
        axes = self.pelvis_axes(i)
        if axes is None:
            return self.src(self.roles["pelvis"], i)
        centre = (self.src(self.roles["left_hip"], i) + self.src(self.roles["right_hip"], i)) / 2
        # the robot's root axes ~ the source pelvis's, up to the robot's own facing (its left axis at neutral)
        return centre - axes @ self._facing() @ self.hip_offset

    def _facing(self) -> np.ndarray:
        """Rotation about z taking the robot root's own axes to (forward, left, up) (iCub faces -x: a half turn)."""
        if self.left_axis is None:
            return np.eye(3)
        a = np.arctan2(self.left_axis[1], self.left_axis[0]) - np.pi / 2
        c, s = np.cos(a), np.sin(a)
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])

    def heading_yaw(self, i: int) -> float:
        """Base yaw (rad) turning the robot's left axis onto the source's at frame i."""
        axes = self.pelvis_axes(i)
        if axes is None or self.left_axis is None:
            return 0.0
        yaw = np.arctan2(axes[1, 1], axes[0, 1]) - np.arctan2(self.left_axis[1], self.left_axis[0])
        return float(np.angle(np.exp(1j * yaw)))  # in (-pi, pi]

    def limb_vector(self, a: str, b: str, i: int) -> np.ndarray:
        """Target of frame b from frame a at frame i (m, world axes): the source direction, the robot's length."""
        length = np.linalg.norm(self.neutral[b].translation - self.neutral[a].translation)
        return _unit(self.src(b, i) - self.src(a, i)) * length


def _frame_goals(plan: _Plan, i: int, holds: dict[str, np.ndarray], tolerances: dict = TOLERANCES,
                 contact_weight: float = WEIGHTS["contact"], clearance: dict | None = None,
                 level: dict | None = None) -> list:
    """Frame i's goal list (see the module docstring), each goal met within its family's ``tolerances``; a held
    foot weighs ``contact_weight``; a swing foot's frame stays ``clearance[frame]`` (m; default its sole height at
    neutral) above the floor; ``level`` ``{foot: (3, 3) rotation}``: the level orientations the feet keep within
    :data:`LEVEL_BAND`."""
    clearance = plan.sole if clearance is None else clearance
    goals = [Position(plan.roles["pelvis"], plan.root_target(i), WEIGHTS["root"], tolerances["root"])]
    axes = plan.pelvis_axes(i)
    if axes is not None and plan.left_axis is not None:
        goals.append(Direction(plan.roles["pelvis"], plan.left_axis, axes[:, 1], WEIGHTS["heading"],
                               tolerances["heading"]))
    in_limbs = {plan.roles["pelvis"]}
    for group, limbs in plan.limbs.items():
        for a, b in limbs:
            in_limbs.update((a, b))
            vector = plan.limb_vector(a, b, i)
            length = float(np.linalg.norm(vector))
            # rows in m scale with the limb's length: weight 1 / length^2 makes every limb's residual an angle
            # (rad, times LIMB_REFERENCE_LENGTH), so a short limb is steered as firmly as a long one
            weight = WEIGHTS["trunk" if group == "trunk" else "limb"] * (LIMB_REFERENCE_LENGTH / max(length, 1e-3)) ** 2
            if (a, b) in plan.rigid:  # b fixed on a (G1's head on its torso): frame a's axis towards b
                goals.append(Direction(a, plan.rigid[(a, b)], vector, weight, tolerances["limb"]))
            else:
                goals.append(RelativePosition(a, b, vector, "world", weight, tolerances["limb"] * length))
    for frame, flags in plan.contacts.items():
        if flags[i] and frame in holds:
            goals.append(Position(frame, holds[frame], contact_weight, tolerances["contact"]))
        elif plan.ground is not None:  # sole between the floor and 2 FLOOR_BAND above it; x, y free
            xy = plan.src(frame, i)[:2] if frame in plan.src_index else np.zeros(2)
            z = plan.ground + clearance[frame] + FLOOR_BAND
            goals.append(Position(frame, [xy[0], xy[1], z], WEIGHTS["floor"], (np.inf, np.inf, FLOOR_BAND)))
    for frame, rotation in (level or {}).items():  # a foot near level (roll, pitch); yaw free
        band = LEVEL_BAND["stance" if plan.contacts[frame][i] and frame in holds else "swing"]
        goals.append(Orientation(frame, rotation, WEIGHTS["level"], (band, band, np.inf)))
    for frame, _ in plan.pairs:
        if frame not in in_limbs and frame not in plan.contacts:
            goals.append(Position(frame, plan.src(frame, i), WEIGHTS["point"], tolerances["point"]))
    return goals


def _update_holds(plan: _Plan, i: int, holds: dict[str, np.ndarray], poses_prev) -> list[str]:
    """Touchdown at frame i sets a foot's hold point: x, y where the robot's foot is at the previous frame
    (``poses_prev``: the feet's poses there, :class:`_FootPoses`; the scaled source ankle's at frame 0), z the floor
    plus the sole (without a floor: that z as well); lift-off drops it. Returns the feet that touched down (their
    holds are re-anchored on the answer, :func:`_anchor_holds`)."""
    touched = []
    for frame, flags in plan.contacts.items():
        if not flags[i]:
            holds.pop(frame, None)
        elif frame not in holds:
            if i > 0:
                p = np.array(poses_prev[frame].translation)
            elif frame in plan.src_index:
                p = plan.src(frame, i).copy()
            else:
                continue
            if plan.ground is not None:
                p[2] = plan.ground + plan.sole[frame]
            holds[frame] = p
            touched.append(frame)
    return touched


def _hold_slip(plan: _Plan, i: int, holds: dict[str, np.ndarray], poses) -> float:
    """Largest distance (m) of a held foot (in contact at frame i) from its hold point at the feet's ``poses``
    (:class:`_FootPoses` of an answer); 0 without one."""
    return max((float(np.linalg.norm(poses[frame].translation - holds[frame]))
                for frame, flags in plan.contacts.items() if flags[i] and frame in holds), default=0.0)


def _anchor_holds(plan: _Plan, touched: list[str], holds: dict[str, np.ndarray], poses) -> None:
    """The feet that touched down at this frame are held where the answer put them (``poses``: the feet's there;
    x, y; z on the floor): a touchdown the velocity box did not let the foot finish would otherwise slide it over the
    next frames."""
    for frame in touched:
        p = np.array(poses[frame].translation)
        if plan.ground is not None:
            p[2] = plan.ground + plan.sole[frame]
        holds[frame] = p


def _level(plan: _Plan, foot: str, rotation: np.ndarray) -> np.ndarray:
    """(3, 3) the foot's orientation at neutral turned about the world's z to its heading when its frame has
    ``rotation`` (3, 3)."""
    neutral = plan.neutral[foot].rotation
    x = rotation @ neutral.T[:, 0]
    yaw = np.arctan2(x[1], x[0])
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ neutral


class _FootPoses:
    """The feet's poses (``pin.SE3``, base frame) at a configuration: one kinematics pass per configuration, the last
    few kept (a frame asks for them at the previous answer and several times at each new one)."""

    KEPT = 8

    def __init__(self, robot, frames) -> None:
        self._robot, self._frames = robot, list(frames)
        self._ids = [robot.frame_id(f) for f in self._frames]
        self._kept: dict[bytes, dict] = {}

    def __call__(self, q: np.ndarray) -> dict:
        """``{foot frame: pose}`` at ``q`` (n,) (a finite float array: an answer of the solve)."""
        q = np.ascontiguousarray(q, dtype=float)
        key = q.tobytes()
        poses = self._kept.get(key)
        if poses is None:
            poses = dict(zip(self._frames, self._robot.frame_poses_unchecked(q, self._ids), strict=True))
            if len(self._kept) >= self.KEPT:
                self._kept.pop(next(iter(self._kept)))
            self._kept[key] = poses
        return poses


def _initial_q(robot, plan: _Plan) -> np.ndarray:
    q = np.zeros(robot.n)
    q[3] = plan.heading_yaw(0)
    base = np.array(robot.fk(q, plan.roles["pelvis"]).translation)  # root frame at the base origin: offset 0
    q[:3] = plan.root_target(0) - base
    return q


def _first_bounds(robot, plan: _Plan) -> tuple[np.ndarray, np.ndarray]:
    lower, upper = robot.lower.copy(), robot.upper.copy()
    root = plan.points[:, plan.src_index[plan.roles["pelvis"]]]
    lower[:3] = root.min(axis=0) - BASE_BOX_SLACK
    upper[:3] = root.max(axis=0) + BASE_BOX_SLACK
    yaw = plan.heading_yaw(0)
    # yaw unwrapped along the clip, two turns either way (no bound at +-pi to flip across); a warm-started frame's
    # velocity box keeps it near the previous one
    lower[3], upper[3] = yaw - 4 * np.pi, yaw + 4 * np.pi
    # a joint that moves no mapped frame and whose URDF gives it no speed (a hand's fingers) stays at rest: no goal
    # asks it to move and no speed is known safe for it (the library's default would let it flap at 3 rad/s); idle
    # joints with a speed limit (a wrist past the hand's frame) stay free, for the collision repairs
    moving = set().union(*(robot.moving_joints(f) for f, _ in plan.pairs))
    idle = np.array([name not in moving for name in robot.joint_names]) & without_urdf_speed(robot)
    rest = np.minimum(np.maximum(0.0, lower), upper)
    lower[idle] = upper[idle] = rest[idle]
    return lower, upper


class _Frame:
    """One frame's solves: on the clip's bound goal stacks (``stacks``, :class:`.frame_stacks.FrameStacks`) or, with
    ``stacks`` None, through :func:`evoik_pin.solve` on ``goals_of``'s goal list; ``feet`` (holds, clearance, level)
    as :func:`_frame_goals` takes them (read at each solve: a floor retry raises a clearance); ``box`` (lower,
    upper) (n,); ``budget``: the solve's timeout (s, None: none)."""

    def __init__(self, robot, i: int, stacks, rng, goals_of, feet: tuple, box: tuple, budget) -> None:
        self.robot, self.i, self.stacks, self.rng, self.goals_of = robot, i, stacks, rng, goals_of
        self.feet, self.box, self.budget = feet, box, budget

    def solve(self, tolerances: dict = TOLERANCES, contact_weight: float = WEIGHTS["contact"], start=None,
              scene=None, options: dict | None = None, timeout=None) -> tuple[np.ndarray, bool, object]:
        """(q (n,) in the box, success, the goal errors as :func:`_named` reads them, once the clip is solved) of
        the frame's goals from ``start`` (n,) with these
        ``tolerances`` and ``contact_weight``; with a ``scene`` (the general solve only: the first frame's
        retry) an answer in collision is no success. ``options``
        (default: the first frame's or a warm-started frame's) and ``timeout`` (default the frame's budget) go to
        :func:`evoik_pin.solve`."""
        from .. import api  # the public solve; imported here: evoik_pin's top level imports this module

        lower, upper = self.box
        seed = int(self.rng.integers(2**31))  # drawn on either path: the clip's random stream does not depend on it
        if self.stacks is not None:
            holds, clearance, level = self.feet
            out = self.stacks.solve(self.i, holds, clearance, level, tolerances, contact_weight, start, lower, upper)
            return np.minimum(np.maximum(out.q, lower), upper), out.success, out
        if options is None:
            options = FIRST_FRAME_OPTIONS if self.i == 0 else FRAME_OPTIONS
        goals = self.goals_of(tolerances, contact_weight)
        result = api.solve(self.robot, goals, seed=seed, q0=start, bounds=(lower, upper),
                           timeout=self.budget if timeout is None else timeout, scene=scene, **options)
        return np.minimum(np.maximum(result.q, lower), upper), result.success, (goals, result.goal_errors)


def _named(errors) -> list[tuple[str, float]]:
    """Per goal (its kind's name, its error: m, or rad for a goal without a position) of a frame's ``errors``: a
    :class:`.frame_stacks.FrameSolve`, (goals, their errors: per goal (m or None, rad or None), or None), or None
    (no errors reported)."""
    if errors is None:
        return []
    goals, goal_errors = (errors.goals, errors.goal_errors) if isinstance(errors, FrameSolve) else errors
    return [(type(g).__name__, e[0] if e[0] is not None else e[1]) for g, e in zip(goals, goal_errors or [],
                                                                                     strict=False)]


@functools.lru_cache(maxsize=4)
def self_collision_scene(robot):
    """``Scene(robot, self_collision=True)``, kept for the last few robots (building one takes 50-500 ms: the
    collision meshes' convex hulls), read-only here. Not thread-safe (a Scene's Pinocchio data is shared)."""
    from ..scene import Scene

    return Scene(robot, self_collision=True)


@functools.lru_cache(maxsize=4)
def self_collision_check(robot):
    """:class:`.self_collision_check.SelfCollisionCheck` of :func:`self_collision_scene` (the same verdicts, a broad
    phase: ~3x cheaper on G1), kept for the last few robots. Not thread-safe."""
    from .self_collision_check import SelfCollisionCheck

    return SelfCollisionCheck(self_collision_scene(robot))


def retarget(robot, motion: Motion, mapping="cmu", scale="auto", contacts="auto", ground="auto",
             self_collision: bool = True, velocity_limits=True, seed=0, timeout: float | None = None,
             progress: bool = False) -> Clip:
    """Retarget ``motion`` onto ``robot`` (a :class:`~evoik_pin.Robot` loaded with ``floating_base=True``).

    Args:
        robot: the humanoid; a fixed base raises :class:`~evoik_pin.errors.MappingError`.
        motion: keypoints (N, K, 3) m, z up, at ``motion.fps``.
        mapping: ``"cmu"`` or ``"smpl"`` (presets by ``robot.name``) or a dict ``{robot frame: keypoint}``; the
            root frame must follow the pelvis keypoint (``Hips``/``pelvis``).
        scale: ``"auto"`` (robot leg length over the source's) or a factor > 0.
        contacts: ``"auto"`` (from the source ankles' height and speed, :func:`~evoik_pin.motion.detect_contacts`),
            ``{robot frame: (N,) bool}`` or None (no foot held).
        ground: ``"auto"`` (the floor under the source's feet), a height in m (source world), or None (no floor:
            uneven terrain; contacts still hold the feet where they landed).
        self_collision: keep every frame free of self-collision (a colliding answer steps back towards the
            previous frame); False: collisions are only counted in the report.
        velocity_limits: True (URDF limits, base :data:`BASE_LINEAR_SPEED` m/s and :data:`BASE_ANGULAR_SPEED` rad/s),
            False, a factor of True's, or an array (n,) rad/s, m/s.
        seed: int; the same seed and inputs give the same clip.
        timeout: each frame's solve budget in s (default :data:`FRAME_TIMEOUT`).
        progress: print one line per 30 frames.

    Returns:
        A :class:`~evoik_pin.motion.Clip`; ``clip.report`` holds: ``success_rate`` (frames meeting every goal),
        ``max_goal_error_m`` (per goal kind, m or rad for a Direction, over the frames whose solver answer was kept:
        not those a collision changed), ``collision_resolves`` (frames made collision-free by the relaxed solve or
        by stepping back; ``drawn``: of those, stepped back from a drawn configuration), ``firm_contact_frames``
        (frames re-solved with firm feet), ``collision_frames``, ``joint_limit_frames``, ``velocity_limit_frames``
        (frame indices), ``foot_skating_mm`` (mean and max per frame of a held foot),
        ``ground_penetration_mm`` (max sole depth below the floor), ``limb_angle_deg`` (per group legs, trunk,
        arms: mean and max angle between robot and source limb), ``fps`` (frames solved per second, set-up
        excluded), ``setup_s`` (s: the clip's plan and, on a robot's first clip, its collision scene's convex
        hulls), ``first_frame_s`` (s: the first frame's search), ``steady_fps`` (frames per second after the first:
        the warm-started rate; NaN for a one-frame clip), ``scale``.
    """
    if not isinstance(motion, Motion):
        raise OptionError(f"retarget takes a evoik_pin.motion.Motion (load_bvh, load_clip, Motion(...)); got "
                          f"{type(motion).__name__}")
    if not isinstance(self_collision, bool):
        _choice(self_collision, "self_collision", "True or False")
    frame_timeout = FRAME_TIMEOUT if timeout is None else float(timeout)
    if not (np.isfinite(frame_timeout) and frame_timeout > 0):
        _choice(timeout, "timeout", "None or a number of seconds > 0")
    setup_start = time.perf_counter()
    plan = _Plan(robot, motion, mapping, scale, contacts, ground)
    v_max = velocity_limits_of(robot, velocity_limits)
    dt = 1.0 / motion.fps
    scene = self_collision_scene(robot)  # the solver's (a colliding first frame's retry); set-up, built once a robot
    check = self_collision_check(robot)  # every other check, the report's too: collisions are counted either way
    rng = np.random.default_rng(seed)
    first_lower, first_upper = _first_bounds(robot, plan)
    # the frames' goal lists bound once per structure, their targets written per frame (the ones that do not depend
    # on the previous frame computed for every frame here)
    stacks = FrameStacks(robot, plan, functools.partial(_frame_goals, plan), FLOOR_BAND)
    q_init = np.minimum(np.maximum(_initial_q(robot, plan), first_lower), first_upper)
    box = np.maximum(q_init - v_max * dt, first_lower), np.minimum(q_init + v_max * dt, first_upper)
    stacks.prepare(TOLERANCES, WEIGHTS["contact"], *box)
    feet = _FootPoses(robot, plan.contacts)
    n_frames = motion.frames
    Q = np.zeros((n_frames, robot.n))
    success = np.zeros(n_frames, dtype=bool)
    errors: list = []  # per frame: what _named reads
    stepped_back = relaxed = firmed = drawn = 0
    holds: dict[str, np.ndarray] = {}
    q_prev = q_init
    start = time.perf_counter()
    setup_s, first_frame_end = start - setup_start, start
    for i in range(n_frames):
        poses_prev = feet(q_prev)
        touched = _update_holds(plan, i, holds, poses_prev)
        # a swing foot tilts (toe-off, heel strike): its frame keeps the height over the floor that its lowest
        # corner needs at the previous frame's tilt, which changes little in one frame
        clearance = {f: max(plan.sole[f], _sole_height_at(plan.corners[f], poses_prev[f].rotation)) if i > 0
                     else plan.sole[f] for f in plan.contacts}
        level = {f: _level(plan, f, poses_prev[f].rotation) for f in plan.contacts}
        goals_of = functools.partial(_frame_goals, plan, i, holds, clearance=clearance, level=level)
        if i == 0:  # FIRST_FRAME_RESTARTS bound the work; the yaw within half a turn of the source's heading
            lower, upper, budget = first_lower.copy(), first_upper.copy(), None
            lower[3], upper[3] = q_prev[3] - np.pi, q_prev[3] + np.pi
        else:
            lower = np.maximum(q_prev - v_max * dt, first_lower)
            upper = np.minimum(q_prev + v_max * dt, first_upper)
            budget = frame_timeout
        # a warm-started frame is one LM run from its start (FRAME_OPTIONS): on the clip's bound goal stacks; the
        # first frame (a search) and a box in which a joint spans a full turn take the general solve
        frame = _Frame(robot, i, stacks if i > 0 and stacks.usable(lower, upper) else None, rng, goals_of,
                       (holds, clearance, level), (lower, upper), budget)
        solve = frame.solve
        q0 = np.minimum(np.maximum(q_prev, lower), upper)
        q_new, ok, goal_errors = solve(start=q0)
        for _ in range(FLOOR_RETRIES):
            # the tilt the answer gave a swing foot may put its lowest corner under the floor: once more from
            # the answer with that foot's frame kept as high as this tilt needs
            poses = feet(q_new)
            need = {f: _sole_height_at(plan.corners[f], poses[f].rotation) for f in plan.contacts if f not in holds}
            low = {f: h for f, h in need.items() if plan.ground is not None
                   and float(poses[f].translation[2]) - plan.ground < h - FLOOR_SLACK}
            if not low:
                break
            clearance.update({f: max(clearance[f], h) for f, h in low.items()})
            q_new, ok, goal_errors = solve(start=q_new)
        if _hold_slip(plan, i, holds, feet(q_new)) > HOLD_SLIP:
            # the other goals pulled a held foot off its point (a touchdown while the source foot still moves):
            # once more from that answer with the feet weighing far more, kept if the feet end nearer their holds
            firm = solve(contact_weight=FIRM_CONTACT_WEIGHT, start=q_new)
            if _hold_slip(plan, i, holds, feet(firm[0])) < _hold_slip(plan, i, holds, feet(q_new)):
                (q_new, ok, goal_errors), firmed = firm, firmed + 1
        if self_collision and check.in_collision(q_new):
            free = None
            if i == 0:  # the first frame's search again, with the scene; a warm-started frame steps back at once
                again_q, again_ok, _ = solve(RELAXED_TOLERANCES, start=q0, scene=scene, timeout=frame_timeout,
                                             options=FIRST_COLLISION_RETRY_OPTIONS)
                free = again_q if again_ok and not check.in_collision(again_q) else None
            if free is None:
                if i > 0:
                    free = step_back_free(robot, check, q_prev, q_new, plan.foot_joints)
                if free is None or np.array_equal(free, q_prev):
                    # no free previous frame (frame 0), or only the whole previous frame is free (the legs moved
                    # into where the arm was): step back from a free configuration drawn near the answer, inside
                    # the box, with the feet's joints where the answer put them
                    near = free_nearby(robot, check, q_new, lower, upper, rng, plan.foot_joints)
                    if near is not None:
                        free = step_back_free(robot, check, near, q_new, plan.foot_joints)
                        drawn += 1
                stepped_back += free is not None
            else:
                relaxed += 1
            if free is not None:  # the solver's goal errors were those of the colliding answer: not reported
                q_new = np.clip(free, lower, upper)
                ok, goal_errors = False, None
        _anchor_holds(plan, touched, holds, feet(q_new))
        q_prev = q_new
        Q[i], success[i] = q_prev, ok
        errors.append(goal_errors)  # named after the clip: not a frame's work
        if i == 0:
            first_frame_end = time.perf_counter()
        if progress and (i % 30 == 0 or i == n_frames - 1):
            print(f"retarget {robot.name}: frame {i + 1}/{n_frames}, success {success[:i + 1].mean():.2f}")
    elapsed = time.perf_counter() - start
    from .retarget_report import clip_report  # the quality figures: one concept per file

    report = clip_report(robot, plan, Q, success, [_named(e) for e in errors], v_max, dt, check, first_lower,
                         first_upper)
    report["collision_resolves"] = {"relaxed": relaxed, "step_back": stepped_back, "drawn": drawn}
    report["firm_contact_frames"] = firmed
    report["fps"] = n_frames / elapsed if elapsed > 0 else float("inf")
    # apart: the one-time set-up (the clip's plan; the scene's convex hulls on a robot's first clip) and the first
    # frame (a search from the neutral pose), then the rate of the warm-started frames after it
    report["setup_s"] = setup_s
    report["first_frame_s"] = first_frame_end - start
    later = elapsed - report["first_frame_s"]
    report["steady_fps"] = (n_frames - 1) / later if n_frames > 1 and later > 0 else float("nan")
    report["scale"] = plan.scale
    configurations = np.array([robot.full_configuration(q) for q in Q])
    fm = robot.full_model
    joint_names = tuple(name for j, name in enumerate(fm.names) if j >= 2 for _ in range(fm.joints[j].nq))
    return Clip(q=Q, configurations=configurations, fps=motion.fps, robot_name=robot.name, joint_names=joint_names,
                frames=tuple(f for f, _ in plan.pairs), report=report, keypoints=plan.points,
                keypoint_names=tuple(motion.names))
