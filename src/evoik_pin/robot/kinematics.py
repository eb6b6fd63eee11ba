"""The robot's kinematics under its former module name: :class:`~.robot.Robot` lives in :mod:`.robot` now (with
:mod:`.tree`, :mod:`.population` and :mod:`.joints`); these names keep working from here."""

from .joints import DEFAULT_PRISMATIC_RANGE
from .robot import MAX_CHAIN_JOINTS, Robot

__all__ = ["DEFAULT_PRISMATIC_RANGE", "MAX_CHAIN_JOINTS", "Robot"]
