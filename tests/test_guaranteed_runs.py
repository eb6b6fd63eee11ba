"""The compiled single-target fast path (issue 24): the compiled ranking of the seed table (solvers/search/nearest.py)
gives the table's ranking, and memetic's guaranteed runs made in one compiled call
(solvers/search/guaranteed_runs.py) give the Results of the runs made one by one, bit for bit, over many targets."""

import numpy as np
import pytest

import evoik_pin as ek
from evoik_pin.solvers.search import memetic
from evoik_pin.solvers.search.nearest import select_few, select_k, table_distances
from evoik_pin.solvers.search.repeat_call import RepeatCall
from evoik_pin.solvers.search.seed_table import default_table_size, seed_table


def targets(robot, count, seed):
    rng = np.random.default_rng(seed)
    return [robot.fk(q) for q in robot.random_configurations(count, rng)], robot.random_configurations(count, rng)


@pytest.mark.parametrize("name", ["panda", "ur5", "redundant7r"])
def test_compiled_ranking_is_the_tables_over_many_targets(name):
    """table_distances + select_few (guaranteed_runs's ranking: the same formula summed in the features' order, where
    NumPy uses BLAS) rank the entries as SeedTable.ranked does, over thousands of poses and positions; select_few on
    NumPy's own distances too, with and without a mask. (select_few, the function guaranteed_runs calls on its float64
    distances, is what select_k runs for these k; select_k itself is called on float32 distances only, and its
    float64 variant would be compiled for this test alone.)"""
    robot = ek.load_robot(name)
    table = seed_table(robot, robot.lower, robot.upper, default_table_size(robot.n))
    poses, _ = targets(robot, 2000, 11)
    allowed = np.random.default_rng(3).random(table.Q.shape[0]) < 0.3
    out = np.empty(17, dtype=np.int64)
    every = np.zeros(0, dtype=bool)
    d = np.empty(table.Q.shape[0])
    for i, T in enumerate(poses):
        for target in (ek.Target(T.translation, T.rotation), ek.Target(T.translation.copy())):
            problem = ek.IKProblem(robot, target)
            key = table.frame_search(problem)
            f = table.target_point(problem, key)
            _, FT, sq = key[:3]
            table_distances(FT, sq, f, d)
            reference = list(table.ranked(key, f, 17))
            m = select_few(d, every, 17, out)
            assert out[:m].tolist() == reference
            assert np.allclose(d, table.distances(key, f), rtol=0.0, atol=1e-12)
            if i % 10 == 0:
                m = select_few(table.distances(key, f), every, 4, out)
                assert out[:m].tolist() == reference[:4]
                m = select_few(table.distances(key, f), allowed, 17, out)
                assert out[:m].tolist() == list(table.ranked(key, f, 17, allowed))


def test_selection_edge_cases():
    # float32 distances, as select_k's callers (the goal lists' rankings) pass them: the variant they compile
    d = np.array([3.0, 1.0, 2.0, 1.0, 0.5], dtype=np.float32)
    out = np.empty(5, dtype=np.int64)
    every = np.zeros(0, dtype=bool)
    assert select_k(d, every, 0, out) == 0
    assert select_k(d, every, 5, out) == 5 and out.tolist() == [4, 1, 3, 2, 0]  # ties: the lower index first
    assert select_k(d, every, 2, out) == 2 and out[:2].tolist() == [4, 1]
    assert select_k(d, np.zeros(5, dtype=bool), 3, out) == 0
    assert select_k(d, np.array([True, False, True, False, False]), 3, out) == 2 and out[:2].tolist() == [2, 0]


def same(a, b):
    assert np.array_equal(a.q, b.q)
    assert (a.success, a.position_error, a.orientation_error, a.cost, a.evaluations, a.generations, a.message) == (
        b.success, b.position_error, b.orientation_error, b.cost, b.evaluations, b.generations, b.message)
    assert a.history.keys() == b.history.keys()
    for key in a.history:
        assert np.array_equal(a.history[key], b.history[key])


