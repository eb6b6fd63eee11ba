import numpy as np
import pytest


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture
def reachable_pose():
    """``reachable_pose(robot, seed) -> pin.SE3``: the tip pose of a random in-limits configuration."""

    def pose(robot, seed):
        return robot.fk(robot.random_configurations(1, np.random.default_rng(seed))[0])

    return pose
