"""evoik_pin: inverse kinematics by evolutionary computation, on Pinocchio.

Load any serial-chain URDF (or one of the papers' arms) with :func:`load_robot`, then :func:`solve` with
the evolutionary methods of five research papers or the memetic default. See README.md.
"""

from .api import BatchResults, IKSolver, make_problem, prepare, solve, solve_all, solve_many, solve_trajectory
from .goals import RelativePosition
from .motion.retarget import retarget
from .motion.tracker import Tracker
from .problem import IKProblem, Target
from .reach import ReachMap, reachability_map
from .result import Front, Result
from .robot import Robot, list_robots, load_robot
from .scene import Scene
from .solvers import methods

__all__ = ["BatchResults", "Front", "IKProblem", "IKSolver", "ReachMap", "Result", "RelativePosition", "Robot",
           "Scene", "Target", "Tracker", "list_robots", "load_robot", "make_problem", "methods", "prepare",
           "reachability_map", "retarget", "solve", "solve_all", "solve_many", "solve_trajectory"]
__version__ = "0.1.0"
