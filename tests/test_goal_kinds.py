"""evoik_pin.goals' kinds on one frame beyond a plain pose or position: per-axis tolerance bands and free axes
(Pose, Position, Orientation), Orientation, Direction, LookAt. Their checks when made; the compiled residuals'
Jacobians against finite differences on a chain (UR5) and a tree (Talos); the kernel's errors equal to the NumPy
twin's (populations, Result.goal_errors); LM solves judged by geometry from Pinocchio's kinematics: free="rz"
with twists up to pi, a band of +-2 mm and +-5 degrees, pointing goals."""

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import evoik_pin as ek
from evoik_pin.errors import OptionError, TargetError
from evoik_pin.goals import Direction, LookAt, Orientation, Pose, Position
from evoik_pin.goals.pose import KIND_POSE, KIND_POSE_AXES
from evoik_pin.goals.position import KIND_POSITION
from evoik_pin.goals.registry import TASK_ROWS
from evoik_pin.problem import IKProblem
from evoik_pin.solvers.lm.axes import axes_error, axes_jacobian

TALOS_HAND, TALOS_HEAD = "arm_right_7_link", "rgbd_optical_frame"
#: Solves bounded by restarts, not by the wall clock (the machine may be busy).
BUDGET = {"timeout": None, "max_restarts": 50}


@pytest.fixture(scope="module")
def ur5():
    return ek.load_robot("ur5")


@pytest.fixture(scope="module")
def talos():
    return ek.load_robot("talos", tips=[TALOS_HAND, TALOS_HEAD])


def _twist(T: pin.SE3, angle: float) -> pin.SE3:
    """T turned by ``angle`` (rad) about its own z axis."""
    return T * pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, angle), np.zeros(3))


def _angle(a, b) -> float:
    """Angle (rad) between two 3-vectors, by atan2 (accurate near 0)."""
    return float(np.arctan2(np.linalg.norm(np.cross(a, b)), np.dot(a, b)))