@pytest.mark.parametrize("name", ["panda", "ur5", "redundant7r"])
def test_guaranteed_runs_give_the_one_by_one_results(name, monkeypatch):
    """Over many poses and positions, from random q0s, near q0s and none, on an IKSolver (the compiled entry) and
    through evoik_pin.solve: the Results of the runs made one by one (COMPILED_GUARANTEED_RUNS off), bit for bit; also
    where no guaranteed run converges and memetic goes on from their state (later entries, DE restarts, out-of-reach
    targets)."""
    robot = ek.load_robot(name)
    poses, Qs = targets(robot, 300, 23)
    budget = {"timeout": None, "max_restarts": 2}  # deterministic: the clock cannot change an answer
    solver = ek.IKSolver(robot, **budget)
    rng = np.random.default_rng(2)
    calls = []
    for i, T in enumerate(poses):
        target = T if i % 3 else T.translation.copy()
        q0 = None if i % 2 else Qs[i]
        if i % 5 == 0:  # a q0 near a solution: tried first
            q0 = robot.random_configurations(1, rng)[0]
            target = robot.fk(q0)
            q0 = np.clip(q0 + 0.01, robot.lower, robot.upper)
        if i % 50 == 1:  # out of reach: no guaranteed run converges, memetic searches from the start
            target = 3.0 * T.translation
        calls.append((target, q0, i))
    made = []  # every call makes the compiled guaranteed runs once: memetic's own, or an IKSolver lane's
    one_call, lane_call = memetic._guaranteed_runs, RepeatCall.solve
    monkeypatch.setattr(memetic, "_guaranteed_runs", lambda *args: made.append(1) or one_call(*args))
    monkeypatch.setattr(RepeatCall, "solve", lambda *args, **kw: made.append(2) or lane_call(*args, **kw))
    fast = [solver.solve(t, q0=q0, seed=i) for t, q0, i in calls]
    general = [ek.solve(robot, t, q0=q0, seed=i, **budget) for t, q0, i in calls[::7]]
    assert len(made) == len(calls) + len(general)
    assert made.count(2) >= len(calls) - 4  # the lanes (one per kind) open after a target of their kind
    monkeypatch.setattr(memetic, "COMPILED_GUARANTEED_RUNS", False)
    slow = [ek.IKSolver(robot, **budget).solve(t, q0=q0, seed=i) for t, q0, i in calls]
    for a, b in zip(fast, slow, strict=True):
        same(a, b)
    for a, b in zip(general, slow[::7], strict=True):
        same(a, b)
    stages = {r.message.split(" (")[0] for r in fast}
    assert {"tolerance reached by LM from q0", "tolerance reached by LM from seed table"} <= stages
    assert sum(not r.success for r in fast) >= 5
    # and some solved after the guaranteed runs (memetic went on from the compiled runs' state)
    runs = [int(r.message.split(" LM run(s)")[0].split("(")[-1]) for r in fast if r.success]
    assert any(k > memetic.GUARANTEED_TABLE_RUNS + 1 for k in runs)
    from evoik_pin.solvers.search.guaranteed_runs import STAGE_Q0

    assert memetic._FROM_Q0 == STAGE_Q0



def one_goal(kind, frame, T):
    from evoik_pin.goals import Orientation, Pose, Position

    if kind == "pose":
        return [Pose(frame, T)]
    if kind == "free":
        return [Pose(frame, T, free="rz")]
    if kind == "band":
        return [Pose(frame, T, tolerance=[0.002] * 3 + [0.05] * 3, weight=2.0)]
    if kind == "position":
        return [Position(frame, T.translation.copy(), weight=0.5)]
    return [Orientation(frame, T.rotation.copy())]


