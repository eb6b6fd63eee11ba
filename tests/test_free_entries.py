"""The entries of q no goal depends on (goals.stack.free_entries: another arm, the head) come out at q0's values, or
without q0 at the box's point nearest the zero configuration, on every route (IKSolver, evoik_pin.solve, the repeat
call, a paper method, solve_many's batched rounds): a seed-table entry's or a DE member's values there were arbitrary,
and no goal's error depends on them."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import evoik_pin as ek
from evoik_pin.goals import Pose, Position
from evoik_pin.goals.stack import bind, free_entries

HAND = "arm_left_7_link"


@pytest.fixture(scope="module")
def talos():
    return ek.load_robot("talos")


def hand_goals(robot, rows):
    return [[Pose(HAND, robot.fk(q, HAND))] for q in rows]


def right_arm(robot):
    return np.array([j.startswith(("arm_right", "leg_", "head")) for j in robot.joint_names])


def test_the_free_entries_of_a_goal_list(talos):
    free = free_entries(talos, bind(talos, [Pose(HAND, talos.fk(np.zeros(talos.n), HAND))])[1])
    names = {j for j, f in zip(talos.joint_names, free, strict=True) if f}
    assert {"arm_right_1_joint", "leg_left_1_joint", "head_1_joint", "gripper_left_joint"} <= names
    assert not names & {"torso_1_joint", "torso_2_joint", "arm_left_1_joint", "arm_left_7_joint"}
    panda = ek.load_robot("panda")
    assert free_entries(panda, bind(panda, [Pose(panda.tip, panda.fk(np.zeros(7)))])[1]) is None


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_property_free_entries_change_no_goal_error(seed):
    """Any values in the free entries leave every goal's error as it was, to the last bit."""
    talos = ek.load_robot("talos")
    rng = np.random.default_rng(seed)
    q, other = talos.random_configurations(2, rng)
    target = talos.fk(talos.random_configurations(1, rng)[0], HAND)
    goals = [Pose(HAND, target), Position("arm_left_4_link", [0.1, 0.3, 0.2])]
    free = free_entries(talos, bind(talos, goals)[1])
    moved = np.where(free, other, q)
    problem = ek.make_problem(talos, goals)[0]
    assert problem.goal_errors(moved) == problem.goal_errors(q)


def test_every_route_settles_them(talos):
    rng = np.random.default_rng(3)
    lists = hand_goals(talos, talos.random_configurations(4, rng))
    q0 = np.clip(np.full(talos.n, 0.1), talos.lower, talos.upper)
    rest = np.clip(np.zeros(talos.n), talos.lower, talos.upper)
    free = free_entries(talos, bind(talos, lists[0])[1])
    solver = ek.IKSolver(talos)
    for i, goals in enumerate(lists):  # the second and later: the repeat call of the goal stack
        for start, expected in ((None, rest), (q0, q0)):
            for r in (solver.solve(goals, q0=start, seed=i), ek.solve(talos, goals, q0=start, seed=i),
                      ek.solve(talos, goals, q0=start, seed=i, method="de", max_generations=30, population=20)):
                assert np.array_equal(r.q[free], expected[free]), r.method
                if r.method == "memetic":
                    assert r.success
    for start, expected in ((None, rest), (q0, q0)):
        batch = ek.solve_many(talos, lists, q0=start, seed=1, workers=1)
        assert batch.success.all() and np.array_equal(batch.q[:, free], np.tile(expected[free], (len(lists), 1)))


def test_a_scene_keeps_them_as_found(talos):
    """With a scene the free joints carry collision geometry: the answer's values stay (no settle)."""
    from evoik_pin.call_setup import settle_free

    goals = hand_goals(talos, talos.random_configurations(1, np.random.default_rng(5)))[0]
    scene = ek.Scene(talos)
    problem = ek.make_problem(talos, goals, scene=scene)[0]
    r = ek.solve(talos, goals, seed=0)
    q = r.q.copy()
    q[right_arm(talos)] = 0.3
    r.q = q.copy()
    assert np.array_equal(settle_free(problem, r).q, q)


def test_a_posture_preference_still_places_them(talos):
    """A Posture among the goals refines the free joints towards it: the rule does not undo a preference."""
    from evoik_pin.goals import Posture

    rng = np.random.default_rng(9)
    goals = hand_goals(talos, talos.random_configurations(1, rng))[0]
    free = free_entries(talos, bind(talos, goals)[1])
    wanted = np.clip(np.full(talos.n, 0.3), talos.lower, talos.upper)
    r = ek.solve(talos, [*goals, Posture(wanted)], seed=0)
    rest = np.clip(np.zeros(talos.n), talos.lower, talos.upper)
    assert r.success
    assert np.abs(r.q[free] - wanted[free]).max() < 0.5 * np.abs(rest[free] - wanted[free]).max()
