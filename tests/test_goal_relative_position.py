"""RelativePosition (evoik_pin.goals.relative_position): frame b's origin placed relative to frame a's, in frame a's
axes or the world's. Its compiled rows and Jacobian against Pinocchio and finite differences, its reported errors
against a direct Pinocchio computation (hypothesis), its checks, its goals-file entry, its (absent) viewer marker,
and solves on Baxter's two grippers by the default method and by a paper method."""

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from kernel_helpers import numeric_jacobian, rows

import evoik_pin as ek
from evoik_pin.errors import FrameError, GoalsFileError, OptionError, TargetError
from evoik_pin.goals import Pose, RelativePosition, bind
from evoik_pin.io.goals_file import goal_kind_name, load_goals, save_goals
from evoik_pin.problem import IKProblem

HANDS = ("left_gripper", "right_gripper")


@pytest.fixture(scope="module")
def baxter():
    return ek.load_robot("baxter")


@pytest.fixture(scope="module")
def talos():
    return ek.load_robot("talos", floating_base=True)


def direct(robot, goal, q):
    """The goal's residual (3,) at q by Pinocchio's forward kinematics of the two frames."""
    Ta, Tb = robot.fk(q, goal.frame_a), robot.fk(q, goal.frame_b)
    d = Tb.translation - Ta.translation
    return (Ta.rotation.T @ d if goal.expressed_in == "a" else d) - goal.p


@pytest.mark.parametrize("expressed_in", ["a", "world"])
def test_rows_and_jacobian_equal_pinocchio_and_finite_differences(baxter, talos, expressed_in):
    """The compiled rows (scaled by sqrt(weight)) are the residual by Pinocchio, their Jacobian its finite
    differences, on Baxter (its arms share no joint) and on Talos with a floating base (whose base joints move both
    hands: in the world's axes they turn the vector, in frame a's they cancel)."""
    rng = np.random.default_rng(3)
    for robot, a, b in ((baxter, *HANDS), (talos, "arm_left_7_link", "arm_right_7_link")):
        goal = RelativePosition(a, b, [0.05, -0.3, 0.02], expressed_in=expressed_in, weight=2.0)
        for q in robot.random_configurations(3, rng):
            e, E, ge = rows(robot, [goal], q)
            assert e.shape == (3,)
            assert np.allclose(e / np.sqrt(2.0), direct(robot, goal, q), atol=1e-12, rtol=0)
            assert ge[0, 0] == pytest.approx(np.linalg.norm(direct(robot, goal, q)), abs=1e-12)
            assert np.allclose(E, numeric_jacobian(lambda x, r=robot, g=goal: rows(r, [g], x)[0], q), atol=1e-6)


def test_world_and_frame_a_axes_differ_when_frame_a_turns(baxter):
    """The two readings of p are different goals: with frame a turned, p in its axes is not p in the world's."""
    q = baxter.random_configurations(1, np.random.default_rng(5))[0]
    p = [0.0, -0.3, 0.0]
    in_a, in_world = (direct(baxter, RelativePosition(*HANDS, p, expressed_in=w), q) for w in ("a", "world"))
    assert np.linalg.norm(in_a - in_world) > 1e-3


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), expressed_in=st.sampled_from(["a", "world"]),
       p=st.lists(st.floats(-0.5, 0.5), min_size=3, max_size=3))
def test_reported_errors_are_pinocchios(baxter, seed, expressed_in, p):
    """At random configurations the error every path reports (the goal's own, the problem's per-goal errors, the
    population violation the evolutionary methods rank by, the kernel's) is |residual| by Pinocchio, no angle."""
    goal = RelativePosition(*HANDS, p, expressed_in=expressed_in, tolerance=1e-4)
    Q = baxter.random_configurations(4, np.random.default_rng(seed))
    expected = [float(np.linalg.norm(direct(baxter, goal, q))) for q in Q]
    problem = IKProblem(baxter, [goal])
    pos, rot, _ = problem._goal_population_members(Q)
    assert np.allclose(pos[:, 0], expected, atol=1e-12, rtol=0) and not rot.any()
    for q, want in zip(Q, expected, strict=True):
        assert goal.robot_errors(baxter, q) == (pytest.approx(want, abs=1e-12), None)
        assert problem.goal_errors(q)[0] == (pytest.approx(want, abs=1e-12), None)
        assert rows(baxter, [goal], q)[2][0, 0] == pytest.approx(want, abs=1e-12)


