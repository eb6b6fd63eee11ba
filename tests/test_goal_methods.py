"""Goal lists in the methods that return more than one answer or one front: nsga2 (every goal as the constraint, the
manipulability of the stacked goal frames), hga (GA + Nelder-Mead on the goals' cost), memetic-all / solve_all (every
distinct solution, each meeting every goal), and the closed forms (one Pose or Position goal on the tip, or a
MethodError naming the methods that take goal lists).

Answers are judged by Pinocchio's forward kinematics of the whole URDF (test_goal_batch.consistent); the problems are
small (a 4-joint planar tree made here, Baxter's two grippers, one Talos floating-base solve_all) and the budgets
deterministic (populations, generations, LM starts), so the same seed gives the same answer.
"""

import json

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from test_goal_batch import TALOS_FRAMES, consistent, pinocchio_errors
from urdf_helpers import joint_xml, robot_xml

import evoik_pin as ek
from evoik_pin.cli import main
from evoik_pin.errors import MethodError, OptionError
from evoik_pin.goals import Pose, Position
from evoik_pin.io.goals_file import save_goals
from evoik_pin.lie import wrap_angle
from evoik_pin.problem import IKProblem
from evoik_pin.solvers.paper.analytic import planar2r_ik
from evoik_pin.solvers.paper.clustering import joint_differences
from evoik_pin.solvers.paper.nsga2 import GoalManipulability
from evoik_pin.solvers.search.all_solutions import DEFAULT_CLASS_RADIUS, goal_moving_joints
from evoik_pin.viz import html_commands

# A planar tree: a shared joint j0, then branch a (ja1, ja2) to tip_a and branch b (jb1) to tip_b. Two position goals
# (x, y on each tip; z stays 0) are 4 equations in 4 joints: finitely many solutions, 4 for Q_TREE (each branch's
# two elbows; none on a limit).
TREE = robot_xml("ytree", ["base", "l0", "a1", "a2", "tip_a", "b1", "tip_b"], [
    joint_xml("j0", "revolute", "base", "l0", axis="0 0 1", lo=-3, hi=3),
    joint_xml("ja1", "revolute", "l0", "a1", xyz="0.3 0 0", axis="0 0 1", lo=-2.5, hi=2.5),
    joint_xml("ja2", "revolute", "a1", "a2", xyz="0.25 0 0", axis="0 0 1", lo=-2.5, hi=2.5),
    joint_xml("jat", "fixed", "a2", "tip_a", xyz="0.2 0 0"),
    joint_xml("jb1", "revolute", "l0", "b1", xyz="0.3 0 0", rpy="0 0 1.0", axis="0 0 1", lo=-2.5, hi=2.5),
    joint_xml("jbt", "fixed", "b1", "tip_b", xyz="0.35 0 0"),
])
Q_TREE = np.array([0.4, -0.7, 1.1, -1.2])


@pytest.fixture(scope="module")
def tree():
    return ek.load_robot(TREE, tips=["tip_a", "tip_b"])


@pytest.fixture(scope="module")
def baxter():
    return ek.load_robot("baxter", tips=["left_gripper", "right_gripper"])


def tree_goals(robot, tolerance=1e-6):
    return [Position(f, robot.fk(Q_TREE, f).translation, tolerance=tolerance) for f in ("tip_a", "tip_b")]


def baxter_goals(robot):
    q = robot.random_configurations(1, np.random.default_rng(11))[0]
    return [Pose("left_gripper", robot.fk(q, "left_gripper")),
            Position("right_gripper", robot.fk(q, "right_gripper").translation)]


def meets_every_goal(robot, goals, q) -> bool:
    """Every goal within its tolerances by Pinocchio's kinematics at ``q``, which lies in the bounds."""
    errors = pinocchio_errors(robot, goals, q)
    return robot.within_bounds(q) and all(g.met(p, o) for g, (p, o) in zip(goals, errors, strict=True))


def errors_match(errors, expected) -> bool:
    """Two lists of per-goal (position m, rotation rad or None) errors agree within 1e-9."""
    return len(errors) == len(expected) and all(
        abs(p - pp) <= 1e-9 and (o is None) == (po is None) and (o is None or abs(o - po) <= 1e-9)
        for (p, o), (pp, po) in zip(errors, expected, strict=True))


