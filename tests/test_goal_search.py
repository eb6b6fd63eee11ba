"""memetic's search over goal lists (whole robots): the seed table's ranking by the goals' summed nearness, the starts
composed goal by goal, the number of starts before DE restarts, and the frame look-ups a solve repeats."""

import numpy as np
import pytest

import evoik_pin as ek
from evoik_pin.errors import FrameError
from evoik_pin.goals import CenterOfMass, Pose, Position
from evoik_pin.problem import IKProblem
from evoik_pin.robot.frames import find_frame
from evoik_pin.solvers.search.seed_table import DEFAULT_GOAL_TABLE_SEEDS, default_table_size, seed_table

GO2_FEET = ("FL_foot", "FR_foot", "RL_foot", "RR_foot")


@pytest.fixture(scope="module")
def baxter():
    return ek.load_robot("baxter", tips=["left_gripper", "right_gripper"])


@pytest.fixture(scope="module")
def go2():
    return ek.load_robot("go2", tips=["base", *GO2_FEET], floating_base=True)


def _baxter_goals(robot, q):
    return [Pose("left_gripper", robot.fk(q, "left_gripper"), weight=3.0),
            Position("right_gripper", robot.fk(q, "right_gripper").translation)]


def _go2_goals(robot, q):
    return [Pose("base", robot.fk(q, "base"))] + [Position(f, robot.fk(q, f).translation) for f in GO2_FEET]


def _table(problem):
    robot = problem.robot
    return seed_table(robot, problem.lower, problem.upper, default_table_size(robot.n))


def _distances(table, goals, P, R, pt, Rt):
    """(size, G) per-goal nearness of frame poses P (size, G, 3), R (size, G, 3, 3) to targets pt (G, 3), Rt
    (G, 3, 3): weight x (|p - p_t|^2 + w^2 |R - R_t|_F^2 for a pose), written out from the definition."""
    d = np.zeros((P.shape[0], len(goals)))
    for g, goal in enumerate(goals):
        d[:, g] = ((P[:, g] - pt[g]) ** 2).sum(axis=1)
        if goal.has_orientation:
            d[:, g] += table.weight**2 * ((R[:, g] - Rt[g]) ** 2).sum(axis=(1, 2))
        d[:, g] *= goal.weight
    return d


def test_ranked_goals_is_the_summed_weighted_nearness(baxter):
    q = baxter.random_configurations(1, np.random.default_rng(3))[0]
    goals = _baxter_goals(baxter, q)
    problem = IKProblem(baxter, goals)
    table = _table(problem)
    P, R = baxter.fk_batch(table.Q, frames=[g.frame for g in goals])
    _, pt, Rt = problem.goal_stack()
    expected = np.argsort(_distances(table, goals, P, R, pt, Rt).sum(axis=1), kind="stable")[:10]
    assert list(table.ranked_goals(problem, 10)) == expected.tolist()
    # the features are cached per frames, kinds and weights: other weights rank by their own sum
    heavy = [Pose("left_gripper", goals[0].target), Position("right_gripper", goals[1].encode()[0], weight=50.0)]
    problem = IKProblem(baxter, heavy)
    expected = np.argsort(_distances(table, heavy, P, R, pt, Rt).sum(axis=1), kind="stable")[:10]
    assert list(table.ranked_goals(problem, 10)) == expected.tolist()


def _relative_poses(robot, Q, frames):
    """Frame poses relative to the root link: the floating base's six entries set to zero."""
    Q = np.array(Q, dtype=float, ndmin=2)
    if robot.floating_base:
        Q[:, :6] = 0.0
    return robot.fk_batch(Q, frames=list(frames))


