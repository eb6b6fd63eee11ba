"""The LM iteration's constants and the layouts of the kernel's ``params`` (PARAMS_SIZE,) at the ``P_*`` indices
(:func:`kernel_params`) and ``box`` (5, n) (:func:`box_constants`): rows ``B_LO``, ``B_HI`` (the search box, rad or
m), ``B_CLO``, ``B_CHI`` (the clip box: +-inf on wrapping joints) and ``B_WRAP`` (1.0 on wrapping joints). Shared by
:mod:`.kernel` and :mod:`.reference`; the goal layouts are :mod:`evoik_pin.goals.stack`'s.
"""

from __future__ import annotations

import weakref

import numpy as np

__all__ = ["DEFAULT_DAMPING", "DEFAULT_ITERATIONS", "DEFAULT_MAX_STEP", "DEFAULT_STALL_RATIO",
           "DEFAULT_STALL_WINDOW", "box_constants", "kernel_params", "wrapping_joints"]

TWO_PI = 2.0 * np.pi
#: Initial damping lambda (m^2, rad^2): small against the entries of E E^T (about reach^2 ~ 0.1-1 m^2).
DEFAULT_DAMPING = 1e-2
#: Steps allowed to one LM run started from a seed (converging runs need about 5-15).
DEFAULT_ITERATIONS = 30
#: Stall test: a run stops when |e| has not dropped below DEFAULT_STALL_RATIO times its value
#: DEFAULT_STALL_WINDOW accepted steps earlier.
DEFAULT_STALL_WINDOW, DEFAULT_STALL_RATIO = 4, 0.5
#: Largest length |dq| of one step (rad or m, Euclidean); longer steps are scaled down (trust region).
DEFAULT_MAX_STEP = 1.0
#: Damping bounds and its factors after an accepted / a rejected step.
LAMBDA_MIN, LAMBDA_MAX = 1e-12, 1e4
SHRINK, GROW = 0.2, 8.0
#: |e|^2 below which a converged run needs no finishing step (|e| = 1e-12: about FK round-off for 1 m arms).
FINISHED = 1e-24
#: Geodesic acceleration: used after an accepted step that left |e|^2 above GEO_SLOW times its value (|e| not
#: halved) while |e|^2 < GEO_NEAR (|e| < 1 cm + rad: a run creeping along a narrow curved valley, the signature
#: of a near-singular target), so the fast, quadratic phase pays nothing; kept when |a| <= GEO_ALPHA |v| / 2;
#: GEO_H is the finite-difference step.
GEO_SLOW, GEO_NEAR, GEO_ALPHA, GEO_H = 0.25, 1e-4, 0.75, 0.1

#: Layout of the kernel's ``params`` vector.
P_DAMPING, P_MAX_STEP, P_STALL_WINDOW, P_STALL_RATIO, P_FINISH, P_ITERATIONS = range(6)
PARAMS_SIZE = 6
#: Rows of the kernel's ``box``.
B_LO, B_HI, B_CLO, B_CHI, B_WRAP = range(5)
#: Columns of the per-run ``stats`` rows the batch kernels write: errors (the largest over the goals), converged,
#: iterations, evaluations, cost (the weighted |e|^2 of the end configuration).
S_POS, S_ROT, S_CONVERGED, S_ITERATIONS, S_EVALUATIONS, S_COST = range(6)
STATS_SIZE = 6


def wrapping_joints(robot, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """(n,) bool: revolute joints whose search range spans a full turn (continuous ones, UR-style [-2 pi, 2 pi]
    ones), so wrapping by 2 pi keeps them inside."""
    return robot.revolute & ((upper - lower) >= TWO_PI - 1e-9)


_BOX_CACHE: dict = {}


def box_constants(robot, lower: np.ndarray, upper: np.ndarray):
    """(wrap mask (n,), any wrap, clip lower, clip upper, kernel box (5, n)) of a search box, cached (the same box
    recurs every solve); the clip bounds are +-inf for wrapping joints, which are never clipped."""
    key = (id(robot), lower.tobytes(), upper.tobytes())
    hit = _BOX_CACHE.get(key)
    if hit is None or hit[0]() is not robot:  # a weak reference: the cache must not keep robots alive
        wrap = wrapping_joints(robot, lower, upper)
        clip = (np.where(wrap, -np.inf, lower), np.where(wrap, np.inf, upper))
        box = np.empty((5, robot.n))
        box[[B_LO, B_HI, B_CLO, B_CHI, B_WRAP]] = lower, upper, *clip, wrap
        hit = (weakref.ref(robot), (wrap, bool(wrap.any()), *clip, box))
        if len(_BOX_CACHE) > 64:
            _BOX_CACHE.clear()
        _BOX_CACHE[key] = hit
    return hit[1]


def kernel_params(iterations: int = 0, damping: float = DEFAULT_DAMPING, max_step: float = DEFAULT_MAX_STEP,
                  stall_window: int = DEFAULT_STALL_WINDOW, stall_ratio: float = DEFAULT_STALL_RATIO,
                  finish: bool = True) -> np.ndarray:
    """The kernel's ``params`` vector (PARAMS_SIZE,) (layout: the ``P_*`` indices); the tolerances are the
    goals' (:class:`GoalStack`)."""
    params = np.empty(PARAMS_SIZE)
    params[[P_DAMPING, P_MAX_STEP, P_STALL_WINDOW, P_STALL_RATIO, P_FINISH, P_ITERATIONS]] = (
        damping, max_step, stall_window, stall_ratio, float(finish), iterations)
    return params
