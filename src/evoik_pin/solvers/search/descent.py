"""prefer="nearest" | "manipulability"'s compiled descent (:func:`descend`): the answers collected
(:mod:`.answer_choice`), as arrays, taken along the goals' self-motion by :mod:`..lm.nullspace`'s kernels, best first;
which answers it takes (:func:`distinct_rows`), how they are costed (:func:`answer_costs`) and turned
(:func:`turned_rows`), and when the descent applies (:func:`descent_mode`)."""

from __future__ import annotations

import time
import weakref

import numpy as np

from ...goals.stack import owned
from ..lm import LevenbergMarquardt
from ..lm.nullspace import MODE_MANIPULABILITY, MODE_NEAREST, nullspace_kernel
from .prefer import RESTORE_ITERATIONS, Criterion, flipped

__all__ = ["DESCEND_COUNT", "MANIP_COUNT", "SURE_FINAL", "answer_costs", "descend", "descent_mode", "distinct",
           "distinct_rows", "turned_rows"]

#: The compiled descent (:func:`descend`): the best DESCEND_COUNT distinct answers descended DESCEND_TRIAL steps
#: each, the best DESCEND_FINAL of them on in rounds of DESCEND_STEPS while the clock allows (DESCEND_ROUNDS at
#: most); steps of DESCEND_MAX_STEP (rad or m) at most.
DESCEND_COUNT, DESCEND_TRIAL, DESCEND_FINAL, DESCEND_STEPS, DESCEND_ROUNDS = 6, 4, 2, 10, 4
DESCEND_MAX_STEP = 1.0
#: prefer="manipulability": the best MANIP_FIRST distinct answers descended MANIP_TRIAL steps whatever the clock
#: says, then as many more as fit before the finish (MANIP_COUNT in all at most): the raw measure says little about
#: the local optimum an answer's self-motion reaches, and the closed-form gradient makes a step cheap.
MANIP_COUNT, MANIP_FIRST, MANIP_TRIAL = 12, 8, 4
#: The best answers (this many) get the first round of DESCEND_STEPS whatever the clock says: a trial's few steps
#: leave the winner short of its optimum.
SURE_FINAL = 1

#: Per robot: whether its tree couples joints to q (mimic joints), which the compiled descent leaves to Python's refine.
_COUPLED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def descent_mode(prefer: str, criterion: Criterion, variants) -> int | None:
    """The compiled descent's mode (:mod:`..lm.nullspace`) for prefer="nearest" | "manipulability" alone (no
    further preferences) on the compiled engine; None otherwise (the Python :func:`.prefer.refine` then)."""
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
    """:func:`.prefer.nearest_turn` of each row of ``Q`` (N, n), the same numbers, by the compiled
    :func:`..lm.nullspace.nearest_turn_rows` (loaded with :func:`..lm.nullspace.nullspace_kernel`, before the
    clock)."""
    if not wrap.any():
        return Q
    out = np.empty(Q.shape)
    nullspace_kernel()["nearest_turn_rows"](owned(Q, float), owned(q0, float), owned(lower, float),
                                            owned(upper, float), owned(wrap), out)
    return out


def answer_costs(criterion: Criterion, mode: int | None, lm: LevenbergMarquardt, Q: np.ndarray) -> np.ndarray:
    """``criterion.costs(Q)`` (N,) of answers Q (N, n); for prefer="manipulability" alone on the compiled descent
    (``mode`` :data:`..lm.nullspace.MODE_MANIPULABILITY`, ``lm`` an engine of the problem) the compiled
    :func:`..lm.nullspace.log_manipulability_rows`: the same cost to about 1e-12."""
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
    (:func:`.prefer.euler_flips`, q0 given), the answers' flips inside the box are candidates too (the descent takes
    them onto the goals first). A descended answer in collision keeps its start (a flip is dropped). With one
    variant and no scene, the trial and the best one's first round are one kernel call
    (:func:`..lm.nullspace.descend_batch_then_best`). Returns (the answers best first, evaluations)."""
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
    return [answers[k] for k in distinct_rows(np.array([a[1] for a in answers]), count)]