# ---------------------------------------------------------------------------------------------- the problem's verdicts
def test_goal_violation_and_rows_met_judge_each_goal_by_its_own_tolerances(baxter):
    q = baxter.random_configurations(1, np.random.default_rng(11))[0]
    goals = [Pose("left_gripper", baxter.fk(q, "left_gripper"), tolerance=1e-3, rotation_tolerance=1e-2),
             Position("right_gripper", baxter.fk(q, "right_gripper").translation, tolerance=1e-4)]
    Q = np.vstack([q + d for d in np.linspace(0.0, 2e-3, 8)[:, None] * np.ones(baxter.n)])  # met, then not
    problem = IKProblem(baxter, goals)
    violation = problem.goal_violation(Q)
    assert problem.evaluations == len(Q)
    for row, v in zip(Q, violation, strict=True):
        (p0, o0), (p1, _) = pinocchio_errors(baxter, goals, row)
        expected = max(p0 - 1e-3, 0.0) + max(o0 - 1e-2, 0.0) + max(p1 - 1e-4, 0.0)
        assert v == pytest.approx(expected, abs=1e-12)
    met = problem.rows_met(Q)
    assert problem.evaluations == len(Q)  # bookkeeping, not search
    assert met.tolist() == [meets_every_goal(baxter, goals, row) for row in Q] and met[0] and not met[-1]


def test_a_tightened_goal_problem_runs_lm_to_the_smaller_tolerance(tree):
    from evoik_pin.solvers.lm import LevenbergMarquardt

    goals = tree_goals(tree, tolerance=1e-3)
    problem = IKProblem(tree, goals)
    tight = problem.tightened(1e-12)
    assert tight.goals == goals and [g.tolerance for g in tight.goals] == [1e-3, 1e-3]
    start = Q_TREE + 0.05
    loose, exact = LevenbergMarquardt(problem).run(start, 100), LevenbergMarquardt(tight).run(start, 100)
    assert loose.converged and exact.converged and exact.position_error <= 1e-12 < loose.position_error


# ---------------------------------------------------------------------------------------------- nsga2
def test_nsga2_meets_every_goal_and_its_front_is_feasible(baxter):
    goals = baxter_goals(baxter)
    r = ek.solve(baxter, goals, method="nsga2", seed=0, population=20, max_generations=6)
    assert r.success and r.method == "nsga2"
    consistent(baxter, goals, r)
    assert len(r.front) >= 1 and np.all(r.front.violation == 0.0) and "all feasible" in r.message
    assert all(meets_every_goal(baxter, goals, q) for q in r.front.q)
    # the answer is the front's member of least smoothness S (the objectives' last column), q0 absent: |q|
    S = np.linalg.norm(r.front.q, axis=1)
    assert r.front.objectives[:, 1] == pytest.approx(S, abs=1e-12)
    assert np.array_equal(r.q, r.front.q[int(S.argmin())])
    again = ek.solve(baxter, goals, method="nsga2", seed=0, population=20, max_generations=6)
    assert np.array_equal(again.q, r.q) and np.array_equal(again.front.q, r.front.q)


def test_nsga2_manipulability_of_a_goal_list_is_that_of_the_stacked_goal_jacobians(baxter):
    """Y = sqrt(det(J J^T)) of the rows each goal constrains (a Pose: six, a Position: three), every goal frame's
    base-frame Jacobian by Pinocchio stacked; manipulability_goals picks goals by index or frame."""
    Q = baxter.random_configurations(3, np.random.default_rng(4))
    objective = GoalManipulability(["left_gripper", "right_gripper"], [range(6), range(3)], form="value")
    left_only = GoalManipulability(["left_gripper"], [range(6)], form="value")
    for q, y, y_left in zip(Q, objective(Q, robot=baxter), left_only(Q, robot=baxter), strict=True):
        J = [baxter.jacobian(q, of=f) for f in ("left_gripper", "right_gripper")]  # pinocchio.computeFrameJacobian
        stacked = np.vstack([J[0], J[1][:3]])
        assert y == pytest.approx(np.sqrt(np.linalg.det(stacked @ stacked.T)), rel=1e-9)
        assert y_left == pytest.approx(np.sqrt(np.linalg.det(J[0] @ J[0].T)), rel=1e-9)
    goals = baxter_goals(baxter)
    r = ek.solve(baxter, goals, method="nsga2", seed=1, population=12, max_generations=2,
                 manipulability_goals=["left_gripper"])
    consistent(baxter, goals, r)


