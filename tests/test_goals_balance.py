"""CenterOfMass and RelativePose goals (evoik_pin.goals): their checks when made and bound; the compiled centre of
mass and its Jacobian against Pinocchio (centerOfMass, jacobianCenterOfMass, finite differences) on Talos and G1
with a floating base, a chain, and random trees with random inertias; the support polygon's one-sided rows; the
relative pose's rows against finite differences; populations' violations; and memetic solves judged by
Pinocchio."""

import re

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from kernel_helpers import numeric_jacobian, rows
from test_robot_tree import random_trees
from urdf_helpers import joint_xml

import evoik_pin as ek
from evoik_pin.errors import FrameError, OptionError, TargetError
from evoik_pin.goals import CenterOfMass, Pose, RelativePose, bind
from evoik_pin.goals.center_of_mass import com_batch, com_of, contact_points, polygon_distance
from evoik_pin.problem import IKProblem


@pytest.fixture(scope="module")
def talos():
    return ek.load_robot("talos", floating_base=True)


def check_com(robot, q):
    """The kernel's CoM (a point goal at the origin: e = CoM) and its Jacobian against Pinocchio's centerOfMass of
    the whole URDF, its finite differences, and jacobianCenterOfMass where the reduced model holds every mass."""
    e, E, _ = rows(robot, [CenterOfMass(point=np.zeros(3))], q)
    assert np.allclose(e, com_of(robot, q), atol=1e-12, rtol=0)
    assert np.allclose(com_batch(robot, q[None])[0], e, atol=1e-12, rtol=0)
    assert np.allclose(E, numeric_jacobian(lambda x: com_of(robot, x), q), atol=1e-6)
    model = robot.model
    if model.inertias[0].mass == robot.full_model.inertias[0].mass and not robot.mimic_joints:
        data = model.createData()
        J = np.reshape(pin.jacobianCenterOfMass(model, data, robot.to_pinocchio(q)), (3, -1))
        assert np.allclose(E, robot.tree.base_R @ J, atol=1e-10)


@pytest.mark.parametrize("name, kw", [("talos", {"floating_base": True}), ("g1", {"floating_base": True}),
                                      ("panda", {}), ("talos", {"tips": ["arm_left_7_link"]}),
                                      ("ur5", {"base": "base_link"})])
def test_compiled_center_of_mass_and_jacobian_equal_pinocchio(name, kw, rng):
    robot = ek.load_robot(name, **kw)
    for q in robot.random_configurations(2, rng):
        check_com(robot, q)


@st.composite
def massive_trees(draw):
    """A random tree of test_robot_tree (revolute, continuous, prismatic, fixed and mimic joints) whose every link
    gets a random mass (some 0) at a random centre, with an inertia."""
    xml = draw(random_trees())
    for name in re.findall(r'<link name="([^"]+)"/>', xml):
        mass = draw(st.sampled_from([0.0, draw(st.floats(0.1, 5.0))]))
        c = " ".join(f"{v:.6g}" for v in draw(st.lists(st.floats(-0.4, 0.4), min_size=3, max_size=3)))
        inertial = (f'<inertial><origin xyz="{c}" rpy="0.1 0.2 0.3"/><mass value="{mass}"/>'
                    '<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.03"/></inertial>')
        xml = xml.replace(f'<link name="{name}"/>', f'<link name="{name}">{inertial}</link>')
    return xml


@settings(max_examples=40, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])
@given(xml=massive_trees(), floating=st.booleans(), seed=st.integers(0, 2**16), data=st.data())
def test_compiled_center_of_mass_of_random_trees_equals_pinocchio(xml, floating, seed, data):
    links = [f"l{i}" for i in range(xml.count("<joint "))] if "lm" not in xml else ["lm"]
    tips = data.draw(st.one_of(st.just("all"), st.lists(st.sampled_from(links), min_size=1, max_size=2, unique=True)))
    try:
        robot = ek.load_robot(xml, tips=tips, floating_base=floating)
    except ek.errors.RobotLoadError:  # chains of fixed joints only
        return
    if not robot.mass_constants.total > 0:
        with pytest.raises(TargetError, match="no mass"):
            bind(robot, [CenterOfMass(point=np.zeros(3))])
        return
    for q in robot.random_configurations(2, np.random.default_rng(seed)):
        check_com(robot, q)


SOLES = ["left_sole_link", "right_sole_link"]


