"""Taking answers along the goals' self-motion: ``prefer="nearest" | "manipulability"`` (TRAC-IK's Distance and Manip1)
and preferences summed into one :class:`Criterion`, lowered in the goals' null space by :func:`refine` (projected steps
restored by LM) or the compiled :func:`descend`. Nearness is ``|q - q0|``, full-turn joints taken to their turn nearest
``q0`` inside the box (:func:`nearest_turn`)."""

from __future__ import annotations

import time
import weakref

import numpy as np
import pinocchio as pin

from ...errors import MethodError, OptionError
from ...goals.preferences import Manipulability, Posture
from ...goals.registry import TASK_ROWS
from ...goals.stack import owned
from ..lm import LevenbergMarquardt, wrapping_joints
from ..lm.nullspace import MODE_MANIPULABILITY, MODE_NEAREST, nullspace_kernel
from ..options import check_choice

__all__ = ["BRANCHES_PREFER_TIMEOUT", "DEFAULT_PREFER_TIMEOUT", "PREFER", "REFINE_COUNT", "Criterion", "Nearness",
           "answer_costs", "bind_preferences", "check_prefer", "check_prefer_method", "default_prefer_timeout",
           "distinct_rows", "euler_flips", "flipped", "nearest_turn", "refine", "turned_rows"]

#: The answers ``prefer`` picks among: the first found, the nearest q0, the most dexterous.
PREFER = ("first", "nearest", "manipulability")
#: Default budget (s) of ``prefer="nearest" | "manipulability"`` on goals with a null space (a redundant arm on a
#: pose): the work done whatever the clock says (the first batch of LM runs, the descent's trial and the best answer's
#: first round) about fills it; more of it went to the descent's later rounds, which changed few answers (0.6 ms: the
#: same shares on 300 problems a row within a point). Under 0.7 ms with the call's overhead.
DEFAULT_PREFER_TIMEOUT = 0.0004
#: The default budgets (s) on goals without a null space (a 6-joint arm on a pose), where the whole budget collects IK
#: branches (nothing to descend along): the share of answers nearest q0 grows with it (on 300 random q0 of UR3, UR5,
#: UR10, seeds 0 and 1: 97.6-100 % at 0.6 ms, 96.9-98.9 % at 0.55 ms, 95.8-98.6 % at 0.5 ms), the most dexterous
#: branch is found sooner (the same shares at 0.45 ms as at 0.6 ms).
BRANCHES_PREFER_TIMEOUT = {"nearest": 0.00055, "manipulability": 0.00045}
#: Answers refined in the null space (best first; two closer than 1e-3 rad count once).
REFINE_COUNT = 4
#: Null-space steps of one refinement at most (the winner's; each of the best answers first gets TRIAL_STEPS); LM
#: steps restoring the goals after each.
REFINE_STEPS, TRIAL_STEPS, RESTORE_ITERATIONS = 12, 3, 10
#: Largest null-space step (rad or m, Euclidean).
MAX_REFINE_STEP = 0.5
#: The compiled descent (:func:`descend`): the best DESCEND_COUNT distinct answers descended DESCEND_TRIAL steps
#: each, the best DESCEND_FINAL of them on in rounds of DESCEND_STEPS while the clock allows (DESCEND_ROUNDS at
#: most); steps of DESCEND_MAX_STEP (rad or m) at most.
DESCEND_COUNT, DESCEND_TRIAL, DESCEND_FINAL, DESCEND_STEPS, DESCEND_ROUNDS = 6, 4, 2, 10, 4
DESCEND_MAX_STEP = 1.0
#: prefer="manipulability": the best MANIP_FIRST distinct answers descended MANIP_TRIAL steps whatever the clock
#: says, then as many more as fit before the finish (MANIP_COUNT in all at most): the raw measure says little about
#: the local optimum an answer's self-motion reaches (on xArm the answer that reaches TRAC-IK's Manip1 optimum ranks
#: 5th to 13th of ~15), and the closed-form gradient makes a step cheap (~4 kinematics evaluations). A fixed larger
#: trial (6 x 3 steps) gained on warm caches but not in the bench, where our solve follows TRAC-IK's 5 ms with caches
#: cold, and cost ~0.07 ms.
MANIP_COUNT, MANIP_FIRST, MANIP_TRIAL = 12, 4, 4
#: The best answers (this many) get the first round of DESCEND_STEPS whatever the clock says: a trial's few steps
#: leave the winner short of its optimum.
SURE_FINAL = 1


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


