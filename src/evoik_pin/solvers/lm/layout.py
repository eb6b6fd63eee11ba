"""The LM iteration's constants and the memory layouts the compiled kernel reads, defined once.

:mod:`.kernel` (numba) and :mod:`.reference` (the Python loop) both import from here; nothing here imports
them, so there is no import circle.

Kernel arguments built here:

* ``params`` (PARAMS_SIZE,): the run's settings at the ``P_*`` indices (:func:`kernel_params`);
* ``box`` (5, n): rows ``B_LO``, ``B_HI`` (the search box, rad or m), ``B_CLO``, ``B_CHI`` (the clip box:
  +-inf on wrapping joints, which are never clipped) and ``B_WRAP`` (1.0 on wrapping joints)
  (:func:`box_constants`);
* a goal stack (:class:`GoalStack`): per goal g, ``spec[g]`` (GOAL_SIZE,) at the ``G_*`` columns (kind, the
  physical joint its frame sits on, the square root of its weight, its tolerances in m and rad, the first of
  its rows in the stacked error), the frame's folded placement on that joint ``R[g]`` (3, 3), ``p[g]`` (3,),
  and ``support[g]`` (m,) bool, the joints that move it;
* a goal's target as ``pt`` (3,) and ``Rt`` (3, 3) (:func:`encode_target`): pose (position m, rotation),
  position (position, identity), planar (x, y, yaw rad or 0; identity); a stack's targets as (G, 3) and
  (G, 3, 3) arrays.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass, field

import numpy as np

__all__ = ["DEFAULT_DAMPING", "DEFAULT_ITERATIONS", "DEFAULT_MAX_STEP", "DEFAULT_STALL_RATIO",
           "DEFAULT_STALL_WINDOW", "KIND_PLANAR", "KIND_PLANAR_YAW", "KIND_POSE", "KIND_POSITION", "TASK_ROWS",
           "GoalArrays", "GoalStack", "TargetArrays", "box_constants", "encode_target", "encode_targets",
           "kernel_params", "problem_goals", "target_kind", "wrapping_joints", "KIND_POSE_AXES", "KIND_POSITION_BAND",
           "KIND_ORIENTATION", "KIND_DIRECTION", "KIND_LOOK_AT", "ANGLE_KINDS", "POSITIONLESS_KINDS", "owned"]

TWO_PI = 2.0 * np.pi
#: Initial damping lambda (m^2, rad^2): small against the entries of E E^T (about reach^2 ~ 0.1-1 m^2).
DEFAULT_DAMPING = 1e-2
#: Steps allowed to one LM run started from a seed (converging runs need about 5-15).
DEFAULT_ITERATIONS = 30
#: Stall test: a run stops when |e| has not dropped below DEFAULT_STALL_RATIO times its value
#: DEFAULT_STALL_WINDOW accepted steps earlier.
DEFAULT_STALL_WINDOW, DEFAULT_STALL_RATIO = 4, 0.5
#: Largest length |dq| of one step (rad or m, Euclidean); longer steps are scaled down (trust region).
DEFAULT_MAX_STEP = 1.0
#: Damping bounds and its factors after an accepted / a rejected step.
LAMBDA_MIN, LAMBDA_MAX = 1e-12, 1e4
SHRINK, GROW = 0.2, 8.0
#: |e|^2 below which a converged run needs no finishing step (|e| = 1e-12: about FK round-off for 1 m arms).
FINISHED = 1e-24
#: Geodesic acceleration: used after an accepted step that left |e|^2 above GEO_SLOW times its value (|e| not
#: halved) while |e|^2 < GEO_NEAR (|e| < 1 cm + rad: a run creeping along a narrow curved valley, the signature
#: of a near-singular target), so the fast, quadratic phase pays nothing; kept when |a| <= GEO_ALPHA |v| / 2;
#: GEO_H is the finite-difference step.
GEO_SLOW, GEO_NEAR, GEO_ALPHA, GEO_H = 0.25, 1e-4, 0.75, 0.1

#: Goal kinds (the ``G_KIND`` column of a goal's spec) and the rows of the base-frame Jacobian each uses.
KIND_POSITION, KIND_POSE, KIND_PLANAR, KIND_PLANAR_YAW = 0, 1, 2, 3
TASK_ROWS = {KIND_POSITION: (0, 1, 2), KIND_POSE: (0, 1, 2, 3, 4, 5), KIND_PLANAR: (0, 1),
             KIND_PLANAR_YAW: (0, 1, 5)}
#: Kinds beyond one frame (codes 10-15; the kernel's :func:`~.kernel.balance_error` branch, which the kinds above
#: never enter): the whole robot's centre of mass at a point on chosen axes (3 rows, the others zeroed), its ground
#: projection inside a support polygon (2 rows), and one frame's pose seen from another (6 rows). Their numbers
#: (masses, contact points, the second frame) are in the goal's ``aux`` row at the ``A_*`` offsets below.
KIND_COM, KIND_COM_SUPPORT, KIND_RELATIVE_POSE = 10, 11, 12
#: The first kind code handled beyond one frame.
KIND_BEYOND_FRAME = 10
TASK_ROWS.update({KIND_COM: (0, 1, 2), KIND_COM_SUPPORT: (0, 1), KIND_RELATIVE_POSE: (0, 1, 2, 3, 4, 5)})
#: Kinds whose goals constrain orientation.
ORIENTED_KINDS = (KIND_POSE, KIND_PLANAR_YAW)
#: Goal kinds on one frame beyond those (:mod:`.axes`; the goal classes of :mod:`evoik_pin.goals`): a pose with
#: per-axis tolerance bands or free axes (6 rows: position in the target frame, then rotation), a position with
#: bands (3 rows, base frame), an orientation alone (3 rows), a frame axis along a direction, a frame axis at a
#: point (3 rows each: the axis minus the wanted unit direction, base frame).
KIND_POSE_AXES, KIND_POSITION_BAND, KIND_ORIENTATION, KIND_DIRECTION, KIND_LOOK_AT = 4, 5, 6, 7, 8
TASK_ROWS.update({KIND_POSE_AXES: (0, 1, 2, 3, 4, 5), KIND_POSITION_BAND: (0, 1, 2), KIND_ORIENTATION: (3, 4, 5),
                  KIND_DIRECTION: (3, 4, 5), KIND_LOOK_AT: (3, 4, 5)})
ORIENTED_KINDS += (KIND_POSE_AXES, KIND_ORIENTATION)
#: Kinds whose goals put the frame's origin nowhere (their target's pt is a direction or a point to look at).
POSITIONLESS_KINDS = (KIND_ORIENTATION, KIND_DIRECTION, KIND_LOOK_AT)
#: Kinds whose errors include an angle (rad): the oriented ones and the pointing ones.
ANGLE_KINDS = ORIENTED_KINDS + (KIND_DIRECTION, KIND_LOOK_AT)
#: Their goals' ``aux`` columns. Bands (pose with axes, position with bands, orientation): AUX_INNER (6,) the
#: residual's dead-zone half-widths (m x3, rad x3; inf on a free axis, 0 under a norm tolerance), AUX_BAND (6,)
#: the half-widths the success test accepts (inf free, 0 under a norm tolerance), AUX_SWING the one free rotation
#: axis (0, 1, 2: x, y, z of the target frame) whose swing residual replaces the rotation vector, or -1.
#: Pointing (direction, look-at): AUX_AXIS (3,) the frame's unit axis.
AUX_INNER, AUX_BAND, AUX_SWING, AUX_AXIS = 0, 6, 12, 0
AUX_SIZE = 13
#: One frame's pose seen from another with per-axis tolerance bands or free axes (6 rows: those of KIND_POSE_AXES
#: for frame b's pose in frame a's coordinates against the target).
KIND_RELATIVE_POSE_AXES = 13
TASK_ROWS[KIND_RELATIVE_POSE_AXES] = (0, 1, 2, 3, 4, 5)
ORIENTED_KINDS += (KIND_RELATIVE_POSE, KIND_RELATIVE_POSE_AXES)
ANGLE_KINDS += (KIND_RELATIVE_POSE, KIND_RELATIVE_POSE_AXES)
#: aux of the centre-of-mass kinds (``goals.center_of_mass``): total mass M (kg), the first moment (kg m, base
#: frame) of the bodies no joint moves, the axes mask (1.0 on the constrained axes; KIND_COM) or (KIND_COM_SUPPORT)
#: the shrink s (m) of the support polygon and its number K of contact points; then A_COM_BODIES + 5 k (k < m):
#: physical joint k's body mass m_k (kg), first moment m_k c_k (kg m, in the joint's folded frame) and the mass of
#: its whole subtree (kg); then, for KIND_COM_SUPPORT, A_COM_BODIES + 5 m + 4 i: contact point i's physical joint
#: (-1: none) and its position (m) in that joint's folded frame (in the base frame for -1).
A_COM_MASS, A_COM_MOMENT, A_COM_AXES, A_COM_SHRINK, A_COM_POINTS, A_COM_BODIES = 0, 1, 4, 4, 5, 7
#: aux of KIND_RELATIVE_POSE and KIND_RELATIVE_POSE_AXES: frame a's physical joint (-1: the base), its folded
#: placement R (9, row-major), p (3); the AUX_SIZE band columns of a pose with axes from A_REL_BAND (the AUX_*
#: layout above; unused by KIND_RELATIVE_POSE); then A_REL_SIGNS + k (k < m): +1 for joints that move frame b only,
#: -1 for those that move frame a only, else 0.
A_REL_JOINT, A_REL_R, A_REL_P, A_REL_BAND = 0, 1, 10, 13
A_REL_SIGNS = A_REL_BAND + AUX_SIZE
__all__ += ["KIND_BEYOND_FRAME", "KIND_COM", "KIND_COM_SUPPORT", "KIND_RELATIVE_POSE", "KIND_RELATIVE_POSE_AXES"]

#: Layout of the kernel's ``params`` vector.
P_DAMPING, P_MAX_STEP, P_STALL_WINDOW, P_STALL_RATIO, P_FINISH, P_ITERATIONS = range(6)
PARAMS_SIZE = 6
#: Columns of a goal's spec: kind, physical joint of its frame (-1: the base), sqrt(weight), tolerances (m, rad),
#: first row in the stacked error.
G_KIND, G_JOINT, G_WEIGHT, G_TOL, G_RTOL, G_ROW = range(6)
GOAL_SIZE = 6
#: Rows of the kernel's ``box``.
B_LO, B_HI, B_CLO, B_CHI, B_WRAP = range(5)
#: Columns of the per-run ``stats`` rows the batch kernels write: errors (the largest over the goals), converged,
#: iterations, evaluations, cost (the weighted |e|^2 of the end configuration).
S_POS, S_ROT, S_CONVERGED, S_ITERATIONS, S_EVALUATIONS, S_COST = range(6)
STATS_SIZE = 6


def owned(a: np.ndarray, dtype=None) -> np.ndarray:
    """``a`` as the kernel's entry points are compiled for it: a C-contiguous, writable array (of ``dtype`` when
    given): ``a`` itself when it is one, else a copy.

    numba compiles a function once per argument type, and a read-only array is a type of its own (a NumPy broadcast
    or a C-contiguous view of one, an array from Ray's object store, a memory-mapped file): one reaching an entry
    point would have numba compile the whole kernel again for it (half a minute to a minute and a half, inside the
    caller's time budget, and again in every fresh process). The engine passes every array through here once."""
    if a.flags.writeable and a.flags.c_contiguous and (dtype is None or a.dtype == dtype):
        return a
    return np.array(a, dtype=dtype, order="C")


def target_kind(target) -> int:
    """The ``KIND_*`` of a :class:`~evoik_pin.problem.Target`."""
    if target.planar:
        return KIND_PLANAR if target.yaw is None else KIND_PLANAR_YAW
    return KIND_POSITION if target.rotation is None else KIND_POSE


def encode_target(target) -> tuple[np.ndarray, np.ndarray]:
    """The kernel's ``(pt (3,), Rt (3, 3))`` of one target (see the module docstring)."""
    if target.planar:
        pt = np.array([target.position[0], target.position[1], target.yaw or 0.0])
        return pt, np.eye(3)
    Rt = np.eye(3) if target.rotation is None else owned(target.rotation, float)
    return owned(target.position, float), Rt


def encode_targets(targets) -> tuple[np.ndarray, np.ndarray]:
    """``(P (N, 3), Rts (N, 3, 3))`` of N targets of one kind, for the kernel's batch entry points."""
    N = len(targets)
    t0 = targets[0]
    if t0.planar:
        P = np.array([[t.position[0], t.position[1], t.yaw or 0.0] for t in targets], dtype=float)
        return P, np.repeat(np.eye(3)[None], N, axis=0)
    P = np.ascontiguousarray([t.position for t in targets], dtype=float)
    if t0.rotation is None:
        return P, np.repeat(np.eye(3)[None], N, axis=0)
    return P, np.ascontiguousarray([t.rotation for t in targets], dtype=float)


@dataclass(frozen=True)
class TargetArrays:
    """N targets of one kind as the kernel reads them (:func:`encode_targets`), without Target objects: how the
    batch solver carries millions of targets (an (N, 4, 4) array of poses becomes one without a Python loop).

    Attributes:
        kind: their ``KIND_*``. P: (N, 3) positions (m; planar: x, y, yaw rad). Rts: (N, 3, 3) rotations
            (identity for targets without one).
    """

    kind: int
    P: np.ndarray
    Rts: np.ndarray

    @classmethod
    def of(cls, targets) -> TargetArrays:
        """The arrays of a list of :class:`~evoik_pin.problem.Target` of one kind."""
        return cls(target_kind(targets[0]), *encode_targets(targets))

    @classmethod
    def from_poses(cls, H: np.ndarray) -> TargetArrays:
        """Pose targets from (N, 4, 4) homogeneous matrices already checked (``Target.check_poses``)."""
        return cls(KIND_POSE, np.ascontiguousarray(H[:, :3, 3], dtype=float),
                   np.ascontiguousarray(H[:, :3, :3], dtype=float))

    def __len__(self) -> int:
        return int(self.P.shape[0])

    @property
    def oriented(self) -> bool:
        """True when the targets constrain orientation (pose, planar with yaw)."""
        return self.kind in (KIND_POSE, KIND_PLANAR_YAW)

    def take(self, rows: np.ndarray) -> TargetArrays:
        """The targets at ``rows`` (an index array), as new arrays."""
        return TargetArrays(self.kind, self.P[rows], self.Rts[rows])


def wrapping_joints(robot, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """(n,) bool: revolute joints whose search range spans a full turn, so wrapping by 2 pi keeps them inside.

    Every continuous joint qualifies (its range is [-pi, pi]), and so does a UR-style [-2 pi, 2 pi] joint.
    """
    return robot.revolute & ((upper - lower) >= TWO_PI - 1e-9)


_BOX_CACHE: dict = {}


def box_constants(robot, lower: np.ndarray, upper: np.ndarray):
    """(wrap mask (n,), any wrap, clip lower, clip upper, kernel box (5, n)) of a search box, cached: the same
    box recurs every solve.

    The clip bounds are the box with +-inf for wrapping joints, which are never clipped.
    """
    key = (id(robot), lower.tobytes(), upper.tobytes())
    hit = _BOX_CACHE.get(key)
    if hit is None or hit[0]() is not robot:  # a weak reference: the cache must not keep robots alive
        wrap = wrapping_joints(robot, lower, upper)
        clip = (np.where(wrap, -np.inf, lower), np.where(wrap, np.inf, upper))
        box = np.empty((5, robot.n))
        box[[B_LO, B_HI, B_CLO, B_CHI, B_WRAP]] = lower, upper, *clip, wrap
        hit = (weakref.ref(robot), (wrap, bool(wrap.any()), *clip, box))
        if len(_BOX_CACHE) > 64:
            _BOX_CACHE.clear()
        _BOX_CACHE[key] = hit
    return hit[1]


def kernel_params(iterations: int = 0, damping: float = DEFAULT_DAMPING, max_step: float = DEFAULT_MAX_STEP,
                  stall_window: int = DEFAULT_STALL_WINDOW, stall_ratio: float = DEFAULT_STALL_RATIO,
                  finish: bool = True) -> np.ndarray:
    """The kernel's ``params`` vector (PARAMS_SIZE,) (layout: the ``P_*`` indices); the tolerances are the
    goals' (:class:`GoalStack`)."""
    params = np.empty(PARAMS_SIZE)
    params[[P_DAMPING, P_MAX_STEP, P_STALL_WINDOW, P_STALL_RATIO, P_FINISH, P_ITERATIONS]] = (
        damping, max_step, stall_window, stall_ratio, float(finish), iterations)
    return params


@dataclass(frozen=True)
class GoalStack:
    """G goals on frames of one robot as the kernel reads them (see the module docstring): which frame, which
    kind, how much weight, which tolerances; the targets come apart (:func:`encode_target`), so one stack serves
    any number of problems.

    Attributes:
        spec: (G, GOAL_SIZE) the ``G_*`` columns. R: (G, 3, 3), p: (G, 3) (m) each frame's folded placement on
            its joint (``Robot.frame_constants``). support: (G, m) bool, the physical joints that move each frame.
        rows: total rows of the stacked error. kinds: (G,) the ``KIND_*``. frames: the frame names.
        aux: (G, A) float, A >= 1: each goal's further numbers, read by its kind's code in the kernel (a band of
            tolerances, an axis, a second frame, ...; zeros for kinds that need none).
        any_oriented: some goal constrains orientation.
    """

    spec: np.ndarray
    R: np.ndarray
    p: np.ndarray
    support: np.ndarray
    rows: int
    kinds: tuple
    frames: tuple
    aux: np.ndarray = None
    any_oriented: bool = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "any_oriented", any(k in ORIENTED_KINDS for k in self.kinds))
        if self.aux is None:
            object.__setattr__(self, "aux", np.zeros((self.spec.shape[0], 1)))

    @property
    def arrays(self) -> tuple:
        """The stack's arguments of the kernel's entry points, in their order: spec, R, p, support, aux."""
        return self.spec, self.R, self.p, self.support, self.aux

    @classmethod
    def of(cls, robot, frames, kinds, weights, tolerances, rotation_tolerances, aux=None) -> GoalStack:
        """The stack of goals on ``frames`` (names; None: the robot's tip) of ``kinds`` (``KIND_*``) with
        ``weights`` (> 0), ``tolerances`` (m) and ``rotation_tolerances`` (rad), one each per goal; ``aux``: per
        goal its further numbers (a 1-d array or None), packed into the (G, A) ``aux`` array (zero-padded).

        Cached per robot and these values (the last 64 stacks): a goal list solved again with new targets (an
        :class:`~evoik_pin.IKSolver`'s calls, a trajectory) gets the same stack object, so an LM engine kept from
        solve to solve is retargeted in place instead of rebuilt. A stack is never written (a tightened copy is
        made with ``dataclasses.replace``)."""
        key = (id(robot), tuple(frames), tuple(int(k) for k in kinds), tuple(float(w) for w in weights),
               tuple(float(t) for t in tolerances), tuple(float(t) for t in rotation_tolerances),
               None if aux is None else tuple(None if a is None else np.asarray(a, dtype=float).tobytes()
                                              for a in aux))
        hit = _STACK_CACHE.get(key)
        if hit is not None and hit[0]() is robot:
            return hit[1]
        stack = cls._made(robot, frames, kinds, weights, tolerances, rotation_tolerances, aux)
        if len(_STACK_CACHE) >= 64:
            _STACK_CACHE.pop(next(iter(_STACK_CACHE)))
        _STACK_CACHE[key] = (weakref.ref(robot), stack)
        return stack

    @classmethod
    def _made(cls, robot, frames, kinds, weights, tolerances, rotation_tolerances, aux) -> GoalStack:
        """:meth:`of`'s stack, built."""
        G = len(frames)
        spec = np.empty((G, GOAL_SIZE))
        R, p = np.empty((G, 3, 3)), np.empty((G, 3))
        joints = []
        row = 0
        for g in range(G):
            j, R[g], p[g] = robot.frame_constants(frames[g])
            joints.append(j)
            spec[g] = (kinds[g], j, np.sqrt(weights[g]), tolerances[g], rotation_tolerances[g], row)
            row += len(TASK_ROWS[kinds[g]])
        packed = None
        if aux is not None and any(a is not None for a in aux):
            width = max(len(a) for a in aux if a is not None)
            packed = np.zeros((G, width))
            for g, a in enumerate(aux):
                if a is not None:
                    packed[g, :len(a)] = a
        return cls(spec, R, p, robot.tree.support_mask(joints), row, tuple(int(k) for k in kinds),
                   tuple(robot.tip if f is None else f for f in frames), packed)

    @classmethod
    def single(cls, robot, kind: int, tolerance: float, rotation_tolerance: float) -> GoalStack:
        """The one goal of a single-target problem: the tip, weight 1 (cached per robot, kind and tolerances:
        every single-target solve builds one)."""
        key = (id(robot), kind, float(tolerance), float(rotation_tolerance))
        hit = _SINGLE_CACHE.get(key)
        if hit is None or hit[0]() is not robot:
            stack = cls.of(robot, [None], [kind], [1.0], [tolerance], [rotation_tolerance])
            if len(_SINGLE_CACHE) > 64:
                _SINGLE_CACHE.clear()
            hit = _SINGLE_CACHE[key] = (weakref.ref(robot), stack)
        return hit[1]

    def __len__(self) -> int:
        return int(self.spec.shape[0])

    @property
    def oriented(self) -> np.ndarray:
        """(G,) bool: the goals that constrain orientation."""
        return np.array([k in ORIENTED_KINDS for k in self.kinds], dtype=bool)


_SINGLE_CACHE: dict = {}
_STACK_CACHE: dict = {}  # GoalStack.of's: key -> (weak reference to the robot, stack)


@dataclass(frozen=True)
class GoalArrays:
    """N problems over one goal stack (the same frames, kinds, weights and tolerances; different targets) as the
    kernel's pair entry point reads them: how :func:`~evoik_pin.solve_many` carries goal lists.

    Attributes:
        stack: the :class:`GoalStack` every problem shares. P: (N, G, 3) target positions (m). Rts: (N, G, 3, 3)
            target rotations (identity for goals without one).
    """

    stack: GoalStack
    P: np.ndarray
    Rts: np.ndarray

    def __len__(self) -> int:
        return int(self.P.shape[0])

    @property
    def oriented(self) -> bool:
        """True when some goal constrains orientation."""
        return self.stack.any_oriented

    def take(self, rows: np.ndarray) -> GoalArrays:
        """The problems at ``rows`` (an index array), as new arrays."""
        return GoalArrays(self.stack, self.P[rows], self.Rts[rows])


def problem_goals(problem) -> tuple[GoalStack, np.ndarray, np.ndarray]:
    """(goal stack, targets pt (G, 3), Rt (G, 3, 3)) of an :class:`~evoik_pin.problem.IKProblem`: its goal list
    (``problem.goal_stack()``) when it has one, else its single target on the robot's tip."""
    if getattr(problem, "goals", None) is not None:
        return problem.goal_stack()
    stack = GoalStack.single(problem.robot, target_kind(problem.target), float(problem.tolerance),
                             float(problem.rotation_tolerance))
    pt, Rt = encode_target(problem.target)
    return stack, pt[None], Rt[None]
