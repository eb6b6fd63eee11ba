"""Choosing among answers: goal sets (any one of several targets), ``prefer="nearest" | "manipulability"``
(TRAC-IK's Distance and Manip1) and preferences (:mod:`evoik_pin.goals.preferences`).

* **Goal sets** (``Pose(frame, [T1, ..., Tk])``): the problem's combinations of members
  (:meth:`~evoik_pin.problem.IKProblem.variants`) are ranked by the seed table's nearness (one compiled call for
  all of them, :func:`.nearest.table_distances_many`: the distance of each to its nearest table entry), then
  tried round by round: LM from ``q0`` and
  each variant's nearest entry, then each one's next entries, the variants whose last run came nearest first. An
  unreachable member costs a stalled LM run or two (about 10 us each), so ten members of which seven are out of
  reach cost little more than one. When the table's starts are spent, memetic's own search runs on the variants
  that came nearest, sharing the time left.
* **prefer**: ``"first"`` stops at the first answer (memetic's behaviour); ``"nearest"`` and ``"manipulability"``
  keep collecting answers for :data:`COLLECT_SHARE` of the budget (LM from ``q0`` first, then batches of the
  table's entries nearest each variant, the first batch whatever the clock says; for "nearest" the entries nearest
  in pose *and* near q0 in joint space (:data:`NEAR_JOINT_WEIGHT`) and one start in :data:`NEAR_EVERY` drawn around
  q0; then uniform random starts), then take the best of them along the goals' self-motion manifold and return the
  best. prefer acting alone on the compiled engine: the compiled descent (:mod:`..lm.nullspace`, :func:`_descend`:
  projected criterion steps, each restored onto the goals by Gauss-Newton and kept only when every goal is met and
  the criterion improved; a few steps for each of the best :data:`DESCEND_COUNT` distinct answers, then the best
  two on to their optimum in as many steps as the clock allows); with further preferences (or the Python engine):
  :func:`refine`, the same step in Python, on the best :data:`REFINE_COUNT`.
  Nearness is ``|q - q0|`` with joints whose range spans a full turn taken to their turn nearest ``q0`` inside the
  box (:func:`nearest_turn`). The budget is ``timeout``, :data:`DEFAULT_PREFER_TIMEOUT` (0.7 ms) unless given.
* **Preferences** add their costs to what answers are ranked and refined by; with ``prefer="first"`` the method's
  own answer is refined alone (:meth:`evoik_pin.IKSolver.solve`), so they never cost success.

Why a null-space step and a ranking, both: on a redundant arm (Panda on a pose: a one-dimensional self-motion)
the answers LM finds from random starts lie anywhere on the self-motion manifold, and projected steps take the best
of them to the local optimum of the criterion on their branch (measured in ``scripts/bench_goal_kinds_prefer.py``:
the Python refinement, 30 us a step, got a few steps within 0.7 ms, and Panda's answer was no farther than TRAC-IK's
5 ms Distance's on 80-89 % of the targets; the compiled descent, 1-2 us a step, converges on several answers and
reaches 91-96 %, the misses being branches the collection did not find; table starts near q0 in joint space as well
as near the pose, 98-100 %: 42 % of such starts lead to an answer no farther than TRAC-IK's, 26 % of those ranked
by pose alone); on a non-redundant arm (UR10 on a pose) the null space is empty and only the ranking of the distinct
answers (at most 8 branches) acts.
"""

from __future__ import annotations

import copy
import itertools
import time

import numpy as np

from ...errors import MethodError, OptionError
from ...goals.preferences import Manipulability, Posture
from ...goals.registry import KIND_BEYOND_FRAME, TASK_ROWS
from ...goals.stack import owned, target_kind
from ...problem import errors_text, shortfall_text
from ...result import Result
from ..lm import LevenbergMarquardt, wrapping_joints
from ..lm.layout import S_CONVERGED, S_COST, S_EVALUATIONS, S_POS, S_ROT, STATS_SIZE, kernel_params
from ..lm.nullspace import MODE_MANIPULABILITY, MODE_NEAREST, nullspace_kernel
from ..options import check_choice
from . import memetic as memetic_module
from .nearest import table_distances_many
from .seed_table import DEFAULT_GOAL_TABLE_SEEDS, DEFAULT_TABLE_SEEDS

__all__ = ["COLLECT_SHARE", "DEFAULT_PREFER_TIMEOUT", "PREFER", "REFINE_COUNT", "choose", "nearest_turn", "refine"]

