"""Memetic IK (``memetic``, the default method): each stage only while the tolerances are unmet, (1) LM from ``q0``,
(2) LM from the seed table's nearest entries (:mod:`.seed_table`; q0 after the nearest when farther than it), (3) DE
populations polished by LM (:mod:`.memetic_runs`). Stages 1-2's guaranteed runs are one compiled call where it serves
(:mod:`.guaranteed_runs`); every random draw is stage 3's, from ``rng``."""

from __future__ import annotations

import itertools
import time

import numpy as np

from ...errors import OptionError
from ...problem import IKProblem, shortfall_text
from ...result import Result
from .. import get_solver, register
from ..collision_verdict import pairs_text
from ..lm import DEFAULT_ITERATIONS, ENGINES, LevenbergMarquardt, LMOutcome, compiled_kernel, wrapping_joints
from ..lm.compiling import compiled_entry, load
from ..lm.engine import later_kinds
from ..options import check_choice, check_int, check_positive
from .memetic_runs import LMRuns, de_restart, kernel_goal_errors
from .seed_table import (
    DEFAULT_GOAL_TABLE_SEEDS,
    DEFAULT_TABLE_SEEDS,
    FrameFeatures,
    SeedTable,
    default_table_size,
    load_goal_helpers,
    one_frame,
    seed_table,
    seed_targets,
)
from .stance_table import stance_starts, stance_table

__all__ = ["DEFAULT_TIMEOUT", "GUARANTEED_TABLE_RUNS", "MemeticSetup", "memetic", "prepare"]

#: Default time budget (s): TRAC-IK's default.
DEFAULT_TIMEOUT = 0.005
#: LM runs from the nearest seed-table entries (and q0's) made whatever the clock says: a minimum of useful work.
GUARANTEED_TABLE_RUNS = 4
#: Seed-table entries tried for one frame's target with a scene: converged answers may be rejected in collision, and
#: the collision-free entries, farther ones included, stay better (cheaper) starts than stage 3's DE draws.
DEFAULT_SCENE_TABLE_SEEDS = 48
#: LM engines (and compiled guaranteed-runs entries) a MemeticSetup keeps, one per goal stack, retargeted, not rebuilt.
KEPT_ENGINES = 8
#: About how long (s, one core) compiling a variant of the compiled guaranteed runs takes from an empty cache.
GUARANTEED_RUNS_COMPILE_SECONDS = 5.0


def prepare(robot, lower: np.ndarray, upper: np.ndarray, table_size: int, engine: str = "compiled", scene=None,
            margin: float = 0.0, kernel: bool = True) -> tuple[SeedTable | None, np.ndarray | None]:
    """memetic's one-time work for a robot and a search box: the compiled LM kernel loaded (``kernel``), the cached
    seed table of ``table_size`` entries (0: none) and, with a scene, its collision-free mask: (table, mask or None)."""
    if engine == "compiled" and kernel:
        compiled_kernel()
    table = seed_table(robot, lower, upper, table_size) if table_size > 0 else None
    free = table.free_mask(scene, margin) if table is not None and scene is not None else None
    return table, free


def check_options(*, timeout, max_restarts, population, generations, polish_count, table_size, table_seeds,
                  table_offset, batch, iterations, engine, n: int) -> tuple:
    """memetic's options (:func:`memetic`'s keywords; ``n`` the robot's joints) as a tuple in the signature's order,
    ``table_size`` resolved; OptionError naming an option out of range."""
    timeout = None if timeout is None else check_positive("timeout (s; or None)", timeout)
    max_restarts = None if max_restarts is None else check_int("max_restarts", max_restarts, 0)
    if timeout is None and max_restarts is None:
        raise OptionError("memetic needs a finite budget: give timeout (s) or max_restarts (or both)")
    population = check_int("population", population, 4)
    generations = check_int("generations", generations, 0)
    polish_count = check_int("polish_count", polish_count, 1)
    if polish_count > population:
        raise OptionError(f"polish_count ({polish_count}) cannot exceed population ({population})")
    table_size = default_table_size(n) if table_size is None else check_int("table_size", table_size, 0)
    return (timeout, max_restarts, population, generations, polish_count, table_size,
            None if table_seeds is None else check_int("table_seeds", table_seeds, 0),
            check_int("table_offset", table_offset, 0),
            check_int("batch", batch, 1), check_int("iterations", iterations, 1),
            check_choice("engine", engine, ENGINES))