# ------------------------------------------------------------------------------------------ construction
def test_kinds_check_their_inputs():
    T = pin.SE3.Random()
    assert Pose("hand", T).kind == KIND_POSE and Position("hand", [0, 0, 0]).kind == KIND_POSITION
    for goal in (Pose("hand", T, tolerance=None), Position("hand", [0, 0, 0], tolerance=None),
                 Orientation("hand", T, tolerance=None), Direction("hand", [1, 0, 0], [0, 0, 1], tolerance=None)):
        assert goal.tolerance == goal.rotation_tolerance == 1e-6  # None: the default
    g = Pose("hand", T, free="rz")
    assert g.kind == KIND_POSE_AXES and g.free == ("rz",) and g.tolerance == 1e-6 and "free='rz'" in repr(g)
    assert Pose("hand", T, free=["rx", "z"]).free == ("z", "rx")
    b = Pose("hand", T, tolerance=[0.002] * 3 + [0.1] * 3, free="rz")
    assert b.band.tolist() == [0.002] * 3 + [0.1, 0.1, np.inf] and b.tolerance == 0.0
    with pytest.raises(OptionError, match="unknown free axis 'w'; accepted: x y z rx ry rz"):
        Pose("hand", T, free="w rz")
    with pytest.raises(OptionError, match="names an axis twice"):
        Pose("hand", T, free="rz rz")
    with pytest.raises(OptionError, match="all six axes"):
        Pose("hand", T, free="x y z rx ry rz")
    with pytest.raises(OptionError, match=r"takes 6 half-widths \(x y z rx ry rz\), got shape \(3,\)"):
        Pose("hand", T, tolerance=[0.1, 0.1, 0.1])
    with pytest.raises(OptionError, match=r"half-widths must be >= 0 \(inf: free\)"):
        Pose("hand", T, tolerance=[0.1, -0.1, 0.1, 0, 0, 0])
    with pytest.raises(OptionError, match=r"half-widths must be >= 0"):
        Position("hand", [0, 0, 0], tolerance=[0.1, np.nan, 0.1])
    with pytest.raises(OptionError, match="rotation_tolerance goes with one number"):
        Pose("hand", T, tolerance=[0.1] * 6, rotation_tolerance=0.1)
    with pytest.raises(OptionError, match="tolerances.*>= 0"):
        Pose("hand", T, tolerance=-1.0, free="rz")
    with pytest.raises(OptionError, match=r"takes 3 half-widths \(x y z\)"):
        Position("hand", [0, 0, 0], tolerance=[0.1] * 6)
    o = Orientation("hand", T, free="rz")
    assert np.allclose(o.target, T.rotation) and not o.has_position and o.has_orientation
    assert np.allclose(Orientation("hand", T.homogeneous).target, T.rotation)
    with pytest.raises(OptionError, match="unknown free axis 'z'; accepted: rx ry rz"):
        Orientation("hand", T.rotation, free="z")
    with pytest.raises(OptionError, match=r"takes 3 half-widths \(rx ry rz\)"):
        Orientation("hand", T.rotation, tolerance=[0.1] * 6)
    with pytest.raises(TargetError, match="Orientation on 'hand' takes a 3 x 3 rotation.*not a rotation matrix"):
        Orientation("hand", 2 * np.eye(3))
    d = Direction("tool", [0, 0, 2], [0, 0, -1], tolerance=1e-3)
    assert d.axis.tolist() == [0, 0, 1.0] and d.rotation_tolerance == 1e-3 and d.reports_angle
    for bad, match in (([0, 0, 0], "is zero, which points nowhere"), ([1, 0], r"3 numbers \(a direction\)"),
                       ([1, np.inf, 0], "3 finite numbers"), ("up", "3 numbers")):
        with pytest.raises(TargetError, match=f"Direction on 'tool': axis .*{match}"):
            Direction("tool", bad, [0, 0, 1])
        with pytest.raises(TargetError, match=f"LookAt on 'cam': axis .*{match}"):
            LookAt("cam", bad, [1, 0, 0])
        with pytest.raises(TargetError, match=f"Direction on 'tool': direction .*{match}"):
            Direction("tool", [0, 0, 1], bad)
    with pytest.raises(TargetError, match=r"LookAt on 'cam': point must be 3 finite numbers \(m\)"):
        LookAt("cam", [0, 0, 1], [1, 0])
    with pytest.raises(OptionError, match="tolerances.*>= 0"):
        LookAt("cam", [0, 0, 1], [1, 0, 0], tolerance=-1)
    assert LookAt("cam", [1, 0, 0], point=[1, 2, 3]).point.tolist() == [1, 2, 3]


# ------------------------------------------------------------------------------- residuals and Jacobians
def _encoded(goal):
    """(pt, Rt, aux) of ``goal`` as the kernel hands them to its compiled code: C-ordered and writable (rows of the
    goal stack's arrays). As ``encode()`` and ``aux()`` give them (Rt in Fortran order from an SE3, aux read-only),
    they would compile variants of axes_error and axes_jacobian that nothing but this test uses (seconds of numba's
    time on a fresh clone); the values are the same."""
    pt, Rt = goal.encode()
    return np.ascontiguousarray(pt), np.ascontiguousarray(Rt), np.array(goal.aux())


def _residual(robot, goal, q):
    """(rows e, errors (pos, rot)) of ``goal`` at q by the compiled code of its kind."""
    T = robot.fk(q, goal.frame)
    e = np.zeros(len(TASK_ROWS[goal.kind]))
    c, pos, rot = axes_error(goal.kind, np.ascontiguousarray(T.rotation), np.ascontiguousarray(T.translation),
                             *_encoded(goal), np.empty((3, 3)), np.empty(3), e)
    assert c == pytest.approx(e @ e, rel=1e-12, abs=1e-300)
    return e, (pos, rot)


