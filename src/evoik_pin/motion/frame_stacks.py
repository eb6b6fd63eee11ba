"""A retargeted clip's warm-started frame solves on goal stacks bound once per clip: only the targets change per
frame.

A frame's goal list (:func:`~evoik_pin.motion.retarget._frame_goals`) has one of a few structures over a clip: which
feet are held (a held foot's Position and stance level band, or a swing foot's floor band and swing level band),
the tolerances (normal, or relaxed for a colliding frame's retry) and the held feet's weight (normal or firm). Each
structure's goal list is made and bound once (:func:`evoik_pin.goals.stack.bind`'s checks, its
:class:`~evoik_pin.goals.stack.GoalStack`) with a Levenberg-Marquardt engine on it
(:class:`~evoik_pin.solvers.lm.engine.LevenbergMarquardt`); a frame writes its targets into that engine
(``set_targets``), its velocity box (``confine``) and makes one LM run from ``q0``: the run ``memetic`` makes with the
retargeter's per-frame options (no seed table, no restarts; its first run from ``q0`` is made whatever the clock
says), without building goal objects, binding them, setting up a solver and a kinematics pass of the goal errors
per frame (the kernel's errors at the answer are reported, as memetic does for one goal and the velocity-box stage
for any).

The targets that do not depend on the previous frame (the root, the heading, the limbs, the other mapped points)
are computed for every frame at once when the stacks are made; the feet's (hold points, floor clearance, level
orientation) come per frame.
"""

from __future__ import annotations

import numpy as np

from ..goals.pointing import unit_vector
from ..goals.stack import owned
from ..solvers.lm.engine import LevenbergMarquardt
from ..solvers.lm.layout import DEFAULT_ITERATIONS, wrapping_joints
from ..solvers.search.memetic_runs import kernel_goal_errors

__all__ = ["FrameStacks", "FrameSolve"]

#: Structures a clip keeps engines for (4 contact states x normal / firm / relaxed: at most 12; more would mean a
#: changed goal layout, and the oldest is dropped).
KEPT_STRUCTURES = 16


class FrameSolve:
    """One frame's answer: ``q`` (n,), ``success`` (every goal within its tolerance, on the kernel's errors at q, as
    memetic and the velocity-box stage judge them) and the frame's ``goals`` (the structure's goal objects: their
    kinds and tolerances; their targets are those of the frame the structure was first bound on);
    :attr:`goal_errors` read on demand from the run's outcome."""

    __slots__ = ("_outcome", "goals", "q", "success")

    def __init__(self, q: np.ndarray, success: bool, outcome, goals: list) -> None:
        self.q, self.success, self._outcome, self.goals = q, success, outcome, goals

    @property
    def goal_errors(self) -> list:
        """Per goal (position m or None, angle rad or None): the kernel's at q (:meth:`Goal.reported`)."""
        return kernel_goal_errors(self.goals, self._outcome)


class _MetTest:
    """Whether an LM outcome meets every goal of a list (each goal's :meth:`~evoik_pin.goals.Goal.met` on the
    kernel's errors, :func:`kernel_goal_errors`), on arrays: the goals' tolerances and which errors they report,
    read once per goal stack."""

    def __init__(self, goals: list) -> None:
        self._goals = goals
        self._position = np.array([g.has_position for g in goals], dtype=bool)
        self._angle = np.array([g.reports_angle for g in goals], dtype=bool)
        try:
            self._tolerance = np.array([g.tolerance for g in goals], dtype=float)
            self._rotation_tolerance = np.array([g.rotation_tolerance for g in goals], dtype=float)
        except (TypeError, ValueError):  # a tolerance that is no number: each goal's own test
            self._tolerance = None

    def __call__(self, out) -> bool:
        if self._tolerance is None or out.goal_errors is None:
            return all(g.met(p, r) for g, (p, r) in zip(self._goals, kernel_goal_errors(self._goals, out),
                                                           strict=True))
        e = out.goal_errors
        return bool(((~self._position | (e[:, 0] <= self._tolerance))
                     & (~self._angle | (e[:, 1] <= self._rotation_tolerance))).all())