def test_support_rows_are_the_distance_outside_the_shrunk_polygon(talos, rng):
    """On Talos, whose soles move with the base: |e| is the distance from the CoM's ground point to the convex hull
    of the soles' contact points shrunk by margin + tolerance (0 inside), Pinocchio's kinematics the judge."""
    margin = 0.02
    goal = CenterOfMass(support=SOLES, margin=margin)
    inside = outside = 0
    q0 = np.zeros(talos.n)
    Q = np.vstack([q0, q0 + 0.3 * rng.standard_normal((30, talos.n))])
    Q = np.clip(Q, talos.lower, talos.upper)
    for q in Q:
        e, E, ge = rows(talos, [goal], q)
        ground = np.concatenate([contact_points(talos, f) @ talos.fk(q, f).rotation.T + talos.fk(q, f).translation
                                 for f in SOLES])
        d = polygon_distance(com_of(talos, q)[:2], ground, margin + goal.tolerance)
        assert ge[0, 0] == pytest.approx(d, abs=1e-9) and np.linalg.norm(e) == pytest.approx(d, abs=1e-9)
        if d == 0:
            assert not E.any()
            inside += 1
        else:
            outside += 1
    assert inside and outside


@pytest.mark.parametrize("square", [(-0.05, 0.05), (0.2, 0.3), (-0.4, 0.4)])
def test_support_jacobian_is_the_finite_difference_over_fixed_contact_points(square, rng):
    """Contact points on a frame no joint moves (Panda's base link): the 2 rows' Jacobian equals their finite
    differences, inside (zero), on an edge and at a vertex of the shrunk square."""
    robot = ek.load_robot("panda")
    lo, hi = square
    pts = np.array([[lo, lo, 0], [hi, lo, 0], [hi, hi, 0], [lo, hi, 0], [0.5 * (lo + hi), lo, 0]])
    goal = CenterOfMass(support={"panda_link0": pts}, margin=0.01)
    for q in robot.random_configurations(6, rng):
        e, E, _ = rows(robot, [goal], q)
        assert np.allclose(E, numeric_jacobian(lambda x: rows(robot, [goal], x)[0], q), atol=1e-6)


def test_relative_pose_rows_are_log6_and_their_finite_differences(rng):
    """Baxter's right gripper seen from its left one, and Talos's hands with a floating base: e = log6(T^-1 T_a^-1
    T_b) by Pinocchio, E its finite differences, the errors (|position|, angle)."""
    for robot, a, b in ((ek.load_robot("baxter", tips="all"), "left_gripper", "right_gripper"),
                        (ek.load_robot("talos", floating_base=True), "arm_left_7_link", "arm_right_7_link")):
        T = pin.SE3(pin.rpy.rpyToMatrix(0.1, -0.4, 2.9), np.array([0.05, -0.3, 0.02]))
        goal = RelativePose(a, b, T, weight=2.0)
        for q in robot.random_configurations(3, rng):
            e, E, ge = rows(robot, [goal], q)
            M = T.inverse() * robot.fk(q, a).inverse() * robot.fk(q, b)
            assert np.allclose(e / np.sqrt(2.0), pin.log6(M).vector, atol=1e-10)
            assert np.allclose(ge[0], goal.robot_errors(robot, q), atol=1e-10)
            assert np.allclose(E, numeric_jacobian(lambda x, r=robot, g=goal: rows(r, [g], x)[0], q), atol=1e-6)
            pos, rot = goal.robot_population_errors(robot, q[None])
            assert np.allclose([pos[0], rot[0]], ge[0], atol=1e-10)


def test_goals_check_their_inputs(talos):
    with pytest.raises(TargetError, match="exactly one"):
        CenterOfMass()
    with pytest.raises(TargetError, match="exactly one"):
        CenterOfMass(point=[0, 0, 1], support=SOLES)
    with pytest.raises(TargetError, match="3-vector"):
        CenterOfMass(point=[0, 0])
    for bad in ("xyw", "", "xx", 3):
        with pytest.raises(OptionError, match="axes"):
            CenterOfMass(point=[0, 0, 1], axes=bad)
    assert CenterOfMass(point=[0, 0, 1], axes="yx").axes == "xy"
    with pytest.raises(OptionError, match="margin .* >= 0"):
        CenterOfMass(support=SOLES, margin=-0.01)
    for bad in ({"foot": np.zeros((4, 2))}, {"foot": np.zeros((0, 3))}, {"foot": [[0, 0, np.nan]]}, {"foot": "x"}):
        with pytest.raises(TargetError, match="support points of 'foot'"):
            CenterOfMass(support=bad)
    with pytest.raises(TargetError, match="names no frame"):
        CenterOfMass(support=[])
    with pytest.raises(OptionError, match="weight of the centre-of-mass goal"):
        CenterOfMass(point=[0, 0, 1], weight=0)
    with pytest.raises(FrameError, match="no frame 'left_sol'"):
        bind(talos, [CenterOfMass(support=["left_sol"])])
    T = np.eye(4)
    with pytest.raises(FrameError, match="twice"):
        RelativePose("a", "a", T)
    with pytest.raises(TargetError, match="RelativePose of 'b' seen from 'a'"):
        RelativePose("a", "b", [1, 2, 3])
    with pytest.raises(FrameError, match="no frame 'hand'"):
        bind(talos, [RelativePose("arm_left_7_link", "hand", T)])
    with pytest.raises(FrameError, match="relative to"):
        bind(talos, [RelativePose("left_sole_link", "leg_left_6_link", T)])
    massless = ek.load_robot('<?xml version="1.0"?><robot name="m"><link name="a"/><link name="b"/>'
                             + joint_xml("j", "revolute", "a", "b") + "</robot>")
    with pytest.raises(TargetError, match="no mass"):
        bind(massless, [CenterOfMass(point=[0, 0, 0])])
    with pytest.raises(FrameError, match="carries no collision geometry"):
        contact_points(massless, "b")


