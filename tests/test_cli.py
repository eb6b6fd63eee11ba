import json

import numpy as np

from evoik_pin.cli import main
from evoik_pin.robot import load_robot


def test_robots_lists_names(capsys):
    assert main(["robots"]) == 0
    out = capsys.readouterr().out
    assert "ax18" in out and "panda" in out


def test_fk_degrees_and_radians(capsys):
    assert main(["fk", "ax18", "--q", "45", "72.42", "-2.29", "-133.6", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert np.allclose(info["position_m"], [0.1, 0.1, 0.1], atol=5e-5)
    q = np.radians([45, 72.42, -2.29, -133.6])
    assert main(["fk", "ax18", "--rad", "--q", *map(str, q), "--json"]) == 0
    info2 = json.loads(capsys.readouterr().out)
    assert np.allclose(info2["position_m"], load_robot("ax18").fk(q).translation)
    assert main(["fk", "ax18", "--q", "0", "0", "0", "0"]) == 0
    assert "position (m)" in capsys.readouterr().out


def test_fk_bad_input_is_a_clear_error(capsys):
    assert main(["fk", "ax18", "--q", "1", "2"]) == 2
    assert "expected (4,)" in capsys.readouterr().err
    assert main(["fk", "nosuchrobot"]) == 2
    assert "unknown robot" in capsys.readouterr().err


def test_garbage_robot_files_are_bad_input_not_tracebacks(tmp_path, capsys):
    """README: exit 1 means "not reached", 2 "bad input"; unreadable URDFs are bad input, the message says why."""
    garbage = tmp_path / "garbage.urdf"
    garbage.write_bytes(bytes(np.random.default_rng(1).integers(0, 256, 2048, dtype=np.uint8)))
    empty = tmp_path / "empty.urdf"
    empty.write_bytes(b"")
    for path, message in ((garbage, "not decodable"), (empty, "is empty"), (tmp_path, "is a directory")):
        assert main(["fk", str(path)]) == 2
        err = capsys.readouterr().err
        assert err.startswith("evoik fk: error: ") and message in err and str(path) in err
        assert "Traceback" not in err
        assert main(["solve", str(path), "--xyz", "0.1", "0.1", "0.1"]) == 2
        assert message in capsys.readouterr().err


def test_cli_process_exit_status_and_stderr(tmp_path):
    import subprocess
    import sys

    garbage = tmp_path / "garbage.urdf"
    garbage.write_bytes(b"\x00\x01\x02binary\xff\xfe" * 50)
    proc = subprocess.run([sys.executable, "-m", "evoik_pin.cli", "fk", str(garbage)], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.startswith("evoik fk: error:") and "binary file" in proc.stderr
    assert "Traceback" not in proc.stderr and "urdfdom" not in proc.stderr


def test_load_warnings_are_one_line(tmp_path, capsys):
    f = tmp_path / "arm.urdf"
    f.write_text(load_robot("planar2r").urdf_xml.replace("</joint>", '<mimic joint="nowhere"/></joint>', 1))
    assert main(["fk", str(f), "--q", "0", "0"]) == 0
    err = capsys.readouterr().err
    assert err.startswith("evoik fk: warning: ") and "mimics 'nowhere'" in err and len(err.splitlines()) == 1


def test_view_no_block_prints_the_written_file(tmp_path, capsys):
    html = tmp_path / "scene.html"
    assert main(["view", "planar2r", "--html", str(html), "--no-block"]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"wrote {html}") and "stops when evoik exits" in out and html.is_file()
    assert main(["view", "planar2r", "--no-block"]) == 2  # nothing would remain to look at
    assert "--no-block without --html" in capsys.readouterr().err


def test_prismatic_joint_values_are_metres_not_degrees(capsys):
    """vehicle_arm's first two joints slide (m): --q gives them in m, only the revolute joints in degrees, and the
    solve output shows them the same way (q_deg keeps metres for prismatic joints)."""
    robot = load_robot("vehicle_arm")
    assert list(robot.revolute[:2]) == [False, False] and robot.revolute[2:].all()
    typed = [0.3, -0.2, 30.0, -45.0, 60.0]
    q = np.array([0.3, -0.2, *np.radians([30.0, -45.0, 60.0])])
    assert main(["fk", "vehicle_arm", "--q", *map(str, typed), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert np.allclose(info["position_m"], robot.fk(q).translation)
    x, y = robot.fk(q).translation[:2]
    assert main(["solve", "vehicle_arm", "--xyz", str(x), str(y), "0", "--q0", *map(str, typed), "--json"]) in (0, 1)
    out = json.loads(capsys.readouterr().out)
    assert np.allclose(out["q_deg"][:2], out["q_rad"][:2])
    assert np.allclose(out["q_deg"][2:], np.degrees(out["q_rad"][2:]))