#: How close (m, rad) a frame's pose must stay under a joint-triple flip for :func:`euler_flips` to take it as exact
#: (URDFs round their angles: xArm's shoulder flip moves the tip by ~1e-5); LM meets the goals again from there.
FLIP_TOLERANCE = 1e-4
#: Configurations :func:`euler_flips` tests a flip at (fixed draws in the limits).
FLIP_TRIALS = 3
_FLIPS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def euler_flips(robot, frame: str | None) -> tuple[tuple[int, float], ...]:
    """The joint triples (i, i+1, i+2) whose flip ``(q_i + pi, m - q_{i+1}, q_{i+2} + pi)`` leaves the pose of
    ``frame`` unchanged, as (i, m) with m 0 or pi: the two Euler-angle solutions of a spherical joint group (a
    7-joint arm's shoulder), other IK branches of the same pose whose self-motion prefer="nearest" also searches
    (:func:`flipped`). Tested at :data:`FLIP_TRIALS` configurations within :data:`FLIP_TOLERANCE`, each of the three
    joints moving the frame; cached per robot and frame."""
    cache = _FLIPS.setdefault(robot, {})
    if frame in cache:
        return cache[frame]
    fid = robot.frame_id(frame)
    Q = robot.random_configurations(FLIP_TRIALS, np.random.default_rng(0))
    poses = [robot.frame_poses_unchecked(q, [fid])[0] for q in Q]
    moving = np.any(np.abs(robot.jacobian_world_unchecked(Q[0], fid)) > 1e-9, axis=0)
    flips = []
    for i in range(robot.n - 2):
        if not moving[i:i + 3].all():
            continue
        for m in (0.0, np.pi):
            ok = True
            for q, T in zip(Q, poses, strict=True):
                F = robot.frame_poses_unchecked(flipped(q[None], ((i, m),))[0], [fid])[0]
                if (np.linalg.norm(F.translation - T.translation) > FLIP_TOLERANCE
                        or np.linalg.norm(pin.log3(T.rotation.T @ F.rotation)) > FLIP_TOLERANCE):
                    ok = False
                    break
            if ok:
                flips.append((i, m))
                break
    cache[frame] = tuple(flips)
    return cache[frame]


def flipped(Q: np.ndarray, flips) -> np.ndarray:
    """Each row of ``Q`` (N, n) under each flip of ``flips`` (:func:`euler_flips`) in turn: (N x len(flips), n),
    not taken into any box."""
    out = []
    for i, m in flips:
        F = Q.copy()
        F[:, i] += np.pi
        F[:, i + 1] = m - Q[:, i + 1]
        F[:, i + 2] += np.pi
        out.append(F)
    return np.concatenate(out) if out else Q[:0]


class Nearness(Posture):
    """prefer="nearest"'s term: ``Posture(q0)`` over every joint with plain differences (answers are taken to their
    turn nearest q0 first, :func:`nearest_turn`), its costs and gradient written without Posture's joint mask and
    turn wrapping, which do nothing here: the same numbers, a few NumPy calls instead of a dozen per batch of
    answers (prefer's hot path)."""

    def costs(self, Q):
        d = Q - self._ref
        return 0.5 * self.weight * (d * d).sum(axis=-1)

    def cost(self, q):
        return float(self.costs(q))

    def gradient(self, q):
        return self.weight * (q - self._ref)


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

    def null_gradient(self, q: np.ndarray, N: np.ndarray) -> np.ndarray:
        """The cost's gradient in the null-space basis ``N`` (r, n) (orthonormal rows): analytic terms exactly,
        the others (manipulability) by forward differences along each basis vector."""
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