#: The answers ``prefer`` picks among: the first found, the nearest q0, the most dexterous.
PREFER = ("first", "nearest", "manipulability")
#: Default budget (s) of ``prefer="nearest" | "manipulability"``: about 1 ms with the call's overhead, a fifth of
#: TRAC-IK's 5 ms Distance / Manip1 modes, which always spend their whole budget.
DEFAULT_PREFER_TIMEOUT = 0.0007
#: Share of the budget spent collecting answers before the best ones are refined.
COLLECT_SHARE = 0.6
#: Share of the budget left for making the answer (its errors, the result) after the refinement.
FINISH_SHARE = 0.1
#: Answers refined in the null space (best first; two closer than 1e-3 rad count once).
REFINE_COUNT = 4
#: Null-space steps of one refinement at most (the winner's; each of the best answers first gets TRIAL_STEPS); LM
#: steps restoring the goals after each.
REFINE_STEPS, TRIAL_STEPS, RESTORE_ITERATIONS = 12, 3, 10
#: Largest null-space step (rad or m, Euclidean).
MAX_REFINE_STEP = 0.5
#: The compiled descent (prefer alone, :func:`_descend`): the best DESCEND_COUNT distinct answers (MANIP_COUNT for
#: manipulability, whose gradient costs n kinematics evaluations a step) descended DESCEND_TRIAL steps each, of which
#: the best DESCEND_FINAL go on in rounds of DESCEND_STEPS steps while the clock allows (DESCEND_ROUNDS at most);
#: steps of DESCEND_MAX_STEP (rad or m) at most (measured: 0.5 converges more slowly, 2 lands on worse branches
#: more often).
DESCEND_COUNT, MANIP_COUNT, DESCEND_TRIAL, DESCEND_FINAL, DESCEND_STEPS, DESCEND_ROUNDS = 8, 4, 4, 2, 10, 4
DESCEND_MAX_STEP = 1.0
#: prefer="nearest": the best answers (this many) get the first round of DESCEND_STEPS whatever the clock says (a
#: loaded machine's clock otherwise cut it off after the trial's steps). Measured on Panda against TRAC-IK's Distance,
#: interleaved: 98.2 % no farther with one, 96.4 % with none, the solve's median time equal to before this change's
#: (two: 50 us more); manipulability's steps cost n evaluations more each: none.
SURE_FINAL = 1
#: prefer="nearest" draws one start in NEAR_EVERY around q0, with these standard deviations (times each joint's
#: half-range, at most pi) in turn.
NEAR_SCALES = (0.1, 0.25, 0.5)
#: prefer="nearest" ranks the seed table by pose nearness plus this times the squared joint distance to q0 (rad^2),
#: times the table's weight squared (its m per unit of rotation distance, a quarter of the reach: the term scales with
#: the arm): 1 rad from q0 counts like sqrt(NEAR_JOINT_WEIGHT) quarter-reaches of pose distance.
NEAR_JOINT_WEIGHT = 0.1
NEAR_EVERY = 4
#: LM runs per kernel call while prefer collects answers, and their steps at most (None: memetic's iterations).
COLLECT_BATCH = 16
COLLECT_ITERATIONS = None
#: The batch on goals without a null space (UR10 on a pose), whose whole budget collects: the answer is the nearest
#: branch found, and more runs find more of the branches. Measured on UR10 against TRAC-IK's Distance (each target
#: solved with each size in turn, the order rotated, 272-363 targets of three seeds): no farther on 97.1-97.9 % with
#: 32, 95.6 % with 24, 90.4-95.0 % with 16; the median solve 5-10 % slower with 32 than with 16 (the first batch
#: runs whatever the clock says), 48: 98.5 % and 20 % slower.
COLLECT_BATCH_BRANCHES = 32
#: Table entries tried per variant of a goal set in the first rounds (at least).
MIN_SEEDS_PER_VARIANT = 4


def check_prefer(prefer, q0_given: bool = True) -> str:
    """``prefer`` checked: one of :data:`PREFER`; OptionError naming them otherwise, or for "nearest" without a q0
    (``q0_given`` False)."""
    prefer = check_choice("prefer", prefer, PREFER)
    if prefer == "nearest" and not q0_given:
        raise OptionError("prefer='nearest' picks the answer nearest q0: give q0 (the current joints)")
    return prefer


def check_prefer_method(prefer: str, method: str) -> None:
    """MethodError for ``prefer`` other than ``"first"`` with a method other than memetic: it gives one answer,
    nothing to choose among."""
    if prefer != "first" and method != "memetic":
        raise MethodError(f"prefer={prefer!r} collects answers with method 'memetic'; {method!r} gives one "
                          "(use prefer='first', the default)")


def nearest_turn(q: np.ndarray, q0: np.ndarray, lower: np.ndarray, upper: np.ndarray, wrap: np.ndarray) -> np.ndarray:
    """``q`` (n,) with each ``wrap`` joint (its range spans a full turn) moved by a multiple of 2 pi to the value
    nearest ``q0`` that stays inside [lower, upper] (the same pose: a full turn)."""
    if not wrap.any():
        return q
    two_pi = 2.0 * np.pi
    shifted = q + two_pi * np.round((q0 - q) / two_pi)
    shifted = np.where(shifted > upper, shifted - two_pi, shifted)
    shifted = np.where(shifted < lower, shifted + two_pi, shifted)
    ok = wrap & (shifted >= lower) & (shifted <= upper)
    return np.where(ok, shifted, q)


class Criterion:
    """The sum of bound preferences (``prefer``'s term first), what answers are ranked and refined by."""

    def __init__(self, terms: list) -> None:
        self.terms = terms
        self.curvature = sum(t.curvature for t in terms)

    def __bool__(self) -> bool:
        return bool(self.terms)

    def cost(self, q: np.ndarray) -> float:
        return float(sum(t.cost(q) for t in self.terms))

    def costs(self, Q: np.ndarray) -> np.ndarray:
        """:meth:`cost` of each row of ``Q`` (N, n)."""
        return sum((t.costs(Q) for t in self.terms), np.zeros(Q.shape[0]))

    def analytic_gradient(self, q: np.ndarray) -> np.ndarray | None:
        """d cost / dq (n,) when every term has it in closed form, else None."""
        total = np.zeros(q.shape[0])
        for t in self.terms:
            g = t.gradient(q)
            if g is None:
                return None
            total += g
        return total

    def null_gradient(self, q: np.ndarray, N: np.ndarray, f: float) -> np.ndarray:
        """The cost's gradient in the null-space basis ``N`` (r, n) (orthonormal rows): analytic terms exactly,
        the others (manipulability) by forward differences along each basis vector (``f``: the cost at q)."""
        c = np.zeros(N.shape[0])
        numeric = []
        for t in self.terms:
            g = t.gradient(q)
            if g is None:
                numeric.append(t)
            else:
                c += N @ g
        if numeric:
            h = 1e-6
            f0 = sum(t.cost(q) for t in numeric)
            for i in range(N.shape[0]):
                c[i] += (sum(t.cost(q + h * N[i]) for t in numeric) - f0) / h
        return c