def test_nsga2_on_a_planar_tree_leaves_out_the_rows_no_joint_moves(tree):
    goals = tree_goals(tree)
    r = ek.solve(tree, goals, method="nsga2", seed=2, population=16, max_generations=4)
    assert r.success and meets_every_goal(tree, goals, r.q)
    consistent(tree, goals, r)
    assert "(tip_a:vz, tip_b:vz)" in r.message  # a planar tree's goal frames never move along z


def test_nsga2_along_a_trajectory_of_goal_lists_stays_on_the_branch_of_the_previous_answer(tree):
    """solve_trajectory hands each answer to the next point as q0, from which nsga2's smoothness S is measured: the
    answers follow one branch (of the tree's four) in small steps; solve_many solves the same lists one by one."""
    lists = [[Position(f, tree.fk(Q_TREE + 0.05 * k, f).translation) for f in ("tip_a", "tip_b")] for k in range(3)]
    options = {"population": 16, "max_generations": 3}
    path = ek.solve_trajectory(tree, lists, method="nsga2", seed=0, **options)
    for goals, r in zip(lists, path, strict=True):
        consistent(tree, goals, r)
        assert r.success
    assert max(np.abs(b.q - a.q).max() for a, b in zip(path[:-1], path[1:], strict=True)) < 0.2
    many = ek.solve_many(tree, lists, method="nsga2", seed=0, workers=1, **options)
    for goals, r in zip(lists, many, strict=True):
        consistent(tree, goals, r)
        assert r.success


def test_nsga2_refuses_bad_options_on_goal_lists(baxter):
    goals = baxter_goals(baxter)
    with pytest.raises(OptionError, match="manipulability_goals"):
        ek.solve(baxter, goals, method="nsga2", manipulability_rows=[0, 1, 2])
    with pytest.raises(OptionError, match=r"indices 0..1 or the goals' frames \['left_gripper', 'right_gripper'\]"):
        ek.solve(baxter, goals, method="nsga2", manipulability_goals=["head"])
    with pytest.raises(OptionError, match="got 1.5"):
        ek.solve(baxter, goals, method="nsga2", manipulability_goals=1.5)
    with pytest.raises(OptionError, match="distinct goals"):
        ek.solve(baxter, goals, method="nsga2", manipulability_goals=[0, "left_gripper"])
    with pytest.raises(OptionError, match="manipulability_rows"):
        ek.solve("planar2r", [0.2, 0.2, 0.0], method="nsga2", manipulability_goals=[0])
    with pytest.raises(OptionError, match="population"):
        ek.solve(baxter, goals, method="nsga2", population=2)


def test_nsga2_repairs_a_goal_of_any_class_by_its_kind_s_kernel_rows(baxter):
    """The repair reads the LM kernel's rows of each goal's kind (test_nsga2_repair.py covers every kind), so a goal
    class of the user's own, here a Position subclass, is repaired as its kind is, and met."""
    class Marker(Position):
        pass

    q = baxter.random_configurations(1, np.random.default_rng(12))[0]
    goals = [baxter_goals(baxter)[0], Marker("right_gripper", baxter.fk(q, "right_gripper").translation)]
    r = ek.solve(baxter, goals, method="nsga2", seed=0, population=20, max_generations=6)
    consistent(baxter, goals, r)
    assert r.success and meets_every_goal(baxter, goals, r.q)
    plain = ek.solve(baxter, goals, method="nsga2", seed=0, population=8, max_generations=1, repair_steps=0)
    consistent(baxter, goals, plain)


