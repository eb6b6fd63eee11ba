"""``evoik solve ROBOT --goals FILE``, ``--floating-base`` / ``--tips`` and ``evoik fk --frame``: per-goal output,
JSON checked by Pinocchio's own forward kinematics, exit codes, and errors naming the flags and the file."""

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from evoik_pin.cli import main
from evoik_pin.goals import Position
from evoik_pin.io.goals_file import load_goals, save_goals
from evoik_pin.robot import load_robot
from evoik_pin.viz import html_commands

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = str(ROOT / "examples" / "talos_hands_feet.yaml")
#: A budget of LM restarts instead of wall-clock time: the same answer on a loaded machine.
DETERMINISTIC = ["--timeout", "none", "--option", "max_restarts=3"]


@pytest.fixture(scope="module")
def talos():
    return load_robot("talos", floating_base=True)


def _run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def _pinocchio_pose(robot, q_pinocchio, frame: str) -> pin.SE3:
    """The pose of ``frame`` by Pinocchio alone: the URDF's free-flyer model at the JSON's configuration."""
    model = pin.buildModelFromUrdf(str(robot.urdf_path), pin.JointModelFreeFlyer())
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.asarray(q_pinocchio))
    return data.oMf[model.getFrameId(frame)]


def test_solve_with_a_goals_file_meets_every_goal_by_pinocchio(talos, capsys):
    # no --floating-base: the file's floating_base: true fills it in
    code, out, _ = _run(capsys, "solve", "talos", "--goals", EXAMPLE, "--json", *DETERMINISTIC)
    info = json.loads(out)
    assert code == 0 and info["success"] and info["floating_base"] and info["goals_file"] == EXAMPLE
    goals = load_goals(EXAMPLE)
    assert [r["frame"] for r in info["goal_errors"]] == [g.frame for g in goals]
    assert [r["kind"] for r in info["goal_errors"]] == ["pose", "pose", "pose", "position"]
    assert all(r["met"] for r in info["goal_errors"]) and info["goal_errors"][3]["rotation_error_rad"] is None
    q = np.array(info["q_rad"])
    assert np.all(q >= talos.lower) and np.all(q <= talos.upper)
    assert np.array_equal(talos.full_configuration(q), info["q_pinocchio"])
    for goal, row in zip(goals, info["goal_errors"], strict=True):
        T = _pinocchio_pose(talos, info["q_pinocchio"], goal.frame)
        pt, Rt = goal.encode()
        assert np.linalg.norm(T.translation - pt) <= 1e-6
        assert row["position_error_m"] == pytest.approx(np.linalg.norm(T.translation - pt), abs=1e-12)
        if goal.has_orientation:
            angle = np.linalg.norm(pin.log3(Rt.T @ T.rotation))
            assert angle <= 1e-6 and row["rotation_error_rad"] == pytest.approx(angle, abs=1e-12)

    code, out, _ = _run(capsys, "solve", "talos", "--floating-base", "--goals", EXAMPLE, *DETERMINISTIC)
    assert code == 0 and "reached" in out
    lines = [line.split() for line in out.splitlines() if line.strip().startswith(("0 ", "1 ", "2 ", "3 "))]
    assert [w[1:3] for w in lines] == [["left_sole_link", "pose"], ["right_sole_link", "pose"],
                                       ["arm_left_7_link", "pose"], ["arm_right_7_link", "position"]]
    assert [w[-1] for w in lines] == ["yes"] * 4 and lines[3][-2] == "free"


def test_unreachable_goals_exit_1_with_the_unmet_goal_marked(talos, tmp_path, capsys):
    goals = load_goals(EXAMPLE)[:3] + [Position("arm_right_7_link", [5.0, 0.0, 1.0])]  # 5 m away
    path = save_goals(goals, tmp_path / "far.json", robot=talos)
    code, out, _ = _run(capsys, "solve", "talos", "--goals", str(path), "--json", "--timeout", "0.05")
    info = json.loads(out)
    assert code == 1 and not info["success"] and not info["goal_errors"][3]["met"]
    assert info["goal_errors"][3]["position_error_m"] > 1.0
    code, out, _ = _run(capsys, "solve", "talos", "--goals", str(path), "--timeout", "0.05")
    assert code == 1 and "NOT reached" in out
    assert out.splitlines()[-1].split()[1:3] == ["arm_right_7_link", "position"] and out.rstrip().endswith("NO")


@pytest.mark.parametrize(("argv", "expected"), [
    (["--goals", EXAMPLE, "--xyz", "0.1", "0.2", "0.3"], "--goals and --xyz: give the targets one way"),
    (["--goals", EXAMPLE, "--xyz", "0.1", "0.2", "0.3", "--rpy", "0", "0", "0"], "--goals and --xyz/--rpy"),
    (["--goals", EXAMPLE, "--rpy", "0", "0", "0"], "--goals and --rpy"),
    ([], "needs a target: --xyz X Y Z"),
    (["--goals", EXAMPLE, "--tolerance", "1e-4"], "--tolerance and --goals: each goal has its own tolerances"),
    (["--goals", EXAMPLE, "--rotation-tolerance", "1e-4"], "--rotation-tolerance and --goals"),
    # the file says no tips: --tips is used; the chains to the four goal frames free every joint a goal needs
    (["--goals", EXAMPLE, "--tips", "left_sole_link", "right_sole_link", "arm_left_7_link", "arm_right_7_link"], None),
    # one arm's chain leaves the legs locked, and the file's floating base would carry the soles alone
    (["--goals", EXAMPLE, "--tips", "arm_left_7_link"], "only the floating base moves frame 'left_sole_link'"),
])
def test_flag_errors_name_the_flags(capsys, argv, expected):
    code, _, err = _run(capsys, "solve", "talos", *argv, "--timeout", "0.001", "--json")
    if expected is None:
        assert code in (0, 1) and err == ""
    else:
        assert code == 2 and expected in err and "Traceback" not in err


