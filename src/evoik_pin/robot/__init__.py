"""The robot layer: the active joints of a URDF (a serial chain or a whole tree), as Pinocchio sees them; the only
code in evoik_pin that runs Pinocchio's kinematics. Modules, data flowing down: :mod:`.loading` (:func:`load_robot`,
:func:`list_robots`) and :mod:`.catalog`; :mod:`.urdf_text` and :mod:`.urdf_checks` (URDF text and what it must
be); :mod:`.robot` (:class:`Robot`) with :mod:`.joint_bounds` (its search box and the checks of joint vectors);
:mod:`.tree`, :mod:`.population`, :mod:`.joints`, :mod:`.frames`, :mod:`.mass` and :mod:`.locking` (its kinematics
helpers).

The joint vector ``q`` has one entry per independent degree of freedom (rad for revolute joints, m for prismatic
ones; a floating base is six entries in front); poses are those of frames in the base frame.
"""

from .catalog import WHOLE_ROBOTS
from .joints import DEFAULT_PRISMATIC_RANGE as DEFAULT_PRISMATIC_RANGE
from .loading import (
    BUNDLED_ROBOTS,
    EXAMPLE_ARMS,
    bundled_robots_dir,
    example_robot_data_dir,
    list_robots,
    load_robot,
)
from .robot import Robot

__all__ = [
    "BUNDLED_ROBOTS",
    "EXAMPLE_ARMS",
    "WHOLE_ROBOTS",
    "Robot",
    "bundled_robots_dir",
    "example_robot_data_dir",
    "list_robots",
    "load_robot",
]