# ---------------------------------------------------------------------------------------------- hga
def test_hga_finds_distinct_solutions_that_meet_every_goal(tree):
    goals = tree_goals(tree)
    options = {"population": 200, "max_generations": 8, "max_starts": 8}
    r = ek.solve(tree, goals, method="hga", seed=0, **options)
    assert r.success and len(r.solutions) >= 2
    consistent(tree, goals, r)
    for s in r.solutions:
        assert s.success and meets_every_goal(tree, goals, s.q)
        assert errors_match(s.goal_errors, pinocchio_errors(tree, goals, s.q))
    Q = np.array([s.q for s in r.solutions])
    for i in range(len(Q) - 1):  # distinct: more than solution_radius (1e-4 rad) apart
        assert np.linalg.norm(Q[i + 1:] - Q[i], axis=1).min() > 1e-4
    sols = ek.solve_all(tree, goals, method="hga", seed=0, **options)
    assert [s.q.tolist() for s in sols] == Q.tolist()
    with pytest.raises(OptionError, match="max_starts"):
        ek.solve(tree, goals, method="hga", max_starts=0)


def test_hga_on_a_whole_robot_that_it_does_not_solve_says_what_does(baxter):
    goals = baxter_goals(baxter)
    r = ek.solve(baxter, goals, method="hga", seed=0, population=20, max_generations=1, max_starts=2,
                 max_polish_evaluations=20)
    assert not r.success and r.solutions == [] and "goals not met: left_gripper" in r.message
    assert "Nelder-Mead over 14 joints rarely meets a goal list's tolerances; memetic-all finds" in r.message
    consistent(baxter, goals, r)


# ---------------------------------------------------------------------------------------------- memetic-all
def test_solve_all_of_a_goal_list_with_finitely_many_solutions_finds_each_once(tree):
    goals = tree_goals(tree)
    sols = ek.solve_all(tree, goals, seed=0)
    assert len(sols) == 4 and "4 distinct solution(s)" in sols.message  # both elbows of each branch
    Q = np.array([s.q for s in sols])
    assert any(np.allclose(q, Q_TREE, atol=1e-9) for q in Q)
    for s in sols:
        assert s.success and meets_every_goal(tree, goals, s.q)
        assert errors_match(s.goal_errors, pinocchio_errors(tree, goals, s.q))
    wrap = np.zeros(tree.n, dtype=bool)
    for i in range(len(Q) - 1):
        assert np.linalg.norm(joint_differences(Q[i + 1:], Q[i], wrap), axis=1).min() > DEFAULT_CLASS_RADIUS
    assert [s.q.tolist() for s in ek.solve_all(tree, goals, seed=0)] == Q.tolist()
    # solve() with memetic-all: the first solution, with the goals' verdict
    r = ek.solve(tree, goals, method="memetic-all", seed=0)
    consistent(tree, goals, r)
    assert r.success and np.array_equal(r.q, Q[0]) and len(r.solutions) == 4


def tree_closed_form(goals) -> np.ndarray:
    """Every solution (M, 4) within the limits of the planar tree's two position goals, by two planar 2R closed
    forms: tip_b fixes (j0, jb1) (links 0.3 and 0.35 m, jb1 after a fixed 1 rad turn), then tip_a, seen from l0's
    end, fixes (ja1, ja2) (links 0.25 and 0.2 m)."""
    pa, pb = (g.encode()[0][:2] for g in goals)
    out = []
    for j0, phi in planar2r_ik(pb[0], pb[1], 0.3, 0.35):
        c, s = np.cos(j0), np.sin(j0)
        d = np.array([[c, s], [-s, c]]) @ (pa - 0.3 * np.array([c, s]))
        for ja1, ja2 in planar2r_ik(d[0], d[1], 0.25, 0.2):
            out.append([j0, ja1, ja2, wrap_angle(phi - 1.0)])
    Q = np.array(out).reshape(-1, 4)
    return Q[np.all((Q >= [-3, -2.5, -2.5, -2.5]) & (Q <= [3, 2.5, 2.5, 2.5]), axis=1)]


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_solve_all_of_the_planar_tree_is_its_closed_form_set(tree, seed):
    """Targets of a random configuration: solve_all returns exactly the closed-form solutions (matched one to one
    within 1e-6 rad), away from the limits and the elbows' singular (straight) configurations."""
    q = tree.random_configurations(1, np.random.default_rng(seed))[0]
    goals = [Position(f, tree.fk(q, f).translation) for f in ("tip_a", "tip_b")]
    reference = tree_closed_form(goals)
    assert len(reference) and np.abs(reference - q).max(axis=1).min() < 1e-9  # q is among them
    assume(np.all(np.abs(np.sin(reference[:, [2]])) > 0.05) and np.all(np.abs(np.sin(reference[:, 3] + 1.0)) > 0.05))
    assume(np.all(np.minimum(reference - tree.lower, tree.upper - reference) > 1e-3))
    for r in reference:
        assert meets_every_goal(tree, goals, r)
    sols = ek.solve_all(tree, goals, seed=0, timeout=None)
    Q = np.array([s.q for s in sols])
    assert len(Q) == len(reference), (Q, reference)
    D = np.abs(Q[:, None] - reference[None]).max(axis=2)
    assert np.all(D.min(axis=1) < 1e-6) and np.all(D.min(axis=0) < 1e-6)


