"""memetic over goal sets (any one of several targets) and with ``prefer`` or preferences (:func:`choose`): the
variants (combinations of members) tried nearest the seed table first, LM from q0 and their table starts, then
memetic's search; with ``prefer`` other than "first", answers collected for :data:`COLLECT_SHARE` of the budget, the
best taken along the goals' self-motion (:mod:`.prefer`, :mod:`.descent`)."""

from __future__ import annotations

import copy
import itertools
import time
from functools import cached_property

import numpy as np

from ...goals.stack import owned
from ...problem import shortfall_text
from ...result import Result
from ..lm import DEFAULT_ITERATIONS, LevenbergMarquardt, wrapping_joints
from ..lm.layout import S_CONVERGED, S_COST, S_EVALUATIONS, S_POS, S_ROT, STATS_SIZE, kernel_params
from ..lm.nullspace import nullspace_kernel
from . import memetic as memetic_module
from .descent import answer_costs, descend, descent_mode, distinct, turned_rows
from .memetic_runs import kernel_goal_errors
from .nearest import table_distances_many
from .prefer import (
    REFINE_COUNT,
    REFINE_STEPS,
    TRIAL_STEPS,
    check_prefer,
    default_prefer_timeout,
    euler_flips,
    has_null_space,
    make_criterion,
    nearest_turn,
    refine,
)
from .seed_table import DEFAULT_GOAL_TABLE_SEEDS, DEFAULT_TABLE_SEEDS, nearest_order, one_frame

__all__ = ["COLLECT_SHARE", "choose", "member_distances"]

#: Share of the budget spent collecting answers before the best ones are refined.
COLLECT_SHARE = 0.6
#: Share of the budget left for making the answer (its errors, the result) after the refinement.
FINISH_SHARE = 0.1
#: prefer="nearest" draws one start in NEAR_EVERY around q0, with these standard deviations (times each joint's
#: half-range, at most pi) in turn.
NEAR_SCALES, NEAR_EVERY = (0.1, 0.25, 0.5), 4
#: prefer="nearest" ranks the seed table by pose nearness plus this x the squared joint distance to q0 (rad^2) x the
#: table's weight squared (the term scales with the arm).
NEAR_JOINT_WEIGHT = 0.1
#: LM runs per kernel call while prefer collects answers; prefer="nearest"'s (with a null space, whose answers nearest
#: q0 come from more starts): 6 draws near q0 and the table's :data:`~.seed_table.DEFAULT_TABLE_SEEDS` nearest entries.
COLLECT_BATCH, NEAREST_BATCH = 16, 23
#: The batch on goals without a null space (UR10 on a pose), whose whole budget collects the branches.
COLLECT_BATCH_BRANCHES = 32
#: Table entries tried per variant of a goal set in the first rounds (at least).
MIN_SEEDS_PER_VARIANT = 4


class _Variant:
    """One combination of goal-set members (or the problem itself): its targets, its problem and LM engine (made on
    first use), its starts, its best run's rank (-1 once it met the goals)."""

    def __init__(self, parent, choice, pt, Rt, base_lm: LevenbergMarquardt | None, engine: str) -> None:
        self.parent, self.choice, self.pt, self.Rt = parent, choice, pt, Rt
        self._base_lm, self._engine = base_lm, engine
        self.starts = iter(())
        self.best_rank = np.inf

    @cached_property
    def problem(self):
        return self.parent.variant(self.choice, self.pt, self.Rt)

    @cached_property
    def lm(self) -> LevenbergMarquardt:
        base = self._base_lm
        if base is None or base.engine != "compiled" or base._pt.shape != self.pt.shape:
            return LevenbergMarquardt(self.problem, engine=self._engine)
        # the same goal stack and box, other targets: the kernel's arguments with those swapped
        lm = copy.copy(base)
        lm._pt, lm._Rt = np.ascontiguousarray(self.pt), np.ascontiguousarray(self.Rt)
        lm._args = (*base._args[:-2], lm._pt, lm._Rt)
        lm.problem = self.problem if self.parent.goal_sets else self.parent
        return lm


