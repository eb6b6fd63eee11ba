"""evoik_pin: inverse kinematics by evolutionary computation, on Pinocchio.

Load any serial-chain URDF (or one of the papers' arms) with :func:`load_robot`, then solve with the
evolutionary methods of five research papers or the memetic default. See README.md.
"""

from .robot import Robot, list_robots, load_robot

__all__ = ["Robot", "list_robots", "load_robot"]
__version__ = "0.1.0"