def _redundant(problem) -> bool:
    """Whether the goals leave a null space to refine in: fewer task rows than joints."""
    if problem.goals is None:
        rows = len(TASK_ROWS[target_kind(problem.target)])
    else:
        rows = sum(len(TASK_ROWS.get(g.kind, range(6))) for g in problem.goals)
    return rows < problem.robot.n


def _task_jacobian(problem, q: np.ndarray, lm: LevenbergMarquardt) -> np.ndarray:
    """The goals' stacked task Jacobian (rows, n) at ``q``: its null space is the joint motion that leaves every goal
    met to first order. On the compiled engine, the rows LM's own step reads
    (:func:`..lm.population_rows.task_rows`), right
    for every kind: a free axis's swing rows (the turn about it is free), a band's and a support polygon's rows zero
    where inactive (inside), a relative pose's and a centre of mass's from their own Jacobians, LookAt's with the
    frame's motion across the line of sight. The Python engine (pose, position and planar goals only): the frames'
    base-frame rows (LOCAL_WORLD_ALIGNED; a pose goal's log6 error has the same null space)."""
    if lm.engine == "compiled":
        stack = lm.goals
        e, E, ge = np.empty(stack.rows), np.empty((stack.rows, lm.n)), np.empty((len(stack.kinds), 2))
        nullspace_kernel()["task_rows"](np.ascontiguousarray(q, dtype=float), *lm._tree, *lm._goal_arrays, lm._pt,
                                        lm._Rt, e, E, ge)
        return E
    robot = problem.robot
    if problem.goals is None:
        return robot.jacobian_world_unchecked(q)[list(TASK_ROWS[target_kind(problem.target)])]
    blocks = [robot.jacobian_world_unchecked(q, robot.frame_id(g.frame))[list(TASK_ROWS.get(g.kind, range(6)))]
              for g in problem.goals]
    return np.vstack(blocks)


def _null_basis(E: np.ndarray) -> np.ndarray:
    """Orthonormal basis (r, n) of the null space of ``E`` (rows, n)."""
    _, s, Vt = np.linalg.svd(E)
    rank = int(np.count_nonzero(s > 1e-9 * max(s[0], 1e-300))) if s.size else 0
    return Vt[rank:]


#: Smallest pivot of the Cholesky factor of E E^T, relative to its largest, for which :func:`_null_projection` trusts
#: it (a condition number of E E^T up to 1e8); below it, the SVD.
GRAM_PIVOT = 1e-4


def _null_projection(E: np.ndarray, g: np.ndarray) -> np.ndarray:
    """``g`` (n,) projected on the null space of ``E`` (rows, n). Zero rows (an inactive band's, a support polygon's
    with the CoM inside) bind nothing and are dropped; then ``g - E^T (E E^T)^-1 E g`` when the rows left are well
    independent (E E^T's Cholesky pivots within :data:`GRAM_PIVOT` of each other: a few microseconds), else by the
    SVD's null basis (tens to hundreds of microseconds): some kinds' rows are dependent by design (a free axis's
    three swing rows have rank two, LookAt's too near its answer)."""
    E = E[np.any(E != 0.0, axis=1)]
    if E.shape[0] == 0:
        return g
    if E.shape[0] < E.shape[1]:
        A = E @ E.T
        try:
            pivots = np.diagonal(np.linalg.cholesky(A))
            if pivots.min() > GRAM_PIVOT * pivots.max():
                return g - E.T @ np.linalg.solve(A, E @ g)
        except np.linalg.LinAlgError:  # not positive definite: dependent rows
            pass
    N = _null_basis(E)
    return N.T @ (N @ g)


def refine(problem, lm: LevenbergMarquardt, q: np.ndarray, criterion: Criterion, deadline: float | None,
           steps: int = REFINE_STEPS) -> tuple[np.ndarray, float, int]:
    """Lower ``criterion`` from an answer ``q`` (every goal met) by steps in the null space of the goals'
    Jacobian: the projected gradient step (scaled by the criterion's curvature, so a quadratic term's step is
    its minimum on the tangent plane; at most :data:`MAX_REFINE_STEP`), then an LM run from there restoring
    every goal within its tolerance. A step is kept only when that run converges, the cost drops and, with a
    scene, the configuration is collision-free (``problem.margin``); otherwise the step is halved. Returns (q, its
    cost, LM evaluations)."""
    f = criterion.cost(q)
    scale, evaluations = 1.0, 0
    scene = problem.scene
    for _ in range(steps):
        if deadline is not None and time.perf_counter() >= deadline:
            break
        E = _task_jacobian(problem, q, lm)
        g = criterion.analytic_gradient(q)
        if g is not None:
            proj = _null_projection(E, g)
        else:
            N = _null_basis(E)
            if N.shape[0] == 0:
                break
            proj = N.T @ criterion.null_gradient(q, N, f)
        norm = float(np.linalg.norm(proj))
        if norm < 1e-12:
            break
        step = -proj / criterion.curvature if criterion.curvature > 0 else -proj * (0.2 / norm)
        length = float(np.linalg.norm(step)) * scale
        step *= scale * min(1.0, MAX_REFINE_STEP / max(length, 1e-300))
        out = lm.run(q + step, RESTORE_ITERATIONS)
        evaluations += out.evaluations
        f_new = criterion.cost(out.q) if out.converged else np.inf
        if f_new < f - 1e-15 * max(1.0, abs(f)) and (scene is None or not scene.in_collision(out.q, problem.margin)):
            q, f, scale = out.q, f_new, min(1.0, 2.0 * scale)
        else:
            scale *= 0.5
            if scale < 1e-3:
                break
    return q, f, evaluations


