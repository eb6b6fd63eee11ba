"""The one Levenberg-Marquardt engine of evoik_pin: :mod:`.engine` (:class:`LevenbergMarquardt`,
:func:`solve_pairs`), its numba kernel :mod:`.kernel` (with :mod:`.tree_kinematics`, :mod:`.chain`, :mod:`.axes`,
:mod:`.balance`) and the Python reference :mod:`.reference`; :mod:`.layout` (constants), :mod:`.run_outcome`,
:mod:`.population_rows` (NSGA-II's task rows), :mod:`.nullspace` (prefer=), :mod:`.polish` (``polish=True``).
"""

from .engine import ENGINES, LevenbergMarquardt, compiled_kernel, solve_pairs
from .layout import DEFAULT_ITERATIONS, wrapping_joints
from .run_outcome import LMOutcome, PairsOutcome

__all__ = ["DEFAULT_ITERATIONS", "ENGINES", "LMOutcome", "LevenbergMarquardt", "PairsOutcome", "compiled_kernel",
           "solve_pairs", "wrapping_joints"]
