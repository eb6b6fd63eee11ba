"""``evoik solve``: text and JSON output, degrees/radians, pose targets, exit codes and bad input."""

import json

import numpy as np
import pinocchio as pin
import pytest

from evoik_pin.cli import main
from evoik_pin.robot import load_robot


def test_solve_json_reaches_the_target(capsys):
    code = main(["solve", "redundant7r", "--xyz", "0.4", "0.3", "0.7", "--method", "isade", "--seed", "1",
                 "--tolerance", "1e-9", "--json"])
    info = json.loads(capsys.readouterr().out)
    assert code == 0 and info["success"] and info["method"] == "isade"
    robot = load_robot("redundant7r")
    assert np.linalg.norm(robot.fk(np.array(info["q_rad"])).translation - [0.4, 0.3, 0.7]) <= 1e-9
    assert np.allclose(info["q_deg"], np.degrees(info["q_rad"]))
    assert info["position_error_m"] <= 1e-9 and info["orientation_error_rad"] is None
    assert info["generations"] >= 0 and info["evaluations"] > 0 and info["time_s"] > 0


def test_solve_text_output_in_degrees_and_radians(capsys):
    args = ["solve", "ax18", "--xyz", "0.1", "0.1", "0.1", "--method", "isade", "--seed", "0"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "reached" in out and "q (deg)" in out and "position error (m)" in out and "generations" in out
    assert main([*args, "--rad"]) == 0
    assert "q (rad)" in capsys.readouterr().out


def test_solve_pose_target_with_rpy_in_degrees(capsys):
    robot = load_robot("aerial6r")
    q = robot.random_configurations(1, np.random.default_rng(4))[0]
    T = robot.fk(q)
    rpy_deg = np.degrees(pin.rpy.matrixToRpy(T.rotation))
    code = main(["solve", "aerial6r", "--xyz", *map(str, T.translation), "--rpy", *map(str, rpy_deg),
                 "--method", "de", "--seed", "2", "--tolerance", "1e-5", "--population", "40",
                 "--max-generations", "60", "--json"])
    info = json.loads(capsys.readouterr().out)
    assert info["target_rpy_deg"] == list(rpy_deg)
    assert code == (0 if info["success"] else 1)
    # the degrees were read as roll-pitch-yaw: the reported errors are those of q against that pose
    R_target = pin.rpy.rpyToMatrix(*np.radians(rpy_deg))
    T_q = robot.fk(np.array(info["q_rad"]))
    assert info["orientation_error_rad"] == pytest.approx(np.linalg.norm(pin.log3(R_target.T @ T_q.rotation)),
                                                          abs=1e-9)
    assert info["position_error_m"] == pytest.approx(np.linalg.norm(T_q.translation - T.translation), abs=1e-12)


def test_solve_q0_and_unreachable_exit_code(capsys):
    code = main(["solve", "planar2r", "--xyz", "3", "0", "0", "--method", "isade", "--max-generations", "20",
                 "--q0", "10", "20", "--json"])
    info = json.loads(capsys.readouterr().out)
    assert code == 1 and not info["success"]
    assert abs(info["position_error_m"] - (3.0 - 0.41)) < 1e-6


def test_solve_bad_input_is_a_clear_error(capsys):
    assert main(["solve", "ax18", "--xyz", "0.1", "0.1", "0.1", "--method", "nosuch"]) == 2
    assert "unknown method 'nosuch'" in capsys.readouterr().err
    assert main(["solve", "ax18", "--xyz", "0.1", "0.1", "nan", "--method", "isade"]) == 2
    assert "NaN" in capsys.readouterr().err
    assert main(["solve", "ax18", "--xyz", "0.1", "0.1", "0.1", "--method", "isade", "--q0", "1", "2"]) == 2
    assert "expected (4,)" in capsys.readouterr().err
    assert main(["solve", "ax18", "--xyz", "0.1", "0.1", "0.1", "--method", "isade", "--population", "-4"]) == 2
    assert "population" in capsys.readouterr().err
    assert main(["solve", "ax18", "--xyz", "0.1", "0.1", "0.1", "--method", "isade", "--tolerance", "-1"]) == 2
    assert "tolerance" in capsys.readouterr().err


def test_solve_html_writes_the_solution_and_target_scene(tmp_path, capsys):
    """`evoik solve --html` (issue 6): the exported page holds the robot and the target triad."""
    from evoik_pin.viz import html_commands

    out = tmp_path / "solution.html"
    assert main(["solve", "aerial6r", "--xyz", "0.1", "-0.2", "0.3", "--rpy", "0", "10", "15", "--method", "memetic",
                 "--html", str(out)]) in (0, 1)
    assert f"wrote {out}" in capsys.readouterr().err
    paths = {c.get("path", "") for c in html_commands(out.read_text())}
    assert any(p.startswith("/meshcat/robot") for p in paths)
    assert any(p.startswith("/meshcat/target") for p in paths)


def test_solve_html_to_a_missing_directory_fails_before_solving(tmp_path, capsys):
    assert main(["solve", "ax18", "--xyz", "0.1", "0.1", "0.1", "--html", str(tmp_path / "no" / "x.html")]) == 2
    err = capsys.readouterr()
    assert "does not exist" in err.err and "position error" not in err.out


def test_readme_main_job_in_a_fresh_process():
    # The README's first command, as a new process runs it: the first solve imports numba and loads the
    # compiled LM kernel (or compiles it), which must not eat the 5 ms time budget.
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-m", "evoik_pin.cli", "solve", "ax18", "--xyz", "0.1", "0.1", "0.1",
                          "--seed", "0", "--json"], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    info = json.loads(out.stdout)
    assert info["success"] and info["position_error_m"] <= 1e-6 and info["method"] == "memetic"