def _jacobian(robot, goal, q):
    T = robot.fk(q, goal.frame)
    J = np.ascontiguousarray(robot.jacobian(q, "world", of=goal.frame))
    E = np.zeros((len(TASK_ROWS[goal.kind]), robot.n))
    axes_jacobian(goal.kind, np.ascontiguousarray(T.rotation), np.ascontiguousarray(T.translation), J,
                  *_encoded(goal), np.empty(3), np.empty((3, 3)), np.empty((3, 3)), E, 0)
    return E


def _check_jacobian(robot, goal, q, h=1e-6):
    """The compiled Jacobian against central differences of the compiled residual."""
    E = _jacobian(robot, goal, q)
    F = np.empty_like(E)
    for k in range(robot.n):
        dq = np.zeros(robot.n)
        dq[k] = h
        F[:, k] = (_residual(robot, goal, q + dq)[0] - _residual(robot, goal, q - dq)[0]) / (2 * h)
    assert np.abs(E - F).max() <= 1e-6 * max(1.0, np.abs(F).max()), (goal, np.abs(E - F).max())
    return E


def _goals_on(frame, T, rng):
    """One goal of every kind of :mod:`evoik_pin.solvers.lm.axes` on ``frame``, its targets near-random about T."""
    Tt = T * pin.SE3(pin.exp3(rng.normal(size=3) * 0.6), rng.normal(size=3) * 0.05)
    small = [0.002, 0.004, 0.006, 0.01, 0.02, 0.03]  # the errors lie well outside (dead zones' live rows)
    wide = [1.0, 1.0, 1.0, 3.0, 3.0, 3.0]  # well inside (zero rows)
    return [Pose(frame, Tt, free="rz"), Pose(frame, Tt, free="x ry"), Pose(frame, Tt, free="rx ry"),
            Pose(frame, Tt, tolerance=small), Pose(frame, Tt, tolerance=wide), Pose(frame, Tt, tolerance=small,
                                                                                    free="rz"),
            Position(frame, Tt.translation, tolerance=small[:3]), Position(frame, Tt.translation, tolerance=wide[:3]),
            Orientation(frame, Tt), Orientation(frame, Tt, free="rz"), Orientation(frame, Tt, tolerance=small[3:]),
            Direction(frame, rng.normal(size=3), rng.normal(size=3)),
            LookAt(frame, rng.normal(size=3), T.translation + rng.normal(size=3) * 0.3)]


@pytest.mark.parametrize("robot_name", ["ur5", "talos"])
def test_jacobians_equal_finite_differences(robot_name, ur5, talos):
    robot = {"ur5": ur5, "talos": talos}[robot_name]
    rng = np.random.default_rng(3)
    frames = [robot.tip] if robot_name == "ur5" else [TALOS_HAND, TALOS_HEAD]
    for _ in range(2):
        q = robot.random_configuration(rng) if hasattr(robot, "random_configuration") else rng.uniform(
            robot.lower, robot.upper)
        for frame in frames:
            for goal in _goals_on(frame, robot.fk(q, frame), rng):
                E = _check_jacobian(robot, goal, q)
                if goal.aux()[6] == 1.0:  # the wide band: every row inside its dead zone
                    assert not E[:3].any()


def test_pointing_residual_has_no_zero_when_opposite(ur5):
    q = np.zeros(ur5.n)
    z = ur5.fk(q).rotation[:, 2]
    e, (_, rot) = _residual(ur5, Direction(ur5.tip, [0, 0, 1], -z), q)
    assert np.linalg.norm(e) == pytest.approx(2.0) and rot == pytest.approx(np.pi)
    e, (_, rot) = _residual(ur5, Direction(ur5.tip, [0, 0, 1], z), q)
    assert np.linalg.norm(e) < 1e-15 and rot < 1e-15
    p = ur5.fk(q).translation
    e, (_, rot) = _residual(ur5, LookAt(ur5.tip, [0, 0, 1], p - 0.5 * z), q)  # the point behind the camera
    assert np.linalg.norm(e) == pytest.approx(2.0) and rot == pytest.approx(np.pi)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**31 - 1), st.sampled_from(range(13)))
