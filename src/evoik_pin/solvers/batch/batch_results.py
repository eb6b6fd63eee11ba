"""What a batch of targets came to: arrays (:class:`BatchOutcome`), and what :func:`~evoik_pin.solve_many` returns
(:class:`BatchResults`: the arrays, and a :class:`~evoik_pin.Result` per target made on first access)."""

from __future__ import annotations

import math
import operator
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ...result import Result
from ..collision_verdict import with_collision_verdict

__all__ = ["SOURCE_Q0", "SOURCE_SINGLE", "SOURCE_TABLE", "BatchOutcome", "BatchResults"]

#: ``BatchOutcome.source`` codes: solved by the batched rounds from q0 / from a seed-table entry, or one by one.
SOURCE_Q0, SOURCE_TABLE, SOURCE_SINGLE = 0, 1, 2
_LABELS = {SOURCE_Q0: "q0", SOURCE_TABLE: "seed table"}


@dataclass
class BatchOutcome:
    """What a batch of N targets came to, as arrays (cheap to send between processes).

    Attributes:
        q: (N, n) answers. position_error (m), orientation_error (rad; NaN for targets without orientation),
            cost, time_s (s; a batched target's share of its rounds), evaluations: (N,).
        success: (N,) bool. source: (N,) int8, ``SOURCE_Q0`` / ``SOURCE_TABLE`` (batched rounds) or
            ``SOURCE_SINGLE`` (solved one by one: its full :class:`Result` is ``singles[i]``).
        collision_checked: the batched answers passed a scene's exact check.
        goal_errors: for goal lists, (N,) object array: each row's (G, 2) goal errors (position m, rotation rad or
            NaN for a goal without orientation), the errors above being the largest of them; None for single targets.
        note: appended to the message of every batched row's :class:`Result` (e.g. the joints a call locked).
    """

    q: np.ndarray
    position_error: np.ndarray
    orientation_error: np.ndarray
    cost: np.ndarray
    success: np.ndarray
    evaluations: np.ndarray
    time_s: np.ndarray
    source: np.ndarray
    singles: dict[int, Result] = field(default_factory=dict)
    collision_checked: bool = False
    goal_errors: np.ndarray | None = None
    note: str = ""

    @classmethod
    def empty(cls, N: int, n: int, goals: bool = False) -> BatchOutcome:
        """An outcome of N rows left to the one-by-one solver; ``goals``: rows of goal lists (``goal_errors`` kept)."""
        nan = np.full(N, np.nan)
        return cls(np.zeros((N, n)), nan, nan.copy(), nan.copy(), np.zeros(N, dtype=bool), np.zeros(N, dtype=np.int64),
                   np.zeros(N), np.full(N, SOURCE_SINGLE, dtype=np.int8),
                   goal_errors=np.full(N, None, dtype=object) if goals else None)

    def __len__(self) -> int:
        return int(self.q.shape[0])

    def set_single(self, i: int, r: Result) -> None:
        self.singles[i] = r
        self.q[i] = r.q
        self.position_error[i] = r.position_error
        self.orientation_error[i] = np.nan if r.orientation_error is None else r.orientation_error
        self.cost[i], self.success[i], self.evaluations[i], self.time_s[i] = r.cost, r.success, r.evaluations, r.time_s
        self.source[i] = SOURCE_SINGLE
        if self.goal_errors is not None and r.goal_errors is not None:
            self.goal_errors[i] = np.array([(np.nan if p is None else p, np.nan if o is None else o)
                                            for p, o in r.goal_errors], dtype=float)

    def put(self, rows: np.ndarray, res, mask: np.ndarray) -> None:
        """Rows ``rows`` set from the batched LM answers ``res`` (:func:`~evoik_pin.solvers.lm.solve_pairs`') where
        ``mask``; their cost, success, time and source are the caller's."""
        self.q[rows] = res.q[mask]
        self.position_error[rows] = res.position_error[mask]
        if res.orientation_error is not None:
            self.orientation_error[rows] = res.orientation_error[mask]
        self.evaluations[rows] = res.evaluations[mask]
        if self.goal_errors is not None:  # one by one: a slice assignment would broadcast the (G, 2) arrays
            for r, v in zip(rows.tolist(), res.goal_errors[mask], strict=True):
                self.goal_errors[r] = v

    @classmethod
    def concatenate(cls, parts: list[BatchOutcome]) -> BatchOutcome:
        """One outcome of consecutive parts (their ``singles`` re-indexed)."""
        if len(parts) == 1:
            return parts[0]
        out = cls(*(np.concatenate([getattr(p, name) for p in parts]) for name in
                    ("q", "position_error", "orientation_error", "cost", "success", "evaluations", "time_s",
                     "source")), collision_checked=any(p.collision_checked for p in parts),
                  goal_errors=None if parts[0].goal_errors is None else np.concatenate([p.goal_errors for p in parts]))
        start = 0
        for p in parts:
            out.singles.update({start + i: r for i, r in p.singles.items()})
            start += len(p)
        return out

    def result(self, j: int, template=None) -> Result | None:
        """Target ``j``'s :class:`Result` (None for a target left unsolved without a per-target solve).
        ``template``: the problem of the call (with a scene, a batched answer gets its collision verdict,
        ``min_distance`` included)."""
        single = self.singles.get(j)
        if single is not None or self.source[j] == SOURCE_SINGLE:
            return single
        made = self.__dict__.get("_made")
        if made is None:
            # the Results copy one real Result's __dict__ (cheaper than the dataclass __init__), from the columns
            # as Python lists (cheaper to read item by item than NumPy scalars)
            base = Result(q=self.q[0], position_error=0.0, orientation_error=None, cost=0.0, success=True,
                          generations=0, evaluations=0, time_s=0.0, method="memetic",
                          collision_free=True if self.collision_checked else None).__dict__
            messages = {s: f"tolerance reached by batched LM from {label} (solve_many){self.note}"
                        for s, label in _LABELS.items()}
            history = np.zeros((len(self), 3, 1))
            history[:, 0, 0] = history[:, 1, 0] = self.cost
            rot = [None if math.isnan(v) else v for v in self.orientation_error.tolist()]
            made = self.__dict__["_made"] = (base, messages, history, rot, *(
                a.tolist() for a in (self.position_error, self.cost, self.evaluations, self.time_s, self.source)))
        base, messages, history, rot, pos, cost, evals, times, source = made
        h = history[j]
        d = base.copy()
        d.update(q=self.q[j], position_error=pos[j], orientation_error=rot[j], cost=cost[j], evaluations=evals[j],
                 time_s=times[j], message=messages[source[j]],
                 history={"best_cost": h[0], "mean_cost": h[1], "diversity": h[2]})
        if self.goal_errors is not None:
            d["goal_errors"] = [(None if math.isnan(p) else p, None if math.isnan(o) else o)
                                for p, o in self.goal_errors[j].tolist()]
        r = Result.__new__(Result)
        r.__dict__ = d
        if template is not None and template.scene is not None:
            r = with_collision_verdict(template, r)
        return r

    def results(self, template=None) -> list[Result]:
        """Every target's :class:`Result`, in order (see :meth:`result`)."""
        return [self.result(j, template) for j in range(len(self))]


