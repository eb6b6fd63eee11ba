"""The local engine of :func:`~evoik_pin.solve_many` (``backend="local"``): :class:`BatchSolver` and its threads,
and what the Ray backend shares with it (chunks, per-problem generators, the progress bar)."""

from __future__ import annotations

import contextlib
import gc
import os
import threading
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

import numpy as np

from ...goals import is_goal_list
from ...goals.preferences import holds_preferences, split_preferences
from ...goals.stack import G_WEIGHT, GoalArrays, TargetArrays, free_entries
from ...objectives import default_cost
from ...problem import Target, coerce_scene
from ..lm import solve_pairs
from ..options import check_int
from ..search.seed_table import DEFAULT_TABLE_SEEDS, default_table_size, seed_table
from .batch_results import SOURCE_Q0, SOURCE_SINGLE, SOURCE_TABLE, BatchOutcome
from .goal_lists import GoalBlock, GoalTree, source_of

__all__ = ["BatchSolver", "ProgressBar", "check_call", "check_workers", "chunk_bounds", "default_workers", "gc_paused",
           "root_entropy", "target_generator"]


#: Guided chunks (:func:`chunk_bounds`): each a 1 / (GUIDED_SHARE * workers) share of the targets left, at least
#: MIN_CHUNK targets.
GUIDED_SHARE = 2
MIN_CHUNK = 256
#: The seed-table search of the batched rounds is approximate (``cKDTree.query(eps=NEAREST_EPS)``: within (1 + eps)
#: times the nearest distance; docs/BENCHMARKS.md): 12-D features defeat exact k-d tree search.
NEAREST_EPS = 1.0


# ---------------------------------------------------------------------- workers, randomness, chunks
def default_workers() -> int:
    """The cores this process may run on (its CPU affinity where the OS tells, else ``os.cpu_count()``)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # macOS, Windows
        return max(1, os.cpu_count() or 1)


def check_workers(workers) -> int:
    """``workers`` as an int >= 1; None: :func:`default_workers`."""
    return default_workers() if workers is None else check_int("workers", workers, 1)


def root_entropy(seed) -> int:
    """The entropy every per-target generator of a call derives from: ``seed`` itself (an int >= 0), fresh
    entropy for None, or one draw from a ``numpy.random.Generator`` (so a generator passed twice gives two
    different, reproducible batches)."""
    if isinstance(seed, np.random.Generator):
        return int(seed.integers(0, 2**63))
    if seed is None:
        return int(np.random.SeedSequence().entropy)
    return int(seed)


def target_generator(entropy: int, i: int) -> np.random.Generator:
    """Target ``i``'s own generator: ``SeedSequence(entropy).spawn(N)[i]`` without spawning the N - 1 others."""
    return np.random.default_rng(np.random.SeedSequence(entropy, spawn_key=(int(i),)))


