"""The robot layer: one serial chain of a URDF, as Pinocchio sees it.

This package is the only code in evoik_pin that runs Pinocchio's kinematics on a ``Model``/``Data`` (the
viewer draws with the placements :class:`Robot` returns). Five modules, data flowing down:

* :mod:`.loading`: finding and reading a robot (bundled paper arms, example-robot-data arms, URDF and xacro
  files and strings, default tips of named arms, mesh package directories): :func:`load_robot`,
  :func:`list_robots`;
* :mod:`.urdf_text`: bytes to URDF text (the XML declaration's encoding; empty and binary files refused),
  xacro expansion (xacrodoc), and urdfdom's stderr captured into our errors;
* :mod:`.urdf_checks`: what a URDF must be (one tree, joint types, origins, axes, limits) before Pinocchio reads
  it, and its mimic couplings;
* :mod:`.kinematics`: :class:`Robot`, the chain: bounds, the Pinocchio configuration mapping (continuous and
  mimic joints), forward kinematics, Jacobians and manipulability, one configuration or a whole population,
  the folded chain constants and coupling compiled kernels use, and the placements the viewer draws;
* :mod:`.frames`: frame look-up in a Pinocchio model (names to ids, root link, deepest link) and joint locking
  (``buildReducedModel``) that survives joints and links sharing a name.

The joint vector ``q`` users and solvers see has one entry per independent degree of freedom (rad for revolute
joints, m for prismatic ones; a mimic joint follows the joint it mimics); poses are those of the tip frame in
the base frame (the world frame when no base is chosen).
"""

from .kinematics import DEFAULT_PRISMATIC_RANGE as DEFAULT_PRISMATIC_RANGE
from .kinematics import Robot
from .loading import (
    BUNDLED_ROBOTS,
    EXAMPLE_ARMS,
    bundled_robots_dir,
    example_robot_data_dir,
    list_robots,
    load_robot,
)

__all__ = [
    "BUNDLED_ROBOTS",
    "EXAMPLE_ARMS",
    "Robot",
    "bundled_robots_dir",
    "example_robot_data_dir",
    "list_robots",
    "load_robot",
]