#: The search over goal sets (:func:`.answer_choice.choose`), which puts itself here when imported (the solver registry
#: imports it with the solvers): memetic cannot import it, choose builds on memetic.
GOAL_SET_SEARCH: dict = {}


@register("memetic", "Memetic IK: Levenberg-Marquardt on the SE(3) error from q0 and a seed table, then DE "
          "populations polished by LM until the tolerance or the time budget (default 5 ms)", check=check_options)
def memetic(problem: IKProblem, rng: np.random.Generator, *, timeout: float | None = DEFAULT_TIMEOUT,
            max_restarts: int | None = None, population: int = 32, generations: int = 3, polish_count: int = 8,
            table_size: int | None = None, table_seeds: int | None = None, table_offset: int = 0, batch: int = 1,
            iterations: int = DEFAULT_ITERATIONS, engine: str = "compiled") -> Result:
    """Solve ``problem`` with LM from q0 and the seed table, then DE populations polished by LM.

    Args:
        problem: the IK problem; its tolerances decide success.
        rng: source of every random draw (stage 3 only).
        timeout: wall-clock budget (s; None: none, then ``max_restarts`` bounds the work), checked between LM runs and
            generations; the clock starts after the one-time set-up, and the guaranteed runs (q0's and
            ``GUARANTEED_TABLE_RUNS`` entries') are made whatever it says.
        max_restarts: DE populations at most (None: no limit; 0: stages 1-2 only).
        population: DE population size (>= 4). generations: DE generations per population (>= 0).
        polish_count: members of each population polished by LM, best first (1..population).
        table_size: seed-table size (0 disables stage 2); default 2^(n+5) clamped to [256, 4096].
        table_seeds: table entries (a goal list: starts) tried in stage 2; default 17 (a goal list, or a scene: 48).
        table_offset: skip the first ``table_offset`` entries (starts).
        batch: LM runs handed to the engine together (>= 1), the clock checked between groups.
        iterations: LM steps allowed per run (>= 1).
        engine: ``"compiled"`` (the numba kernel) or ``"python"`` (the reference loop over Pinocchio).

    Returns:
        A :class:`Result`: ``generations`` DE generations, ``evaluations`` kinematics evaluations, ``history``
        (``best_cost``, ``mean_cost``, ``diversity``; ``attempt_error`` (m + rad) per LM run); an unmet problem gives
        the best approximation with ``success=False`` and a message saying why."""
    t_setup = time.perf_counter()
    setup = MemeticSetup(problem.robot, timeout=timeout, max_restarts=max_restarts, population=population,
                         generations=generations, polish_count=polish_count, table_size=table_size,
                         table_seeds=table_seeds, table_offset=table_offset, batch=batch, iterations=iterations,
                         engine=engine)
    return setup.solve(problem, rng, t_setup)


