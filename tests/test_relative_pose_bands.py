"""RelativePose with per-axis tolerance bands and free axes (issue 23): Pose's semantics in the target frame T
(the error of ``T^-1 T_a^-1 T_b``). Its checks (the very messages of Pose's); the compiled rows equal to a Pose's
when frame a is the fixed base (hypothesis); its Jacobian against finite differences on two moving frames (Baxter)
and a floating base (Talos); the kernel's errors equal to the NumPy twin's (populations, goal_errors) and to the
components computed from Pinocchio's kinematics; Baxter holding a 0.3 m box free to turn about its axis, and within
+-2 mm / +-5 degrees, judged by Pinocchio; goals files and the CLI."""

import re

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_goals_balance import numeric_jacobian, rows

import evoik_pin as ek
from evoik_pin.errors import GoalsFileError, OptionError
from evoik_pin.goals import Pose, RelativePose
from evoik_pin.goals.bands import AXES
from evoik_pin.goals.relative_pose import KIND_RELATIVE_POSE, KIND_RELATIVE_POSE_AXES
from evoik_pin.problem import IKProblem

LEFT, RIGHT = "left_gripper", "right_gripper"
#: The right gripper seen from the left one holding a 0.3 m box: 0.3 m along the left's z, facing it.
BOX = pin.SE3(pin.rpy.rpyToMatrix(np.pi, 0.0, 0.0), np.array([0.0, 0.0, 0.3]))
#: +-2 mm and +-5 degrees on every axis.
BAND = np.array([0.002] * 3 + [np.radians(5.0)] * 3)
#: Solves bounded by restarts, not by the wall clock (the machine may be busy).
BUDGET = {"timeout": None, "max_restarts": 10}


@pytest.fixture(scope="module")
def baxter():
    return ek.load_robot("baxter", tips=[LEFT, RIGHT])


def _relative(robot, q, a=LEFT, b=RIGHT) -> pin.SE3:
    """Frame b's pose seen from frame a at q, by Pinocchio's kinematics."""
    return robot.fk(q, a).actInv(robot.fk(q, b))


def _components(robot, q, goal) -> np.ndarray:
    """The 6 error components of a relative pose goal at q as Pose defines them, in its target frame T: position
    ``R_t^T (p - p_t)`` (m), then ``log3(R_t^T R)`` (rad), for (R, p) frame b seen from frame a."""
    M, T = _relative(robot, q, goal.frame_a, goal.frame), goal.target
    return np.concatenate([T.rotation.T @ (M.translation - T.translation), pin.log3(T.rotation.T @ M.rotation)])


def _angle(a, b) -> float:
    return float(np.arctan2(np.linalg.norm(np.cross(a, b)), np.dot(a, b)))


# ------------------------------------------------------------------------------------------ construction
def test_relative_pose_takes_poses_tolerance_and_free():
    g = RelativePose("a", "b", BOX, free="rz")
    assert g.kind == KIND_RELATIVE_POSE_AXES and g.free == ("rz",) and g.band is None and g.tolerance == 1e-6
    assert "free='rz'" in repr(g) and "RelativePose('a', 'b'" in repr(g)
    b = RelativePose("a", "b", BOX, tolerance=[0.002] * 3 + [0.1] * 3, free="rz")
    assert b.band.tolist() == [0.002] * 3 + [0.1, 0.1, np.inf] and b.tolerance == b.rotation_tolerance == 0.0
    assert "tolerance=[0.002" in repr(b)
    plain = RelativePose("a", "b", BOX, tolerance=1e-4, rotation_tolerance=1e-3)
    assert plain.kind == KIND_RELATIVE_POSE and plain.band is None and plain.free == ()
    assert RelativePose("a", "b", BOX, free=["rx", "z"]).free == ("z", "rx")


BAD_AXES = [{"free": "w rz"}, {"free": "rz rz"}, {"free": "x y z rx ry rz"}, {"free": 3},
            {"tolerance": [0.1, 0.1, 0.1]}, {"tolerance": [0.1, -0.1, 0.1, 0, 0, 0]},
            {"tolerance": [0.1, np.nan, 0.1, 0, 0, 0]}, {"tolerance": ["a"] * 6},
            {"tolerance": [0.1] * 6, "rotation_tolerance": 0.1}, {"tolerance": -1.0, "free": "rz"}]