class _Around:
    """``starts`` with every :data:`NEAR_EVERY`-th start drawn around ``q0`` (normal, :data:`NEAR_SCALES` x each
    joint's half-range in turn, clipped into the box); once ``starts`` ends, uniform starts when ``endless``. Taken a
    batch at a time (:meth:`take`)."""

    def __init__(self, starts, rng, q0: np.ndarray, lower: np.ndarray, upper: np.ndarray, endless: bool) -> None:
        self.starts, self.rng, self.q0, self.lower, self.upper, self.endless = starts, rng, q0, lower, upper, endless
        # the draws' standard deviations (len(NEAR_SCALES), n), cycled through
        self.cycle = np.array(NEAR_SCALES)[:, None] * np.minimum(0.5 * (upper - lower), np.pi)
        self.k = 0  # near starts drawn so far (the scale cycles with it)
        self.done = False

    def take(self, size: int) -> np.ndarray:
        """Up to ``size`` starts (rows; none once the starts have ended)."""
        n = self.q0.shape[0]
        if self.done or size <= 0:
            return np.empty((0, n))
        m = -(-size // NEAR_EVERY)  # near q0: every NEAR_EVERY-th, the first included
        scales = self.cycle[np.arange(self.k, self.k + m) % len(NEAR_SCALES)]
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
    """The table's rows ``Q`` by ``d`` (T,), the nearest first, at most ``k`` and only finite ones, in
    :func:`~.seed_table.nearest_first`'s order: an iterator of rows (the first costs an argmin), and :meth:`take` for a
    batch in one indexing (the ranking made once, in arrays: prefer's batches take most of it at once)."""

    def __init__(self, Q: np.ndarray, d: np.ndarray, k: int) -> None:
        self.Q, self.d, self.k = Q, d, min(k, int(np.count_nonzero(np.isfinite(d))))
        self.order: np.ndarray | None = None  # the ranking, made on first need
        self.taken = 0

    def _ranking(self) -> np.ndarray:
        """Indices of the k nearest entries (:func:`~.seed_table.nearest_order`)."""
        if self.order is None:
            self.order = nearest_order(self.d, self.k)
        return self.order

    def take(self, size: int) -> np.ndarray:
        """Up to ``size`` entries (rows), the nearest not yet taken."""
        rows = self._ranking()[self.taken:self.taken + max(size, 0)]
        self.taken += rows.shape[0]
        return self.Q[rows]

    def __iter__(self):
        return self

    def __next__(self) -> np.ndarray:
        if self.taken == 0 and self.order is None and self.k > 0:  # the nearest alone: no ranking yet
            self.taken = 1
            return self.Q[int(self.d.argmin())]
        order = self._ranking()
        if self.taken >= order.shape[0]:
            raise StopIteration
        self.taken += 1
        return self.Q[order[self.taken - 1]]


def _variant_starts(table, parent, variants, k: int, free, joint=None, P=None, R=None) -> list[float]:
    """Give each variant its lazy table starts and return each one's squared distance to its nearest entry (zeros
    without a table). ``joint``: the entries' weighted squared joint distances to q0 (size,), added to their pose
    nearness (prefer="nearest", one target or goal). P (V, G, 3), R (V, G, 3, 3): the variants' targets
    (read for a goal set of one goal)."""
    if table is None:
        return [0.0] * len(variants)
    if len(variants) == 1 and one_frame(parent):  # one goal on one frame
        ff = table.frame_search(parent)
        d = table.distances(ff, table.target_point(parent, ff)) + (0.0 if joint is None else joint)
        if free is not None:
            d[~free] = np.inf
        variants[0].starts = _TableStarts(table.Q, d, k)
        return [0.0]
    if len(parent.goals) > 1:  # a whole robot: composed starts too (SeedTable.goal_starts), the sets' order
        for v in variants:
            v.starts = table.goal_starts(v.problem, k, free)
        return [float(i) for i in range(len(variants))]
    spec = table.goal_spec(parent.goals)
    ff = table.frame_features((parent.goals[0].frame, spec[0]))  # the table's features of the goal's frame
    D, near = member_distances(table, ff, spec, P, R, joint, free)
    for v, d in zip(variants, D, strict=True):
        v.starts = _TableStarts(table.Q, d, k)
    return near.tolist()


def member_distances(table, ff, spec, P: np.ndarray, R: np.ndarray, joint=None,
                     free=None) -> tuple[np.ndarray, np.ndarray]:
    """The nearness of V targets of one goal on one frame (a goal set's members) to the seed table: (D (V, size)
    float32, each entry's squared feature distance less the target's own |f|^2, inf where not ``free``; near (V,)
    float64, each target's squared distance to its nearest entry), the members ranked by ``near``. ``ff``: the
    table's features of the goal's frame (:meth:`~.seed_table.SeedTable.frame_features`), ``spec``: the goal's
    :meth:`~.seed_table.SeedTable.goal_spec`; P (V, 1, 3) m, R (V, 1, 3, 3); ``joint`` (size,): added to every row."""
    f = table.goal_features(spec, P, R)  # (V, d)
    # |F - f|^2 = sq - 2 F.f + |f|^2: the first two terms compiled, in single precision; |f|^2 to compare variants
    D = np.empty((f.shape[0], ff.FT32.shape[1]), dtype=np.float32)
    table_distances_many(ff.FT32, ff.sq32, f.astype(np.float32), D)
    if joint is not None:
        D += joint
    if free is not None:
        D[:, ~free] = np.inf
    return D, D.min(axis=1) + (f * f).sum(axis=1)


def choose(problem, rng, *, prefer: str = "first", preferences=(), timeout: float | None = None,
           max_restarts: int | None = None, population: int = 32, generations: int = 3, polish_count: int = 8,
           table_size: int | None = None, table_seeds: int | None = None, table_offset: int = 0, batch: int = 1,
           iterations: int = DEFAULT_ITERATIONS, engine: str = "compiled", setup=None) -> Result:
    """memetic over goal sets and with ``prefer`` / preferences (see the module docstring); memetic's options.

    ``timeout`` (s): default memetic's for ``prefer="first"``, :func:`~.prefer.default_prefer_timeout` otherwise;
    ``table_offset`` is not used. ``setup``: the :class:`~.memetic.MemeticSetup` handing a goal set over, whose LM
    engine is retargeted instead of a new one made."""
    from .memetic import DEFAULT_TIMEOUT, check_options, memetic, prepare

    prefer = check_prefer(prefer)
    if timeout is None and max_restarts is None:
        timeout = DEFAULT_TIMEOUT if prefer == "first" else default_prefer_timeout(problem, prefer)
    t_setup = time.perf_counter()
    robot = problem.robot
    (timeout, max_restarts, population, generations, polish_count, table_size, table_seeds, _, batch, iterations,
     engine) = check_options(timeout=timeout, max_restarts=max_restarts, population=population,
                             generations=generations, polish_count=polish_count, table_size=table_size,
                             table_seeds=table_seeds, table_offset=table_offset, batch=batch, iterations=iterations,
                             engine=engine, n=robot.n)
    wrap = wrapping_joints(robot, problem.lower, problem.upper)
    criterion = make_criterion(problem, prefer, preferences, wrap)
    single = one_frame(problem)
    if single:  # one goal on one frame: one variant, the problem itself (its targets read from its engine, base_lm)
        choices, P, R = [(None,)], [None], [None]
    else:
        choices, P, R = problem.variant_targets()
    base_lm = LevenbergMarquardt(problem, engine=engine) if setup is None else setup._engine(problem, engine)
    variants = [_Variant(problem, c, P[v], R[v], base_lm, engine) for v, c in enumerate(choices)]
    if len(variants) == 1:
        variants[0].problem, variants[0].lm = problem, base_lm
    if table_seeds is None:
        table_seeds = DEFAULT_TABLE_SEEDS if single else DEFAULT_GOAL_TABLE_SEEDS
    use_table = table_size > 0 and table_seeds > 0
    table, free = prepare(robot, problem.lower, problem.upper, table_size if use_table else 0, engine,
                          problem.scene, problem.margin)
    if table is not None and not single:
        table.prepare_goals(problem.goals)
    if prefer != "first" and engine == "compiled":
        nullspace_kernel()  # compiled or loaded before the clock starts
    mode = descent_mode(prefer, criterion, variants)  # the compiled descent's, or None (Python's refine)
    # prefer="nearest": the answers' flips (other branches of the same pose) descended too
    flips = euler_flips(robot, problem.goals[0].frame) if prefer == "nearest" and single else ()
    t0 = time.perf_counter()
    deadline, collect_until, finish = (None, None, None) if timeout is None else (
        t0 + timeout, t0 + COLLECT_SHARE * timeout, t0 + (1.0 - FINISH_SHARE) * timeout)  # finish: the answer made
    redundant = has_null_space(problem)
    per_variant = table_seeds if prefer != "first" else max(MIN_SEEDS_PER_VARIANT, table_seeds // len(variants))
    joint = None
    if prefer == "nearest" and table is not None and len(problem.goals) == 1:
        # entries near q0 too: LM from them lands on answers near q0
        joint = table.joint_distances(problem.q0, wrap)
        joint *= NEAR_JOINT_WEIGHT * table.weight**2
    near = _variant_starts(table, problem, variants, per_variant, free, joint, P, R)
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
            v.best_rank = min(v.best_rank, out.rank)
            return False
        q = nearest_turn(out.q, q0, problem.lower, problem.upper, wrap) if q0 is not None else out.q
        v.best_rank = -1.0
        if prefer == "first" and not criterion:
            winner = (q, i, out)
            return True
        answers.append((float(answer_costs(criterion, mode, v.lm, q[None])[0]), q, i))
        return prefer == "first"

    def run_batch(i: int, Q: np.ndarray) -> None:
        """LM runs from every row of ``Q`` towards variant i, all to their end (one kernel call), each answer kept."""
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
        lm._kernel["lm_runs"](owned(Q, float), *lm._args[:-2], P, Rts, kernel_params(iterations), Q_out, stats,
                              np.empty((N, pt.shape[0], 2)))
        runs += N
        evaluations += int(stats[:, S_EVALUATIONS].sum())
        ok = stats[:, S_CONVERGED] != 0.0
        if scene is not None:
            for k in np.nonzero(ok)[0]:
                if scene.in_collision(Q_out[k], problem.margin):
                    ok[k], rejected = False, rejected + 1
        if not ok.all():
            rank = stats[~ok, S_COST] if pt.shape[0] > 1 else stats[~ok, S_POS] + stats[~ok, S_ROT]
            v.best_rank = min(v.best_rank, float(rank.min()))
        if ok.any():
            A = Q_out[ok]
            if q0 is not None:  # compiled (nullspace_kernel is loaded on this path): the same numbers
                A = turned_rows(A, q0, problem.lower, problem.upper, wrap)
            v.best_rank = -1.0
            answers.extend(zip(answer_costs(criterion, mode, lm, A).tolist(), A, [i] * A.shape[0], strict=True))

    def out_of(limit) -> bool:
        return limit is not None and runs >= len(variants) and time.perf_counter() >= limit

    done = False
    limit = deadline if prefer == "first" else collect_until
    lead = {}  # q0 at the head of a variant's first batch
    if q0 is not None and prefer != "first" and len(variants) == 1:
        # prefer on one variant: q0's run in the first batch's kernel call (its own LM run costs more in Python)
        lead = {order[0]: q0[None]}
    elif q0 is not None:  # round 0: q0 towards every variant (prefer="nearest": the nearest answers start there)
        for i in order:
            if run(i, q0):
                done = True
                break
    if prefer != "first":  # collect: batches of starts per variant, all run to their end, until the budget
        batch_size = NEAREST_BATCH if prefer == "nearest" else COLLECT_BATCH
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
        if not progressed:  # prefer="first" (the others collected above): the table's starts are spent
            break
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

        if redundant and mode is not None:  # compiled: a first pass over more answers, then the best further
            refined, ev = descend(answers, variants, q0, mode, criterion, scene, problem, wrap, finish, flips)
            evaluations += ev
        elif criterion and redundant:  # a few steps for each of the best, then the rest of the time for the winner
            refined = [improve(*a, TRIAL_STEPS) for a in distinct(answers, REFINE_COUNT)]
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
    choice = variants[winner[1]].choice
    members = [g if m is None else g.alternatives[m] for g, m in zip(problem.goals, choice, strict=True)]
    if len(winner) > 2 and all(g.on_one_frame for g in members):
        # the first answer, met by one LM run: each goal's errors are the kernel's of that run, as memetic's are (other
        # kinds' errors the general verdict computes on its own)
        goal_errors, chosen = kernel_goal_errors(members, winner[2]), list(choice)
        within = all(g.met(*e) for g, e in zip(members, goal_errors, strict=True))
    else:
        if single:  # the errors from one LM evaluation at q (no step: the kernel's, as memetic's answers are assessed)
            at_q = variants[winner[1]].lm.run(q, 0)
            evaluations += at_q.evaluations
            goal_errors, chosen = kernel_goal_errors(problem.goals, at_q), [None]
        else:
            goal_errors, chosen = problem.goal_errors_and_chosen(q)
        within = problem.goals_met(goal_errors)
    pos, rot, cost = problem.summary(q, goal_errors)
    free_q = None if scene is None else not scene.in_collision(q, problem.margin)
    success = within and free_q is not False
    what = {"first": "the first answer", "nearest": "the answer nearest q0",
            "manipulability": "the most dexterous answer"}[prefer]
    if success:
        message = (f"{what} of {max(len(answers), 1)} found by LM from {stage} ({runs} LM run(s), "
                   f"{len(variants)} variant(s))")
    else:
        best = shortfall_text(problem, pos, rot, goal_errors)
        message = f"no answer within the budget after {runs} LM run(s) over {len(variants)} variant(s); {best}"
    if rejected:
        message += f"; {rejected} LM answer(s) reached the goals in collision"
    message += extra
    history = {"best_cost": np.array([cost]), "mean_cost": np.array([cost]), "diversity": np.zeros(1),
               "answers": np.array([a[0] for a in answers], dtype=float)}
    return Result(q=q, position_error=pos, orientation_error=rot, cost=cost, success=bool(success), generations=0,
                  evaluations=evaluations + problem.evaluations, time_s=time.perf_counter() - t0, history=history,
                  message=message, method="memetic", setup_s=t0 - t_setup, collision_free=free_q,
                  goal_errors=problem.reported(goal_errors), chosen=problem.reported(chosen))


memetic_module.GOAL_SET_SEARCH["choose"] = choose  # memetic hands goal sets over to choose (see there)