class MemeticSetup:
    """memetic's options checked once for one robot, and its per-problem set-up kept from solve to solve: the seed table
    of the box, the LM engines retargeted in place, the compiled guaranteed-runs entries. :meth:`solve` is
    :func:`memetic`'s body (the same answers). Not thread-safe: one per thread.

    Args:
        robot: the robot every problem is posed on.
        options: :func:`memetic`'s keywords (OptionError when out of range)."""

    def __init__(self, robot, *, timeout=DEFAULT_TIMEOUT, max_restarts=None, population=32, generations=3,
                 polish_count=8, table_size=None, table_seeds=None, table_offset=0, batch=1,
                 iterations=DEFAULT_ITERATIONS, engine="compiled") -> None:
        self.robot = robot
        #: the options as given (choose reads None as its own defaults: a goal set's table size, prefer's steps)
        self.given = dict(timeout=timeout, max_restarts=max_restarts, population=population, generations=generations,
                          polish_count=polish_count, table_size=table_size, table_seeds=table_seeds,
                          table_offset=table_offset, batch=batch, iterations=iterations, engine=engine)
        self.options = check_options(**self.given, n=robot.n)
        self._box = None  # (lower, upper, table size): the box the cached table is for (the arrays themselves)
        self._table = None
        self._lm: LevenbergMarquardt | None = None
        self._engines: list[LevenbergMarquardt] = []  # the last few engines made, newest first (_engine)
        self._entry: tuple = (None, None, None)  # (engine arguments, table, guaranteed_runs's compiled entry)
        # the last few such entries found, of both functions (a solver alternating goal stacks), newest first
        self._entries: list[tuple] = []
        # guaranteed_runs' scratch: each run's error, the goal's errors, a q0 never read, the best run's q and numbers
        self._scratch = (np.empty(GUARANTEED_TABLE_RUNS + 1), np.empty((1, 2)), np.zeros(robot.n), np.empty(robot.n),
                         np.empty(6))

    def _prepare(self, problem: IKProblem, size: int, engine: str) -> tuple[SeedTable | None, np.ndarray | None]:
        """:func:`prepare` for ``problem``, the table kept while the problems share their box arrays; the scene's free
        mask looked up every time (it follows the scene's version)."""
        box = self._box
        if box is None or box[0] is not problem.lower or box[1] is not problem.upper or box[2] != size:
            self._table = prepare(self.robot, problem.lower, problem.upper, size, engine, kernel=False)[0]
            self._box = (problem.lower, problem.upper, size)
        table, scene = self._table, problem.scene
        return table, None if table is None or scene is None else table.free_mask(scene, problem.margin)

    def _engine(self, problem: IKProblem, engine: str) -> LevenbergMarquardt:
        """The LM engine of ``problem``: the last one retargeted, else one of the last ``KEPT_ENGINES`` (one per goal
        stack), else a new one."""
        lm = self._lm
        if lm is not None and lm.engine == engine and lm.retarget(problem):
            return lm
        for other in self._engines:
            if other is not lm and other.engine == engine and other.retarget(problem):
                self._lm = other
                return other
        lm = self._lm = LevenbergMarquardt(problem, engine=engine)
        self._engines = [lm, *self._engines[:KEPT_ENGINES - 1]]
        return lm

    def guaranteed_runs(self, args: tuple, lm: LevenbergMarquardt, table: SeedTable,
                        goal_list: bool = False) -> tuple[tuple, float]:
        """(:func:`~.guaranteed_runs.guaranteed_runs`, or with ``goal_list``
        :func:`~.guaranteed_runs.goal_guaranteed_runs`, in the variant of ``lm``'s kernel, on ``args``; the seconds
        spent loading it: set-up). Once the engine's arguments stay, numba's compiled entry is kept per engine
        arguments and table (the last ``KEPT_ENGINES``) and called directly."""
        kept, current = self._entries, self._entry
        if not goal_list and current[2] is not None and current[0] is lm._args and current[1] is table:
            return current[2](*args), 0.0
        for i, entry in enumerate(kept):
            if entry[0] is lm._args and entry[1] is table:
                kept.insert(0, kept.pop(i))  # by index: list.remove compares the entries' arrays (ValueError)
                if not goal_list:
                    self._entry = entry
                return entry[2](*args), 0.0
        t = time.perf_counter()
        from . import guaranteed_runs as compiled  # its module and numba's imports: set-up too

        extra = later_kinds(lm.goals)  # the variant of the engine's kernel
        which = "goal_guaranteed_runs" if goal_list else "guaranteed_runs"
        function, loading = getattr(compiled, which if extra else which + "_basic"), 0.0
        if function not in _LOADED:
            load(f"memetic's guaranteed runs{' of goal lists' if goal_list else ''} for "
                 + ("every goal kind" if extra else "pose, position and planar goals"),
                 [(function, args)], GUARANTEED_RUNS_COMPILE_SECONDS)  # the runs made again below: args' buffers only
            _LOADED.append(function)
            loading = time.perf_counter() - t
        entry = None
        if lm._owned if goal_list else current[1] is not None:
            entry = compiled_entry(function, args) or function
        if not goal_list:
            self._entry = (lm._args, table, entry)
        if entry is not None and entry is not function:  # a compiled entry found
            kept[:] = [(lm._args, table, entry), *kept[:KEPT_ENGINES - 1]]
        return function(*args), loading

    def solve(self, problem: IKProblem, rng: np.random.Generator, t_setup: float | None = None) -> Result:
        """:func:`memetic` on ``problem`` with the setup's options; ``t_setup``: when the call began (``perf_counter``;
        default now), for ``Result.setup_s``. Goal sets go to :func:`.answer_choice.choose`."""
        if problem.goal_sets:  # any one of several targets: tried in answer_choice.py
            if not GOAL_SET_SEARCH:  # memetic imported on its own: the registry loads every solver module, choose too
                get_solver("memetic")
            return GOAL_SET_SEARCH["choose"](problem, rng, setup=self, **self.given)
        return _solve(self, problem, rng, time.perf_counter() if t_setup is None else t_setup)

    def resume(self, problem: IKProblem, rng: np.random.Generator, resumed: tuple) -> Result:
        """:meth:`solve` going on from the compiled guaranteed runs a :class:`~.repeat_call.RepeatCall` made for
        ``problem``, none of which converged (``resumed``: (clock start, :func:`resumed_state`))."""
        return _solve(self, problem, rng, resumed[0], resumed)


