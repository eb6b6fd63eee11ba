"""Per-axis tolerance bands and free axes (Pose, Position, Orientation, RelativePose; docs/GOALS.md), their kernel
``aux`` row, and the NumPy twin of the kernel's errors of the banded kinds (``solvers/lm/axes.py``): the norm of the
excess over the bands (0 when met), with one free rotation axis the swing angle."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..errors import OptionError
from ..lie import log3
from .registry import BANDED_LOG6, BANDED_POINT

__all__ = ["AUX_BAND", "AUX_INNER", "AUX_SIZE", "AUX_SWING", "AXES", "DEFAULT_GOAL_TOLERANCE", "angles", "band_aux",
           "band_errors", "parse_axes", "pose_text"]

#: The ``aux`` row of a goal with bands or free axes (read by the compiled ``solvers/lm/axes.py``): AUX_INNER (6,)
#: the residual's dead-zone half-widths (m x3, rad x3; inf on a free axis, 0 under a norm tolerance), AUX_BAND (6,)
#: the half-widths the success test accepts (inf free, 0 under a norm tolerance), AUX_SWING the one free rotation
#: axis (0, 1, 2: x, y, z of the target frame) whose swing residual replaces the rotation vector, or -1.
AUX_INNER, AUX_BAND, AUX_SWING = 0, 6, 12
AUX_SIZE = 13
#: Default tolerance of a goal: 1e-6 m (and rad for a pose's rotation); no band is narrower.
DEFAULT_GOAL_TOLERANCE = 1e-6

#: The axis names of a pose's six error components, in their order.
AXES = ("x", "y", "z", "rx", "ry", "rz")


def parse_axes(tolerance, rotation_tolerance, free, axes: tuple[str, ...], where: str
               ) -> tuple[np.ndarray | None, tuple[str, ...]]:
    """(band or None, free axes in :data:`AXES` order) of a goal whose error components are ``axes``: ``tolerance``
    one number (a norm tolerance, checked by the goal) or one half-width per axis (m or rad, >= 0; inf: free; the free
    axes' set to inf), ``free`` None, a string of names or a list of them, among ``axes``. OptionError, naming
    ``where``, for a wrong length, NaN or a negative half-width, a ``rotation_tolerance`` beside half-widths, an
    unknown or repeated free axis, or every axis free."""
    band = None
    if np.ndim(tolerance) != 0:
        try:
            band = np.array(tolerance, dtype=float)
        except (TypeError, ValueError):
            raise OptionError(f"{where}: tolerance must be a number or {len(axes)} numbers (half-widths), "
                              f"got {tolerance!r}") from None
        if band.shape != (len(axes),):
            raise OptionError(f"{where}: a tolerance band takes {len(axes)} half-widths ({' '.join(axes)}), "
                              f"got shape {band.shape}")
        if np.isnan(band).any() or (band < 0).any():
            raise OptionError(f"{where}: tolerance half-widths must be >= 0 (inf: free), got {band.tolist()}")
        if rotation_tolerance is not None:
            raise OptionError(f"{where}: rotation_tolerance goes with one number as tolerance; a 6-number tolerance "
                              "already holds the rotation's half-widths (rx ry rz, rad)")
    try:
        names = [] if free is None else free.replace(",", " ").split() if isinstance(free, str) else list(free)
    except TypeError:
        raise OptionError(f"{where}: free must name axes among {' '.join(axes)} (a string or a list), "
                          f"got {free!r}") from None
    for name in names:
        if name not in axes:
            raise OptionError(f"{where}: unknown free axis {name!r}; accepted: {' '.join(axes)}")
    if len(set(names)) != len(names):
        raise OptionError(f"{where}: free names an axis twice: {names}")
    if len(names) == len(axes):
        raise OptionError(f"{where}: free names all {({3: 'three'}).get(len(axes), 'six')} axes, which leaves "
                          "nothing to meet; drop the goal")
    free = tuple(a for a in AXES if a in names)
    return (None if band is None else np.where(np.isin(axes, free), np.inf, band)), free


def pose_text(goal) -> str:
    """How a pose-like goal's repr shows its target, weight, tolerances and free axes."""
    T = goal.target
    rpy = np.round(pin.rpy.matrixToRpy(T.rotation), 6).tolist()
    text = f"position={np.round(T.translation, 6).tolist()}, rpy={rpy}, weight={goal.weight:g}, "
    text += (f"tolerance={goal.tolerance:g}, rotation_tolerance={goal.rotation_tolerance:g}" if goal.band is None
             else f"tolerance={goal.band.tolist()}")
    return text + (f", free={' '.join(goal.free)!r}" if goal.free else "")


def band_aux(band: np.ndarray | None, free: tuple[str, ...], axes: tuple[str, ...]) -> np.ndarray:
    """The kernel's aux row (AUX_SIZE,) of a goal whose error components are ``axes``: ``band`` (len(axes),) or None
    (a norm tolerance), ``free`` the free axes; no band narrower than :data:`DEFAULT_GOAL_TOLERANCE` (m, rad), LM
    aiming half of it inside each band."""
    aux = np.full(AUX_SIZE, np.inf)
    aux[AUX_SWING] = -1.0
    for i, name in enumerate(AXES):
        if name not in axes or name in free:
            continue
        if band is None:
            aux[AUX_INNER + i] = aux[AUX_BAND + i] = 0.0
        else:
            b = band[axes.index(name)]
            if np.isfinite(b):
                b = max(b, DEFAULT_GOAL_TOLERANCE)
                aux[AUX_INNER + i], aux[AUX_BAND + i] = b - 0.5 * DEFAULT_GOAL_TOLERANCE, b
    free_rot = [i for i in (3, 4, 5) if AXES[i] in free]
    if band is None and len(free_rot) == 1:
        aux[AUX_SWING] = free_rot[0] - 3
    return aux


def _excess_norm(V: np.ndarray, band: np.ndarray) -> np.ndarray:
    """Norm (N,) of how far the components V (N, 3) lie beyond the half-widths band (3,) (inf: never)."""
    X = np.maximum(np.abs(V) - band, 0.0)
    return np.sqrt((X * X).sum(axis=1))


def angles(A: np.ndarray, D: np.ndarray) -> np.ndarray:
    """Angles (N,) rad between the vectors A (N, 3) and D (N, 3), by atan2 (accurate near 0 and pi)."""
    return np.arctan2(np.linalg.norm(np.cross(A, D), axis=1), (A * D).sum(axis=1))


def band_errors(kind: int, P: np.ndarray, R: np.ndarray, pt: np.ndarray, Rt: np.ndarray,
                aux: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(position errors (N,) m, orientation errors (N,) rad; 0 where a kind has none) of frame poses P (N, 3),
    R (N, 3, 3) for a banded goal of ``kind`` with target (pt (3,), Rt (3, 3)) and aux row ``aux``, as the kernel's
    success test computes them."""
    N = P.shape[0]
    zeros = np.zeros(N)
    pos = zeros
    if kind == BANDED_POINT:
        return _excess_norm(P - pt, aux[AUX_BAND:AUX_BAND + 3]), zeros
    if kind == BANDED_LOG6:
        pos = _excess_norm((P - pt) @ Rt, aux[AUX_BAND:AUX_BAND + 3])  # rows: R_t^T (p - p_t)
    j = int(aux[AUX_SWING])
    if j >= 0:
        return pos, angles(R[:, :, j], np.broadcast_to(Rt[:, j], (N, 3)))
    return pos, _excess_norm(log3(Rt.T @ R), aux[AUX_BAND + 3:AUX_BAND + 6])