def meets(robot, goals, q, tolerance):
    """Every goal within ``tolerance`` by Pinocchio's kinematics (RelativePosition: its residual; Pose: position and
    angle)."""
    for g in goals:
        if isinstance(g, RelativePosition):
            if np.linalg.norm(direct(robot, g, q)) > tolerance:
                return False
        else:
            T = robot.fk(q, g.frame)
            if (np.linalg.norm(T.translation - g.target.translation) > tolerance
                    or np.linalg.norm(pin.log3(g.target.rotation.T @ T.rotation)) > tolerance):
                return False
    return True


@pytest.mark.parametrize("expressed_in, p", [("world", [0.0, -0.3, 0.0]), ("a", [0.0, 0.0, 0.3])])
def test_the_default_method_holds_baxters_hands_apart_with_a_pose_on_one(baxter, expressed_in, p):
    """Two grippers 0.3 m apart (in the world's axes, and along the left gripper's z): held from a random start; then
    with the left gripper also on the pose one such answer gives it (a problem known to have a solution), solved
    again from another random start. Every answer within the tolerances by Pinocchio's kinematics."""
    rng = np.random.default_rng(7)
    rel = RelativePosition(*HANDS, p, expressed_in=expressed_in, tolerance=1e-6)
    for i in range(3):
        held = ek.solve(baxter, [rel], q0=baxter.random_configurations(1, rng)[0], seed=i, timeout=None,
                        max_restarts=2)
        assert held.success and meets(baxter, [rel], held.q, 1e-6)
        goals = [rel, Pose(HANDS[0], baxter.fk(held.q, HANDS[0]))]
        r = ek.solve(baxter, goals, q0=baxter.random_configurations(1, rng)[0], seed=i, timeout=None,
                     max_restarts=5)
        assert r.success and baxter.within_bounds(r.q) and meets(baxter, goals, r.q, 1e-6)
        assert r.goal_errors[0][1] is None and r.goal_errors[0][0] <= 1e-6


@pytest.mark.parametrize("expressed_in", ["a", "world"])
def test_a_paper_method_holds_the_hands_apart(baxter, expressed_in):
    """Differential evolution (a paper method taking goal lists) ranks by the goal's population violation."""
    goal = RelativePosition(*HANDS, [0.0, -0.3, 0.1], expressed_in=expressed_in, tolerance=1e-3)
    r = ek.solve(baxter, [goal], method="de", seed=0)
    assert r.success and meets(baxter, [goal], r.q, 1e-3)


def test_goals_file_round_trip(tmp_path):
    goals = [RelativePosition(*HANDS, [0.1, -0.3, 0.05]),
             RelativePosition(*HANDS, [0.0, 0.0, 0.3], expressed_in="world", weight=2.0, tolerance=1e-4),
             Pose(HANDS[0], np.eye(4))]
    for suffix in ("yaml", "json"):
        path = save_goals(goals, tmp_path / f"g.{suffix}")
        back = load_goals(path)
        assert [goal_kind_name(g) for g in back] == ["relative_position", "relative_position", "pose"]
        for g, h in zip(goals[:2], back[:2], strict=True):
            assert type(h) is RelativePosition and (h.frame_a, h.frame_b, h.expressed_in) == (
                g.frame_a, g.frame_b, g.expressed_in)
            assert np.array_equal(h.p, g.p) and (h.weight, h.tolerance) == (g.weight, g.tolerance)
    text = (tmp_path / "g.yaml").read_text()
    assert "kind: relative_position" in text and "expressed_in: world" in text


