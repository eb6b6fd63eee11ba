"""``evoik solve ... --all``: every solution printed (text and JSON), drawn as ghosts with --html, exit codes."""

import json

import numpy as np
import pinocchio as pin

from evoik_pin.cli import main
from evoik_pin.robot import load_robot


def _pose_args(robot, seed: int) -> tuple[list[str], pin.SE3]:
    T = robot.fk(robot.random_configurations(1, np.random.default_rng(seed))[0])
    rpy = np.degrees(pin.rpy.matrixToRpy(T.rotation))
    return ["--xyz", *map(repr, map(float, T.translation)), "--rpy", *map(repr, map(float, rpy))], T


def test_all_prints_every_solution_one_per_line(capsys):
    robot = load_robot("ur5")
    args, _ = _pose_args(robot, 0)
    assert main(["solve", "ur5", *args, "--all"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("ur5 (6 joints), method memetic-all: 8 solution(s)")
    rows = [line for line in out[2:] if "position error" in line]
    assert [int(line.split()[0]) for line in rows] == list(range(8))
    assert "q (deg): shoulder_pan_joint" in out[1]


def test_all_json_lists_solutions_that_reach_the_pose(capsys):
    robot = load_robot("ur10")
    args, T = _pose_args(robot, 1)
    assert main(["solve", "ur10", *args, "--all", "--json", "--rad"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["method"] == "memetic-all" and info["success"] and info["count"] == len(info["solutions"]) >= 2
    target = pin.SE3(pin.rpy.rpyToMatrix(*np.radians(info["target_rpy_deg"])), np.array(info["target_position_m"]))
    for row in info["solutions"]:
        q = np.array(row["q_rad"])
        assert np.allclose(np.degrees(q), row["q_deg"])
        err = pin.log6(target.actInv(robot.fk(q))).vector
        assert np.linalg.norm(err[:3]) <= 1e-6 and np.linalg.norm(err[3:]) <= 1e-6
        assert row["position_error_m"] <= 1e-6 and row["orientation_error_rad"] <= 1e-6
    assert np.linalg.norm(target.translation - T.translation) < 1e-9


def test_all_on_an_unreachable_target_exits_1_and_says_why(capsys):
    assert main(["solve", "puma3r", "--xyz", "2", "0", "0", "--all", "--json"]) == 1
    info = json.loads(capsys.readouterr().out)
    assert info["solutions"] == [] and not info["success"] and "out of reach" in info["message"]


def test_all_with_another_multi_solution_method_and_a_single_solution_one(capsys):
    assert main(["solve", "puma3r", "--xyz", "-0.3", "-0.2", "0.43", "--all", "--method", "algebraic", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["count"] == 4
    assert main(["solve", "puma3r", "--xyz", "-0.3", "-0.2", "0.43", "--all", "--method", "memetic"]) == 2
    assert "returns one solution" in capsys.readouterr().err


def test_all_html_draws_every_solution_as_a_ghost(tmp_path, capsys):
    from evoik_pin.viz import html_commands

    out = tmp_path / "all.html"
    assert main(["solve", "planar2r", "--xyz", "0.2", "0.2", "0", "--all", "--html", str(out)]) == 0
    assert f"wrote {out}" in capsys.readouterr().err
    paths = {c.get("path", "") for c in html_commands(out.read_text())}
    assert any(p.startswith("/meshcat/robot") for p in paths) and any(p.startswith("/meshcat/target") for p in paths)
    ghosts = {p.split("/")[3] for p in paths if p.startswith("/meshcat/solutions/")}
    assert ghosts == {"0", "1"}  # both elbows