def test_kernel_errors_equal_the_numpy_twins(ur5, seed, which):
    """The kernel's errors of every kind equal Goal.errors (Result.goal_errors) and IKProblem.evaluate's (DE, ISADE,
    PSO, GA read those) at random configurations."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(ur5.lower, ur5.upper)
    goal = _goals_on(ur5.tip, ur5.fk(rng.uniform(ur5.lower, ur5.upper)), rng)[which]
    _, (pos, rot) = _residual(ur5, goal, q)
    p_err, r_err = goal.errors(ur5.fk(q))
    assert (p_err is None) == (not goal.has_position) and (r_err is None) == isinstance(goal, Position)
    assert (p_err or 0.0) == pytest.approx(pos, abs=1e-12) and (r_err or 0.0) == pytest.approx(rot, abs=1e-9)
    ev = IKProblem(ur5, [goal]).evaluate(q[None])
    assert ev.position_error[0] == pytest.approx(pos, abs=1e-12)
    if r_err is not None:
        assert ev.orientation_error[0] == pytest.approx(rot, abs=1e-9)


# ------------------------------------------------------------------------------------------- solving
def test_free_rz_with_twists_up_to_pi(ur5):
    """Targets turned about their z by angles up to pi: every answer's tool z axis within 1e-6 rad of the
    target's and its position within 1e-6 m (Pinocchio's kinematics), with the norm tolerance (swing residual)
    and with bands (rotation-vector components) alike."""
    rng = np.random.default_rng(7)
    for _ in range(2):
        T = ur5.fk(rng.uniform(-np.pi, np.pi, ur5.n))
        for angle in (0.0, 1.0, 2.5, 3.1, np.pi - 1e-9, np.pi, -np.pi + 1e-4):
            Tt = _twist(T, angle)
            for goal in (Pose(ur5.tip, Tt, free="rz"), Pose(ur5.tip, Tt, tolerance=[0.0] * 5 + [np.inf])):
                r = ek.solve(ur5, [goal], seed=1, **BUDGET)
                assert r.success, (angle, goal, r.goal_errors)
                Tq = ur5.fk(r.q)
                assert _angle(Tq.rotation[:, 2], Tt.rotation[:, 2]) <= 2e-6
                assert np.linalg.norm(Tq.translation - Tt.translation) <= 2e-6
                if goal.band is None:
                    assert _angle(Tq.rotation[:, 2], Tt.rotation[:, 2]) <= 1e-6
                    assert np.linalg.norm(Tq.translation - Tt.translation) <= 1e-6


def test_band_answers_lie_inside_it(ur5):
    """+-2 mm and +-5 degrees about targets off reachable poses by 0.5 to 0.95 half-widths per component (the
    reachable pose inside the band): every answer inside the band, each component of the error as the issue
    defines it (target frame, log3), by Pinocchio's kinematics."""
    rng = np.random.default_rng(11)
    band = np.array([0.002] * 3 + [np.radians(5)] * 3)
    for _ in range(6):
        T = ur5.fk(rng.uniform(-np.pi, np.pi, ur5.n))
        v = rng.uniform(0.5, 0.95, 6) * rng.choice([-1.0, 1.0], 6) * band  # T seen from the target
        Rt = T.rotation @ pin.exp3(v[3:]).T
        Tt = pin.SE3(Rt, T.translation - Rt @ v[:3])
        r = ek.solve(ur5, [Pose(ur5.tip, Tt, tolerance=band)], seed=2, **BUDGET)
        assert r.success and r.goal_errors == [(0.0, 0.0)]
        Tq = ur5.fk(r.q)
        v = np.concatenate([Tt.rotation.T @ (Tq.translation - Tt.translation), pin.log3(Tt.rotation.T @ Tq.rotation)])
        assert (np.abs(v) <= band).all(), v