# ---------------------------------------------------------------------------------------------- files and CLI
def test_goals_files_keep_the_new_kinds(tmp_path):
    from evoik_pin.io.goals_file import load_goals, save_goals

    T = pin.SE3(pin.rpy.rpyToMatrix(np.pi, 0.1, 0), np.array([0.0, 0.01, 0.3]))
    goals = [CenterOfMass(point=[0.1, -0.2, 0.9], axes="xy", weight=2.0),
             CenterOfMass(support=SOLES, margin=0.02),
             CenterOfMass(support={"left_sole_link": [[0.1, 0.05, 0], [-0.1, 0.05, 0], [0, -0.05, 0]]}, tolerance=1e-8),
             RelativePose("left_gripper", "right_gripper", T, rotation_tolerance=1e-5)]
    for ext in ("yaml", "json"):
        back = load_goals(save_goals(goals, tmp_path / f"g.{ext}"))
        assert [repr(g) for g in back] == [repr(g) for g in goals]
        assert np.array_equal(back[3].target.homogeneous, T.homogeneous)
        assert np.array_equal(back[2].support["left_sole_link"], goals[2].support["left_sole_link"])
    bad = {"kind: center_of_mass\n  frame: x": "unknown key.*'frame'",
           "kind: center_of_mass": "needs target",
           "kind: center_of_mass\n  support: [a]\n  margin: -1": "margin",
           "kind: center_of_mass\n  support: {a: [[1, 2]]}": "support points of 'a'",
           "kind: center_of_mass\n  target: {position: [0, 0, 0]}\n  axes: w": "axes",
           "kind: relative_pose\n  frame: b\n  target: {position: [0, 0, 0], rpy: [0, 0, 0]}":
               "missing field 'frame_a'"}
    for text, match in bad.items():
        path = tmp_path / "bad.yaml"
        path.write_text(f"goals:\n- {text}\n")
        with pytest.raises(ek.errors.GoalsFileError, match=match):
            load_goals(path)


def test_cli_solves_a_standing_goals_file(talos, tmp_path, capsys):
    from evoik_pin.cli import main
    from evoik_pin.io.goals_file import save_goals

    q = np.zeros(talos.n)
    q[2] = 1.02
    goals = [Pose(f, talos.fk(q, f)) for f in SOLES] + [CenterOfMass(support=SOLES, margin=0.02)]
    path = save_goals(goals, tmp_path / "stand.yaml", robot=talos)
    code = main(["solve", "talos", "--goals", str(path), "--timeout", "none", "--option", "max_restarts=3"])
    out = capsys.readouterr().out
    assert code == 0 and re.search(r"2  center of mass +center_of_mass +0.000e\+00 +free +yes", out)


# ---------------------------------------------------------------------------------------------- populations, solves
def test_population_violations_follow_the_goals_errors(talos, rng):
    T = pin.SE3(np.eye(3), np.array([0.0, -0.4, 0.0]))
    goals = [CenterOfMass(point=[0.0, 0.0, 0.8], axes="xz"), CenterOfMass(support=SOLES, margin=0.01),
             RelativePose("arm_left_7_link", "arm_right_7_link", T)]
    problem = IKProblem(talos, goals)
    q0 = np.zeros(talos.n)
    Q = np.clip(q0 + 0.3 * rng.standard_normal((12, talos.n)), talos.lower, talos.upper)
    pos, rot, _ = problem._goal_population_members(Q)
    ev = problem.evaluate(Q)
    assert np.allclose(ev.position_error, pos.max(axis=1)) and ev.orientation_error is not None
    for q, p, r in zip(Q, pos, rot, strict=True):
        errors = problem.goal_errors(q)
        assert p[0] == pytest.approx(errors[0][0], abs=1e-12) and errors[0][1] is None
        d = errors[1][0]
        assert (p[1] == 0) == (d == 0) and p[1] <= d + 1e-12  # the half-plane violation: 0 inside, below the distance
        assert p[2] == pytest.approx(errors[2][0], abs=1e-12) and r[2] == pytest.approx(errors[2][1], abs=1e-9)