def test_a_file_for_another_robot_or_other_settings_is_an_error_naming_the_flag_and_the_file(tmp_path, capsys):
    code, _, err = _run(capsys, "solve", "panda", "--goals", EXAMPLE)
    assert code == 2 and f"goals file {EXAMPLE!r} is for robot 'talos', not 'panda'" in err
    hand = tmp_path / "hand.yaml"
    hand.write_text("robot: panda\nfloating_base: false\ntips: [panda_hand]\n"
                    "goals: [{frame: panda_hand, kind: position, target: {position: [0.5, 0.0, 0.5]}}]\n")
    code, _, err = _run(capsys, "solve", "panda", "--floating-base", "--goals", str(hand))
    assert code == 2 and "--floating-base: goals file" in err and "floating_base: false" in err
    code, _, err = _run(capsys, "solve", "panda", "--tips", "panda_link7", "--goals", str(hand))
    assert code == 2 and "--tips panda_link7: goals file" in err and "tips: ['panda_hand']" in err
    code, out, _ = _run(capsys, "solve", "panda", "--tips", "panda_hand", "--goals", str(hand), "--json",
                        *DETERMINISTIC)
    assert code == 0 and json.loads(out)["goal_errors"][0]["met"]


def test_bad_goals_files_exit_2_naming_the_file_and_the_goal(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("goals:\n  - {frame: panda_hand, kind: position, target: {position: [0.5, 0, 0.5]}}\n"
                   "  - {frame: panda_hnd, kind: position, target: {position: [0.5, 0, 0.6]}}\n")
    code, _, err = _run(capsys, "solve", "panda", "--goals", str(bad))
    assert code == 2 and f"goals file {str(bad)!r}: goal 1 (panda_hnd)" in err and "panda_hand" in err
    bad.write_text("goals: [{frame: panda_hand, kind: pose, target: {position: [0.5, 0, 0.5]}}]\n")
    code, _, err = _run(capsys, "solve", "panda", "--goals", str(bad))
    assert code == 2 and "goal 0 (panda_hand): target of a pose needs one of rpy" in err
    several = save_goals([[Position("panda_hand", [0.5, 0, 0.5])]] * 2, tmp_path / "two.yaml")
    code, _, err = _run(capsys, "solve", "panda", "--goals", str(several))
    assert code == 2 and "holds 2 problems" in err and "solve_many" in err
    code, _, err = _run(capsys, "solve", "panda", "--goals", str(tmp_path / "none.yaml"))
    assert code == 2 and f"goals file {str(tmp_path / 'none.yaml')!r}: not found" in err


def test_html_of_a_goals_file_answer_has_a_marker_per_goal(tmp_path, capsys):
    path = save_goals([Position("panda_hand", [0.5, 0.1, 0.5])], tmp_path / "hand.yaml")
    html = tmp_path / "hand.html"
    code, _, err = _run(capsys, "solve", "panda", "--goals", str(path), "--html", str(html), *DETERMINISTIC)
    assert code == 0 and f"wrote {html}" in err
    objects = {c["path"] for c in html_commands(html.read_text()) if c["type"] == "set_object"}
    assert {"/meshcat/goals/panda_hand/point", "/meshcat/goals/panda_hand/label"} <= objects


def test_fk_of_any_frame_with_a_floating_base_and_tips(talos, capsys):
    q_deg = np.zeros(talos.n)
    q_deg[:3] = [0.1, -0.2, 0.9]  # the base's position in m, its angles and the joints in degrees
    q_deg[3] = 30.0
    code, out, _ = _run(capsys, "fk", "talos", "--floating-base", "--frame", "arm_left_7_link", "--json",
                        "--q", *map(str, q_deg))
    info = json.loads(out)
    assert code == 0 and info["frame"] == "arm_left_7_link" and info["tip"] != "arm_left_7_link"
    q = np.array(info["q_rad"])
    assert np.allclose(q[:3], [0.1, -0.2, 0.9]) and q[3] == pytest.approx(np.radians(30.0))
    T = _pinocchio_pose(talos, talos.full_configuration(q), "arm_left_7_link")
    assert np.allclose(info["position_m"], T.translation, atol=1e-12)
    assert np.allclose(info["rotation"], T.rotation, atol=1e-12)
    code, out, _ = _run(capsys, "fk", "talos", "--frame", "arm_left_7_link")
    assert code == 0 and "-> frame 'arm_left_7_link'" in out
    code, _, err = _run(capsys, "fk", "talos", "--frame", "arm_left_7_lnk")
    assert code == 2 and "arm_left_7_link" in err and "Traceback" not in err

    baxter = load_robot("baxter", tips=["left_gripper", "right_gripper"])
    code, out, _ = _run(capsys, "fk", "baxter", "--tips", "left_gripper", "right_gripper", "--frame", "right_gripper",
                        "--json")
    info = json.loads(out)
    assert code == 0 and len(info["q_rad"]) == baxter.n == 14
    assert np.allclose(info["position_m"], baxter.fk(np.zeros(baxter.n), frame="right_gripper").translation)
