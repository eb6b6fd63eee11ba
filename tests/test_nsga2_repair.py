"""NSGA-II's repair steps on goal lists of every goal kind (issue 23, gap f).

The repair reads the LM kernel's own rows for a whole population (:func:`evoik_pin.solvers.lm.population_rows.
task_rows_batch`, equal bit for bit to :func:`.task_rows` one configuration at a time);
its damped-least-squares steps bring random starts onto Direction, LookAt, Orientation, Pose with a free axis,
RelativePose and CenterOfMass goals; a goal set is repaired towards the member each configuration is nearest to; and
NSGA-II with its default repair meets goal lists with pointing goals, judged by Pinocchio's kinematics of the whole
URDF (the frames' placements), not by the solver's own numbers.
"""

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import evoik_pin as ek
from evoik_pin.goals import CenterOfMass, Direction, LookAt, Orientation, Pose, Position, RelativePose, bind
from evoik_pin.goals.center_of_mass import com_of
from evoik_pin.problem import IKProblem
from evoik_pin.robot.frames import find_frame
from evoik_pin.solvers.lm.population_rows import task_rows, task_rows_batch
from evoik_pin.solvers.paper.nsga2 import dls_repair, goal_task

SOLES = ["left_sole_link", "right_sole_link"]
Z = np.array([0.0, 0.0, 1.0])


@pytest.fixture(scope="module")
def talos():
    return ek.load_robot("talos", floating_base=True)


@pytest.fixture(scope="module")
def baxter():
    return ek.load_robot("baxter", tips=["left_gripper", "right_gripper"])


def one_rows(robot, stack, q, pt, Rt):
    """(e, E, goal errors) of the kernel's task_rows at one configuration q for targets pt (G, 3), Rt (G, 3, 3)."""
    G = stack.spec.shape[0]
    e, E, ge = np.empty(stack.rows), np.empty((stack.rows, robot.n)), np.empty((G, 2))
    task_rows(np.asarray(q, dtype=float), *robot.tree_constants(), *stack.arrays, pt, Rt, e, E, ge)
    return e, E, ge


def placement(robot, q, frame) -> pin.SE3:
    """The frame's placement at q (n,) by Pinocchio's forward kinematics of the whole URDF."""
    model = robot.full_model
    data = model.createData()
    pin.framesForwardKinematics(model, data, robot.full_configuration(q))
    return data.oMf[find_frame(model, frame)]


def angle(a, b) -> float:
    """The angle (rad) between two 3-vectors."""
    return float(np.arctan2(np.linalg.norm(np.cross(a, b)), np.dot(a, b)))


def kernel_error(problem, Q) -> np.ndarray:
    """|e| (N,) of the kernel's stacked task error of a goal list at each row of Q (N, n), one task_rows call each."""
    stack, pt, Rt = problem.goal_stack()
    return np.array([np.linalg.norm(one_rows(problem.robot, stack, q, pt, Rt)[0]) for q in Q])