@pytest.mark.parametrize("name, frame", [("ur5", None), ("panda", "panda_link6")])
def test_one_goal_lists_take_the_guaranteed_runs_with_the_general_paths_answers(name, frame, monkeypatch):
    """A goal list of one goal on one frame (a Pose, with free axes or bands, a Position, an Orientation; on the tip
    and on a frame before it) goes through the compiled guaranteed runs (issue 23 gap a), with the Results of memetic's
    runs made one by one (COMPILED_GUARANTEED_RUNS off), bit for bit, goal errors and chosen members included: from
    random q0s, near ones and none, where a guaranteed run converges and where memetic goes on from their state."""
    robot = ek.load_robot(name)
    frame = frame or robot.tip
    _, Qs = targets(robot, 150, 31)
    kinds = ("pose", "free", "band", "position", "orientation")
    budget = {"timeout": None, "max_restarts": 2}
    solver = ek.IKSolver(robot, **budget)
    rng = np.random.default_rng(4)
    calls = []
    for i, q in enumerate(robot.random_configurations(len(Qs), np.random.default_rng(32))):
        T = robot.fk(q, frame)
        q0 = None if i % 2 else Qs[i]
        if i % 5 == 0:  # a q0 near a solution: tried first
            q0 = np.clip(q + 0.01 * rng.standard_normal(robot.n), robot.lower, robot.upper)
        if i % 30 == 1:  # out of reach: memetic goes on from the guaranteed runs' state
            T = T.copy()
            T.translation = 3.0 * T.translation
        calls.append((one_goal(kinds[i % len(kinds)], frame, T), q0, i))
    made = []  # each call's compiled guaranteed runs: memetic's own (one_goal True), or a goal lane's (a solver
    # alternating five goal structures keeps a lane for each)
    one_call, lane_call = memetic._guaranteed_runs, RepeatCall.solve
    monkeypatch.setattr(memetic, "_guaranteed_runs", lambda *args: made.append(args[-1] is not None) or one_call(*args))
    monkeypatch.setattr(RepeatCall, "solve", lambda *args, **kw: made.append("lane") or lane_call(*args, **kw))
    fast = [solver.solve(g, q0=q0, seed=i) for g, q0, i in calls]
    general = [ek.solve(robot, g, q0=q0, seed=i, **budget) for g, q0, i in calls[::7]]
    assert len(made) == len(calls) + len(general) and set(made) == {True, "lane"}
    assert made.count("lane") >= len(calls) - 2 * len(kinds)  # each structure's lane open after its second solve
    monkeypatch.setattr(memetic, "COMPILED_GUARANTEED_RUNS", False)
    slow = [ek.IKSolver(robot, **budget).solve(g, q0=q0, seed=i) for g, q0, i in calls]
    for a, b in zip(fast + general, slow + slow[::7], strict=True):
        same(a, b)
        assert a.goal_errors == b.goal_errors and a.chosen == b.chosen == [None]
    stages = {r.message.split(" (")[0] for r in fast}
    assert {"tolerance reached by LM from q0", "tolerance reached by LM from seed table"} <= stages
    assert sum(r.success for r in fast) >= 0.8 * len(fast) and sum(not r.success for r in fast) >= 3


def test_several_goals_take_the_goal_lists_guaranteed_runs(monkeypatch):
    """Two goals, a pointing goal: not one goal on one frame, so not the single target's compiled guaranteed runs but
    the goal list's (memetic._guaranteed_runs without a frame); a goal set: answer_choice.py searches it, then the
    single target's guaranteed runs from the member it met open the set's repeat call
    (IKSolver._open_set_repeat_call)."""
    from evoik_pin.goals import Direction, Pose, Position

    robot = ek.load_robot("panda")
    T = robot.fk(robot.random_configurations(1, np.random.default_rng(0))[0])
    made = []  # every call makes the compiled guaranteed runs once: memetic's own, or an IKSolver lane's
    one_call, lane_call = memetic._guaranteed_runs, RepeatCall.solve
    monkeypatch.setattr(memetic, "_guaranteed_runs",
                        lambda *args: made.append(1 if args[-1] is not None else 3) or one_call(*args))
    monkeypatch.setattr(RepeatCall, "solve", lambda *args, **kw: made.append(2) or lane_call(*args, **kw))
    for goals in ([Pose(robot.tip, T), Position("panda_link4", robot.fk(np.zeros(robot.n)).translation)],
                  [Direction(robot.tip, [0, 0, 1], T.rotation[:, 2])], [Pose(robot.tip, [T, T])]):
        ek.solve(robot, goals, seed=1)
    assert made == [3, 3, 1]


@pytest.mark.parametrize("name, frame", [("ur5", None), ("panda", "panda_link6")])
def test_one_goal_errors_are_the_kernels_and_pinocchios(name, frame):
    """A one-goal list's Result.goal_errors are the kernel's errors of the answer (trusted as a single target's are):
    they are the goal's errors by Pinocchio's kinematics (IKProblem.goal_errors) within rounding, of every kind, met
    or not, and the verdict (success) is the goal's tolerances on them, which Pinocchio's errors give too."""
    robot = ek.load_robot(name)
    frame = frame or robot.tip
    kinds = ("pose", "free", "band", "position", "orientation")
    solver = ek.IKSolver(robot, timeout=None, max_restarts=1)
    rng = np.random.default_rng(8)
    solved = failed = 0
    for i, q in enumerate(robot.random_configurations(60, rng)):
        T = robot.fk(q, frame)
        if i % 10 == 3:  # out of reach: unmet goals' errors too
            T = T.copy()
            T.translation = 3.0 * T.translation
        goals = one_goal(kinds[i % len(kinds)], frame, T)
        r = solver.solve(goals, q0=None if i % 2 else robot.random_configurations(1, rng)[0], seed=i)
        exact = solver.problem(goals).goal_errors(r.q)
        (p, a), = r.goal_errors
        (pe, ae), = exact
        assert (p is None) == (pe is None) and (a is None) == (ae is None)
        assert p is None or abs(p - pe) <= 1e-12 * max(1.0, pe)
        assert a is None or abs(a - ae) <= 1e-12
        assert r.success == goals[0].met(p, a) == goals[0].met(pe, ae)
        assert r.chosen == [None]
        solved += r.success
        failed += not r.success
    assert solved >= 40 and failed >= 5