def test_position_band_and_orientation_and_direction(ur5):
    rng = np.random.default_rng(5)
    T = ur5.fk(rng.uniform(-np.pi, np.pi, ur5.n))
    p = T.translation + [0.01, -0.01, 0.3]
    r = ek.solve(ur5, [Position(ur5.tip, p, tolerance=[0.002, 0.002, np.inf])], seed=1, **BUDGET)
    d = ur5.fk(r.q).translation - p
    assert r.success and abs(d[0]) <= 0.002 and abs(d[1]) <= 0.002 and r.goal_errors == [(0.0, None)]
    r = ek.solve(ur5, [Orientation(ur5.tip, T.rotation)], seed=1, **BUDGET)
    assert r.success and np.linalg.norm(pin.log3(T.rotation.T @ ur5.fk(r.q).rotation)) <= 1e-6
    assert r.goal_errors[0][0] is None and r.goal_errors[0][1] <= 1e-6
    Tt = T * pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.05]))  # 5 cm along the tool's z, free to slide there
    r = ek.solve(ur5, [Pose(ur5.tip, Tt, free="z")], seed=1, **BUDGET)
    Tq = ur5.fk(r.q)
    v = Tt.rotation.T @ (Tq.translation - Tt.translation)
    assert r.success and np.linalg.norm(v[:2]) <= 1e-6 and np.linalg.norm(pin.log3(Tt.rotation.T @ Tq.rotation)) <= 1e-6
    goals = [Position(ur5.tip, T.translation), Direction(ur5.tip, [0, 0, 1], [0, 0, -1])]  # a tool pointing down
    r = ek.solve(ur5, goals, seed=1, **BUDGET)
    Tq = ur5.fk(r.q)
    assert r.success and _angle(Tq.rotation[:, 2], [0, 0, -1]) <= 1e-6
    assert np.linalg.norm(Tq.translation - T.translation) <= 1e-6


def test_look_at_with_a_hand_pose_on_a_tree(talos):
    """Talos's head camera (optical z) looking at a point while the right hand reaches a pose (both reachable:
    from a random configuration): both met by Pinocchio's kinematics."""
    rng = np.random.default_rng(2)
    for _ in range(3):
        q = rng.uniform(talos.lower, talos.upper)
        T_hand, T_cam = talos.fk(q, TALOS_HAND), talos.fk(q, TALOS_HEAD)
        point = T_cam.translation + rng.uniform(0.3, 1.0) * T_cam.rotation[:, 2]
        goals = [Pose(TALOS_HAND, T_hand), LookAt(TALOS_HEAD, [0, 0, 1], point)]
        r = ek.solve(talos, goals, seed=3, **BUDGET)
        assert r.success, r.goal_errors
        cam = talos.fk(r.q, TALOS_HEAD)
        assert _angle(cam.rotation[:, 2], point - cam.translation) <= 1e-6
        assert np.linalg.norm(talos.fk(r.q, TALOS_HAND).translation - T_hand.translation) <= 1e-6


def test_de_reads_the_kinds_violations(ur5):
    """An evolutionary solver (DE) on a Direction goal: its population errors are the kind's angle."""
    r = ek.solve(ur5, [Direction(ur5.tip, [0, 0, 1], [0, 0, -1], tolerance=1e-2)], method="de", seed=1)
    assert r.success and _angle(ur5.fk(r.q).rotation[:, 2], [0, 0, -1]) <= 1e-2


