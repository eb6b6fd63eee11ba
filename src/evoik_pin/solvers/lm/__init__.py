"""The one Levenberg-Marquardt engine of evoik_pin (:mod:`.engine`), its numba kernel (:mod:`.kernel`) and the
Python reference loop (:mod:`.reference`)."""

from .engine import ENGINES, LevenbergMarquardt, compiled_kernel, solve_pairs
from .layout import DEFAULT_ITERATIONS, wrapping_joints
from .run_outcome import LMOutcome, PairsOutcome

__all__ = ["DEFAULT_ITERATIONS", "ENGINES", "LMOutcome", "LevenbergMarquardt", "PairsOutcome", "compiled_kernel",
           "solve_pairs", "wrapping_joints"]