@pytest.mark.parametrize("bad", BAD_AXES)
def test_bad_tolerance_or_free_gets_poses_own_message(bad):
    """Every bad tolerance / free is refused with Pose's message, the goal named its own way."""
    with pytest.raises(OptionError) as pose_error:
        Pose("b", BOX, **bad)
    with pytest.raises(OptionError) as relative_error:
        RelativePose("a", "b", BOX, **bad)
    pose_text, relative_text = str(pose_error.value), str(relative_error.value)
    tail = pose_text.split("Pose on 'b': ", 1)[-1].replace("the goal on 'b'", "")
    assert tail.strip() and tail in relative_text.replace("the goal on 'b'", ""), (pose_text, relative_text)
    if "Pose on 'b'" in pose_text:
        assert "RelativePose of 'b' seen from 'a'" in relative_text


# ------------------------------------------------------------------------------- rows and Jacobians
_PANDA = []


def _panda():
    if not _PANDA:
        _PANDA.append(ek.load_robot("panda"))
    return _PANDA[0]


_HALF_WIDTHS = st.sampled_from([0.0, 1e-3, 0.05, 0.5, np.inf])


@settings(max_examples=60, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])
@given(free=st.sets(st.sampled_from(AXES), max_size=5), band=st.one_of(st.none(), st.lists(_HALF_WIDTHS, min_size=6,
                                                                                             max_size=6)),
       weight=st.sampled_from([1.0, 3.0]), seed=st.integers(0, 2**16))
def test_rows_equal_a_poses_when_frame_a_is_the_fixed_base(free, band, weight, seed):
    """Frame a the base (Panda's panda_link0, at the identity): the relative pose's rows, Jacobian and errors are
    those of the Pose with the same target, tolerance and free axes (the same maths), bands, swing and log6 alike."""
    robot = _panda()
    rng = np.random.default_rng(seed)
    q, near = robot.random_configurations(2, rng)
    T = robot.fk(near if seed % 2 else q + 0.05 * rng.standard_normal(robot.n))
    tolerance = 1e-3 if band is None else band
    free = " ".join(free) or None
    pose = Pose(robot.tip, T, weight=weight, tolerance=tolerance, free=free)
    relative = RelativePose("panda_link0", robot.tip, T, weight=weight, tolerance=tolerance, free=free)
    e_p, E_p, g_p = rows(robot, [pose], q)
    e_r, E_r, g_r = rows(robot, [relative], q)
    assert np.allclose(e_r, e_p, rtol=0, atol=1e-12) and np.allclose(E_r, E_p, rtol=0, atol=1e-11)
    assert np.allclose(g_r, g_p, rtol=0, atol=1e-12)
    assert np.allclose(relative.robot_errors(robot, q), g_r[0], rtol=0, atol=1e-9)


def _band_goals(robot, q, rng):
    """Relative pose goals of every form about the relative pose at q: free rz (a target twisted about its z),
    free x and ry, and bands some of whose components hold the pose inside (zero rows), some not."""
    M = _relative(robot, q)
    twist = pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, 2.0), np.zeros(3))
    twisted = M * twist * pin.SE3(pin.exp3(np.array([0.1, -0.2, 0.0])), np.array([0.01, 0, -0.02]))
    off = M * pin.SE3(pin.exp3(rng.uniform(-0.1, 0.1, 3)), rng.uniform(-0.01, 0.01, 3))
    return [RelativePose(LEFT, RIGHT, twisted, free="rz"), RelativePose(LEFT, RIGHT, off, free="x ry", weight=2.0),
            RelativePose(LEFT, RIGHT, off, tolerance=[0.005, 0.0, np.inf, 0.02, 0.5, 0.0]),
            RelativePose(LEFT, RIGHT, off, tolerance=[0.001] * 3 + [0.01] * 3, free="rz")]


def test_band_jacobians_equal_finite_differences_on_two_moving_frames(baxter, rng):
    """Both grippers move (Baxter's two arms): the compiled Jacobian of every form equals the finite differences of
    the compiled rows; then Talos's hands with a floating base."""
    talos = ek.load_robot("talos", floating_base=True)
    for robot, a, b in ((baxter, LEFT, RIGHT), (talos, "arm_left_7_link", "arm_right_7_link")):
        for q in robot.random_configurations(2, rng):
            off = _relative(robot, q, a, b) * pin.SE3(pin.exp3(np.array([0.3, 0.1, 1.0])), np.ones(3) / 9)
            goals = _band_goals(robot, q, rng) if robot is baxter else [RelativePose(a, b, off, free=f)
                                                                        for f in ("rz", "y rx")]
            for goal in goals:
                _, E, _ = rows(robot, [goal], q)
                F = numeric_jacobian(lambda x, r=robot, g=goal: rows(r, [g], x)[0], q)
                assert np.abs(E - F).max() <= 1e-6 * max(1.0, np.abs(F).max()), goal