# ---------------------------------------------------------------------------------------------- the batch rows
@settings(max_examples=8, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_batch_rows_equal_the_kernel_rows_one_configuration_at_a_time(talos, seed):
    """Every goal kind the kernel knows, one goal weighted, each configuration with its own targets."""
    rng = np.random.default_rng(seed)
    q = talos.random_configurations(1, rng)[0]
    A, B = talos.fk(q, "arm_left_7_link"), talos.fk(q, "arm_right_7_link")
    goals = [Pose(SOLES[0], talos.fk(q, SOLES[0]), weight=2.5), Pose(SOLES[1], talos.fk(q, SOLES[1]), free="rz"),
             Position("head_2_link", talos.fk(q, "head_2_link").translation, tolerance=[0.01, 0.02, 0.0]),
             Orientation("torso_2_link", talos.fk(q, "torso_2_link").rotation),
             Direction("arm_left_7_link", Z, A.rotation @ Z), LookAt("arm_right_7_link", Z, [1.0, 0.2, 0.3]),
             RelativePose("arm_left_7_link", "arm_right_7_link", (A.inverse() * B).homogeneous, weight=0.5),
             CenterOfMass(point=com_of(talos, q)), CenterOfMass(support=SOLES, margin=0.01)]
    _, stack, pt, Rt = bind(talos, goals)
    N, G = 5, len(goals)
    Q = talos.random_configurations(N, rng)
    P = pt + rng.normal(0.0, 0.05, (N, G, 3))
    Rts = np.repeat(Rt[None], N, axis=0)
    e, E, ge = np.empty((N, stack.rows)), np.empty((N, stack.rows, talos.n)), np.empty((N, G, 2))
    task_rows_batch(Q, *talos.tree_constants(), *stack.arrays, P, Rts, e, E, ge)
    for i in range(N):
        e1, E1, ge1 = one_rows(talos, stack, Q[i], P[i], Rts[i])
        assert np.array_equal(e[i], e1) and np.array_equal(E[i], E1) and np.array_equal(ge[i], ge1)
    assert np.abs(E).max() > 0 and np.abs(e).max() > 0  # rows of every configuration were written


def test_a_tip_targets_rows_and_members_are_its_tip_goals(baxter):
    """A tip target's problem is its one goal on the tip: the same task rows and (no) goal-set members."""
    p = np.array([0.5, 0.2, 0.3])
    Q = np.zeros((2, baxter.n))
    Q[1] += 0.1
    target, goal = IKProblem(baxter, p), IKProblem(baxter, [Position(baxter.tip, p)])
    e, E = target.goal_rows(Q)
    e_goal, E_goal = goal.goal_rows(Q)
    assert e.shape == (2, 3) and np.array_equal(e, e_goal) and np.array_equal(E, E_goal)
    assert np.allclose(e, baxter.fk_batch(Q, validate=False)[0] - p)
    assert target.nearest_members(Q).tolist() == [[0], [0]]


def test_goal_task_is_the_kernel_rows_with_the_repair_sign(talos, rng):
    q = talos.random_configurations(1, rng)[0]
    goals = [Pose(SOLES[0], talos.fk(q, SOLES[0])), Direction("arm_left_7_link", Z, [0.0, 0.0, -1.0], weight=3.0)]
    problem = IKProblem(talos, goals)
    Q = talos.random_configurations(4, rng)
    e, J = goal_task(problem, Q)
    assert problem.evaluations == 0  # dls_repair counts its steps
    stack, pt, Rt = problem.goal_stack()
    for i in range(len(Q)):
        e1, E1, _ = one_rows(talos, stack, Q[i], pt, Rt)
        assert np.array_equal(e[i], -e1) and np.array_equal(J[i], E1)


# ---------------------------------------------------------------------------------------------- the repair steps
def talos_lists(talos):
    """Goal lists of the kinds beyond Pose and Position, each met at one configuration of Talos (a standing one for
    the support polygon, whose soles a Pose each pins)."""
    q = talos.random_configurations(1, np.random.default_rng(5))[0]
    A, B = talos.fk(q, "arm_left_7_link"), talos.fk(q, "arm_right_7_link")
    standing = np.zeros(talos.n)
    soles = [Pose(f, talos.fk(standing, f)) for f in SOLES]
    return {
        "direction": [Direction("arm_left_7_link", Z, A.rotation @ Z)],
        "look_at": [LookAt("arm_left_7_link", Z, A.translation + 0.4 * A.rotation @ Z)],
        "pose_free_rz": [Pose("arm_left_7_link", A, free="rz")],
        "orientation": [Orientation("arm_left_7_link", A.rotation)],
        "relative_pose": [RelativePose("arm_left_7_link", "arm_right_7_link", (A.inverse() * B).homogeneous)],
        "relative_pose_free_rz": [RelativePose("arm_left_7_link", "arm_right_7_link", (A.inverse() * B).homogeneous,
                                               free="rz")],
        "center_of_mass": [CenterOfMass(point=com_of(talos, q))],
        "support": soles + [CenterOfMass(support=SOLES, margin=0.02)],
    }


@pytest.mark.parametrize("kind", ["direction", "look_at", "pose_free_rz", "orientation", "relative_pose",
                                  "relative_pose_free_rz", "center_of_mass", "support"])
def test_repair_steps_bring_random_starts_towards_every_goal_kind(talos, kind):
    """The initial population's repair (4 x the default 3 steps) lowers the kernel's error of every start, the median
    at least tenfold (uniform random starts; near the standing pose for the support polygon)."""
    problem = IKProblem(talos, talos_lists(talos)[kind])
    rng = np.random.default_rng(0)
    if kind == "support":
        Q = np.clip(rng.normal(0.0, 0.3, (32, talos.n)), problem.lower, problem.upper)
    else:
        Q = talos.random_configurations(32, rng)
    before = kernel_error(problem, Q)
    repaired = dls_repair(problem, Q, 12, task=lambda Y: goal_task(problem, Y))
    assert problem.evaluations == 12 * len(Q)
    assert np.all((repaired >= problem.lower) & (repaired <= problem.upper))
    after = kernel_error(problem, repaired)
    assert np.all(after < before)
    assert np.median(after) <= np.median(before) / 10


def test_repair_weights_spare_the_high_gain_joints(talos):
    """W = 1 / K: a joint of a thousandfold gain moves a thousandfold less per unit of the others' motion."""
    problem = IKProblem(talos, talos_lists(talos)["direction"])
    Q = talos.random_configurations(8, np.random.default_rng(1))
    W = np.ones(talos.n)
    heavy = talos.joint_names.index("arm_left_4_joint")
    W[heavy] = 1e-3
    plain = dls_repair(problem, Q, 1, task=lambda Y: goal_task(problem, Y)) - Q
    weighted = dls_repair(problem, Q, 1, weights=W, task=lambda Y: goal_task(problem, Y)) - Q
    assert np.abs(weighted[:, heavy]).max() < 1e-2 * np.abs(plain[:, heavy]).max()
    assert np.all(kernel_error(problem, Q + weighted) < kernel_error(problem, Q))


# ---------------------------------------------------------------------------------------------- goal sets
def test_a_goal_set_is_repaired_towards_the_member_each_configuration_is_nearest(baxter):
    q1, q2 = baxter.random_configurations(2, np.random.default_rng(7))
    T1, T2 = baxter.fk(q1, "left_gripper"), baxter.fk(q2, "left_gripper")
    p = baxter.fk(q1, "right_gripper").translation
    problem = IKProblem(baxter, [Pose("left_gripper", [T1, T2]), Position("right_gripper", p)])
    Q = np.vstack([q1, q2, q2 + 0.01, q1 - 0.01])
    nearest = [0, 1, 1, 0]  # at or beside the configuration that puts the gripper on each member
    for q, m in zip(Q, nearest, strict=True):  # by Pinocchio: the member nearest by position + angle
        T = placement(baxter, q, "left_gripper")
        d = [np.linalg.norm(T.translation - M.translation) + angle_of(T.rotation, M.rotation) for M in (T1, T2)]
        assert int(np.argmin(d)) == m
    assert problem.nearest_members(Q).tolist() == [[m, 0] for m in nearest]  # the Position has one target
    e, J = goal_task(problem, Q)
    for i, m in enumerate(nearest):
        _, stack, pt, Rt = bind(baxter, [Pose("left_gripper", (T1, T2)[m]), Position("right_gripper", p)])
        e1, E1, _ = one_rows(baxter, stack, Q[i], pt, Rt)
        assert np.array_equal(e[i], -e1) and np.array_equal(J[i], E1)
    assert np.abs(e[0]).max() <= 1e-12 and np.abs(e[1, :6]).max() <= 1e-12  # on its member: nothing to repair
    assert np.abs(e[1, 6:]).max() > 0.01  # the right gripper at q2, far from p (q1's)


def angle_of(Ra, Rb) -> float:
    """The angle (rad) of the rotation between Ra and Rb."""
    return float(np.linalg.norm(pin.log3(Ra.T @ Rb)))


def test_nsga2_meets_a_goal_set(baxter):
    q1, q2 = baxter.random_configurations(2, np.random.default_rng(8))
    members = [baxter.fk(q, "left_gripper") for q in (q1, q2)]
    p = baxter.fk(q1, "right_gripper").translation
    goals = [Pose("left_gripper", members), Position("right_gripper", p)]
    r = ek.solve(baxter, goals, method="nsga2", seed=0, population=20, max_generations=6)
    assert r.success
    T, Tr = placement(baxter, r.q, "left_gripper"), placement(baxter, r.q, "right_gripper")
    assert min(max(np.linalg.norm(T.translation - M.translation), angle_of(T.rotation, M.rotation))
               for M in members) <= 1e-6
    assert np.linalg.norm(Tr.translation - p) <= 1e-6 and baxter.within_bounds(r.q)


# ---------------------------------------------------------------------------------------------- nsga2 answers
def baxter_pointing_lists(baxter, seed):
    """Two goal lists met at one random configuration of Baxter: a Pose and a Direction, a Position and a LookAt."""
    q = baxter.random_configurations(1, np.random.default_rng(seed))[0]
    Tl, Tr = baxter.fk(q, "left_gripper"), baxter.fk(q, "right_gripper")
    return [[Pose("left_gripper", Tl), Direction("right_gripper", Z, Tr.rotation @ Z)],
            [Position("left_gripper", Tl.translation),
             LookAt("right_gripper", Z, Tr.translation + 0.5 * Tr.rotation @ Z)]]


def meets_by_pinocchio(robot, goals, q) -> bool:
    """Every goal of a list of Pose, Position, Direction and LookAt goals within its tolerance by the frames'
    placements (Pinocchio, whole URDF): distances (m), rotation angles and angles between axes (rad)."""
    ok = robot.within_bounds(q)
    for g in goals:
        T = placement(robot, q, g.frame)
        if isinstance(g, Pose):
            ok &= np.linalg.norm(T.translation - g.target.translation) <= g.tolerance
            ok &= angle_of(T.rotation, g.target.rotation) <= g.rotation_tolerance
        elif isinstance(g, Position):
            ok &= np.linalg.norm(T.translation - g.target) <= g.tolerance
        elif isinstance(g, Direction):
            ok &= angle(T.rotation @ g.axis, g.direction) <= g.tolerance
        else:  # LookAt: the axis along the line from the frame's origin to the point
            ok &= angle(T.rotation @ g.axis, g.point - T.translation) <= g.tolerance
    return bool(ok)


@pytest.mark.parametrize("seed", [11, 12])
@pytest.mark.parametrize("which", [0, 1], ids=["pose+direction", "position+look_at"])
def test_nsga2_with_its_default_repair_meets_pointing_goals(baxter, seed, which):
    goals = baxter_pointing_lists(baxter, seed)[which]
    r = ek.solve(baxter, goals, method="nsga2", seed=seed, population=20, max_generations=6)
    assert r.success and "all feasible" in r.message
    assert meets_by_pinocchio(baxter, goals, r.q)
    assert all(meets_by_pinocchio(baxter, goals, q) for q in r.front.q)
    again = ek.solve(baxter, goals, method="nsga2", seed=seed, population=20, max_generations=6)
    assert np.array_equal(again.q, r.q) and np.array_equal(again.front.q, r.front.q)