def test_solve_all_of_a_redundant_goal_list_returns_count_spread_solutions(baxter):
    goals = baxter_goals(baxter)
    sols = ek.solve_all(baxter, goals, seed=0, count=3, timeout=None, max_starts=256)
    assert len(sols) == 3 and "spread over the self-motion manifold" in sols.message
    for s in sols:
        assert s.success and meets_every_goal(baxter, goals, s.q)
    Q = np.array([s.q for s in sols])
    spread = sols.result.history["min_pairwise_distance"][0]
    assert spread > DEFAULT_CLASS_RADIUS
    for i in range(len(Q) - 1):
        assert np.linalg.norm(Q[i + 1:] - Q[i], axis=1).min() >= spread - 1e-12
    again = ek.solve_all(baxter, goals, seed=0, count=3, timeout=None, max_starts=256)
    assert [s.q.tolist() for s in again] == Q.tolist()


def test_solve_all_on_a_floating_base_puts_joints_no_goal_moves_at_q0():
    talos = ek.load_robot("talos", floating_base=True)
    q = talos.random_configurations(1, np.random.default_rng(3))[0]
    goals = [Pose(f, talos.fk(q, f)) for f in TALOS_FRAMES]
    q0 = talos.clip(np.full(talos.n, 0.1))
    sols = ek.solve_all(talos, goals, seed=0, count=2, q0=q0, timeout=None, max_starts=128)
    assert len(sols) == 2
    stack = IKProblem(talos, goals).goal_stack()[0]
    still = ~goal_moving_joints(talos, stack)
    assert still.any()  # the head and the grippers move no goal frame
    assert {talos.joint_names[k] for k in np.flatnonzero(~still)} == set().union(
        *(talos.moving_joints(f) for f in TALOS_FRAMES))
    for s in sols:
        assert meets_every_goal(talos, goals, s.q)
        assert np.array_equal(s.q[still], q0[still])


def test_memetic_all_refuses_bad_options_on_goal_lists(tree):
    goals = tree_goals(tree)
    with pytest.raises(OptionError, match="count"):
        ek.solve_all(tree, goals, count=0)
    with pytest.raises(OptionError, match="compiled LM engine only"):
        ek.solve_all(tree, goals, engine="python")


def test_solve_all_of_goals_out_of_reach_is_empty_and_names_the_goals(tree):
    goals = [Position("tip_a", [2.0, 0.0, 0.0]), Position("tip_b", tree.fk(Q_TREE, "tip_b").translation)]
    sols = ek.solve_all(tree, goals, seed=0, timeout=None, max_starts=64)
    assert sols == [] and "goals not met: tip_a" in sols.message and "out of reach" in sols.message
    assert not sols.result.success