def _descent_mode(prefer: str, criterion: Criterion, variants) -> int | None:
    """The compiled descent's mode (:mod:`..lm.nullspace`) for prefer="nearest" | "manipulability" alone (no
    further preferences) on the compiled engine; None otherwise (the Python :func:`refine` then)."""
    if prefer == "first" or len(criterion.terms) != 1 or any(v.lm.engine != "compiled" for v in variants):
        return None
    lm = variants[0].lm
    if lm._tree[4].shape[0] != lm.n or _mimic(lm):  # mimic joints: the descent leaves answers as they are
        return None
    return MODE_NEAREST if prefer == "nearest" else MODE_MANIPULABILITY


def _mimic(lm: LevenbergMarquardt) -> bool:
    """Whether the engine's tree couples physical joints to q (mimic joints; ``Robot.tree_constants``)."""
    index, scale, offset = lm._tree[4:7]
    return bool(np.any(index != np.arange(index.shape[0])) or np.any(scale != 1.0) or np.any(offset != 0.0))


def _descend(answers, variants, q0, mode: int, criterion: Criterion, scene, problem, wrap: np.ndarray,
             finish: float | None) -> tuple[list, int]:
    """prefer's answers (cost, q, variant), best first, taken along their self-motion manifolds by the compiled
    descent (:func:`..lm.nullspace.descend_batch`): the best :data:`DESCEND_COUNT` (:data:`MANIP_COUNT`) distinct
    ones :data:`DESCEND_TRIAL` steps each, then the best :data:`DESCEND_FINAL` of those :data:`DESCEND_STEPS` steps
    more a round, in rounds while the clock allows (until ``finish``; nearest's first round for the best
    :data:`SURE_FINAL` whatever it says) and they move. A descended
    answer in collision keeps its start. Returns the refined answers, best first, and the kinematics evaluations."""
    descend = nullspace_kernel()["descend_batch"]
    target = np.zeros(variants[0].lm.problem.robot.n) if q0 is None else owned(q0, float)
    picked = _distinct(answers, DESCEND_COUNT if mode == MODE_NEAREST else MANIP_COUNT)
    evaluations = 0

    def run(batch, steps):
        """Each answer of ``batch`` descended ``steps`` steps at most: one kernel call per variant, the answers'
        turns and costs for all of them at once (a Python call per answer cost as much as the descent)."""
        nonlocal evaluations
        out = []
        for i in sorted({a[2] for a in batch}):
            mine = [a for a in batch if a[2] == i]
            Q = np.array([a[1] for a in mine])
            Q_out, f = np.empty_like(Q), np.empty(Q.shape[0])
            evaluations += int(descend(Q, target, mode, *variants[i].lm._args, steps, RESTORE_ITERATIONS,
                                       DESCEND_MAX_STEP, Q_out, f))
            if scene is not None:
                for k in range(Q.shape[0]):
                    if scene.in_collision(Q_out[k], problem.margin):
                        Q_out[k] = Q[k]
            if q0 is not None:
                Q_out = nearest_turn(Q_out, q0, problem.lower, problem.upper, wrap)
            out.extend(zip(criterion.costs(Q_out).tolist(), Q_out, [i] * Q.shape[0], strict=True))
        return sorted(out, key=lambda a: a[0])

    picked = run(picked, DESCEND_TRIAL)
    for k in range(DESCEND_ROUNDS):  # rounds of the best on towards their optimum while the clock allows
        final = DESCEND_FINAL
        if finish is not None and time.perf_counter() >= finish:
            if k or mode != MODE_NEAREST or not SURE_FINAL:
                break
            final = SURE_FINAL  # nearest's first round, for the best, whatever the clock says
        before = [a[0] for a in picked[:final]]
        picked = sorted(run(picked[:final], DESCEND_STEPS) + picked[final:], key=lambda a: a[0])
        if [a[0] for a in picked[:final]] == before:  # converged
            break
    return picked, evaluations


def _distinct(answers, count: int) -> list:
    """The first ``count`` of ``answers`` (cost, q, variant; best first) no two of which are within 1e-3 (rad or
    m, Euclidean) of each other. One matrix of the pairs' distances, then plain Python: an array operation per
    answer cost some 100 us on 20 answers (measured)."""
    if len(answers) <= 1:
        return list(answers[:count])
    Q = np.array([a[1] for a in answers])
    G = Q @ Q.T
    sq = np.diag(G)
    close = ((sq[:, None] + sq[None, :] - 2.0 * G) < 1e-6).tolist()
    picked, taken = [], []
    for k, row in enumerate(close):
        if len(picked) >= count:
            break
        if not any(row[j] for j in taken):
            picked.append(answers[k])
            taken.append(k)
    return picked


def _criterion(problem, prefer: str, preferences, wrap: np.ndarray) -> Criterion:
    """prefer's term and the bound preferences. OptionError: prefer="nearest" without q0."""
    robot = problem.robot
    first_frame = problem.goals[0].frame if problem.goals is not None else None
    terms = []
    if prefer == "nearest":
        check_prefer(prefer, problem.q0 is not None)
        # plain differences: answers are taken to their turn nearest q0 inside the box first (nearest_turn), and
        # a difference modulo 2 pi would count turns the limits forbid
        terms.append(Posture(problem.q0).bind(robot, problem.q0, problem.lower, problem.upper, np.zeros_like(wrap)))
    elif prefer == "manipulability":
        terms.append(Manipulability(first_frame).bind(robot, problem.q0, problem.lower, problem.upper, wrap))
    for p in preferences:
        if isinstance(p, Manipulability):
            terms.append(p.bind(robot, problem.q0, problem.lower, problem.upper, wrap, first_frame))
        else:
            terms.append(p.bind(robot, problem.q0, problem.lower, problem.upper, wrap))
    return Criterion(terms)


def bind_preferences(problem, preferences) -> Criterion:
    """The preferences checked against the problem's robot (errors naming the joint or frame), as a criterion."""
    return _criterion(problem, "first", preferences, wrapping_joints(problem.robot, problem.lower, problem.upper))