def _column(name: str, doc: str) -> property:
    """A read-only view of the outcome's array ``name``, as a property of :class:`BatchResults`."""

    def view(self) -> np.ndarray:
        a = getattr(self.outcome, name).view()
        a.flags.writeable = False
        return a

    return property(view, doc=doc)


class BatchResults(Sequence):
    """What :func:`evoik_pin.solve_many` returns: one :class:`Result` per target, in order, made on first access
    (``results[i]``, iteration, slices), the same answers as read-only arrays (``q``, ``success``, ``position_error``,
    ``orientation_error``, ``cost``, ``evaluations``: one row per target), and ``stats``.

    ``stats`` (a dict): ``n`` targets, ``solved``, ``success_rate``, ``time_s`` (wall clock of the whole call),
    ``throughput`` (targets per second, ``n / time_s``), ``batched`` (targets solved by the batched LM rounds),
    ``fallback`` (targets handed to the per-target solver, and of those ``fallback_solved``), ``workers`` and
    ``backend``.
    """

    def __init__(self, outcome: BatchOutcome, template=None, stats: dict | None = None) -> None:
        self.outcome = outcome
        self.template = template
        self.stats = stats or {}
        self._made: list[Result | None] = [None] * len(outcome)

    def __len__(self) -> int:
        return len(self._made)

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(len(self)))]
        i = operator.index(i)
        N = len(self._made)
        if i < 0:
            i += N
        if not 0 <= i < N:
            raise IndexError(f"target index {i} out of range for {N} results")
        r = self._made[i]
        if r is None:
            r = self._made[i] = self.outcome.result(i, self.template)
        return r

    def __repr__(self) -> str:
        s = self.stats
        return (f"<BatchResults: {len(self)} targets, {s.get('solved', int(self.success.sum()))} solved"
                + (f", {s['throughput']:,.0f} targets/s" if "throughput" in s else "") + ">")

    q = _column("q", "(N, n) answers (rad or m).")
    success = _column("success", "(N,) bool: the answer meets the tolerances (and, with a scene, is collision-free).")
    position_error = _column("position_error", "(N,) tip position errors (m).")
    orientation_error = _column("orientation_error", "(N,) tip orientation errors (rad); NaN without orientation.")
    cost = _column("cost", "(N,) objective values.")
    evaluations = _column("evaluations", "(N,) forward-kinematics evaluations per target.")