def _solve(setup: MemeticSetup, problem: IKProblem, rng: np.random.Generator, t_setup: float,
           resumed: tuple | None = None) -> Result:
    """memetic's search (:func:`memetic`) with ``setup``'s options and set-up; ``t_setup``: when the call began
    (``perf_counter``); ``resumed``: (clock start, :func:`resumed_state`) when the guaranteed runs were already made."""
    robot = problem.robot
    (timeout, max_restarts, population, generations, polish_count, table_size, table_seeds, table_offset, batch,
     iterations, engine) = setup.options

    # one-time set-up before the clock starts: the seed table and its features, the compiled rankings, the engine
    single = one_frame(problem)
    if table_seeds is None:
        table_seeds = (DEFAULT_GOAL_TABLE_SEEDS if not single else DEFAULT_TABLE_SEEDS if problem.scene is None
                       else DEFAULT_SCENE_TABLE_SEEDS)
    use_table = table_size > 0 and table_seeds > 0
    table, free = setup._prepare(problem, table_size if use_table else 0, engine)
    frame = table.frame_search(problem) if table is not None else None
    if table is not None and problem.target is None:  # the compiled rankings of goal lists (their starts' features)
        load_goal_helpers()
        if frame is None:
            table.prepare_goals(problem.goals)
    lm = setup._engine(problem, engine)
    # a stance (soles fixed, the CoM over them) whose table exists: its standing starts first (stance_table.py)
    stands = use_table and frame is None and problem.scene is None
    stance = stance_table(problem, make=False) if stands else None
    t0 = time.perf_counter()
    setup_s = t0 - t_setup
    if resumed is not None:  # the guaranteed runs' state: made in one compiled call, none converged
        t0, resumed = resumed
        setup_s = 0.0
    elif (COMPILED_GUARANTEED_RUNS and table is not None and (frame is None or not frame.planar) and problem.scene is
            None and engine == "compiled" and batch == 1 and table_offset == 0 and stance is None):
        result, loading, resumed = _guaranteed_runs(setup, problem, table, lm, t0, setup_s, iterations, table_seeds,
                                                    frame)
        if result is not None:
            return result
        t0 += loading  # loading (once: compiling) guaranteed_runs is set-up, not the budget's
        setup_s += loading
    # a stance without its table yet that the guaranteed runs left unsolved: the table made now (set-up, off the
    # clock) and its starts next; only then, so that a problem of a new stance met at once never pays for it
    if stands and stance is None:
        t_stance = time.perf_counter()
        stance = stance_table(problem)
        t_stance = time.perf_counter() - t_stance
        t0 += t_stance
        setup_s += t_stance
    guaranteed = (problem.q0 is not None) + (min(GUARANTEED_TABLE_RUNS, table_seeds) if use_table else 0)
    search = LMRuns(problem, lm, None if timeout is None else t0 + timeout, iterations, batch, guaranteed)
    history: dict[str, list[float]] = {"best_cost": [], "mean_cost": [], "diversity": []}
    stage, n_gen, restarts, solved = "", 0, 0, False
    # Stages 1-2: LM from q0 and the table's starts (lazy; with a scene, the collision-free entries only)
    ranked = starts = first = None
    if table is not None:
        k = table_offset + table_seeds  # a goal list's ranking compiled (single-threaded), a tip target's NumPy's
        ranked = (table.goal_starts(problem, k, free) if frame is None
                  else table.ranked(frame, table.target_point(problem, frame), k, free))
        ranked = itertools.islice(ranked, table_offset, None)
        starts = ranked if frame is None else (table.Q[i] for i in ranked)
        if stance is not None and resumed is None:
            starts = stance_starts(problem, stance, starts, table_seeds)
    q0 = problem.q0
    q0_first = q0 is not None
    if resumed is not None:
        # the compiled call made the guaranteed runs in this order: on from there, the clock checked between runs
        search.attempts, search.evaluations, search.attempt_errors, search.best, made = resumed
        stage = "seed table"
        if not search.out_of_time():
            rest = itertools.islice(starts, made, None)
            solved = search.polish_many(rest if stance is None else stance_starts(problem, stance, rest, table_seeds))
    elif q0 is not None and frame is not None:
        # A q0 farther from the target than the table's nearest entry (a random guess rather than a previous
        # solution) goes second: a failed LM run from it costs as much as a converging one.
        f = table.target_point(problem, frame)
        qc = np.minimum(np.maximum(q0, problem.lower), problem.upper)
        T = robot.frame_poses_unchecked(qc, [robot.frame_id(problem.goals[0].frame)])[0]
        d = f - frame.point(T.translation, T.rotation)
        d0 = float(d.dot(d))
        if d0 > frame.gap:
            first = next(ranked, None)
            q0_first = first is None or d0 <= float((f - frame.F[first]).dot(f - frame.F[first]))
    if q0_first and resumed is None:
        stage = "q0"
        solved = search.polish(q0)
    if resumed is None and not solved and table is not None and not search.out_of_time():
        stage = "seed table"
        if frame is not None:  # the nearest entry, then a farther q0, then the others
            first = next(ranked, None) if first is None else first
            solved = first is not None and search.polish(table.Q[first])
            if not solved and q0 is not None and not q0_first and not search.out_of_time():
                stage = "q0"
                solved = search.polish(q0)
        if not solved and not search.out_of_time():
            stage = "seed table"
            solved = search.polish_many(starts)
    # Stage 3: DE populations, their best members polished by LM, best first.
    if not solved and not search.out_of_time() and max_restarts != 0:
        if search.best is None:  # no q0 and no table: start from the box centre
            solved = search.polish(0.5 * (problem.lower + problem.upper))
        cost = problem.assess(search.best.q, search.best.position_error, search.best.orientation_error)[2]
        history.update(best_cost=[cost], mean_cost=[cost], diversity=[0.0])
        wrap = wrapping_joints(robot, problem.lower, problem.upper)
        while not solved and not search.out_of_time() and (max_restarts is None or restarts < max_restarts):
            stage = "memetic restarts"
            restarts += 1
            solved, n_gen, cost = de_restart(problem, rng, search, population, generations, polish_count, wrap,
                                             history, n_gen, cost)
    if search.best is None:  # every stage disabled
        search.polish(0.5 * (problem.lower + problem.upper))
    q = search.best.q
    # the best run's kernel errors where they are Goal.errors' (its success test's numbers), else a kinematics pass
    goal_errors = (kernel_goal_errors(problem.goals, search.best) if single or (
        search.best.goal_errors is not None and all(g.on_one_frame for g in problem.goals))
        else problem.goal_errors(q))
    pos, rot, cost = problem.summary(q, goal_errors)
    if not history["best_cost"]:
        history.update(best_cost=[cost], mean_cost=[cost], diversity=[0.0])
    within = problem.goals_met(goal_errors)
    success = within and (problem.scene is None or search.best.converged)  # a rejected answer collides
    if success:
        message = f"tolerance reached by LM from {stage} ({search.attempts} LM run(s), {restarts} restart(s))"
    else:
        why = (f"time budget ({timeout:g} s) exhausted" if search.out_of_time()
               else f"max_restarts ({max_restarts}) reached")
        best = shortfall_text(problem, pos, rot, goal_errors) if not within else "no collision-free answer met"
        message = f"{why} after {search.attempts} LM run(s) and {restarts} restart(s); {best}"
    if search.rejected and not success:
        message += (f"; {search.rejected} LM answer(s) reached the target in collision, the last at "
                    f"{pairs_text(search.rejected_pairs)}")
    history["attempt_error"] = search.attempt_errors
    # with a scene, a converged best passed the exact check in _keep (a rejected one is no longer converged)
    return Result(q=q.copy(), position_error=pos, orientation_error=rot, cost=cost, success=bool(success),
                  generations=n_gen, evaluations=search.evaluations + problem.evaluations,
                  time_s=time.perf_counter() - t0, history={k: np.asarray(v, dtype=float) for k, v in history.items()},
                  message=message, method="memetic", setup_s=setup_s,
                  collision_free=True if problem.scene is not None and search.best.converged else None,
                  goal_errors=problem.reported(goal_errors))


