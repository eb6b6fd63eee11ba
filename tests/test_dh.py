import numpy as np
import pytest

from evoik_pin.errors import RobotLoadError
from evoik_pin.papers.dh import DHRow, dh_to_urdf, dh_transform
from evoik_pin.robot import load_robot


def _product(rows, q, convention):
    T = np.eye(4)
    k = 0
    for row in rows:
        if row.kind == "fixed":
            T = T @ dh_transform(row, 0.0, convention)
        else:
            T = T @ dh_transform(row, q[k], convention)
            k += 1
    return T


ROWS = [
    DHRow(0.1, np.pi / 2, 0.3, 0.2, lower=-2, upper=2),
    DHRow(0.0, -np.pi / 3, 0.05, 0.1, kind="prismatic", lower=-0.2, upper=0.4),
    DHRow(0.25, 0.4, -0.02, -0.5, lower=-3, upper=3),
    DHRow(0.05, np.pi / 2, 0.1, 0.3, kind="fixed"),
]


@pytest.mark.parametrize("convention", ["standard", "modified"])
def test_urdf_moves_like_the_table(convention, rng):
    robot = load_robot(dh_to_urdf("t", ROWS, convention))
    assert robot.n == 3 and list(robot.revolute) == [True, False, True]
    assert np.allclose(robot.lower, [-2, -0.2, -3]) and np.allclose(robot.upper, [2, 0.4, 3])
    for q in robot.random_configurations(100, rng):
        ref = _product(ROWS, q, convention)
        T = robot.fk(q)
        assert np.abs(T.translation - ref[:3, 3]).max() < 1e-12
        assert np.abs(T.rotation - ref[:3, :3]).max() < 1e-12


def test_urdf_has_visual_geometry():
    text = dh_to_urdf("t", ROWS)
    assert text.count("<visual>") >= 4 and "<cylinder" in text and "<box" in text


def test_bad_tables_are_rejected():
    with pytest.raises(RobotLoadError, match="kind"):
        DHRow(0, 0, 0, kind="spherical")
    with pytest.raises(RobotLoadError, match="inverted"):
        DHRow(0, 0, 0, lower=1, upper=-1)
    with pytest.raises(RobotLoadError, match="convention"):
        dh_to_urdf("t", ROWS, "craig")
    with pytest.raises(RobotLoadError, match="at least one row"):
        dh_to_urdf("t", [])