def standing(robot, margin=0.02):
    q = np.zeros(robot.n)
    q[2] = 1.02
    return [Pose(f, robot.fk(q, f)) for f in SOLES] + [CenterOfMass(support=SOLES, margin=margin)]


def test_memetic_stands_talos_with_its_hands_on_targets(talos, rng):
    """Soles fixed, CoM over them (2 cm in), both hands on targets reached by a standing configuration: every answer
    meets every goal by Pinocchio's kinematics, its CoM projection inside the shrunk polygon."""
    stance = standing(talos)
    for i in range(4):
        start = talos.random_configurations(1, rng)[0]
        start[:6] = 0.0, 0.0, 1.02, 0.0, 0.0, 0.0
        reached = ek.solve(talos, stance, q0=start, seed=i, timeout=None, max_restarts=2)
        assert reached.success
        hands = [Pose(f, talos.fk(reached.q, f)) for f in ("arm_left_7_link", "arm_right_7_link")]
        r = ek.solve(talos, stance + hands, seed=i, timeout=None, max_restarts=5)
        assert r.success and talos.within_bounds(r.q)
        ground = np.concatenate([contact_points(talos, f) @ talos.fk(r.q, f).rotation.T + talos.fk(r.q, f).translation
                                 for f in SOLES])
        assert polygon_distance(com_of(talos, r.q)[:2], ground, 0.02) == 0.0 and r.goal_errors[2] == (0.0, None)
        for g in stance[:2] + hands:
            T = talos.fk(r.q, g.frame)
            assert np.linalg.norm(T.translation - g.target.translation) <= 1e-6
            assert np.linalg.norm(pin.log3(g.target.rotation.T @ T.rotation)) <= 1e-6


def test_memetic_and_de_put_the_centre_of_mass_on_a_point(rng):
    robot = ek.load_robot("panda")
    target = com_of(robot, robot.random_configurations(1, rng)[0])
    for method, options in (("memetic", {"timeout": None, "max_restarts": 3}),
                            ("de", {"tolerance": 1e-3})):
        goal = CenterOfMass(point=target, axes="xyz", tolerance=options.pop("tolerance", 1e-6))
        r = ek.solve(robot, [goal], method=method, seed=1, **options)
        assert r.success and np.linalg.norm(com_of(robot, r.q) - target) <= goal.tolerance


def test_memetic_holds_a_box_between_baxters_grippers(rng):
    robot = ek.load_robot("baxter", tips=["left_gripper", "right_gripper"])
    box = pin.SE3(pin.rpy.rpyToMatrix(np.pi, 0, 0), np.array([0.0, 0.0, 0.3]))
    rel = RelativePose("left_gripper", "right_gripper", box)
    for i in range(4):
        held = ek.solve(robot, [rel], q0=robot.random_configurations(1, rng)[0], seed=i, timeout=None,
                        max_restarts=2)
        assert held.success
        r = ek.solve(robot, [rel, Pose("left_gripper", robot.fk(held.q, "left_gripper"))], seed=i, timeout=None,
                     max_restarts=5)
        assert r.success
        M = robot.fk(r.q, "left_gripper").actInv(robot.fk(r.q, "right_gripper"))
        assert np.linalg.norm(pin.log6(box.actInv(M)).vector) <= 2e-6


