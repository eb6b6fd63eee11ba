"""The robot layer, the only code in evoik_pin that runs Pinocchio's kinematics: :func:`load_robot` makes a
:class:`Robot`, the active joints of a URDF (a serial chain or a whole tree)."""

from .catalog import BUNDLED_ROBOTS, EXAMPLE_ARMS, WHOLE_ROBOTS
from .joints import DEFAULT_PRISMATIC_RANGE as DEFAULT_PRISMATIC_RANGE
from .loading import bundled_robots_dir, example_robot_data_dir, list_robots, load_robot
from .robot import Robot

__all__ = ["BUNDLED_ROBOTS", "EXAMPLE_ARMS", "WHOLE_ROBOTS", "Robot", "bundled_robots_dir", "example_robot_data_dir",
           "list_robots", "load_robot"]
