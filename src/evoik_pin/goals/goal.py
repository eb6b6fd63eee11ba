"""The base of every goal kind (:class:`Goal`: its frame, weight and tolerances, checked when made), goal sets
(:func:`init_set`), and what the kinds on two frames share (:class:`FramePair`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..errors import FrameError, OptionError, TargetError
from .bands import AUX_SIZE, DEFAULT_GOAL_TOLERANCE, band_aux, band_errors, parse_axes
from .registry import KIND_BEYOND_FRAME, KINDS, register

__all__ = ["A_REL_BAND", "A_REL_JOINT", "A_REL_P", "A_REL_R", "A_REL_SIGNS", "BOTH", "DEFAULT_GOAL_TOLERANCE", "Goal",
           "FramePair", "init_set", "is_set", "number", "point3"]


def number(value, what: str, accepted: str, low: float | None = None, strict: bool = False) -> float:
    """``value`` as a finite float (>= ``low`` when given, > ``low`` when ``strict``), or an OptionError naming
    ``what`` and what is ``accepted``."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        x = math.nan
    if not math.isfinite(x) or low is not None and (x < low or strict and x == low):
        raise OptionError(f"{what} must be {accepted}, got {value!r}")
    return x


def point3(value, what: str) -> np.ndarray:
    """``value`` as 3 finite numbers (m), or a TargetError naming ``what``."""
    try:
        p = np.array(value, dtype=float)
    except (TypeError, ValueError):
        p = None
    if p is None or p.shape != (3,) or not np.isfinite(p).all():
        raise TargetError(f"{what} must be 3 finite numbers (m) (a 3-vector), got {value!r}")
    return p