@pytest.mark.parametrize("which", ["baxter", "go2", "go2 feet"])
def test_composed_starts_take_each_goals_chain_from_its_own_nearest_entry(which, request):
    """Baxter: a fixed base. Go2 with its trunk's pose among the goals: the base put where that goal says. Go2 with
    its feet alone: the base of the nearest ranked entry."""
    robot = request.getfixturevalue(which.split()[0])
    make = _baxter_goals if which == "baxter" else _go2_goals
    q = robot.random_configurations(1, np.random.default_rng(11))[0]
    q[:3] *= 0.2  # the trunk well inside the base box, so the base that meets its goal is not clipped
    goals = make(robot, q)[1 if which == "go2 feet" else 0:]
    problem = IKProblem(robot, goals)
    table = _table(problem)
    starts = list(table.goal_starts(problem, 4))
    ranked = list(table.ranked_goals(problem, 2))
    assert len(starts) == 4
    # composed and table entries alternate, a composed start first (a base set by a goal replaces the entries')
    lo = 6 if which == "go2" else 0
    assert np.array_equal(starts[1][lo:], table.Q[ranked[0], lo:])
    assert np.array_equal(starts[3][lo:], table.Q[ranked[1], lo:])
    composed = starts[0]
    if which == "go2":  # the trunk's goal met by the base alone, in every composed start and table entry
        for start in starts:
            T = robot.fk(start, "base")
            assert np.allclose(T.homogeneous, goals[0].target.homogeneous, atol=1e-9)
    elif which == "go2 feet":
        assert np.array_equal(composed[:6], table.Q[ranked[0], :6])
    frames = [g.frame for g in goals]
    # the goals seen from the root link (the world on a fixed base)
    _, pt, Rt = problem.goal_stack()
    if robot.floating_base:
        B = robot.fk(np.concatenate([composed[:6], np.zeros(robot.n - 6)]), robot.base)
        pt = (pt - B.translation) @ B.rotation
        Rt = np.einsum("ji,gjk->gik", B.rotation, Rt)
    P_all, R_all = _relative_poses(robot, table.Q, frames)
    best = _distances(table, goals, P_all, R_all, pt, Rt).min(axis=0)  # each goal's nearest entry alone
    P, R = _relative_poses(robot, composed, frames)
    got = _distances(table, goals, P, R, pt, Rt)[0]
    assert np.allclose(got, best, rtol=1e-9, atol=1e-12)  # every goal as near as its own nearest entry
    P0, R0 = _relative_poses(robot, table.Q[ranked[0]], frames)
    assert got.sum() <= _distances(table, goals, P0, R0, pt, Rt)[0].sum() + 1e-12


@pytest.mark.parametrize("name, soles", [("g1", ("left_ankle_roll_link", "right_ankle_roll_link")),
                                         ("talos", ("left_sole_link", "right_sole_link"))])
def test_the_table_holds_the_upright_stance_and_a_stance_composes_its_legs(name, soles):
    """The table's last entry is every joint at 0 clipped into the box (a humanoid URDF's upright stance): a stance
    made from it (soles posed, the centre of mass over them) seen from the upright base gets a composed start whose
    legs are that entry's, both soles exactly on their targets."""
    robot = ek.load_robot(name, tips=list(soles), floating_base=True)
    q = robot.clip(np.zeros(robot.n))
    goals = [Pose(f, robot.fk(q, f)) for f in soles] + [CenterOfMass(support=list(soles), margin=0.02)]
    problem = IKProblem(robot, goals)
    table = _table(problem)
    assert np.array_equal(table.Q[-1], q)
    composed = next(iter(table.goal_starts(problem, 1)))
    for g in goals[:2]:
        assert np.allclose(robot.fk(np.concatenate([q[:6], composed[6:]]), g.frame).homogeneous,
                           g.target.homogeneous, atol=1e-9)


@pytest.mark.parametrize("which, index", [("baxter", 12)])
def test_goal_lists_get_more_table_starts_before_restarts(which, index, request):
    """Problems (found by search) that the 17 starts of one target leave unsolved and the goal lists' 48 solve,
    without a DE restart (max_restarts=0: a deterministic budget)."""
    robot = request.getfixturevalue(which)
    make = _baxter_goals if which == "baxter" else _go2_goals
    q = robot.random_configurations(index + 1, np.random.default_rng(0))[index]
    if which == "baxter":  # the search used both poses, weight 1
        goals = [Pose(f, robot.fk(q, f)) for f in ("left_gripper", "right_gripper")]
    else:
        goals = make(robot, q)
    few = ek.solve(robot, goals, seed=0, timeout=None, max_restarts=0, table_seeds=17)
    assert not few.success
    r = ek.solve(robot, goals, seed=0, timeout=None, max_restarts=0)
    assert r.success and "0 restart(s)" in r.message
    assert 17 < len(r.history["attempt_error"]) <= DEFAULT_GOAL_TABLE_SEEDS


def test_goal_features_are_set_up_once_per_frame_list(go2, monkeypatch):
    q = go2.random_configurations(1, np.random.default_rng(4))[0]
    problem = IKProblem(go2, _go2_goals(go2, q))
    table = _table(problem)
    table.prepare_goals(problem.goals)

    def no_kinematics(*args, **kwargs):
        raise AssertionError("table kinematics after the set-up")

    monkeypatch.setattr(go2, "fk_batch", no_kinematics)
    assert len(list(table.goal_starts(problem, 6))) == 6
    assert len(list(table.ranked_goals(problem, 6))) == 6


def test_frame_ids_are_looked_up_once_and_unknown_frames_still_raise(baxter):
    assert baxter.frame_id("left_gripper") == find_frame(baxter.model, "left_gripper")
    assert baxter.frame_id("left_gripper") == find_frame(baxter.model, "left_gripper")  # from the cache
    for _ in range(2):
        with pytest.raises(FrameError, match="no frame 'left_grip'"):
            baxter.frame_id("left_grip")
    with pytest.raises(FrameError, match="named by a string"):
        baxter.frame_id(3)