def _frame_rows(problem) -> list[tuple]:
    """(frame, its task rows) of each goal."""
    return [(g.frame, TASK_ROWS.get(g.kind, range(6))) for g in problem.goals]


def has_null_space(problem) -> bool:
    """Whether the goals leave a null space to refine in: fewer task rows than joints."""
    return sum(len(rows) for _, rows in _frame_rows(problem)) < problem.robot.n


def default_prefer_timeout(problem, prefer: str) -> float:
    """The default budget (s) of ``prefer`` ("nearest" or "manipulability") for ``problem``:
    :data:`DEFAULT_PREFER_TIMEOUT` with a null space to descend along, :data:`BRANCHES_PREFER_TIMEOUT`'s without."""
    return DEFAULT_PREFER_TIMEOUT if has_null_space(problem) else BRANCHES_PREFER_TIMEOUT[prefer]


def _task_jacobian(problem, q: np.ndarray, lm: LevenbergMarquardt) -> np.ndarray:
    """The goals' stacked task Jacobian (rows, n) at ``q``, whose null space leaves every goal met to first order: on
    the compiled engine the rows LM's own step reads (right for every kind: free axes, bands, relative poses, centres
    of mass, LookAt); on the Python engine (pose, position, planar goals) the frames' base-frame rows."""
    if lm.engine == "compiled":
        stack = lm.goals
        e, E, ge = np.empty(stack.rows), np.empty((stack.rows, lm.n)), np.empty((len(stack.kinds), 2))
        nullspace_kernel()["task_rows"](np.ascontiguousarray(q, dtype=float), *lm._tree, *lm._goal_arrays, lm._pt,
                                        lm._Rt, e, E, ge)
        return E
    robot = problem.robot
    return np.vstack([robot.jacobian_world_unchecked(q, None if f is None else robot.frame_id(f))[list(rows)]
                      for f, rows in _frame_rows(problem)])


def _null_basis(E: np.ndarray) -> np.ndarray:
    """Orthonormal basis (r, n) of the null space of ``E`` (rows, n)."""
    _, s, Vt = np.linalg.svd(E)
    rank = int(np.count_nonzero(s > 1e-9 * max(s[0], 1e-300))) if s.size else 0
    return Vt[rank:]


#: Smallest pivot of the Cholesky factor of E E^T, relative to its largest, for which :func:`_null_projection` trusts
#: it (a condition number of E E^T up to 1e8); below it, the SVD.
GRAM_PIVOT = 1e-4


def _null_projection(E: np.ndarray, g: np.ndarray) -> np.ndarray:
    """``g`` (n,) projected on the null space of ``E`` (rows, n), zero rows dropped: ``g - E^T (E E^T)^-1 E g`` when
    the rows are well independent (Cholesky pivots within :data:`GRAM_PIVOT`), else by the SVD's null basis."""
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
    """Lower ``criterion`` from an answer ``q`` (every goal met) by projected gradient steps in the goals' null space
    (scaled by the criterion's curvature, at most :data:`MAX_REFINE_STEP`), each restored by an LM run and kept only
    when it converges, the cost drops and, with a scene, it is collision-free; else halved. Returns (q, cost, LM
    evaluations)."""
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
            proj = N.T @ criterion.null_gradient(q, N)
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


_COUPLED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def descent_mode(prefer: str, criterion: Criterion, variants) -> int | None:
    """The compiled descent's mode (:mod:`..lm.nullspace`) for prefer="nearest" | "manipulability" alone (no
    further preferences) on the compiled engine; None otherwise (the Python :func:`refine` then)."""
    if prefer == "first" or len(criterion.terms) != 1 or any(v.lm.engine != "compiled" for v in variants):
        return None
    lm = variants[0].lm
    robot = lm.problem.robot
    coupled = _COUPLED.get(robot)  # kept per robot: its tree does not change
    if coupled is None:
        # mimic joints (the tree's joints coupled to q): the descent leaves answers as they are
        index, scale, offset = lm._tree[4:7]
        coupled = _COUPLED[robot] = bool(index.shape[0] != lm.n or np.any(index != np.arange(lm.n))
                                         or np.any(scale != 1.0) or np.any(offset != 0.0))
    if coupled:
        return None
    return MODE_NEAREST if prefer == "nearest" else MODE_MANIPULABILITY


