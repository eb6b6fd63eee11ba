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