def chunk_bounds(n: int, workers: int, minimum: int | None = None, maximum: int | None = None) -> list[tuple[int, int]]:
    """[start, stop) ranges cutting n items into chunks: one for one worker; for several, guided chunks, each a
    ``1 / (GUIDED_SHARE * workers)`` share of the items not yet cut, between ``minimum`` (default ``MIN_CHUNK``)
    and ``maximum`` items (none: no cap), so that the workers finish together."""
    minimum = MIN_CHUNK if minimum is None else minimum
    if workers <= 1 or n <= minimum:
        return [(0, n)] if n > 0 else []
    bounds, a = [], 0
    while a < n:
        size = max(minimum, -(-(n - a) // (GUIDED_SHARE * workers)))
        b = min(n, a + (size if maximum is None else min(size, maximum)))
        bounds.append((a, b))
        a = b
    return bounds


# ---------------------------------------------------------------------- the solver
def check_call(robot, make_problem: Callable, method: str, options: dict) -> dict:
    """Every option of a call solving many targets checked before any work, as :func:`evoik_pin.solve` checks
    them (on a probe target at the base origin); returns the options to solve with (a scene file read once into a
    :class:`~evoik_pin.scene.Scene`). Raises OptionError (and the problem's errors) naming the option."""
    from .. import get_solver

    info = get_solver(method)
    options = dict(options)
    if options.get("scene") is not None:
        options["scene"] = coerce_scene(robot, options["scene"])
    _, solver_options = make_problem(robot, np.zeros(3), **dict(options))
    solver_options.pop("polish", None)  # api._run's, not the solver's
    info.check_options(solver_options, robot.n)
    return options


class BatchSolver:
    """Solves batches of problems (:meth:`solve`) for one robot, method and set of options, checked once.

    Args:
        robot: a loaded :class:`~evoik_pin.robot.Robot`.
        make_problem, run: the API's problem builder and solver runner (``api.make_problem``, ``api._run``).
        method: solver name. entropy: see :func:`root_entropy`. options: as for :func:`evoik_pin.solve`.
        fallback: hand what the batched rounds leave to the per-target solver (False: it stays unsolved, with the
            last batched answer: reachability maps want a verdict).
        choose: the API's solve (``choose(robot, target, method, seed, prefer=, **options)``) for the one-by-one
            solves; None: ``make_problem`` and ``run``. prefer: ``"nearest"``, ``"manipulability"`` or None.
        workers: threads :meth:`solve` runs on (checked by the caller).

    With memetic, the problems are solved in batched rounds first, each from its next-nearest seed-table entry (from
    ``q0`` first when given) by one :func:`~evoik_pin.solvers.lm.solve_pairs` call; those left after ``table_seeds``
    rounds, and every problem of other methods, one by one as :func:`evoik_pin.solve` does, each with its own
    generator (:func:`target_generator`): the answers do not depend on the workers, chunks or backend.
    """

    def __init__(self, robot, make_problem: Callable, run: Callable, method: str, entropy: int,
                 options: dict, fallback: bool = True, choose: Callable | None = None,
                 prefer: str | None = None, workers: int = 1) -> None:
        self.robot, self.workers = robot, workers
        self.make_problem, self.run, self.method = make_problem, run, method
        self.entropy = entropy
        self.options = check_call(robot, make_problem, method, options)
        self.fallback = fallback
        self.choose, self.prefer = choose, prefer
        # prefer="nearest" | "manipulability" collects and ranks answers: every target one by one
        self.batched = (method == "memetic" and options.get("objective") is None and not options.get("polish")
                        and prefer is None)
        self.template = None
        self.engine = "compiled"
        self._trees: dict = {}  # (tip targets?, goal stack: frames, kinds, weights) -> its GoalTree
        self._lock = threading.Lock()  # a scene's exact check is not thread-safe (one Pinocchio Data)

    def _prepare(self, target: Target) -> None:
        """The template problem (it checks the shared options once), the seed table and its free entries."""
        target, _ = split_preferences(target)  # a goal list's preferences: the choosing solve's, not the template's
        template, solver_options = self.make_problem(self.robot, target, **dict(self.options))
        self.template = template
        if not self.batched:
            return
        from ..lm import compiled_kernel

        table_size = solver_options.get("table_size")  # checked by check_call
        table_size = default_table_size(self.robot.n) if table_size is None else int(table_size)
        table_seeds = solver_options.get("table_seeds")  # None: memetic's default
        rounds = min(DEFAULT_TABLE_SEEDS if table_seeds is None else int(table_seeds), table_size)
        self.engine = solver_options.get("engine", "compiled")
        if self.engine == "compiled":
            compiled_kernel()  # loaded once here, not by racing threads
        if is_goal_list(target) and self.engine != "compiled":
            rounds = 0  # the reference engine runs one goal problem at a time: the per-target solver does it
        self.table = seed_table(self.robot, template.lower, template.upper, table_size) if rounds else None
        self.free = (self.table.free_mask(template.scene, template.margin)
                     if self.table is not None and template.scene is not None else None)
        if self.free is not None:
            rounds = min(rounds, int(np.count_nonzero(self.free)))
        self.rounds = rounds

    def solve(self, targets, Q0: np.ndarray | None = None, offset: int = 0, progress: bool = False) -> BatchOutcome:
        """Solve ``targets`` (anything :func:`~.goal_lists.source_of` takes) from ``Q0`` (N, n) starts when given;
        ``offset``: the index of the first target in the user's call (it keys the per-target generators);
        ``progress``: a bar advanced chunk by chunk. Chunk by chunk: ``workers - 1`` threads run one chunk's batched
        rounds each; this one encodes the chunks and runs the one-by-one solves (the robot's one Pinocchio data; with
        a scene, after every chunk's rounds), else rounds itself."""
        source = source_of(self.robot, targets)
        progress = ProgressBar("solve_many", enabled=progress)
        if self.template is None:
            self._prepare(source.chunk(0, 1)[0])
        tolerances = (self.template.tolerance, self.template.rotation_tolerance)  # a tip target's one goal's
        # threads only where they gain: batched rounds on the compiled kernel (the Python reference engine and the
        # one-by-one solvers hold the GIL, and use the robot's one Pinocchio Data)
        threads = self.workers if self.batched and self.engine == "compiled" else 1
        bounds = chunk_bounds(len(source), threads)
        progress.grow(len(bounds))
        helpers = min(threads, len(bounds)) - 1
        pool = ThreadPoolExecutor(helpers, thread_name_prefix="evoik-batch") if helpers > 0 else None
        overlap = self.template.scene is None  # one-by-one solves between chunks, not after all of them
        jobs: dict[int, list] = {}  # chunk -> [block, q0, future or None, outcome or None]
        left: deque = deque()  # (start, {row: target}, q0, outcome): chunks with targets for the one-by-one solver
        handed = delivered = 0  # chunks handed out (to a thread or to this one), chunks delivered in order
        parts: list[BatchOutcome] = []

        def take(k: int) -> list:
            a, b = bounds[k]
            return [source.block(a, b, tolerances), None if Q0 is None else Q0[a:b], None, None]

        def running() -> int:
            return sum(1 for job in jobs.values() if job[2] is not None and not job[2].done())

        try:
            while delivered < len(bounds):
                while pool is not None and handed < len(bounds) and running() < helpers + 1:
                    job = jobs[handed] = take(handed)  # keep every thread fed before this thread's own work
                    job[2] = pool.submit(self._chunk_rounds, job[0], job[1])
                    handed += 1
                while delivered in jobs and (jobs[delivered][3] is not None or jobs[delivered][2].done()):
                    block, q0, future, out = jobs.pop(delivered)
                    out = out if future is None else future.result()
                    a = bounds[delivered][0]
                    parts.append(out)
                    rest = np.nonzero(out.source == SOURCE_SINGLE)[0] if self.fallback or not self.batched else ()
                    if len(rest):
                        left.append((a, {int(i): block.target(int(i)) for i in rest}, q0, out))
                    progress.update(1)
                    delivered += 1
                if overlap and left:
                    self._singles(*left.popleft(), offset)
                elif handed < len(bounds):
                    job = jobs[handed] = take(handed)
                    job[3] = self._chunk_rounds(job[0], job[1])
                    handed += 1
                elif delivered in jobs:
                    wait([jobs[delivered][2]], return_when=FIRST_COMPLETED)
        finally:
            progress.close()
            if pool is not None:
                pool.shutdown(wait=True, cancel_futures=True)
        while left:
            self._singles(*left.popleft(), offset)
        return BatchOutcome.concatenate(parts)  # the one-by-one answers are in the parts by now

    def _singles(self, a: int, targets: dict[int, Target], Q0, out: BatchOutcome, offset: int) -> None:
        """The problems ``{row: target}`` of the chunk starting at ``a`` that the batched rounds left (all of them for
        other methods), one by one with each target's own generator, written into ``out``."""
        # memetic skips the table entries the rounds tried; a goal list's starts alternate composed and ranked
        # entries (SeedTable.goal_starts), so its fallback starts from the first composed one (offset 0)
        skip = {"table_offset": self.options.get("table_offset", self.rounds)} if self.batched else {}
        for i, target in targets.items():
            extra = {"table_offset": 0} if self.batched and is_goal_list(target) else skip
            q0, rng = None if Q0 is None else Q0[i], target_generator(self.entropy, offset + a + i)
            if self.choose is not None:  # evoik_pin.solve's pipeline (an IKSolver kept per thread)
                if self.prefer is not None or holds_preferences(target):  # answers collected anew: no table offset
                    extra = {}
                r = self.choose(self.robot, target, self.method, rng, prefer=self.prefer,
                                **{**self.options, **extra, "q0": q0})
            else:
                problem, solver_options = self.make_problem(self.robot, target, q0=q0, **dict(self.options))
                r = self.run(problem, self.method, rng, {**solver_options, **extra})
            out.set_single(i, r)

    def _chunk_rounds(self, block: GoalBlock, Q0) -> BatchOutcome:
        """The batched rounds of one chunk (each goal stack apart): an outcome whose unsolved rows are
        ``SOURCE_SINGLE``."""
        out = BatchOutcome.empty(len(block), self.robot.n, goals=not block.tip)
        if not self.batched:
            return out
        t = self.template
        for rows, arrays in block.groups:
            stack = arrays.stack  # a k-d tree serves a stack's frames, kinds and weights
            key = (block.tip, stack.frames, stack.kinds, stack.spec[:, G_WEIGHT].tobytes())
            if self.table is not None and key not in self._trees:
                with self._lock:  # the k-d tree of this stack is built once, not by every thread
                    if key not in self._trees:
                        self._trees[key] = GoalTree(self.robot, self.table, arrays.stack, self.free, block.tip)
            self._rounds(arrays, rows, Q0, out, self._trees.get(key))
            done = rows[out.source[rows] != SOURCE_SINGLE]
            free = free_entries(self.robot, stack) if t.scene is None else None
            if done.size and free is not None:  # call_setup.settle_free's rule (batched: the errors' objective)
                rest = np.minimum(np.maximum(0.0, t.lower), t.upper)
                out.q[np.ix_(done, free)] = rest[free] if Q0 is None else Q0[np.ix_(done, free)]
            if not block.tip:  # the goals' cost (IKProblem's): weighted sum of position + orientation_weight x angle
                if done.size:
                    E = np.nan_to_num(np.stack(out.goal_errors[done]))  # (k, G, 2)
                    w = arrays.stack.spec[:, G_WEIGHT] ** 2
                    out.cost[done] = (E[:, :, 0] + t.orientation_weight * E[:, :, 1]) @ w
        solved = out.source != SOURCE_SINGLE
        if block.tip:  # a tip target's cost (its problem's objective)
            rot = out.orientation_error[solved]
            out.cost[solved] = default_cost(out.position_error[solved], None if np.isnan(rot).all() else
                                            np.nan_to_num(rot), t.orientation_weight, t.pose_metric)
        out.success[solved] = True
        out.collision_checked = t.scene is not None
        return out

    def _rounds(self, arrays: GoalArrays, rows: np.ndarray, Q0, out: BatchOutcome, tree: GoalTree | None) -> None:
        """The batched rounds of the problems ``arrays`` (of one goal stack), written into ``out``'s rows ``rows``;
        ``tree``: the stack's search of the seed table (None without a table)."""
        t = self.template
        scene, table = t.scene, self.table
        pending = np.arange(len(arrays))  # indices into arrays
        group = arrays
        res = None
        ranked = None  # from the second table round: the table_seeds nearest entries of each pending target
        plan = ([(SOURCE_Q0, None)] if Q0 is not None else []) + [(SOURCE_TABLE, r) for r in range(self.rounds)]
        for source, rank in plan:
            if pending.size == 0:
                break
            t0 = time.perf_counter()
            if rank is None:
                Qs = Q0[rows[pending]]
            elif rank == 0:  # most targets converge from their nearest entry: ask the k-d tree for one only
                Qs = table.Q[tree.nearest(group, 1, NEAREST_EPS)[:, 0]]
            else:  # the rest: every further entry in one query (not one query per round)
                if ranked is None:
                    ranked = tree.nearest(group, self.rounds, NEAREST_EPS)
                Qs = table.Q[ranked[:, rank]]
            # the Python reference engine runs one-goal tip problems as the single targets they are
            pairs = group if self.engine == "compiled" else TargetArrays(group.stack.kinds[0], group.P[:, 0],
                                                                         group.Rts[:, 0])
            res = solve_pairs(self.robot, Qs, pairs, t.lower, t.upper, t.tolerance, t.rotation_tolerance,
                              engine=self.engine)
            converged = res.converged
            if scene is not None:  # the exact check: an answer in collision stays pending for the next round
                with self._lock:
                    for j in np.nonzero(converged)[0]:
                        converged[j] = not scene.in_collision(res.q[j], t.margin)
            done = rows[pending[converged]]
            out.put(done, res, converged)
            out.time_s[done] = (time.perf_counter() - t0) / pending.size
            out.source[done] = source
            pending = pending[~converged]
            if ranked is not None:
                ranked = ranked[~converged]
            if pending.size:
                group = arrays.take(pending)
        if res is not None and pending.size and not self.fallback:  # no per-target search: the last round's answers
            out.put(rows[pending], res, ~converged)


@contextlib.contextmanager
def gc_paused():
    """The cyclic garbage collector paused while many small acyclic objects (targets, results) are made: its passes
    over the growing heap cost more than making them."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


class ProgressBar:
    """A tqdm bar drawn when its total is first known (:meth:`grow`) and grown as more work is planned; inert when
    not ``enabled``. As a context manager, closed on exit."""

    def __init__(self, what: str, unit: str = "chunk", enabled: bool = True) -> None:
        self.what, self.unit, self.enabled = what, unit, enabled
        self.tqdm = None

    def __enter__(self) -> ProgressBar:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def grow(self, units: int) -> None:
        if not (self.enabled and units):
            return
        if self.tqdm is None:
            from tqdm.auto import tqdm

            self.tqdm = tqdm(total=units, desc=self.what, unit=self.unit, leave=False)
        else:
            self.tqdm.total += units
            self.tqdm.refresh()

    def update(self, units: int) -> None:
        if self.tqdm is not None:
            self.tqdm.update(units)

    def close(self) -> None:
        if self.tqdm is not None:
            self.tqdm.close()