# ------------------------------------------------------------------------------------------- goals files
@pytest.mark.parametrize("ext", ["yaml", "json"])
def test_goals_files_keep_every_kind(tmp_path, ext):
    from evoik_pin.io.goals_file import load_goals, save_goals

    T = pin.SE3.Random()
    goals = [Pose("a", T, free="rz"), Pose("b", T, tolerance=[0.002] * 3 + [0.1, 0.1, np.inf]),
             Position("c", [1, 2, 3], tolerance=[0.1, np.inf, 0.2]), Orientation("d", T, free="rx"),
             Orientation("e", T, tolerance=[0.1, 0.2, 0.3]), Direction("f", [0, 0, 1], [0, 0, -1], tolerance=1e-3),
             LookAt("g", [1, 0, 0], [0.5, 0, 1.2], weight=2)]
    back = load_goals(save_goals(goals, tmp_path / f"goals.{ext}"))
    for a, b in zip(goals, back, strict=True):
        assert type(a) is type(b) and repr(a) == repr(b)
        assert (a.aux() is None and b.aux() is None) or np.array_equal(a.aux(), b.aux())


def test_goals_files_name_what_is_wrong(tmp_path):
    from evoik_pin.errors import GoalsFileError
    from evoik_pin.io.goals_file import load_goals

    cases = {"kind: direction\n    target: {direction: [0, 0, 1]}": "missing field 'axis'",
             "kind: direction\n    axis: [0, 0]\n    target: {direction: [0, 0, 1]}": "axis must be a list of 3",
             "kind: look_at\n    axis: [0, 0, 0]\n    target: {point: [0, 0, 1]}": "is zero, which points nowhere",
             "kind: pose\n    free: w\n    target: {position: [0, 0, 0], rpy: [0, 0, 0]}": "unknown free axis 'w'",
             "kind: pose\n    tolerance: [1, 2]\n    target: {position: [0, 0, 0], rpy: [0, 0, 0]}": "6 half-widths",
             "kind: orientation\n    target: {position: [0, 0, 0]}": "unknown key"}
    for text, match in cases.items():
        path = tmp_path / "g.yaml"
        path.write_text(f"goals:\n  - frame: tool0\n    {text}\n")
        with pytest.raises(GoalsFileError, match=match):
            load_goals(path)


def test_cli_solves_a_goals_file_of_new_kinds(tmp_path, capsys):
    from evoik_pin.cli import main

    path = tmp_path / "goals.yaml"
    path.write_text("goals:\n"
                    "  - {frame: tool0, kind: position, target: {position: [0.4, 0.1, 0.3]}}\n"
                    "  - {frame: tool0, kind: direction, axis: [0, 0, 1], target: {direction: [0, 0, -1]}}\n")
    assert main(["solve", "ur5", "--goals", str(path), "--seed", "1"]) == 0
    out = capsys.readouterr().out
    assert "direction  free" in out and "kind       position error (m)" in out
    assert main(["solve", "ur5", "--goals", str(path), "--seed", "1", "--json"]) == 0
    rows = __import__("json").loads(capsys.readouterr().out)["goal_errors"]
    assert rows[1]["position_error_m"] is None and rows[1]["rotation_error_rad"] <= 1e-6 and rows[1]["met"]


def test_goals_without_a_position_leave_it_out_of_the_seed_ranking(ur5):
    """An orientation or pointing goal's pt is no place for its frame: the seed table's features skip it (a
    Direction alone still solves, ranked by nothing), and a Position beside it ranks the seeds alone."""
    from evoik_pin.solvers.search.seed_table import SeedTable

    spec = SeedTable.goal_spec([Position(ur5.tip, [0.3, 0.1, 0.4]), Direction(ur5.tip, [0, 0, 1], [0, 0, -1]),
                                Orientation(ur5.tip, np.eye(3))])
    assert spec == ((1.0, False), (1.0, False, False), (1.0, True, False))
    r = ek.solve(ur5, [Direction(ur5.tip, [0, 0, 1], [0, 0, -1])], seed=0, **BUDGET)
    assert r.success and _angle(ur5.fk(r.q).rotation[:, 2], [0, 0, -1]) <= 1e-6