@pytest.mark.parametrize("entry, words", [
    ("{frame_a: left_gripper, frame: right_gripper, kind: relative_position, target: {position: [0, 0, 1]}, "
     "expressed_in: b}", ["goal 0", "expressed_in", "'a', 'world'"]),
    ("{frame: right_gripper, kind: relative_position, target: {position: [0, 0, 1]}}", ["missing field 'frame_a'"]),
    ("{frame_a: l, frame: r, kind: relative_position, target: {position: [0, 1]}}", ["target.position"]),
    ("{frame_a: l, frame: r, kind: relative_position, target: {position: [0, 0, 1]}, tolerence: 1}",
     ["unknown key(s) 'tolerence'"]),
])
def test_goals_file_errors_name_the_field(tmp_path, entry, words):
    path = tmp_path / "bad.yaml"
    path.write_text(f"goals: [{entry}]\n")
    with pytest.raises(GoalsFileError) as info:
        load_goals(path)
    for word in words:
        assert word in str(info.value)


def test_bad_input_is_refused_by_name(baxter):
    with pytest.raises(FrameError, match="two frames"):
        RelativePosition("a", "a", [0, 0, 0.3])
    with pytest.raises(FrameError, match="frame_a is a frame name"):
        RelativePosition(3, "b", [0, 0, 0.3])
    with pytest.raises(FrameError, match="frame name"):
        RelativePosition("a", None, [0, 0, 0.3])
    with pytest.raises(TargetError, match="3 finite numbers"):
        RelativePosition("a", "b", [0, 0])
    with pytest.raises(TargetError, match="3 finite numbers"):
        RelativePosition("a", "b", [0, np.nan, 1])
    with pytest.raises(OptionError, match="expressed_in must be one of 'a', 'world'"):
        RelativePosition("a", "b", [0, 0, 1], expressed_in="b")
    with pytest.raises(OptionError, match="must be > 0"):
        RelativePosition("a", "b", [0, 0, 1], tolerance=0.0)
    with pytest.raises(OptionError, match="weight"):
        RelativePosition("a", "b", [0, 0, 1], weight=-1.0)
    with pytest.raises(FrameError, match="no frame 'nowhere'"):
        bind(baxter, [RelativePosition(HANDS[0], "nowhere", [0, 0, 1])])


def test_its_declaration_and_marker():
    """3 rows from the base Jacobian's translation, beyond one frame, no angle; exported by the package; no marker
    in the base frame (as a relative pose)."""
    from evoik_pin.goals.registry import ANGLE_KINDS, KINDS, ORIENTED_KINDS, TASK_ROWS

    for w in ("a", "world"):
        g = RelativePosition(*HANDS, [0, 0, 0.3], expressed_in=w)
        assert TASK_ROWS[g.kind] == (0, 1, 2) and g.kind not in ORIENTED_KINDS | ANGLE_KINDS
        assert KINDS[g.kind].has_position and g.marker() is None and g.label == "left_gripper -> right_gripper"
    assert ek.RelativePosition is RelativePosition


def test_the_viewer_draws_no_marker_for_it(baxter):
    """The viewer marks what each kind declares: the Pose's triad, nothing for the relative position (its target is
    a vector from frame a, as a relative pose's is a pose seen from it)."""
    from evoik_pin.viz import Viewer

    q = np.zeros(baxter.n)
    goals = [Pose(HANDS[0], baxter.fk(q, HANDS[0])), RelativePosition(*HANDS, [0, -0.3, 0], expressed_in="world")]
    with Viewer(baxter) as v:
        assert v.show_goals(goals, labels=False) == [f"goals/{HANDS[0]}"]


def test_two_frames_on_one_link_in_the_world_axes(baxter):
    """Frames fixed on one link (the wrist and the gripper): no joint moves one relative to the other, yet in the
    world's axes the joints above both turn the vector between them (a head's direction from its neck when
    retargeting): a goal there binds and is met; in frame a's axes the vector never changes, so it is refused."""
    q = baxter.random_configurations(1, np.random.default_rng(11))[0]
    d = baxter.fk(q, "left_gripper").translation - baxter.fk(q, "left_wrist").translation
    goal = RelativePosition("left_wrist", "left_gripper", d, expressed_in="world")
    r = ek.solve(baxter, [goal], seed=0)
    assert r.success, r.message
    got = baxter.fk(r.q, "left_gripper").translation - baxter.fk(r.q, "left_wrist").translation
    assert np.linalg.norm(got - d) <= 1e-6
    with pytest.raises(FrameError, match="moves frame 'left_gripper' relative to 'left_wrist'"):
        bind(baxter, [RelativePosition("left_wrist", "left_gripper", d, expressed_in="a")])