def turned_rows(Q: np.ndarray, q0: np.ndarray, lower: np.ndarray, upper: np.ndarray, wrap: np.ndarray) -> np.ndarray:
    """:func:`nearest_turn` of each row of ``Q`` (N, n), the same numbers, by the compiled
    :func:`..lm.nullspace.nearest_turn_rows` (loaded with :func:`..lm.nullspace.nullspace_kernel`, before the
    clock): prefer's hot path, where NumPy's dozen calls per batch of a few rows cost more than the rows."""
    if not wrap.any():
        return Q
    out = np.empty(Q.shape)
    nullspace_kernel()["nearest_turn_rows"](owned(Q, float), owned(q0, float), owned(lower, float),
                                            owned(upper, float), owned(wrap), out)
    return out


def answer_costs(criterion: Criterion, mode: int | None, lm: LevenbergMarquardt, Q: np.ndarray) -> np.ndarray:
    """``criterion.costs(Q)`` (N,) of answers Q (N, n); for prefer="manipulability" alone on the compiled descent
    (``mode`` :data:`..lm.nullspace.MODE_MANIPULABILITY`, ``lm`` an engine of the problem) the compiled
    :func:`..lm.nullspace.log_manipulability_rows`: the same cost to about 1e-12, ~1 us a row instead of ~10 us
    (prefer="manipulability" costs every answer it collects)."""
    if mode != MODE_MANIPULABILITY:
        return criterion.costs(Q)
    out = np.empty(Q.shape[0])
    nullspace_kernel()["log_manipulability_rows"](owned(Q, float), *lm._args, out)
    return out


class _Pool:
    """Answers as arrays, best first: costs (N,), configurations Q (N, n), variant indices V (N,) int, and ``off``
    (N,) bool, a flip off the goals until the descent takes it onto them."""

    def __init__(self, costs: np.ndarray, Q: np.ndarray, V: np.ndarray, off: np.ndarray) -> None:
        self.costs, self.Q, self.V, self.off = costs, Q, V, off

    @classmethod
    def of(cls, answers, n: int) -> _Pool:
        """The pool of (cost, q, variant) tuples (best first)."""
        return cls(np.array([a[0] for a in answers], dtype=float), np.array([a[1] for a in answers]).reshape(-1, n),
                   np.array([a[2] for a in answers], dtype=np.intp), np.zeros(len(answers), dtype=bool))

    def __len__(self) -> int:
        return self.costs.shape[0]

    def take(self, index) -> _Pool:
        """The answers at ``index`` (an index array or a slice), in that order."""
        return _Pool(self.costs[index], self.Q[index], self.V[index], self.off[index])

    def merged(self, *others: _Pool) -> _Pool:
        """This pool and ``others`` in one, best first; equal costs in the order given (a stable sort, as
        ``sorted``)."""
        if not others:
            return self.take(np.argsort(self.costs, kind="stable"))
        parts = (self, *others)
        costs = np.concatenate([p.costs for p in parts])
        order = np.argsort(costs, kind="stable")
        return _Pool(costs[order], np.concatenate([p.Q for p in parts])[order],
                     np.concatenate([p.V for p in parts])[order], np.concatenate([p.off for p in parts])[order])

    def tuples(self) -> list:
        """The answers as (cost, q, variant) tuples, best first."""
        return list(zip(self.costs.tolist(), self.Q, self.V.tolist(), strict=True))