# ---------------------------------------------------------------------------------------------- closed forms
def test_the_closed_forms_take_one_goal_on_the_tip_and_refuse_other_goal_lists(tree):
    puma = ek.load_robot("puma3r")
    p = puma.fk(np.array([0.3, -0.5, 0.8])).translation
    one = ek.solve(puma, p, method="algebraic")
    goal = ek.solve(puma, [Position(puma.tip, p)], method="algebraic")
    assert goal.success and np.array_equal(goal.q, one.q) and len(goal.solutions) == len(one.solutions) == 4
    assert errors_match(goal.goal_errors, pinocchio_errors(puma, [Position(puma.tip, p)], goal.q))
    assert [s.q.tolist() for s in ek.solve_all(puma, [Position(puma.tip, p)], method="algebraic")] == [
        s.q.tolist() for s in one.solutions]
    for goals in ([Position(puma.tip, p), Position(puma.tip, p)], [Position("link2", p)]):
        with pytest.raises(MethodError, match="only when it is one Pose or Position goal on the tip 'tool'; goal "
                                              "lists are solved by 'memetic', 'memetic-all'"):
            ek.solve(puma, goals, method="algebraic")
    with pytest.raises(MethodError, match="'algebraic' has closed forms for the bundled robots"):
        ek.solve(tree, tree_goals(tree)[:1], method="algebraic")  # a single goal, but on no closed-form arm


# ---------------------------------------------------------------------------------------------- stopping rule
def test_population_methods_stop_when_every_goal_meets_its_own_tolerance(tree):
    """A population method stops once its best member meets every goal's own tolerance (1e-3 m here, not the
    problem's 1e-6); a goal tighter than the problem's tolerance is not declared met early."""
    r = ek.solve(tree, tree_goals(tree, tolerance=1e-3), method="de", seed=0, max_generations=300)
    assert r.success and r.message == "tolerance reached" and r.generations < 300
    assert meets_every_goal(tree, tree_goals(tree, tolerance=1e-3), r.q)
    tight = ek.solve(tree, tree_goals(tree, tolerance=1e-9), method="de", seed=0, max_generations=30, tolerance=1e-2)
    assert not tight.success and tight.position_error < 1e-2 and "goals not met: tip_a" in tight.message
    assert "max_generations (30) reached" in tight.message  # every restart ran its generations


# ---------------------------------------------------------------------------------------------- command line
def test_evoik_solve_all_of_a_goals_file(baxter, tmp_path, capsys):
    """``evoik solve baxter --tips ... --goals FILE --all``: every solution meets every goal by Pinocchio; the text
    output has a line per solution; a method returning one answer is refused naming those that return several."""
    goals = baxter_goals(baxter)
    path = save_goals(goals, tmp_path / "grippers.yaml", robot="baxter", tips=["left_gripper", "right_gripper"])
    argv = ["solve", "baxter", "--goals", str(path), "--all", "--count", "3", "--timeout", "none",
            "--option", "max_starts=256"]
    assert main([*argv, "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["success"] and info["count"] == 3 and info["method"] == "memetic-all"
    for row in info["solutions"]:
        q = np.array(row["q_rad"])
        assert meets_every_goal(baxter, goals, q) and all(e["met"] for e in row["goal_errors"])
        assert errors_match([(e["position_error_m"], e["rotation_error_rad"]) for e in row["goal_errors"]],
                            pinocchio_errors(baxter, goals, q))
        assert np.allclose(row["q_pinocchio"], baxter.full_configuration(q))
    assert main(argv) == 0
    out = capsys.readouterr().out.splitlines()
    assert "3 solution(s) of 2 goals" in out[0] and len(out) == 5 and "every goal met" in out[-1]
    assert main([*argv[:5], "--method", "de"]) == 2
    assert "'de' returns one solution; solve_all needs one of" in capsys.readouterr().err


@pytest.mark.filterwarnings("ignore:ytree. its URDF has no <visual> geometry")
def test_evoik_solve_all_of_a_goals_file_draws_the_goals_and_every_solution(tree, tmp_path, capsys):
    urdf = tmp_path / "ytree.urdf"
    urdf.write_text(TREE)
    path = save_goals(tree_goals(tree), tmp_path / "tips.yaml", tips=["tip_a", "tip_b"])
    html = tmp_path / "all.html"
    assert main(["solve", str(urdf), "--goals", str(path), "--all", "--html", str(html)]) == 0
    assert f"wrote {html}" in capsys.readouterr().err
    objects = {c["path"] for c in html_commands(html.read_text()) if c["type"] == "set_object"}
    assert {"/meshcat/goals/tip_a/point", "/meshcat/goals/tip_b/point"} <= objects
    assert {f"/meshcat/solutions/{k}" for k in range(4)} <= {"/".join(o.split("/")[:4]) for o in objects}