_LOADED: list = []  # the compiled variants of guaranteed_runs and goal_guaranteed_runs loaded in this process
_FROM_Q0 = 0  # guaranteed_runs.STAGE_Q0 (that module imports numba: loaded on first use, as the kernel is)
BASE_FIXED, BASE_FROM_GOAL, BASE_EACH_ENTRY = 0, 1, 2  # guaranteed_runs' base modes (goal_guaranteed_runs)
_NO_BASE = np.zeros(6)  # goal_guaranteed_runs' base where no goal sets one (never read)
_EVERY = np.zeros(0, dtype=bool)  # every table entry (goal_guaranteed_runs' allowed: no scene on that path)

#: Whether memetic makes its guaranteed runs in one compiled call where it serves (:func:`_guaranteed_runs`); the
#: tests turn it off to compare with the runs made one by one.
COMPILED_GUARANTEED_RUNS = True


def _guaranteed_runs(setup: MemeticSetup, problem: IKProblem, table: SeedTable, lm: LevenbergMarquardt, t0: float,
                     setup_s: float, iterations: int, table_seeds: int,
                     ff: FrameFeatures | None) -> tuple[Result | None, float, tuple | None]:
    """:func:`_solve`'s guaranteed runs in one compiled call (:mod:`.guaranteed_runs`), with _solve's order and
    decisions: for a problem searched as one frame's pose (``ff``: :meth:`SeedTable.frame_search`'s; not planar)
    :func:`~.guaranteed_runs.guaranteed_runs`, for a goal list of several goals (``ff`` None)
    :func:`~.guaranteed_runs.goal_guaranteed_runs` (the ranking, the composed starts and the LM runs of
    :meth:`SeedTable.goal_starts`' first starts). Returns (the Result when one met the tolerances else None; the
    seconds spent loading the compiled function; when none converged, the state _solve goes on from
    (:func:`resumed_state`), else None)."""
    goals, q0 = problem.goals, problem.q0
    buffers, args, params = lm.kernel_arguments(iterations)
    table_runs = min(GUARANTEED_TABLE_RUNS, table_seeds)
    q_out = np.empty(problem.n)
    errors, g_out, zeros, best_q, best = setup._scratch
    head = (*buffers, zeros if q0 is None else np.array(q0, dtype=float), q0 is not None)
    if ff is not None:
        call = (*head, False, ff.gap, table.Q, ff.FT, ff.sq, ff.sp, ff.sr, lm.oriented, table_runs, *args, params,
                q_out, g_out, errors, best_q, best)
    else:
        layout = table.goal_layout(goals)
        pt, Rt = seed_targets(problem)
        base_mode, base = BASE_FIXED, _NO_BASE
        if problem.robot.floating_base:
            found = table._base_from_goals(problem, table._goal_parts(goals))
            base_mode, base = (BASE_EACH_ENTRY, _NO_BASE) if found is None else (BASE_FROM_GOAL, found)
        g_out, best_g = np.empty((len(goals), 2)), np.empty((len(goals), 2))
        call = (*head, table.Q, *layout[:8], table.weight, np.ascontiguousarray(pt, dtype=float),
                np.ascontiguousarray(Rt, dtype=float), *layout[8:], base, base_mode, _EVERY, lm.oriented, table_runs,
                *args, params, q_out, g_out, errors, best_q, best, best_g)
    (stage, runs, evaluations, pos, rot, _), loading = setup.guaranteed_runs(call, lm, table, goal_list=ff is None)
    if stage < 0:  # _solve goes on from here: the runs made, their count and errors, the best of them (several goals:
        # ranked by its weighted |e|^2, LMOutcome.rank), the table's starts made
        made, best_g = (table_runs, None) if ff is not None else (runs - (q0 is not None), best_g)
        return None, loading, resumed_state(setup, lm.oriented, runs, evaluations, made, best_g)
    # the goals' errors: the kernel's at q_out where they are Goal.errors' (its success test's numbers), tested again
    if ff is not None:
        goal_errors = [goals[0].reported(pos, rot)]
    elif all(g.on_one_frame for g in goals):
        goal_errors = [g.reported(p, r) for g, (p, r) in zip(goals, g_out.tolist(), strict=True)]
    else:
        goal_errors = problem.goal_errors(q_out)
    pos, rot, cost = problem.summary(q_out, goal_errors)
    if not problem.goals_met(goal_errors):  # converged by the kernel's test, not by the problem's: _solve says why
        return None, loading, None
    return guaranteed_runs_result(q_out, pos, rot, cost, stage, runs, evaluations + problem.evaluations, errors,
                                  time.perf_counter() - t0 - loading, setup_s + loading, problem.reported(goal_errors)
                                  ), loading, None