@dataclass(frozen=True, eq=False)
class Goal:
    """A goal on one frame (abstract: :class:`Pose`, :class:`Position`, ...; see :mod:`evoik_pin.goals`).

    A kind (a subclass) declares ``KIND_CODES``, its kernel codes (:class:`.registry.KindCode`, registered when the
    class is made), :meth:`encode`, :meth:`file_kind` (its goals-file entry) and :meth:`marker` (its viewer marker)."""

    KIND_CODES = ()

    def __init_subclass__(cls, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        if "KIND_CODES" in cls.__dict__:
            register(cls, *cls.KIND_CODES)

    frame: str
    weight: float = 1.0
    tolerance: float = DEFAULT_GOAL_TOLERANCE
    rotation_tolerance: float | None = None
    #: The LM kernel's goal kind (``KIND_*``), and whether the goal constrains orientation.
    kind: int = field(default=-1, init=False, repr=False)
    has_orientation: bool = field(default=False, init=False, repr=False)
    #: A goal set's members (:func:`init_set`): one single-target goal each; None for one target.
    alternatives: tuple | None = field(default=None, init=False, repr=False)

    def _init_common(self, frame, weight, tolerance, rotation_tolerance, kind: int, oriented: bool,
                     what: str | None = None) -> None:
        """Set and check the fields every goal has (a frozen dataclass's fields, hence object.__setattr__): weight
        > 0, tolerances >= 0 (None: the default; ``rotation_tolerance`` None: ``tolerance``), a frame name unless
        ``what`` names a goal without one in the messages."""
        if what is None:
            if not isinstance(frame, str) or not frame:
                raise FrameError(f"a goal's frame is a frame name (a non-empty string), got {frame!r}")
            what = f"the goal on {frame!r}"
        weight = number(weight, f"weight of {what}", "a finite number > 0", 0.0, strict=True)
        tol = DEFAULT_GOAL_TOLERANCE if tolerance is None else number(
            tolerance, f"tolerance (m) of {what}", "a finite number >= 0")
        rtol = tol if rotation_tolerance is None else number(
            rotation_tolerance, f"rotation_tolerance (rad) of {what}", "a finite number >= 0")
        if tol < 0 or rtol < 0:
            raise OptionError(f"tolerances of {what} must be >= 0, got {tolerance!r} m and {rotation_tolerance!r} rad")
        self._set(frame=frame, kind=kind, has_orientation=oriented, weight=weight, tolerance=tol,
                  rotation_tolerance=rtol)

    def _set(self, **fields) -> None:
        """Set fields of this frozen dataclass, as its ``__init__`` does (object.__setattr__)."""
        for name, value in fields.items():
            object.__setattr__(self, name, value)

    def _init_axes(self, frame, weight, tolerance, rotation_tolerance, free, axes: tuple[str, ...],
                   kinds: tuple[int | None, int], where: str) -> None:
        """:meth:`_init_common` with ``band``, ``free`` (:func:`.bands.parse_axes` on the error components ``axes``;
        ``where`` names the goal) and the aux row. ``kinds``: the code under a norm tolerance with no free axis (None:
        always the second), and with bands or free axes."""
        # one number and no free axis (made per call in a control loop): nothing to parse
        band, free = ((None, ()) if free is None and type(tolerance) in (float, int, type(None))
                      else parse_axes(tolerance, rotation_tolerance, free, axes, where))
        plain = band is None and not free and kinds[0] is not None
        if band is not None:  # met at 0
            tolerance = rotation_tolerance = 0.0
        self._init_common(frame, weight, tolerance, rotation_tolerance, kinds[0] if plain else kinds[1], "rx" in axes)
        self._set(band=band, free=free)
        self._set_aux(None if plain else band_aux(band, free, axes))

    @property
    def label(self) -> str:
        """How messages name this goal: its frame (goals beyond one frame say more)."""
        return self.frame

    def aux(self) -> np.ndarray | None:
        """The kernel's ``aux`` row of this goal (read-only; None: its kind reads none)."""
        return self.__dict__.get("_aux")

    def _set_aux(self, aux: np.ndarray | None) -> None:
        if aux is not None:
            aux.setflags(write=False)
        self._set(_aux=aux)

    def population_errors(self, P: np.ndarray, R: np.ndarray, pt: np.ndarray, Rt: np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray] | None:
        """(position errors (N,) m, orientation errors (N,) rad) of frame poses P (N, 3), R (N, 3, 3) for target
        (pt, Rt) as the kernel's success test sees them; None for the kinds without an ``aux`` row."""
        aux = self.aux()
        return None if aux is None else band_errors(self.kind, P, R, pt, Rt, aux)

    #: (``kind:`` name, optional fields, target reader, target writer[, FileKind's options]) (:meth:`file_kind`).
    FILE_ENTRY = None

    @classmethod
    def file_kind(cls):
        """This kind's :class:`.file_entries.FileKind` in goals files (:attr:`FILE_ENTRY`), or None."""
        from .file_entries import FileKind

        if cls.FILE_ENTRY is None:
            return None
        name, fields, read, write, *options = cls.FILE_ENTRY
        return FileKind(name, cls, fields, read, write, pair=issubclass(cls, FramePair),
                        **(options[0] if options else {}))

    #: False for the kinds whose target is no place in the base frame: no viewer marker.
    MARKED = True

    def marker(self) -> tuple[str, np.ndarray, np.ndarray | None] | None:
        """(node name, position (3,) m in the base frame, rotation (3, 3) for a triad or None for a sphere) of this
        goal's viewer marker, or None (:attr:`MARKED`)."""
        if not self.MARKED:
            return None
        p, R = self.encode()
        return self.frame, p, (R if self.has_orientation else None)

    def encode(self) -> tuple[np.ndarray, np.ndarray]:
        """The kernel's target ``(pt (3,) m, Rt (3, 3))`` of this goal, new arrays (identity or zeros where none)."""
        if isinstance(self.target, pin.SE3):
            return np.array(self.target.translation), np.array(self.target.rotation)
        return (np.zeros(3), self.target.copy()) if self.target.shape == (3, 3) else (self.target.copy(), np.eye(3))

    def errors(self, T: pin.SE3) -> tuple[float, float | None]:
        """(position error m or None, rotation error rad or None) of the goal frame at pose ``T`` (base frame)."""
        pt, Rt = self.encode()
        errors = self.population_errors(np.asarray(T.translation)[None], np.asarray(T.rotation)[None], pt, Rt)
        if errors is not None:
            return self.reported(errors[0][0], errors[1][0])
        pos = float(np.linalg.norm(T.translation - pt))
        if not self.has_orientation:
            return pos, None
        return pos, float(np.linalg.norm(pin.log3(Rt.T @ T.rotation)))

    def reported(self, position_error: float, rotation_error: float | None) -> tuple[float | None, float | None]:
        """The kernel's errors (m, rad) as :meth:`errors` reports them: None where the kind has none."""
        return ((float(position_error) if self.has_position else None),
                (float(rotation_error) if self.reports_angle else None))

    @property
    def has_position(self) -> bool:
        """Whether the goal puts a point somewhere (its kind's declaration)."""
        return KINDS[self.kind].has_position

    @property
    def reports_angle(self) -> bool:
        """Whether the goal's errors include an angle (rad)."""
        return KINDS[self.kind].angle

    @property
    def on_one_frame(self) -> bool:
        """Whether the goal matches a position or an orientation of its one frame (no pointing goal, no kind beyond
        one frame): the seed table ranks it as one frame's pose; the kernel's errors of it are its ``errors(T)``."""
        return self.kind < KIND_BEYOND_FRAME and (self.has_position or self.has_orientation)

    def met(self, position_error: float | None, orientation_error: float | None) -> bool:
        """Whether errors (m or None, rad or None) are within this goal's tolerances."""
        return (position_error is None or position_error <= self.tolerance) and (orientation_error is None
                                                     or orientation_error <= self.rotation_tolerance)


# ------------------------------------------------------------------ goal sets
def is_set(target, single_shape: tuple[int, ...]) -> bool:
    """Whether ``target`` is a list of targets rather than one: an array (k, *single_shape), or a list or tuple of
    ``pin.SE3`` or arrays of ``single_shape`` (an empty one too, refused by :func:`init_set`)."""
    if isinstance(target, np.ndarray):
        return target.ndim == len(single_shape) + 1 and target.shape[1:] == single_shape
    if not isinstance(target, (list, tuple)):
        return False
    return all(isinstance(t, pin.SE3) or np.shape(t) == single_shape for t in target)


def init_set(goal, targets, single, what: str) -> None:
    """Make ``goal`` (being constructed) the set of ``single(t)`` for each member ``t`` of ``targets``, any one of
    which will do: packed with its first member's target, its ``alternatives`` the members in order (solvers try
    each: :meth:`evoik_pin.problem.IKProblem.variants`). ``what`` names the kind and its members ("Pose poses").
    TargetError for an empty set, naming the index of a bad member."""
    kind, members = what.split()
    if len(targets) == 0:
        raise TargetError(f"{kind} on {goal.frame!r}: a goal set with no {members}; give at least one "
                          f"(a list of {members}, or one)")
    made = []
    for i, t in enumerate(targets):
        try:
            made.append(single(t))
        except TargetError as exc:
            raise TargetError(f"{kind} on {goal.frame!r}, member {i} of the goal set: {exc}") from None
    pts, Rts = zip(*(m.encode() for m in made), strict=True)  # the members' kernel targets, (k, 3) and (k, 3, 3)
    goal._set(target=made[0].target, alternatives=tuple(made), member_targets=(np.array(pts), np.array(Rts)))


# ------------------------------------------------------------------ goals on two frames
#: The ``aux`` row of the goals on two frames (read by ``solvers/lm/balance.py``): frame a's physical joint (-1: the
#: base), its folded placement R (9, row-major) and p (3,); the band columns (:mod:`.bands`); then per physical joint
#: k: +1 when it moves frame b only, -1 frame a only, :data:`BOTH` (or 0, as the kind asks) both.
A_REL_JOINT, A_REL_R, A_REL_P, A_REL_BAND = 0, 1, 10, 13
A_REL_SIGNS = A_REL_BAND + AUX_SIZE
#: The sign of a joint that moves both frames, for a kind whose error sees them (a vector in the world's axes turns
#: with them); kinds seen in frame a's axes mark those joints 0 (they move the two frames together).
BOTH = 2.0


class FramePair:
    """What the goals on two frames share: frame b is the goal's ``frame``, frame a its ``frame_a``. A kind defines
    :meth:`placement_errors`; the errors of poses and of populations follow from it."""

    #: The aux row's sign of the joints moving both frames: :data:`BOTH` for a kind whose error sees them, else 0.
    both = 0.0
    MARKED = False

    def _init_pair(self, frame_a, kind: str) -> None:
        """Set ``frame_a``: FrameError unless a frame name other than ``frame`` (``kind`` names the goal)."""
        if not isinstance(frame_a, str) or not frame_a:
            raise FrameError(f"{kind}'s frame_a is a frame name (a non-empty string), got {frame_a!r}")
        if frame_a == self.frame:
            raise FrameError(f"{kind} needs two frames, got {frame_a!r} twice")
        self._set(frame_a=frame_a)

    @property
    def frame_b(self) -> str:
        """The goal's ``frame``."""
        return self.frame

    @property
    def frames(self) -> list[str]:
        """[frame_a, frame_b]."""
        return [self.frame_a, self.frame]

    @property
    def label(self) -> str:
        """How messages name this goal: ``frame_a -> frame_b``."""
        return f"{self.frame_a} -> {self.frame}"

    def batch_key(self) -> tuple:
        """What this goal's kernel numbers depend on besides its target (solve_many batches lists alike)."""
        return (self.frame_a,)

    def placement_errors(self, Ra: np.ndarray, d: np.ndarray, Rb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(position errors (N,) m, rotation errors (N,) rad) for frame a's rotations Ra (N, 3, 3), the vectors
        p_b - p_a (N, 3) (m) and frame b's rotations Rb (N, 3, 3), all in the base frame."""
        raise NotImplementedError  # pragma: no cover - abstract

    def pair_errors(self, Ta: pin.SE3, Tb: pin.SE3) -> tuple[float, float | None]:
        """The goal's errors (position m, rotation rad or None) for frame a's and frame b's poses ``Ta``, ``Tb``
        (base frame)."""
        pos, rot = self.placement_errors(Ta.rotation[None], (Tb.translation - Ta.translation)[None], Tb.rotation[None])
        return float(pos[0]), (float(rot[0]) if self.has_orientation else None)

    def robot_errors(self, robot, q) -> tuple[float, float | None]:
        """:meth:`pair_errors` at ``q`` (n,), from Pinocchio's kinematics."""
        return self.pair_errors(robot.fk(q, self.frame_a), robot.fk(q, self.frame))

    def robot_population_errors(self, robot, Q) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`placement_errors` of a population Q (N, n), from the robot's batch kinematics."""
        P, R = robot.fk_batch(Q, validate=False, frames=[self.frame_a, self.frame])
        return self.placement_errors(R[:, 0], P[:, 1] - P[:, 0], R[:, 1])

    def pack(self, robot) -> tuple[np.ndarray, np.ndarray]:
        """(aux row, support row (m,) bool) of this goal on ``robot`` (the ``A_REL_*`` layout above). FrameError for
        an unknown frame, or two frames no joint moves apart (nor, with :attr:`both`, turns together)."""
        ja, Ra, pa = robot.frame_constants(self.frame_a)
        jb = robot.frame_constants(self.frame)[0]
        tree = robot.tree
        on_a, on_b = np.zeros(tree.m, dtype=bool), np.zeros(tree.m, dtype=bool)
        on_a[tree.ancestors(ja)], on_b[tree.ancestors(jb)] = True, True
        signs = on_b.astype(float) - on_a.astype(float)  # joints moving both move the two frames together
        shared = on_a & on_b
        # with ``both`` set (a vector in the world's axes) a revolute joint moving both frames turns the vector: two
        # frames on one link still make a goal then (a head's direction from the neck)
        if not signs.any() and not (self.both and (shared & tree.revolute).any()):
            raise FrameError(f"no active joint of {robot.name} moves frame {self.frame!r} relative to "
                             f"{self.frame_a!r}: load the robot with both among its tips (tips=[...]) or tips='all'")
        signs[shared] = self.both
        aux = np.zeros(A_REL_SIGNS + tree.m)
        aux[A_REL_JOINT] = ja
        aux[A_REL_R:A_REL_R + 9] = Ra.ravel()
        aux[A_REL_P:A_REL_P + 3] = pa
        if self.aux() is not None:  # bands, free axes
            aux[A_REL_BAND:A_REL_BAND + AUX_SIZE] = self.aux()
        aux[A_REL_SIGNS:] = signs
        return aux, on_a | on_b