def test_a_goal_frames_table_features_are_set_up_before_the_clock(monkeypatch):
    """The goal frame's features over the seed table (its kinematics over every entry, ~20 ms on Panda's table) are
    set-up: made before memetic's clock starts, so a process's first one-goal solve does not spend its 5 ms budget on
    them (it ran out of time: tests/test_goal_prefer.py's first solve in a fresh process)."""
    from evoik_pin.goals import Pose, Position

    robot = ek.load_robot("panda")
    seen = []
    one_call = memetic._guaranteed_runs

    def checked(plan, problem, table, *rest):
        made = dict(table._frames)
        table.frame_search(problem)  # finds the features made before the clock: makes none
        seen.append(table._frames == made and len(made) > 0)
        return one_call(plan, problem, table, *rest)

    monkeypatch.setattr(memetic, "_guaranteed_runs", checked)
    q = np.full(robot.n, 0.2)
    for goals in ([Pose(robot.tip, robot.fk(q))], [Position("panda_link6", robot.fk(q, "panda_link6").translation,
                                                            weight=3.0)]):
        r = ek.IKSolver(robot, timeout=None, max_restarts=1).solve(goals, seed=0)
        assert r.success
    assert seen == [True, True]


@pytest.mark.parametrize("name", ["baxter", "talos"])
def test_compiled_per_goal_ranking_is_numpys_over_many_targets(name):
    """SeedTable._nearest_per_goal (one compiled call for every goal: the composed starts of whole robots) gives each
    goal's ranking by NumPy's product of the goal's own features, over many targets, k = 1 and k = 17, with and without
    a mask, goals with and without orientation. It ranks in single precision (nearest.table_distances32: a start's
    order is all it decides), so an entry may trade places with one whose distance is within single precision's
    rounding of it: each place's entry is allowed, distinct, and as near as NumPy's entry at that place to within
    1e-5 of the table's largest squared feature norm (float32's unit roundoff 6e-8 times the 12 features' sums)."""
    from evoik_pin.goals import Orientation, Pose, Position
    from evoik_pin.problem import IKProblem

    robot = ek.load_robot(name, floating_base=name == "talos")
    frames = (["left_gripper", "right_gripper", "head"] if name == "baxter"
              else ["left_sole_link", "right_sole_link", "gripper_left_joint", "torso_2_link"])
    rng = np.random.default_rng(4)
    table = seed_table(robot, robot.lower, robot.upper, default_table_size(robot.n))
    allowed = rng.random(table.Q.shape[0]) < 0.4
    exact = rankings = 0
    for trial, q in enumerate(robot.random_configurations(60, rng)):
        kinds = [Pose, Position, Orientation]
        goals = []
        for g, frame in enumerate(frames):
            T = robot.fk(q, frame=frame)
            kind = kinds[(trial + g) % 3]
            goals.append(kind(frame, T) if kind is Pose else kind(frame, T.translation) if kind is Position
                         else kind(frame, T.rotation))
        problem = IKProblem(robot, goals)
        parts = table._goal_parts(goals)
        _, pt, Rt = problem.goal_stack()
        spec = table.goal_spec(goals)
        for k, mask in ((1, None), (17, None), (1, allowed), (17, allowed)):
            got = table._nearest_per_goal(goals, parts, pt, Rt, k, mask)
            for g, (F, sq, _) in enumerate(parts):
                f = table.goal_features(spec[g:g + 1], pt[g][None, None], Rt[g][None, None])[0]
                d = sq - 2.0 * (F @ f)
                if mask is not None:
                    d = np.where(mask, d, np.inf)
                reference = np.argsort(d, kind="stable")[:k]
                assert len(set(got[g].tolist())) == k and np.isfinite(d[got[g]]).all()
                assert np.abs(d[got[g]] - d[reference]).max() <= 1e-5 * max(1.0, float(sq.max()))
                exact += got[g].tolist() == reference.tolist()
                rankings += 1
    assert exact >= 0.9 * rankings  # only near-ties trade places