def test_solve_many_batches_lists_of_the_new_kinds_by_their_numbers(talos, rng):
    """Lists that differ only in a CoM goal's margin or axes, or a relative pose's first frame, are separate
    structures (their kernel numbers differ); every answer meets its own goals by Pinocchio."""
    q = np.zeros(talos.n)
    q[:6] = 0.0, 0.0, 1.02, 0.0, 0.0, 0.0
    soles = [Pose(f, talos.fk(q, f)) for f in SOLES]
    T = talos.fk(q, "arm_left_7_link").actInv(talos.fk(q, "arm_right_7_link"))
    lists = [soles + [CenterOfMass(support=SOLES, margin=m)] for m in (0.0, 0.03, 0.0)]
    lists += [soles + [CenterOfMass(point=com_of(talos, q), axes=a)] for a in ("xy", "z")]
    lists += [soles + [RelativePose(a, b, T)] for a, b in (("arm_left_7_link", "arm_right_7_link"),
                                                           ("arm_right_7_link", "arm_left_7_link"))]
    lists[-1][-1] = RelativePose("arm_right_7_link", "arm_left_7_link", T.inverse())
    from evoik_pin.solvers.batch.goal_lists import structure

    assert len({structure(g) for g in lists}) == 6
    results = ek.solve_many(talos, lists, seed=0, workers=1)
    for goals, r in zip(lists, results, strict=True):
        assert r.success
        for g, e in zip(goals, IKProblem(talos, goals).goal_errors(r.q), strict=True):
            assert g.met(*e)


def test_viewer_marks_a_centre_of_mass_point_and_skips_goals_without_a_base_frame_target(talos):
    from evoik_pin.viz import Viewer

    q = np.zeros(talos.n)
    q[2] = 1.02
    goals = [Pose("left_sole_link", talos.fk(q, "left_sole_link")), CenterOfMass(point=[0.0, 0.0, 0.9]),
             CenterOfMass(support=SOLES), RelativePose("arm_left_7_link", "arm_right_7_link", np.eye(4))]
    with Viewer(talos) as v:
        assert v.show_goals(goals, labels=False) == ["goals/left_sole_link", "goals/center_of_mass"]
        assert v.scene["goals/center_of_mass"] == "goal point: center_of_mass"


def test_an_unreachable_centre_of_mass_is_named_in_the_message(rng):
    robot = ek.load_robot("panda")
    r = ek.solve(robot, [CenterOfMass(point=[2.0, 0.0, 0.3])], seed=0, timeout=None, max_restarts=1)
    assert not r.success and "goals not met: center of mass" in r.message and r.goal_errors[0][0] > 1.0


@settings(max_examples=60, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])
@given(points=st.lists(st.tuples(st.floats(-0.5, 0.5), st.floats(-0.5, 0.5), st.floats(-0.2, 0.2)), min_size=1,
                       max_size=10),
       margin=st.sampled_from([0.0, 0.01, 0.1]), seed=st.integers(0, 2**16))
def test_support_distance_of_random_polygons_equals_the_exact_one(points, margin, seed):
    """Random contact points on Panda's fixed base link (any count, duplicates and collinear ones included): the
    kernel's support error is the exact distance to their hull shrunk by margin + tolerance, and a shrunk hull that
    is empty or has no area is never met."""
    robot = _panda()
    goal = CenterOfMass(support={"panda_link0": np.array(points)}, margin=margin)
    q = robot.random_configurations(1, np.random.default_rng(seed))[0]
    _, _, ge = rows(robot, [goal], q)
    d = polygon_distance(com_of(robot, q)[:2], np.array(points), margin + goal.tolerance)
    if np.isinf(d):
        assert ge[0, 0] >= 1.0
    else:
        assert ge[0, 0] == pytest.approx(d, abs=1e-9)


_PANDA = []


def _panda():
    if not _PANDA:
        _PANDA.append(ek.load_robot("panda"))
    return _PANDA[0]


def test_the_benchmark_script_reports_both_tasks_and_their_peers():
    import argparse
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
    import bench_goal_kinds_balance as bench

    report = bench.run(argparse.Namespace(n=3, seed=0, timeout=1.0, box_timeout=1.0))
    assert report.startswith("## Balance and two-hand goals") and "Load average" in report
    for row in ("Talos: soles + CoM over the soles + wrists", "Talos, peer", "Baxter: RelativePose", "Baxter, peer",
                'Baxter: RelativePose free="rz"'):
        assert re.search(re.escape(row) + r".*\| 3 / 3 \(100.0 %\)", report), row
    assert "| 3 / 3 |" in report  # every Talos answer with the CoM goal: the CoM inside, by Pinocchio


def test_tolerance_none_is_the_default():
    assert RelativePose("a", "b", np.eye(4), tolerance=None).tolerance == 1e-6
    assert CenterOfMass(point=[0, 0, 0], tolerance=None).tolerance == 1e-6


def test_the_python_reference_lm_refuses_the_new_kinds_by_name():
    robot = ek.load_robot("panda")
    with pytest.raises(OptionError, match="CenterOfMass and RelativePose need the compiled engine"):
        ek.solve(robot, [CenterOfMass(point=[0.0, 0.0, 0.3])], engine="python", seed=0)