def descend(answers, variants, q0, mode: int, criterion: Criterion, scene, problem, wrap: np.ndarray,
            finish: float | None, flips=()) -> tuple[list, int]:
    """prefer's answers (cost, q, variant), best first, taken along their self-motion by the compiled descent
    (:func:`..lm.nullspace.descend_batch`): the best :data:`DESCEND_COUNT` distinct ones :data:`DESCEND_TRIAL` steps
    (manipulability: :data:`MANIP_FIRST` of them :data:`MANIP_TRIAL` steps, then as many more as fit before
    ``finish``, :data:`MANIP_COUNT` at most), then the best :data:`DESCEND_FINAL` on in rounds while the clock allows
    (until ``finish``; the first round for the best :data:`SURE_FINAL` whatever it says). With ``flips``
    (:func:`euler_flips`, q0 given), the answers' flips inside the box are candidates too (the descent takes them
    onto the goals first). A descended answer in collision keeps its start (a flip is
    dropped). Returns (the answers best first, evaluations). The answers are kept as arrays (:class:`_Pool`) in
    between: this bookkeeping, done on lists of tuples, cost as much as the descent's compiled steps."""
    kernels = nullspace_kernel()
    lower, upper = problem.lower, problem.upper
    target = np.zeros(variants[0].lm.problem.robot.n) if q0 is None else owned(q0, float)
    pool = _Pool.of(answers, target.shape[0])
    if flips and q0 is not None and answers:
        F = turned_rows(flipped(pool.Q, flips), q0, lower, upper, wrap)
        keep = np.all((F >= lower) & (F <= upper), axis=1)
        F = F[keep]
        pool = pool.merged(_Pool(criterion.costs(F), F, np.tile(pool.V, len(flips))[keep],
                                 np.ones(F.shape[0], dtype=bool)))
    pool = pool.take(distinct_rows(pool.Q, DESCEND_COUNT if mode == MODE_NEAREST else MANIP_COUNT))
    evaluations = 0

    def run(batch: _Pool, steps: int, further: int = 0) -> _Pool:
        """Each answer of ``batch`` descended ``steps`` steps at most, one kernel call per variant, and with ``further``
        (one variant, no scene) the best of them that many more steps in the same call; best first."""
        nonlocal evaluations
        out = []
        for i in range(len(variants)) if len(variants) > 1 else (0,):
            mine = batch.V == i
            if not mine.any():
                continue
            Q = batch.Q if len(variants) == 1 else batch.Q[mine]
            Q_out, f = np.empty_like(Q), np.empty(Q.shape[0])
            if further:
                evaluations += int(kernels["descend_batch_then_best"](
                    Q, target, mode, *variants[i].lm._args, steps, RESTORE_ITERATIONS, DESCEND_MAX_STEP, further,
                    Q_out, f))
            else:
                evaluations += int(kernels["descend_batch"](Q, target, mode, *variants[i].lm._args, steps,
                                                            RESTORE_ITERATIONS, DESCEND_MAX_STEP, Q_out, f))
            met = np.isfinite(f)  # a flip the descent could not take onto the goals is dropped
            if scene is not None:
                off = batch.off[mine]
                for k in range(Q.shape[0]):
                    if scene.in_collision(Q_out[k], problem.margin):
                        Q_out[k] = Q[k]
                        met[k] &= not off[k]  # a flip's start is off the goals: no answer to keep
            if not met.all():
                Q_out = Q_out[met]
            if q0 is not None:
                Q_out = turned_rows(Q_out, q0, lower, upper, wrap)
            count = Q_out.shape[0]
            out.append(_Pool(answer_costs(criterion, mode, variants[i].lm, Q_out), Q_out,
                             np.full(count, i, dtype=np.intp), np.zeros(count, dtype=bool)))
        return out[0].merged(*out[1:]) if out else batch

    # the best one's first round in the trial's kernel call (a call and its bookkeeping fewer): one variant, no
    # scene (whose check comes between the two)
    fused = SURE_FINAL == 1 and len(variants) == 1 and scene is None
    first_round = 0
    if mode == MODE_NEAREST or finish is None:
        pool = run(pool, DESCEND_TRIAL if mode == MODE_NEAREST else MANIP_TRIAL, DESCEND_STEPS if fused else 0)
        first_round = int(fused)
    else:  # the best MANIP_FIRST whatever the clock says, then as many more as fit before the finish
        t = time.perf_counter()
        trialled = run(pool.take(slice(0, MANIP_FIRST)), MANIP_TRIAL)
        per_answer = (time.perf_counter() - t) / max(min(MANIP_FIRST, len(pool)), 1)
        # the best one's first round (SURE_FINAL) kept in the time: DESCEND_STEPS steps, MANIP_TRIAL an answer
        fit = int((finish - time.perf_counter()) / per_answer) - SURE_FINAL * DESCEND_STEPS // MANIP_TRIAL
        if fit > 0 and len(pool) > MANIP_FIRST:
            trialled = trialled.merged(run(pool.take(slice(MANIP_FIRST, MANIP_FIRST + fit)), MANIP_TRIAL))
        pool = trialled
    for k in range(first_round, DESCEND_ROUNDS):  # rounds of the best on towards their optimum while the clock allows
        final = DESCEND_FINAL
        if finish is not None and time.perf_counter() >= finish:
            if k or not SURE_FINAL:
                break
            final = SURE_FINAL  # the first round, for the best, whatever the clock says
        before = pool.costs[:final]
        pool = run(pool.take(slice(0, final)), DESCEND_STEPS).merged(pool.take(slice(final, None)))
        if np.array_equal(pool.costs[:final], before):  # converged
            break
    return pool.tuples(), evaluations