class _Variant:
    """One combination of goal-set members (or the problem itself): its targets, its problem and LM engine (made on
    first use: most variants of a goal set run once or twice), its starts, its best run."""

    def __init__(self, parent, choice, pt, Rt, base_lm: LevenbergMarquardt | None, engine: str) -> None:
        self.parent, self.choice, self.pt, self.Rt = parent, choice, pt, Rt
        self._base_lm, self._engine = base_lm, engine
        self._problem = self._lm = None
        self.starts = iter(())
        self.best_rank = np.inf

    @property
    def problem(self):
        if self._problem is None:
            self._problem = self.parent.variant(self.choice, self.pt, self.Rt)
        return self._problem

    @property
    def lm(self) -> LevenbergMarquardt:
        if self._lm is None:
            base = self._base_lm
            if base is not None and base.engine == "compiled" and base._pt.shape == self.pt.shape:
                # the same goal stack and box, other targets: the kernel's arguments with those swapped
                lm = copy.copy(base)
                lm._pt, lm._Rt = np.ascontiguousarray(self.pt), np.ascontiguousarray(self.Rt)
                lm._args = (*base._args[:-2], lm._pt, lm._Rt)
                lm.problem = self.problem if self.parent.goal_sets else self.parent
                self._lm = lm
            else:
                self._lm = LevenbergMarquardt(self.problem, engine=self._engine)
        return self._lm


