"""The one Levenberg-Marquardt engine of evoik_pin.

* :mod:`.engine`: :class:`LevenbergMarquardt` (one target; one start, or several in one call) and
  :func:`solve_pairs` (many (start, target) pairs), the task errors and the iteration's description;
* :mod:`.kernel`: the iteration compiled with numba (every goal kind), with :mod:`.tree_kinematics`, :mod:`.chain`,
  :mod:`.axes`, :mod:`.balance` and the closed forms of :mod:`evoik_pin.lie.compiled`;
* :mod:`.reference`: the same iteration as a Python loop over Pinocchio, the reference the kernel is tested
  against (``engine="python"``);
* :mod:`.layout`: the constants and the kernel's memory layouts; :mod:`.run_outcome`: what runs return;
* :mod:`.population_rows`: the kernel's task rows of a whole population in one compiled call (NSGA-II's repair);
* :mod:`.polish`: ``polish=True``, any solver's answer taken to machine precision by one LM run.
"""

from .engine import ENGINES, LevenbergMarquardt, compiled_kernel, solve_pairs
from .layout import DEFAULT_ITERATIONS, wrapping_joints
from .run_outcome import LMOutcome, PairsOutcome

__all__ = ["DEFAULT_ITERATIONS", "ENGINES", "LMOutcome", "LevenbergMarquardt", "PairsOutcome", "compiled_kernel",
           "solve_pairs", "wrapping_joints"]