def test_the_python_reference_lm_refuses_the_new_kinds(ur5):
    with pytest.raises(OptionError, match="engine='python'.*need the compiled engine"):
        ek.solve(ur5, [Pose(ur5.tip, ur5.fk(np.zeros(ur5.n)), free="rz")], engine="python", seed=0)


def test_solve_many_keeps_each_lists_bands_and_axes(ur5):
    """Lists alike but for their free axes or bands are different structures (their aux rows): each solved as its
    own goals say."""
    rng = np.random.default_rng(9)
    lists, checks = [], []
    for i in range(6):
        T = ur5.fk(rng.uniform(-np.pi, np.pi, ur5.n))
        Tt = _twist(T, 2.0)
        if i % 2:
            lists.append([Pose(ur5.tip, Tt, free="rz")])
        else:
            lists.append([Direction(ur5.tip, [1, 0, 0], Tt.rotation[:, 0])])
        checks.append(Tt)
    out = ek.solve_many(ur5, lists, seed=0, **BUDGET)
    assert out.stats["batched"] >= 1
    for i, (Tt, r) in enumerate(zip(checks, out, strict=True)):
        Tq = ur5.fk(r.q)
        assert r.success
        if i % 2:
            assert _angle(Tq.rotation[:, 2], Tt.rotation[:, 2]) <= 1e-6
            assert np.linalg.norm(Tq.translation - Tt.translation) <= 1e-6
        else:
            assert _angle(Tq.rotation[:, 0], Tt.rotation[:, 0]) <= 1e-6


def test_viewer_marks_the_goals_that_have_a_place(ur5):
    """show_goals: a LookAt's point gets a sphere; an Orientation or a Direction, no place, gets no marker."""
    from evoik_pin.viz import Viewer

    T = ur5.fk(np.zeros(ur5.n))
    goals = [Direction(ur5.tip, [0, 0, 1], [0, 0, -1]), Orientation("wrist_3_link", T),
             LookAt("wrist_2_link", [0, 0, 1], [0.5, 0.2, 0.3])]
    with Viewer(ur5) as v:
        assert v.show_goals(goals, labels=False) == ["goals/wrist_2_link"]
        assert v.scene["goals/wrist_2_link"] == "goal point: wrist_2_link"


def test_the_declarations_fill_the_stack_the_kernel_dispatches_on(ur5):
    """Every registered kind code's row count, compiled family and angle flag reach the stack's spec from its
    declaration, and the frame family's compiled row counts (kernel.frame_rows, which the first-four-kinds runs read
    instead of the spec) are the declared ones."""
    from evoik_pin.goals.registry import ANGLE_KINDS, FAMILY_FRAME, KINDS, kind_classes
    from evoik_pin.goals.stack import G_ANGLE, G_FAMILY, G_ROWS, spec_row
    from evoik_pin.solvers.lm.kernel import frame_rows

    assert {Pose, Position, Orientation, Direction, LookAt} <= set(kind_classes())
    for code, declared in KINDS.items():
        spec = spec_row(code, 0, 4.0, 1e-6, 1e-6, 0)
        assert spec[G_ROWS] == len(TASK_ROWS[code]) == len(declared.rows) and spec[G_FAMILY] == declared.family
        assert spec[G_ANGLE] == (code in ANGLE_KINDS) and spec[1] == 0 and spec[2] == 2.0
        if declared.family == FAMILY_FRAME:
            assert frame_rows(code) == len(declared.rows)
    goals = [Pose(ur5.tip, ur5.fk(np.zeros(ur5.n))), Direction(ur5.tip, [0, 0, 1], [0, 0, -1])]
    stack = ek.goals.bind(ur5, goals)[1]
    assert stack.spec[:, G_ROWS].tolist() == [6, 3] and stack.rows == 9