def test_errors_are_poses_in_the_target_frame_by_pinocchio(baxter, rng):
    """The kernel's errors of every form equal the goal's NumPy errors (goal_errors, the evolutionary solvers'
    populations, IKProblem.evaluate) and what Pinocchio's kinematics give: the excess of the components over the
    bands, or for free rz the distance and the angle between the z axes."""
    Q = baxter.random_configurations(6, rng)
    for q in Q[:2]:
        for goal in _band_goals(baxter, q, rng):
            problem = IKProblem(baxter, [goal])
            pos, rot = goal.robot_population_errors(baxter, Q)
            ev = problem.evaluate(Q)
            assert np.allclose(ev.position_error, pos, rtol=0, atol=1e-12)
            for k, x in enumerate(Q):
                _, _, ge = rows(baxter, [goal], x)
                assert np.allclose(ge[0], [pos[k], rot[k]], rtol=0, atol=1e-9)
                assert np.allclose(problem.goal_errors(x)[0], ge[0], rtol=0, atol=1e-9)
                v = _components(baxter, x, goal)
                if goal.band is None:  # a norm tolerance, one free rotation axis (rz; ry with x): the swing angle
                    M = _relative(baxter, x)
                    keep = [i for i in range(3) if AXES[i] not in goal.free]
                    assert ge[0, 0] == pytest.approx(np.linalg.norm(v[keep]), abs=1e-12)
                    j = "xyz".index(goal.free[-1][1])
                    assert ge[0, 1] == pytest.approx(_angle(M.rotation[:, j], goal.target.rotation[:, j]), abs=1e-9)
                    assert goal.met(*ge[0]) == (ge[0, 0] <= 1e-6 and ge[0, 1] <= 1e-6)
                else:
                    X = np.maximum(np.abs(v) - np.maximum(goal.band, 1e-6), 0.0)
                    assert ge[0] == pytest.approx([np.linalg.norm(X[:3]), np.linalg.norm(X[3:])], abs=1e-9)
                    assert goal.met(*ge[0]) == (X == 0).all()


# ------------------------------------------------------------------------------------------- solving
@pytest.mark.parametrize("twist", [0.0, 2.0, np.pi])
def test_baxter_holds_a_box_free_to_turn_about_its_axis(baxter, twist):
    """The box's rotation about its axis free (free="rz"), the target twisted about it by up to pi: every answer
    puts the right gripper 0.3 m along the left's z, its z axis along the target's, by Pinocchio (1e-6)."""
    target = BOX * pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, twist), np.zeros(3))
    rng = np.random.default_rng(3)
    for i in range(2):
        goal = RelativePose(LEFT, RIGHT, target, free="rz")
        r = ek.solve(baxter, [goal], q0=baxter.random_configurations(1, rng)[0], seed=i, **BUDGET)
        assert r.success and baxter.within_bounds(r.q)
        M = _relative(baxter, r.q)
        assert np.linalg.norm(M.translation - target.translation) <= 1e-6
        assert _angle(M.rotation[:, 2], target.rotation[:, 2]) <= 1e-6


def test_baxter_holds_a_box_within_two_millimetres_and_five_degrees(baxter):
    """Targets off a reachable relative pose by 0.5 to 0.95 half-widths per component (that pose inside the band),
    alone and with the left gripper placed: every answer inside the band, each component in the target frame by
    Pinocchio, and goal_errors (0, 0)."""
    rng = np.random.default_rng(11)
    for i in range(4):
        q = baxter.random_configurations(1, rng)[0]
        M = _relative(baxter, q)
        v = rng.uniform(0.5, 0.95, 6) * rng.choice([-1.0, 1.0], 6) * BAND  # M seen from the target
        Rt = M.rotation @ pin.exp3(v[3:]).T
        target = pin.SE3(Rt, M.translation - Rt @ v[:3])
        goal = RelativePose(LEFT, RIGHT, target, tolerance=BAND)
        assert np.allclose(_components(baxter, q, goal), v, atol=1e-12)
        goals = [goal] if i % 2 else [goal, Pose(LEFT, baxter.fk(q, LEFT))]
        r = ek.solve(baxter, goals, seed=i, **BUDGET)
        assert r.success and r.goal_errors[0] == (0.0, 0.0)
        assert (np.abs(_components(baxter, r.q, goal)) <= BAND).all()