def distinct_rows(Q: np.ndarray, count: int) -> list[int]:
    """The indices of the first ``count`` rows of ``Q`` (N, n) no two within 1e-3 (rad or m) of each other, in
    order: a row is taken unless it is near one taken before."""
    N = Q.shape[0]
    if N <= 1:
        return list(range(min(N, count)))
    G = Q @ Q.T
    sq = np.diag(G)
    close = (sq[:, None] + sq[None, :] - 2.0 * G) < 1e-6
    picked: list[int] = []
    blocked = np.zeros(N, dtype=bool)  # near a row taken: blocked[k] is close[k, j] for some taken j
    for k in range(N):
        if len(picked) >= count:
            break
        if not blocked[k]:
            picked.append(k)
            blocked |= close[:, k]
    return picked


def distinct(answers, count: int) -> list:
    """The first ``count`` of ``answers`` (cost, q, variant; best first) no two within 1e-3 (rad or m) of each other."""
    if len(answers) <= 1:
        return list(answers[:count])
    return [answers[k] for k in distinct_rows(np.array([a[1] for a in answers]), count)]


def make_criterion(problem, prefer: str, preferences, wrap: np.ndarray) -> Criterion:
    """prefer's term and the bound preferences. OptionError: prefer="nearest" without q0."""
    robot = problem.robot
    first_frame = problem.goals[0].frame
    terms = []
    if prefer == "nearest":
        check_prefer(prefer, problem.q0 is not None)
        # plain differences: answers are taken to their turn nearest q0 inside the box first (nearest_turn), and
        # a difference modulo 2 pi would count turns the limits forbid
        terms.append(Nearness(problem.q0).bind(robot, problem.q0, problem.lower, problem.upper, np.zeros_like(wrap)))
    elif prefer == "manipulability":
        terms.append(Manipulability(first_frame).bind(robot, problem.q0, problem.lower, problem.upper, wrap))
    for p in preferences:
        frame = (first_frame,) if isinstance(p, Manipulability) else ()
        terms.append(p.bind(robot, problem.q0, problem.lower, problem.upper, wrap, *frame))
    return Criterion(terms)


def bind_preferences(problem, preferences) -> Criterion:
    """The preferences checked against the problem's robot (errors naming the joint or frame), as a criterion."""
    return make_criterion(problem, "first", preferences, wrapping_joints(problem.robot, problem.lower, problem.upper))
