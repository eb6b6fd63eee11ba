"""Goals files (evoik_pin.io.goals_file): the format (YAML and JSON, rpy in degrees or radians, 4 x 4 matrices,
problems), errors naming the file, the goal and the field, and save_goals -> load_goals round trips."""

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from evoik_pin.errors import EvoikError, GoalsFileError
from evoik_pin.goals import Pose, Position
from evoik_pin.io.goals_file import GOAL_KINDS, goal_kind_name, load_goals, load_problems, read_goals_file, save_goals
from evoik_pin.robot import load_robot

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "talos_hands_feet.yaml"


def _write(tmp_path, text: str, name: str = "goals.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _same(a, b) -> bool:
    """Same kind, frame, weight, tolerances and target (bit for bit)."""
    if type(a) is not type(b) or a.frame != b.frame:
        return False
    if (a.weight, a.tolerance, a.rotation_tolerance) != (b.weight, b.tolerance, b.rotation_tolerance):
        return False
    ta, tb = (np.asarray(g.target.homogeneous if isinstance(g, Pose) else g.target) for g in (a, b))
    return np.array_equal(ta, tb)


# ------------------------------------------------------------------ the format
def test_the_example_file_reads_as_its_header_says():
    spec = read_goals_file(EXAMPLE)
    assert (spec.robot, spec.floating_base, spec.tips, spec.several) == ("talos", True, None, False)
    goals = load_goals(EXAMPLE)
    assert [g.frame for g in goals] == ["left_sole_link", "right_sole_link", "arm_left_7_link", "arm_right_7_link"]
    assert [goal_kind_name(g) for g in goals] == ["pose", "pose", "pose", "position"]
    assert np.allclose(goals[2].target.rotation, pin.rpy.rpyToMatrix(*np.radians([37.864, -57.345, -12.043])))
    assert np.array_equal(goals[3].target, [0.2282, -0.4673, 1.0009])
    assert all(g.tolerance == 1e-6 and g.rotation_tolerance == 1e-6 and g.weight == 1.0 for g in goals)


def test_rpy_in_degrees_rpy_rad_and_a_matrix_give_the_same_pose(tmp_path):
    rpy = np.array([10.0, -20.0, 30.0])
    R = pin.rpy.rpyToMatrix(*np.radians(rpy))
    H = np.eye(4)
    H[:3, :3], H[:3, 3] = R, [0.1, 0.2, 0.3]
    text = json.dumps({"goals": [
        {"frame": "a", "kind": "pose", "target": {"position": [0.1, 0.2, 0.3], "rpy": rpy.tolist()}},
        {"frame": "b", "kind": "pose", "target": {"position": [0.1, 0.2, 0.3], "rpy_rad": np.radians(rpy).tolist()}},
        {"frame": "c", "kind": "pose", "target": {"matrix": H.tolist()}}]})
    a, b, c = load_goals(_write(tmp_path, text, "g.json"))
    for g in (a, b, c):
        assert np.allclose(g.target.homogeneous, H, atol=1e-15)


def test_yaml_1_1_exponents_are_numbers_and_fields_reach_the_goal(tmp_path):
    path = _write(tmp_path, """
- {frame: a, kind: pose, target: {position: [0, 0, 1], rpy: [0, 0, 0]}, weight: 0.5, tolerance: 1e-5,
   rotation_tolerance: 2e-4}
- {frame: b, kind: position, target: {position: [1, 2, 3]}, tolerance: 3E-6}
""")  # a bare list of goals at the top level
    a, b = load_goals(path)
    assert (a.weight, a.tolerance, a.rotation_tolerance) == (0.5, 1e-5, 2e-4)
    assert isinstance(b, Position) and b.tolerance == 3e-6 and b.rotation_tolerance == 3e-6


def test_problems_hold_several_goal_lists_and_load_goals_refuses_them(tmp_path):
    path = _write(tmp_path, """
problems:
  - [{frame: a, kind: position, target: {position: [0, 0, 1]}}]
  - - {frame: a, kind: position, target: {position: [0, 0, 2]}}
    - {frame: b, kind: position, target: {position: [0, 1, 2]}}
""")
    problems = load_problems(path)
    assert [[g.frame for g in p] for p in problems] == [["a"], ["a", "b"]]
    with pytest.raises(GoalsFileError, match=r"holds 2 problems .*load_problems"):
        load_goals(path)
    assert [[g.frame for g in p] for p in load_problems(EXAMPLE)] == [[g.frame for g in load_goals(EXAMPLE)]]


def test_goal_kinds_are_the_goal_classes():
    from evoik_pin.goals import CenterOfMass, Direction, LookAt, Orientation, Planar, RelativePose, RelativePosition

    assert {name: kind.cls for name, kind in GOAL_KINDS.items()} == {
        "pose": Pose, "position": Position, "planar": Planar, "orientation": Orientation, "direction": Direction,
        "look_at": LookAt, "center_of_mass": CenterOfMass, "relative_pose": RelativePose,
        "relative_position": RelativePosition}
    assert all(kind.name == name for name, kind in GOAL_KINDS.items())  # each kind class declares its entry


# ------------------------------------------------------------------ errors
GOOD = "{frame: hand, kind: pose, target: {position: [0, 0, 1], rpy: [0, 0, 0]}}"
BAD_FILES = [
    ("goals: [{frame: hand, kind: posse, target: {}}]", ["goal 0 (hand)", "unknown kind 'posse'",
                                                        "accepted kinds: pose, position"]),
    ("goals: [{frame: hand, target: {position: [0, 0, 1]}}]", ["goal 0 (hand)", "kind: missing"]),
    (f"goals: [{GOOD}, {{frame: foot, kind: pose}}]", ["goal 1 (foot)", "missing field 'target'"]),
    ("goals: [{kind: position, target: {position: [0, 0, 1]}}]", ["goal 0", "missing field 'frame'"]),
    (f"goals: [{GOOD}, {{frame: foot, kind: position, target: {{position: [0, 0, 1], rpy: [0, 0, 0]}}}}]",
     ["goal 1 (foot)", "a position goal has no orientation", "kind: pose"]),
    ("goals: [{frame: hand, kind: pose, target: {position: [0, 0, 1]}}]",
     ["goal 0 (hand)", "target of a pose needs one of rpy", "neither"]),
    ("goals: [{frame: hand, kind: pose, target: {position: [0, 0, 1], rpy: [0, 0, 0], rpy_rad: [0, 0, 0]}}]",
     ["goal 0 (hand)", "got both"]),
    ("goals: [{frame: hand, kind: pose, target: {position: [0, 0], rpy: [0, 0, 0]}}]",
     ["goal 0 (hand)", "target.position (m) must be a list of 3 numbers"]),
    ("goals: [{frame: hand, kind: pose, target: {position: [0, .nan, 1], rpy: [0, 0, 0]}}]",
     ["goal 0 (hand)", "target.position (m)[1] must be a finite number"]),
    ("goals: [{frame: hand, kind: pose, target: {matrix: [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]]}}]",
     ["goal 0 (hand)", "target.matrix must be 4 rows of 4 numbers"]),
    ("goals: [{frame: hand, kind: pose, target: {matrix: [[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}}]",
     ["goal 0 (hand)", "target rotation is not a rotation matrix"]),
    ("goals: [{frame: hand, kind: pose, target: {matrix: [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], "
     "position: [0, 0, 1]}}]", ["goal 0 (hand)", "matrix is the whole pose", "position"]),
    ("goals: [{frame: hand, kind: position, target: {position: [0, 0, 1]}, weight: -1}]",
     ["goal 0 (hand)", "weight", "> 0"]),
    ("goals: [{frame: hand, kind: position, target: {position: [0, 0, 1]}, tolerance: small}]",
     ["goal 0 (hand)", "tolerance must be a finite number", "'small'"]),
    ("goals: [{frame: hand, kind: position, target: {position: [0, 0, 1]}, rotation_tolerance: 0.1}]",
     ["goal 0 (hand), a position goal", "unknown key(s) 'rotation_tolerance'", "accepted: frame, kind, target, "
      "weight, tolerance"]),
    ("goals: [{frame: hand, kind: pose, target: {position: [0, 0, 1], rpy: [0, 0, 0]}, tolerence: 0.1}]",
     ["goal 0 (hand)", "unknown key(s) 'tolerence'"]),
    ("goals: []", ["goals is empty"]),
    (f"goals: [{GOOD}, {{frame: hand, kind: planar, target: {{x: 0, y: .nan}}}}]", ["goal 1 (hand)", "target y (m)"]),
    (f"goals: [{GOOD}]\nproblems: [[{GOOD}]]", ["give one of goals:", "got both"]),
    ("robot: talos", ["give one of goals:", "got neither"]),
    (f"goal: [{GOOD}]", ["top level: unknown key(s) 'goal'"]),
    (f"floating_base: yes please\ngoals: [{GOOD}]", ["floating_base must be true or false"]),
    (f"tips: arm\ngoals: [{GOOD}]", ["tips must be a list of frame names"]),
    (f"problems: [[{GOOD}], [{GOOD}, {{frame: foot, kind: pose}}]]", ["problem 1, goal 1 (foot)",
                                                                    "missing field 'target'"]),
    (f"problems: [[{GOOD}], 3]", ["problem 1", "each problem must be a list of goals"]),
    ("goals: [{frame: hand, kind: pose\n", ["YAML syntax error at line 2"]),
    ("", ["the file is empty"]),
    ("3", ["the top level must be a mapping"]),
]


def test_an_empty_posture_vector_is_read_as_given(tmp_path):
    """q_ref: [] is a Posture of no entries (its length is checked against a robot when bound), not a KeyError."""
    from evoik_pin.goals import Posture

    path = _write(tmp_path, f"goals: [{GOOD}, {{kind: posture, q_ref: []}}]")
    posture = read_goals_file(path).problems[0][1]
    assert isinstance(posture, Posture) and len(posture.q_ref) == 0


@pytest.mark.parametrize(("text", "expected"), BAD_FILES, ids=[e[0][:40] for e in BAD_FILES])
def test_a_bad_file_is_a_goals_file_error_naming_the_file_the_goal_and_the_field(tmp_path, text, expected):
    path = _write(tmp_path, text)
    with pytest.raises(GoalsFileError) as info:
        load_goals(path)
    message = str(info.value)
    assert message.startswith(f"goals file {str(path)!r}: ")
    for part in expected:
        assert part in message, message
    assert isinstance(info.value, (EvoikError, ValueError))


def test_missing_files_and_unknown_extensions_are_named(tmp_path):
    with pytest.raises(GoalsFileError, match=r"goals file .*nope\.yaml.*: not found"):
        load_goals(tmp_path / "nope.yaml")
    with pytest.raises(GoalsFileError, match=r"unknown extension '\.txt'; use \.yaml, \.yml, \.json"):
        load_goals(_write(tmp_path, "goals: []", "g.txt"))
    with pytest.raises(GoalsFileError, match=r"JSON syntax error at line 1"):
        load_goals(_write(tmp_path, "{goals: ", "g.json"))
    with pytest.raises(GoalsFileError, match=r"unknown extension"):
        save_goals([Position("a", [0, 0, 1])], tmp_path / "g.txt")


def test_bind_names_the_goal_whose_frame_the_robot_lacks(tmp_path):
    panda = load_robot("panda")
    path = _write(tmp_path, "goals:\n  - {frame: panda_link3, kind: position, target: {position: [0, 0, 0.5]}}\n"
                            "  - {frame: panda_hnd, kind: position, target: {position: [0.5, 0, 0.5]}}\n")
    with pytest.raises(GoalsFileError, match=r"goals file .*: goal 1 \(panda_hnd\): .*panda_hand"):
        read_goals_file(path).bind(panda)
    path = _write(tmp_path, "goals:\n  - {frame: panda_hand, kind: position, target: {position: [0, 0, 0.5]}}\n"
                            "  - {frame: panda_hand, kind: position, target: {position: [0.5, 0, 0.5]}}\n")
    with pytest.raises(GoalsFileError, match=r"goals file .*: frame 'panda_hand' has two goals"):
        read_goals_file(path).bind(panda)


# ------------------------------------------------------------------ writing: round trips
def test_save_goals_writes_the_robot_and_refuses_what_is_no_goal_list(tmp_path):
    talos = load_robot("talos", floating_base=True)
    goals = load_goals(EXAMPLE)
    spec = read_goals_file(save_goals(goals, tmp_path / "t.yaml", robot=talos, tips=["arm_left_7_link"]))
    assert (spec.robot, spec.floating_base, spec.tips) == ("talos", True, ["arm_left_7_link"])
    assert all(_same(a, b) for a, b in zip(goals, spec.problems[0], strict=True))
    for bad in ([], [goals[0], "hand"], [goals, []]):
        with pytest.raises(GoalsFileError, match=r"save_goals: .* must be a non-empty list of goals"):
            save_goals(bad, tmp_path / "bad.yaml")


_finite = st.floats(-2.0, 2.0, allow_nan=False)
_tolerance = st.one_of(st.just(1e-6), st.floats(0.0, 0.1, allow_nan=False))


@st.composite
def _goal(draw, frame: str):
    weight = draw(st.one_of(st.just(1.0), st.floats(1e-3, 1e3)))
    tolerance = draw(_tolerance)
    if draw(st.booleans()):
        return Position(frame, [draw(_finite) for _ in range(3)], weight=weight, tolerance=tolerance)
    quat = np.array([draw(st.floats(-1.0, 1.0)) for _ in range(4)])
    quat = quat / np.linalg.norm(quat) if np.linalg.norm(quat) > 1e-3 else np.array([0.0, 0.0, 0.0, 1.0])
    R = pin.Quaternion(*quat[[3, 0, 1, 2]]).toRotationMatrix()
    rotation_tolerance = draw(st.one_of(st.none(), _tolerance))
    return Pose(frame, pin.SE3(R, np.array([draw(_finite) for _ in range(3)])), weight=weight, tolerance=tolerance,
                rotation_tolerance=rotation_tolerance)


@st.composite
def _goal_list(draw):
    frames = draw(st.lists(st.text("abcdefgh_", min_size=1, max_size=12), min_size=1, max_size=5, unique=True))
    return [draw(_goal(f)) for f in frames]


@settings(max_examples=40, deadline=None)
@given(goals=_goal_list(), ext=st.sampled_from(["yaml", "yml", "json"]))
def test_save_then_load_gives_the_same_goals(tmp_path_factory, goals, ext):
    path = save_goals(goals, tmp_path_factory.mktemp("rt") / f"goals.{ext}")
    back = load_goals(path)
    assert len(back) == len(goals) and all(_same(a, b) for a, b in zip(goals, back, strict=True))


@settings(max_examples=15, deadline=None)
@given(problems=st.lists(_goal_list(), min_size=1, max_size=3), ext=st.sampled_from(["yaml", "json"]))
def test_save_then_load_problems_gives_the_same_goal_lists(tmp_path_factory, problems, ext):
    path = save_goals(problems, tmp_path_factory.mktemp("rt") / f"problems.{ext}")
    back = load_problems(path)
    assert len(back) == len(problems)
    for a, b in zip(problems, back, strict=True):
        assert len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