def resumed_state(setup: MemeticSetup, oriented: bool, runs: int, evaluations: int, made: int,
                  goal_errors: np.ndarray | None = None) -> tuple:
    """The state :func:`_solve` goes on from after compiled guaranteed runs none of which converged, read from the
    setup's scratch: (runs made, their evaluations, each run's error, the best run as an LMOutcome (its ``goal_errors``
    (G, 2) for several goals), the table's starts ``made``)."""
    errors, _, _, best_q, best = setup._scratch
    b_pos, b_rot, b_cost, b_it, b_ev, _ = best.tolist()
    kept = LMOutcome(best_q.copy(), b_pos, b_rot if oriented else None, False, int(b_it), int(b_ev), goal_errors,
                     b_cost)
    return runs, evaluations, errors[:runs].tolist(), kept, made


def guaranteed_runs_result(q: np.ndarray, pos: float, rot: float | None, cost: float, stage: int, runs: int,
                           evaluations: int, errors: np.ndarray, time_s: float, setup_s: float,
                           goal_errors: list | None = None) -> Result:
    """memetic's Result when a compiled guaranteed run met the tolerances: ``q`` (n,), its errors (m, rad or None) and
    cost, ``stage`` (STAGE_Q0 or STAGE_TABLE), ``runs`` made, ``errors`` (>= runs,) each run's error (m + rad)."""
    history = {"best_cost": np.array([cost]), "mean_cost": np.array([cost]), "diversity": np.zeros(1),
               "attempt_error": errors[:runs].copy()}
    return Result(q=q, position_error=pos, orientation_error=rot, cost=cost, success=True, generations=0,
                  evaluations=evaluations, time_s=time_s, history=history, method="memetic", setup_s=setup_s,
                  message=f"tolerance reached by LM from {'q0' if stage == _FROM_Q0 else 'seed table'} ({runs} LM "
                          "run(s), 0 restart(s))", goal_errors=goal_errors)
