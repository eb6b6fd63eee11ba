"""The robot layer: the active joints of a URDF (a serial chain or a whole tree), as Pinocchio sees them.

This package is the only code in evoik_pin that runs Pinocchio's kinematics on a ``Model``/``Data`` (the
viewer draws with the placements :class:`Robot` returns). Its modules, data flowing down:

* :mod:`.loading`: finding and reading a robot (bundled paper arms, example-robot-data arms and whole robots,
  URDF and xacro files and strings, default tips of named arms, the whole tree of a whole robot or of a URDF whose
  joints branch, mesh package directories): :func:`load_robot`,
  :func:`list_robots`; :mod:`.catalog`: the whole robots of example-robot-data that load by name;
* :mod:`.urdf_text`: bytes to URDF text (the XML declaration's encoding; empty and binary files refused),
  xacro expansion (xacrodoc), and urdfdom's stderr captured into our errors;
* :mod:`.urdf_checks`: what a URDF must be (one tree, joint types, origins, axes, limits) before Pinocchio reads
  it, and its mimic couplings;
* :mod:`.robot`: :class:`Robot`: the active joints (chains to tips, or the whole tree; a floating base), bounds,
  the Pinocchio configuration mapping (continuous, mimic and floating-base joints), forward kinematics and
  Jacobians of any frame, manipulability, and the placements the viewer draws;
* :mod:`.tree`: the kinematic tree of the active joints in topological order (parents, folded constants, frames
  on joints, the chain to one frame, the floating base's six joints), what compiled kernels evaluate;
* :mod:`.population`: forward kinematics and Jacobians of whole populations (NumPy) along the chain to a frame;
* :mod:`.joints`: 1-DOF joint helpers (values, axes, limits, mimic couplings);
* :mod:`.frames`: frame look-up in a Pinocchio model (names to ids, root link, deepest link, closest names,
  whether its joints branch) and joint locking (``buildReducedModel``) that survives joints and links sharing a
  name.

The joint vector ``q`` users and solvers see has one entry per independent degree of freedom (rad for revolute
joints, m for prismatic ones; a mimic joint follows the joint it mimics; a floating base is six entries in
front); poses are those of frames in the base frame (the world frame when no base is chosen).
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
