"""What every solver returns: a :class:`Result` (and, for multi-objective methods, a :class:`Front`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Front", "Result"]


@dataclass
class Front:
    """A Pareto set: ``q`` (M, n) joint vectors, ``objectives`` (M, k) values, ``violation`` (M,) >= 0."""

    q: np.ndarray
    objectives: np.ndarray
    violation: np.ndarray

    def __len__(self) -> int:
        return int(self.q.shape[0])


@dataclass
class Result:
    """Outcome of one IK solve.

    Attributes:
        q: (n,) best joint vector (rad or m), inside the search bounds.
        position_error: tip position error of ``q`` (m).
        orientation_error: tip orientation error of ``q`` (rad); None for position-only targets.
        cost: objective value of ``q``.
        success: True when the errors are within the problem's tolerances.
        generations: generations (iterations) run.
        evaluations: configurations evaluated (forward kinematics of one joint vector = 1).
        time_s: wall-clock time of the solve (s); one-time set-up is not part of it (see ``setup_s``).
        history: per-generation series, each an array of length ``generations + 1`` (the initial
            population first): ``best_cost``, ``mean_cost``, ``diversity``, plus method-specific ones.
        message: why the solver stopped, or what went wrong.
        method: registered name of the solver.
        solutions: distinct IK solutions (each a Result), best first, for all-solutions methods.
        front: the final Pareto set, for multi-objective methods.
        setup_s: one-time set-up this call paid outside its clock (s): loading the compiled code, building a seed
            table; 0 once the process has done it (:func:`evoik_pin.prepare`).
        goal_errors: for a goal list, each goal's (position error m, rotation angle rad or None) at ``q``;
            ``position_error`` and ``orientation_error`` are then the largest of them. None for a single target.
        collision_free: with a scene, whether ``q`` passes the exact mesh check at the problem's margin (``success``
            requires it); None without a scene.
        min_distance: with a scene, the signed distance (m) of the closest checked pair at ``q``, computed on first
            access; None without a scene.
    """

    q: np.ndarray
    position_error: float
    orientation_error: float | None
    cost: float
    success: bool
    generations: int
    evaluations: int
    time_s: float
    history: dict[str, np.ndarray] = field(default_factory=dict)
    message: str = ""
    method: str = ""
    solutions: list[Result] | None = None
    front: Front | None = None
    setup_s: float = 0.0
    collision_free: bool | None = None
    goal_errors: list[tuple[float, float | None]] | None = None
    #: for a goal list, per goal the index of the member of its goal set ``q`` meets (``Pose(frame, [T1, ...])``),
    #: None for a goal with one target (:meth:`~evoik_pin.problem.IKProblem.chosen`); None for a single target
    chosen: list[int | None] | None = None
    #: min_distance's value, or a callable computing it on first access (see ``min_distance``)
    distance_source: object = field(default=None, repr=False, compare=False)

    @property
    def min_distance(self) -> float | None:
        if callable(self.distance_source):
            self.distance_source = float(self.distance_source())
        return self.distance_source

    def __repr__(self) -> str:
        rot = "" if self.orientation_error is None else f", orientation_error={self.orientation_error:.3g} rad"
        return (
            f"Result(method={self.method!r}, success={self.success}, position_error={self.position_error:.3g} m"
            f"{rot}, generations={self.generations}, evaluations={self.evaluations}, time_s={self.time_s:.4g}, "
            f"message={self.message!r})"
        )