class FrameStacks:
    """The goal stacks and LM engines of one clip's frames, by structure.

    Args:
        robot: the floating-base :class:`~evoik_pin.Robot` of the clip.
        plan: the retargeter's ``_Plan`` (roles, limbs, the scaled source, contacts, floor).
        goals_of: ``goals_of(i, holds, tolerances, contact_weight, clearance, level)``: frame i's goal list (the
            retargeter's ``_frame_goals``), called once per structure; :meth:`targets` writes the same targets in
            the same order (tests/test_retarget.py holds them equal).
        floor_band: the half-height (m) of a swing foot's floor band (``retarget.FLOOR_BAND``).
    """

    def __init__(self, robot, plan, goals_of, floor_band: float) -> None:
        self.robot, self.plan, self._goals_of, self._floor_band = robot, plan, goals_of, float(floor_band)
        self._stacks: dict = {}
        self.front, self.back = self._fixed_targets()

    # ------------------------------------------------------------------ targets of every frame at once
    def _fixed_targets(self) -> tuple[np.ndarray, np.ndarray]:
        """(front (N, F, 3), back (N, B, 3)) m or unit vectors: the goal targets before the feet's (the root's
        Position, the heading's Direction, each limb's RelativePosition or Direction) and after them (the other
        mapped frames' Positions), for every frame, in the goal list's order."""
        plan = self.plan
        points = plan.points  # (N, K, 3)
        n_frames = points.shape[0]

        def src(frame: str) -> np.ndarray:
            return points[:, plan.src_index[frame]]

        front = [_root_targets(plan, src)]
        axes = _pelvis_axes(plan, src)
        if axes is not None and plan.left_axis is not None:
            # Direction normalises its target (unit_vector): the same arithmetic per frame
            front.append(np.array([unit_vector(v, "heading") for v in axes[:, :, 1]]))
        in_limbs = {plan.roles["pelvis"]}
        for limbs in plan.limbs.values():
            for a, b in limbs:
                in_limbs.update((a, b))
                length = np.linalg.norm(plan.neutral[b].translation - plan.neutral[a].translation)
                vectors = _unit(src(b) - src(a)) * length
                if (a, b) in plan.rigid:
                    vectors = np.array([unit_vector(v, "limb") for v in vectors])
                front.append(vectors)
        back = [src(frame) for frame, _ in plan.pairs if frame not in in_limbs and frame not in plan.contacts]
        stacked = [np.stack(parts, axis=1) if parts else np.zeros((n_frames, 0, 3)) for parts in (front, back)]
        return stacked[0], stacked[1]

    # ------------------------------------------------------------------ per frame
    def _key(self, i: int, holds: dict, tolerances: dict, contact_weight: float) -> tuple:
        plan = self.plan
        held = tuple(bool(flags[i]) and frame in holds for frame, flags in plan.contacts.items())
        return held, id(tolerances), float(contact_weight)

    def targets(self, i: int, holds: dict, clearance: dict, level: dict, pt: np.ndarray, Rt: np.ndarray) -> None:
        """Write frame i's targets into ``pt`` (G, 3) and the level rows of ``Rt`` (G, 3, 3) (the others stay the
        identity): the front, then each foot's hold point or floor band, then each foot's level orientation, then the
        back (:meth:`_fixed_targets`)."""
        plan = self.plan
        front, back = self.front[i], self.back[i]
        k = len(front)
        pt[:k] = front
        for frame, flags in plan.contacts.items():
            if flags[i] and frame in holds:
                pt[k] = holds[frame]
            elif plan.ground is not None:
                xy = plan.src(frame, i)[:2] if frame in plan.src_index else np.zeros(2)
                pt[k] = (xy[0], xy[1], plan.ground + clearance[frame] + self._floor_band)
            else:
                continue
            k += 1
        for frame in plan.contacts:
            pt[k] = 0.0
            Rt[k] = level[frame]
            k += 1
        pt[k:] = back

    def prepare(self, tolerances: dict, contact_weight: float, lower: np.ndarray, upper: np.ndarray) -> None:
        """Bind now (clip set-up) the structures the warm-started frames will use with these ``tolerances`` and
        ``contact_weight``: one per combination of the feet's contact flags over frames 1.. (a foot in contact is
        held there), on a box ``[lower, upper]`` (n,) like a frame's (nothing when a joint spans a full turn in
        it: those frames take the general solve)."""
        plan = self.plan
        if not self.usable(lower, upper):
            return
        first: dict[tuple, int] = {}  # each combination of flags -> the first frame (from 1) that has it
        for i in range(1, plan.points.shape[0]):
            first.setdefault(tuple(bool(flags[i]) for flags in plan.contacts.values()), i)
        clearance = dict(plan.sole)
        level = {f: plan.neutral[f].rotation for f in plan.contacts}
        for row, i in first.items():
            holds = {f: np.array(plan.neutral[f].translation) for f, held in zip(plan.contacts, row, strict=True)
                     if held}
            key = self._key(i, holds, tolerances, contact_weight)
            if key not in self._stacks:
                self._stacks[key] = self._bind(i, holds, clearance, level, tolerances, contact_weight, lower, upper)

    def usable(self, lower: np.ndarray, upper: np.ndarray) -> bool:
        """Whether a frame's box ``[lower, upper]`` (n,) runs on a confined engine: no joint spans a full turn in it
        (a confined engine does not wrap; such a box goes to the general solve)."""
        return not wrapping_joints(self.robot, lower, upper).any()

    def solve(self, i: int, holds: dict, clearance: dict, level: dict, tolerances: dict, contact_weight: float,
              q0: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> FrameSolve:
        """Frame i's LM run from ``q0`` (n,) inside ``[lower, upper]`` (n,) (:meth:`usable`) on its structure's
        engine, the goals as ``goals_of`` makes them with these ``holds``, ``clearance``, ``level``, ``tolerances``
        and ``contact_weight``."""
        key = self._key(i, holds, tolerances, contact_weight)
        kept = self._stacks.get(key)
        if kept is None:
            kept = self._stacks[key] = self._bind(i, holds, clearance, level, tolerances, contact_weight,
                                                  lower, upper)
            if len(self._stacks) > KEPT_STRUCTURES:
                self._stacks.pop(next(iter(self._stacks)))
        goals, engine, pt, Rt, met = kept
        self.targets(i, holds, clearance, level, pt, Rt)
        engine.set_targets(pt, Rt)
        engine.confine(lower, upper)
        out = engine.run(q0, DEFAULT_ITERATIONS)
        return FrameSolve(out.q, met(out), out, goals)

    def _bind(self, i, holds, clearance, level, tolerances, contact_weight, lower, upper) -> tuple:
        """(goals, engine, pt (G, 3), Rt (G, 3, 3)) of a new structure: its goal list made by ``goals_of`` for frame
        i, bound into an IKProblem on the box ``[lower, upper]`` (no joint wrapping: :meth:`usable`) and an engine."""
        from ..call_setup import make_problem  # the public problem set-up (evoik_pin.make_problem)

        goals = self._goals_of(i, holds, tolerances, contact_weight=contact_weight, clearance=clearance,
                               level=level)
        problem, _ = make_problem(self.robot, goals, bounds=(lower, upper))
        engine = LevenbergMarquardt(problem)
        _, pt, Rt = problem.goal_stack()
        pt, Rt = owned(np.array(pt, dtype=float)), owned(np.array(Rt, dtype=float))
        # one run now, discarded: the engine's first targets and box (its compiled entry looked up), its workspace,
        # are set-up, not a frame's work
        engine.set_targets(pt, Rt)
        engine.confine(lower, upper)
        engine.run((lower + upper) / 2, DEFAULT_ITERATIONS)
        return problem.goals, engine, pt, Rt, _MetTest(problem.goals)


def _unit(v: np.ndarray) -> np.ndarray:
    """Rows of ``v`` (..., 3) normalised (a zero row stays zero): the retargeter's ``_unit``."""
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.divide(v, n, out=np.zeros_like(v), where=n > 1e-12)


def _pelvis_axes(plan, src) -> np.ndarray | None:
    """(N, 3, 3) the source pelvis's axes per frame (``_Plan.pelvis_axes`` for every frame), or None."""
    roles = plan.roles
    if "left_hip" not in roles or "right_hip" not in roles:
        return None
    lh, rh = src(roles["left_hip"]), src(roles["right_hip"])
    left = _unit(lh - rh)
    if "torso" in roles:
        up_hint = _unit(src(roles["torso"]) - (lh + rh) / 2)
    else:
        up_hint = np.broadcast_to(np.array([0.0, 0.0, 1.0]), left.shape)
    up = _unit(up_hint - np.einsum("ij,ij->i", up_hint, left)[:, None] * left)
    return np.stack([np.cross(left, up), left, up], axis=2)


def _root_targets(plan, src) -> np.ndarray:
    """(N, 3) m: ``_Plan.root_target`` for every frame."""
    roles = plan.roles
    axes = _pelvis_axes(plan, src)
    if axes is None:
        return np.array(src(roles["pelvis"]))
    centre = (src(roles["left_hip"]) + src(roles["right_hip"])) / 2
    return centre - (axes @ plan._facing()) @ plan.hip_offset