def test_de_meets_a_wide_relative_band(baxter):
    """An evolutionary solver (DE) reads the band's violation: its answer inside +-5 cm / +-30 degrees."""
    band = np.array([0.05] * 3 + [np.radians(30.0)] * 3)
    M = _relative(baxter, baxter.random_configurations(1, np.random.default_rng(2))[0])
    goal = RelativePose(LEFT, RIGHT, M, tolerance=band)
    r = ek.solve(baxter, [goal], method="de", seed=1)
    assert r.success and (np.abs(_components(baxter, r.q, goal)) <= band).all()


# ------------------------------------------------------------------------------------------- files and CLI
@pytest.mark.parametrize("ext", ["yaml", "json"])
def test_goals_files_keep_tolerance_bands_and_free_axes(tmp_path, ext):
    from evoik_pin.io.goals_file import load_goals, save_goals

    goals = [RelativePose(LEFT, RIGHT, BOX, free="rz"), RelativePose(LEFT, RIGHT, BOX, tolerance=BAND, free="x"),
             RelativePose(LEFT, RIGHT, BOX, tolerance=[0.002] * 3 + [0.1, 0.1, np.inf], weight=2.0),
             RelativePose(LEFT, RIGHT, BOX, tolerance=1e-4, rotation_tolerance=1e-3)]
    back = load_goals(save_goals(goals, tmp_path / f"goals.{ext}"))
    for a, b in zip(goals, back, strict=True):
        assert type(b) is RelativePose and repr(a) == repr(b) and a.kind == b.kind
        assert (a.band is None and b.band is None) or np.array_equal(a.band, b.band)
        assert (a.aux() is None and b.aux() is None) or np.array_equal(a.aux(), b.aux())
    cases = {"free: w": "unknown free axis 'w'", "tolerance: [1, 2]": "6 half-widths", "free: 3": "must name axes",
             "tolerance: [0.1, 0.1, 0.1, 0.1, 0.1, 0.1]\n    rotation_tolerance: 0.1": "rotation_tolerance goes with"}
    for text, match in cases.items():
        path = tmp_path / "bad.yaml"
        path.write_text(f"goals:\n  - frame_a: a\n    frame: b\n    kind: relative_pose\n    {text}\n"
                        "    target: {position: [0, 0, 0.3], rpy: [180, 0, 0]}\n")
        with pytest.raises(GoalsFileError, match=f"goal 0.*{match}"):
            load_goals(path)


def test_cli_solves_a_box_free_about_its_axis(baxter, tmp_path, capsys):
    from evoik_pin.cli import main
    from evoik_pin.io.goals_file import save_goals

    path = save_goals([RelativePose(LEFT, RIGHT, BOX, free="rz")], tmp_path / "box.yaml", robot=baxter)
    assert "free: rz" in path.read_text()
    assert main(["solve", "baxter", "--goals", str(path), "--seed", "1", "--timeout", "none",
                 "--option", "max_restarts=10"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"left_gripper -> right_gripper +relative_pose +\S+ +\S+ +yes", out), out


def test_solve_many_keeps_each_lists_bands_and_free_axes(baxter):
    """Lists alike but for a relative pose's free axes or bands are different structures (their aux rows): each
    solved as its own, every answer meeting its own goal by Pinocchio's components."""
    from evoik_pin.solvers.batch.goal_lists import structure

    lists = [[RelativePose(LEFT, RIGHT, BOX, free=f)] for f in (None, "rz", "rx")]
    lists += [[RelativePose(LEFT, RIGHT, BOX, tolerance=b)] for b in (BAND, 2 * BAND)]
    assert len({structure(g) for g in lists}) == len(lists)
    for goals, r in zip(lists, ek.solve_many(baxter, lists, seed=0, workers=1, timeout=None, max_restarts=20),
                        strict=True):
        goal = goals[0]
        assert r.success and goal.met(*IKProblem(baxter, goals).goal_errors(r.q)[0])
        v = _components(baxter, r.q, goal)
        if goal.band is not None:
            assert (np.abs(v) <= goal.band).all()
        elif goal.free:  # one free rotation axis j: frame b's axis j seen from a along T's
            j = "xyz".index(goal.free[0][1])
            M = _relative(baxter, r.q)
            assert np.linalg.norm(v[:3]) <= 1e-6 and _angle(M.rotation[:, j], BOX.rotation[:, j]) <= 1e-6
        else:
            assert np.linalg.norm(v[:3]) <= 1e-6 and np.linalg.norm(v[3:]) <= 1e-6