class _Around:
    """``starts`` with every :data:`NEAR_EVERY`-th start drawn around ``q0`` instead (normal, a standard deviation
    of :data:`NEAR_SCALES` times each joint's half-range, at most pi, in turn; clipped into the box); once ``starts``
    runs out, uniform random starts take its place when ``endless`` (a clock bounds the search), else the starts
    end with it. Taken a batch at a time (:meth:`take`): drawn one by one, the starts cost as much Python time as
    the LM runs took (measured)."""

    def __init__(self, starts, rng, q0: np.ndarray, lower: np.ndarray, upper: np.ndarray, endless: bool) -> None:
        self.starts, self.rng, self.q0, self.lower, self.upper, self.endless = starts, rng, q0, lower, upper, endless
        self.half = np.minimum(0.5 * (upper - lower), np.pi)
        self.k = 0  # near starts drawn so far (the scale cycles with it)
        self.done = False

    def take(self, size: int) -> np.ndarray:
        """Up to ``size`` starts (rows; none once the starts have ended)."""
        n = self.q0.shape[0]
        if self.done or size <= 0:
            return np.empty((0, n))
        m = -(-size // NEAR_EVERY)  # near q0: every NEAR_EVERY-th, the first included
        scales = np.take(NEAR_SCALES, np.arange(self.k, self.k + m) % len(NEAR_SCALES))[:, None] * self.half
        self.k += m
        near = np.minimum(np.maximum(self.q0 + self.rng.normal(size=(m, n)) * scales, self.lower), self.upper)
        rest = _take(self.starts, size - m, n)
        if rest.shape[0] < size - m:
            if self.endless:
                more = self.rng.uniform(self.lower, self.upper, size=(size - m - rest.shape[0], n))
                rest = np.concatenate([rest, more])
            else:
                self.done = True
        return np.concatenate([near, rest])


def _take(starts, size: int, n: int) -> np.ndarray:
    """Up to ``size`` starts (rows) from a start iterator, an :class:`_Around` or a :class:`_TableStarts`."""
    if isinstance(starts, (_Around, _TableStarts)):
        return starts.take(size)
    return np.array(list(itertools.islice(starts, size))).reshape(-1, n)


class _TableStarts:
    """Table entries by ``d`` (T,): ``first`` (its argmin), then the next ``k - 1`` nearest, ranked on first demand
    for more than ``first``. An iterator of rows, and :meth:`take` for a batch of them in one indexing (a generator's
    rows one by one, then stacked, cost 30-60 us of prefer's 0.7 ms per batch, more with cold caches: measured)."""

    def __init__(self, Q: np.ndarray, d: np.ndarray, first: int, k: int) -> None:
        self.Q, self.d, self.first, self.k = Q, d, first, min(k, d.shape[0])
        self.order: np.ndarray | None = None  # the entries' indices, nearest first (once ranked)
        self.next = 0  # entries handed out so far

    def _ranked(self) -> np.ndarray:
        if self.order is None:
            d, k, first = self.d, self.k, self.first
            rest = np.empty(0, dtype=np.intp)
            if k > 1:
                part = np.argpartition(d, k - 1)[:k] if k < d.shape[0] else np.arange(d.shape[0])
                rest = part[np.argsort(d[part])]
                rest = rest[(rest != first) & np.isfinite(d[rest])]
            self.order = np.concatenate([np.array([first], dtype=np.intp), rest])
        return self.order

    def take(self, size: int) -> np.ndarray:
        """Up to ``size`` entries (rows), the nearest not yet taken."""
        if self.next == 0 and size == 1 and self.order is None:  # q0's neighbour alone: no ranking yet
            self.next = 1
            return self.Q[self.first][None]
        order = self._ranked()
        picked = order[self.next:self.next + max(size, 0)]
        self.next += picked.shape[0]
        return self.Q[picked]

    def __iter__(self):
        return self

    def __next__(self) -> np.ndarray:
        rows = self.take(1)
        if rows.shape[0] == 0:
            raise StopIteration
        return rows[0]


def _variant_starts(table, parent, variants, k: int, free, joint=None, P=None, R=None) -> list[float]:
    """Give each variant its lazy table starts (q0 comes before, from the caller) and return each one's squared
    distance to its nearest table entry (the goals' summed nearness; zeros without a table). ``joint``: the
    entries' squared joint distances to q0 (size,) times :data:`NEAR_JOINT_WEIGHT` (m^2), added to their pose
    nearness (prefer="nearest"; a single target or one goal). P (V, G, 3), R (V, G, 3, 3): the variants' targets
    when the caller has them stacked."""
    if table is None:
        return [0.0] * len(variants)
    if parent.goals is None:  # one target on the tip (prefer= alone)
        if joint is None:
            variants[0].starts = (table.Q[i] for i in table.ranked(parent.target, k, free))
        else:
            d = table.distances(*table.one_target_features(parent.target)) + joint
            if free is not None:
                d[~free] = np.inf
            variants[0].starts = _TableStarts(table.Q, d, int(d.argmin()), k)
        return [0.0]
    if len(parent.goals) > 1:  # a whole robot: composed starts too (SeedTable.goal_starts), the sets' order
        for v in variants:
            v.starts = table.goal_starts(v.problem, k, free)
        return [float(i) for i in range(len(variants))]
    spec = table.goal_spec(parent.goals)
    if P is None:
        P, R = np.stack([v.pt for v in variants]), np.stack([v.Rt for v in variants])
    f = table.goal_features(spec, P, R)  # (V, d)
    FT, sq = table.one_goal_features32(parent.goals[0])  # the table's features of the goal's frame
    # |F - f|^2 = sq - 2 F.f + |f|^2: its first two terms compiled, in single precision (nearest.table_distances_many
    # says why), |f|^2 only where variants are compared
    D = np.empty((f.shape[0], FT.shape[1]), dtype=np.float32)
    table_distances_many(FT, sq, f.astype(np.float32), D)
    if joint is not None:
        D += joint
    if free is not None:
        D[:, ~free] = np.inf
    first = D.argmin(axis=1)
    for v, d, i in zip(variants, D, first, strict=True):
        v.starts = _TableStarts(table.Q, d, int(i), k)
    return (D[np.arange(len(variants)), first] + (f * f).sum(axis=1)).tolist()


def choose(problem, rng, *, prefer: str = "first", preferences=(), timeout: float | None = None,
           max_restarts: int | None = None, population: int = 32, generations: int = 3, polish_count: int = 8,
           table_size: int | None = None, table_seeds: int | None = None, table_offset: int = 0, batch: int = 1,
           iterations: int | None = None, engine: str = "compiled", plan=None) -> Result:
    """memetic over goal sets and with ``prefer`` / preferences (see the module docstring); memetic's options.

    ``timeout`` (s): the budget; default memetic's (5 ms) for ``prefer="first"``, :data:`DEFAULT_PREFER_TIMEOUT`
    for the others. ``table_offset`` is not used (the variants rank the table themselves). ``plan``: the
    :class:`~.memetic.MemeticPlan` handing a goal set over (an IKSolver's), whose LM engine is retargeted to the
    problem instead of a new one made.
    """
    from .memetic import DEFAULT_TIMEOUT, check_options, memetic, prepare

    prefer = check_prefer(prefer)
    if timeout is None and max_restarts is None:
        timeout = DEFAULT_TIMEOUT if prefer == "first" else DEFAULT_PREFER_TIMEOUT
    t_setup = time.perf_counter()
    robot = problem.robot
    from ..lm import DEFAULT_ITERATIONS

    iterations = DEFAULT_ITERATIONS if iterations is None else iterations
    (timeout, max_restarts, population, generations, polish_count, table_size, table_seeds, _, batch, iterations,
     engine) = check_options(timeout=timeout, max_restarts=max_restarts, population=population,
                             generations=generations, polish_count=polish_count, table_size=table_size,
                             table_seeds=table_seeds, table_offset=table_offset, batch=batch, iterations=iterations,
                             engine=engine, n=robot.n)
    wrap = wrapping_joints(robot, problem.lower, problem.upper)
    criterion = _criterion(problem, prefer, preferences, wrap)
    goals = problem.goals is not None
    choices, P, R = (problem.variant_targets() if goals else ([()], [None], [None]))
    base_lm = LevenbergMarquardt(problem, engine=engine) if plan is None else plan._engine(problem, engine)
    variants = [_Variant(problem, c, P[v], R[v], base_lm, engine) for v, c in enumerate(choices)]
    if len(variants) == 1:
        variants[0]._problem, variants[0]._lm = problem, base_lm
    if table_seeds is None:
        table_seeds = DEFAULT_GOAL_TABLE_SEEDS if goals else DEFAULT_TABLE_SEEDS
    use_table = table_size > 0 and table_seeds > 0
    table, free = prepare(robot, problem.lower, problem.upper, table_size if use_table else 0, engine,
                          problem.scene, problem.margin)
    if table is not None and goals:
        table.prepare_goals(problem.goals)
    if prefer != "first" and engine == "compiled":
        nullspace_kernel()  # compiled or loaded before the clock starts
    t0 = time.perf_counter()
    deadline = None if timeout is None else t0 + timeout
    collect_until = None if timeout is None else t0 + COLLECT_SHARE * timeout
    finish = None if timeout is None else t0 + (1.0 - FINISH_SHARE) * timeout  # then the answer is made
    redundant = _redundant(problem)
    per_variant = table_seeds if prefer != "first" else max(MIN_SEEDS_PER_VARIANT, table_seeds // len(variants))
    joint = None
    if prefer == "nearest" and table is not None and (not goals or len(problem.goals) == 1):
        # entries near q0 too: LM from them lands on answers near q0 (measured on Panda: 42 % of such starts
        # descend to an answer no farther than TRAC-IK's Distance's, 26 % by pose alone)
        joint = table.joint_distances(problem.q0, wrap)
        joint *= NEAR_JOINT_WEIGHT * table.weight**2
    near = _variant_starts(table, problem, variants, per_variant, free, joint, *((P, R) if goals else ()))
    order = sorted(range(len(variants)), key=lambda i: near[i])
    q0 = problem.q0
    scene = problem.scene
    answers: list[tuple[float, np.ndarray, int]] = []  # (cost, q, variant)
    runs = evaluations = rejected = 0
    winner = None
    stage = "q0" if q0 is not None else "seed table"

    def run(i: int, q_start: np.ndarray) -> bool:
        nonlocal runs, evaluations, rejected, winner
        v = variants[i]
        out = v.lm.run(q_start, iterations)
        runs += 1
        evaluations += out.evaluations
        converged = out.converged
        if converged and scene is not None and scene.in_collision(out.q, problem.margin):
            converged, rejected = False, rejected + 1
        if not converged:
            if out.rank < v.best_rank:
                v.best_rank, v.best = out.rank, out.q
            return False
        q = nearest_turn(out.q, q0, problem.lower, problem.upper, wrap) if q0 is not None else out.q
        v.best_rank, v.best = -1.0, q
        if prefer == "first" and not criterion:
            winner = (q, i, out)
            return True
        answers.append((criterion.cost(q), q, i))
        return prefer == "first"

    def run_batch(i: int, Q: np.ndarray) -> None:
        """LM runs from every row of ``Q`` towards variant i, all to their end (one kernel call), each answer
        kept."""
        nonlocal runs, evaluations, rejected
        v = variants[i]
        lm = v.lm
        if lm.engine != "compiled":
            for q in Q:
                run(i, q)
            return
        N = Q.shape[0]
        pt, Rt = lm._pt, lm._Rt
        P, Rts = np.repeat(pt[None], N, axis=0), np.repeat(Rt[None], N, axis=0)  # writable: layout.owned says why
        Q_out, stats = np.empty((N, robot.n)), np.empty((N, STATS_SIZE))
        lm._kernel["lm_runs"](owned(Q, float), *lm._args[:-2], P, Rts, kernel_params(COLLECT_ITERATIONS or iterations),
                              Q_out, stats, np.empty((N, pt.shape[0], 2)))
        runs += N
        evaluations += int(stats[:, S_EVALUATIONS].sum())
        ok = stats[:, S_CONVERGED] != 0.0
        if scene is not None:
            for k in np.nonzero(ok)[0]:
                if scene.in_collision(Q_out[k], problem.margin):
                    ok[k], rejected = False, rejected + 1
        if not ok.all():
            rank = stats[~ok, S_COST] if pt.shape[0] > 1 else stats[~ok, S_POS] + stats[~ok, S_ROT]
            j = int(np.argmin(rank))
            if rank[j] < v.best_rank:
                v.best_rank, v.best = float(rank[j]), Q_out[~ok][j]
        if ok.any():
            A = Q_out[ok]
            if q0 is not None:
                A = nearest_turn(A, q0, problem.lower, problem.upper, wrap)
            v.best_rank = -1.0
            answers.extend(zip(criterion.costs(A).tolist(), A, [i] * A.shape[0], strict=True))

    def out_of(limit) -> bool:
        return limit is not None and runs >= len(variants) and time.perf_counter() >= limit

    done = False
    limit = deadline if prefer == "first" else collect_until
    lead = {}  # q0 at the head of a variant's first batch
    if q0 is not None and prefer != "first" and len(variants) == 1:
        # prefer on one variant: q0's run in the first batch's kernel call (its own LM run cost 30-70 us more in
        # Python, measured on Panda: a tenth of prefer's budget)
        lead = {order[0]: q0[None]}
    elif q0 is not None:  # round 0: q0 towards every variant (prefer="nearest": the nearest answers start there)
        for i in order:
            if run(i, q0):
                done = True
                break
    if prefer != "first":  # collect: batches of starts per variant, all run to their end, until the budget
        batch_size = COLLECT_BATCH
        if not redundant:  # no null space to refine in: the whole budget collects
            limit, batch_size = finish, COLLECT_BATCH_BRANCHES
        if prefer == "nearest":  # every other start near q0: answers near q0 come from there
            for v in variants:
                v.starts = _Around(v.starts, rng, q0, problem.lower, problem.upper, deadline is not None)
        per_run = 0.0  # seconds per LM run of the last batch
        batches = 0
        while True:  # the first batch whatever the clock says (a stall before it would leave no answer at all)
            if batches and out_of(limit if answers else deadline):
                break
            progressed = False
            for i in order:
                size = batch_size
                if limit is not None and per_run > 0.0:  # a batch that ends near the limit, not far past it
                    left = (limit if answers else deadline) - time.perf_counter()
                    size = int(min(batch_size, max(1.0, left / per_run)))
                chunk = _take(variants[i].starts, size, robot.n)
                if i in lead:
                    chunk = np.concatenate([lead.pop(i), chunk])
                if chunk.shape[0]:
                    progressed = True
                    t_batch = time.perf_counter()
                    run_batch(i, chunk)
                    batches += 1
                    per_run = (time.perf_counter() - t_batch) / len(chunk)
                    if out_of(limit if answers else deadline):
                        break
            if not progressed:
                if deadline is None:  # no clock: the table's starts are the budget
                    break
                stage = "random starts"
                for i in order:
                    variants[i].starts = iter(rng.uniform(problem.lower, problem.upper, size=(64, robot.n)))
            else:
                stage = "seed table" if stage != "random starts" else stage
            order = sorted(order, key=lambda i: variants[i].best_rank)
        done = True
    rnd = 0
    while not done and not out_of(limit):
        stage = "seed table"
        progressed = False
        for i in order:
            q_start = next(variants[i].starts, None)
            if q_start is None:
                continue
            progressed = True
            if run(i, q_start):
                done = True
                break
            if out_of(limit):
                break
        rnd += 1
        if not progressed:
            if prefer == "first" or deadline is None:  # no clock: the table's starts are the budget
                break
            stage = "random starts"  # prefer: keep collecting from uniform random starts until the budget
            for i in order:
                variants[i].starts = iter(rng.uniform(problem.lower, problem.upper, size=(64, robot.n)))
        order = sorted(order, key=lambda i: variants[i].best_rank)  # the variants that came nearest first
    if winner is None and answers:
        answers.sort(key=lambda a: a[0])

        def improve(cost, q, i, steps):
            nonlocal evaluations
            q_r, cost_r, ev = refine(variants[i].problem, variants[i].lm, q, criterion, finish, steps)
            evaluations += ev
            if scene is not None and scene.in_collision(q_r, problem.margin):
                return cost, q, i
            if q0 is not None:
                q_r = nearest_turn(q_r, q0, problem.lower, problem.upper, wrap)
                cost_r = criterion.cost(q_r)
            return cost_r, q_r, i

        mode = _descent_mode(prefer, criterion, variants)
        if redundant and mode is not None:  # compiled: a first pass over more answers, then the best further
            refined, ev = _descend(answers, variants, q0, mode, criterion, scene, problem, wrap, finish)
            evaluations += ev
        elif criterion and redundant:  # a few steps for each of the best, then the rest of the time for the winner
            refined = [improve(*a, TRIAL_STEPS) for a in _distinct(answers, REFINE_COUNT)]
            refined = [improve(*min(refined, key=lambda a: a[0]), REFINE_STEPS)]
        else:  # nothing to refine in (or by): the best answer
            refined = answers[:1]
        cost, q, i = min(refined, key=lambda a: a[0])
        winner = (q, i)
    extra = ""
    if winner is None:  # the table's starts are spent: memetic's search on the variants that came nearest
        stage = "memetic restarts"
        # prefer's short budget bounds the choosing; with no answer yet, the search goes on as prefer="first"'s
        last = None if deadline is None else max(deadline, t0 + (DEFAULT_TIMEOUT if prefer != "first" else 0.0))
        order = sorted(range(len(variants)), key=lambda i: variants[i].best_rank)[:3]
        best = None
        for k, i in enumerate(order):
            left = None if deadline is None else max(last - time.perf_counter(), 1e-4) / (len(order) - k)
            r = memetic(variants[i].problem, rng, timeout=left, max_restarts=max_restarts, population=population,
                        generations=generations, polish_count=polish_count, table_size=0, table_seeds=0,
                        batch=batch, iterations=iterations, engine=engine)
            evaluations += r.evaluations
            runs += 1
            if best is None or r.success or r.cost < best[0].cost:
                best = (r, i)
            if r.success:
                break
        winner = (best[0].q, best[1])
        if best[0].success and criterion:
            q_r, _, ev = refine(variants[best[1]].problem, variants[best[1]].lm, best[0].q, criterion, None)
            evaluations += ev
            winner = (q_r, best[1])
        extra = f"; {best[0].message}"
    q = np.array(winner[0])
    chosen = None
    members = None
    if goals and len(winner) > 2:
        choice = variants[winner[1]].choice
        members = [g if m is None else g.alternatives[m] for g, m in zip(problem.goals, choice, strict=True)]
        if not all(g.kind < KIND_BEYOND_FRAME and (g.has_position or g.has_orientation) for g in members):
            members = None  # kinds whose errors the general verdict computes on its own (memetic.one_frame_goal)
    if members is not None:
        # the first answer, met by one LM run: each goal's errors are the kernel's of that run (its success test's
        # numbers, as a single target's and a one-goal list's are, memetic), each goal set's member the variant's
        out = winner[2]
        errors = ([(out.position_error, out.orientation_error)] if out.goal_errors is None
                  else out.goal_errors.tolist())
        goal_errors = [g.reported(p, np.nan if r is None else r) for g, (p, r) in zip(members, errors, strict=True)]
        chosen = list(choice)
        pos, rot, cost = problem.goal_summary(goal_errors)
        within = all(g.met(*e) for g, e in zip(members, goal_errors, strict=True))
    elif goals:
        goal_errors, chosen = problem.goal_errors_and_chosen(q)
        pos, rot, cost = problem.goal_summary(goal_errors)
        within = problem.goals_met(goal_errors)
    else:
        goal_errors = None
        # the errors from one LM evaluation at q (no step; the kernel's errors, as memetic's answers are assessed):
        # 3 us, where assess's own kinematics and angle cost 35 (measured, warm; 80-130 after other work)
        at_q = variants[winner[1]].lm.run(q, 0)
        evaluations += at_q.evaluations
        pos, rot, cost = problem.assess(q, at_q.position_error, at_q.orientation_error)
        within = bool(problem.succeeded(pos, rot))
    free_q = None if scene is None else not scene.in_collision(q, problem.margin)
    success = within and free_q is not False
    what = {"first": "the first answer", "nearest": "the answer nearest q0",
            "manipulability": "the most dexterous answer"}[prefer]
    if success:
        message = (f"{what} of {max(len(answers), 1)} found by LM from {stage} ({runs} LM run(s), "
                   f"{len(variants)} variant(s))")
    else:
        best = (f"best {errors_text(pos, rot)} (largest over the goals)" if goals
                else shortfall_text(problem, pos, rot))
        message = f"no answer within the budget after {runs} LM run(s) over {len(variants)} variant(s); {best}"
    if rejected:
        message += f"; {rejected} LM answer(s) reached the goals in collision"
    message += extra
    history = {"best_cost": np.array([cost]), "mean_cost": np.array([cost]), "diversity": np.zeros(1)}
    history["answers"] = np.array([a[0] for a in answers], dtype=float)
    return Result(q=q, position_error=pos, orientation_error=rot, cost=cost, success=bool(success), generations=0,
                  evaluations=evaluations + problem.evaluations, time_s=time.perf_counter() - t0, history=history,
                  message=message, method="memetic", setup_s=t0 - t_setup, collision_free=free_q,
                  goal_errors=goal_errors, chosen=chosen)


memetic_module.GOAL_SET_SEARCH["choose"] = choose  # memetic hands goal sets over to choose (see there)
