"""The compiled residuals and Jacobians of the one-frame goal kinds beyond pose, position and planar (the
``FAMILY_AXES`` kinds of :mod:`evoik_pin.goals.registry`), inlined into :mod:`.kernel`. For the goal frame's pose
(R (3, 3), p (3,) m), its target (pt (3,), Rt (3, 3)) and the goal's ``aux`` row (:mod:`evoik_pin.goals.bands`):

* bands (pose with axes: 6 rows; position: 3; orientation: 3): per component v_i of the error (position
  ``R_t^T (p - p_t)`` for a pose, ``p - p_t`` for a position; rotation ``log3(R_t^T R)``) the dead zone
  ``sign(v) max(|v| - h_i, 0)`` (h_i = inf: a free axis), its Jacobian row zero inside. With one free rotation axis a
  and a norm tolerance, the rotation rows are the swing ``R a - R_t a`` instead (smooth through a twist of pi about
  a). Errors: the norm of the components' excess over their accepted half-widths (m; rad), or the swing angle;
* pointing (direction: pt the unit direction; look-at: pt the point, m): rows ``R a - d`` with d the unit direction
  (to the point), error the angle between R a and d (rad).
"""

from __future__ import annotations

import math

from numba import njit

from ...goals.bands import AUX_BAND, AUX_INNER, AUX_SWING
from ...goals.pointing import AUX_AXIS
from ...goals.registry import AXIS_ALONG, AXIS_AT, BANDED_LOG6, BANDED_POINT
from ...lie.compiled import jlog3, log3
from .tree_kinematics import BORROWING

#: Below this distance (m) from its point a look-at frame has no direction to the point.
_NEAR_POINT = 1e-12


@njit(cache=True, nogil=True, forceinline=True)
def _dead(v, h):
    """The dead zone of v beyond half-width h: v - h above, v + h below, 0 inside (always 0 for h = inf)."""
    if v > h:
        return v - h
    if v < -h:
        return v + h
    return 0.0


@njit(cache=True, nogil=True, forceinline=True)
def _excess(v, b):
    """How far |v| lies beyond half-width b (0 inside; always 0 for b = inf)."""
    x = abs(v) - b
    return x if x > 0.0 else 0.0


@njit(cache=True, nogil=True, forceinline=True)
def _angle(a0, a1, a2, d0, d1, d2):
    """Angle (rad, in [0, pi]) between the vectors a and d, by atan2 (accurate near 0 and pi)."""
    c0, c1, c2 = a1 * d2 - a2 * d1, a2 * d0 - a0 * d2, a0 * d1 - a1 * d0
    return math.atan2(math.sqrt(c0 * c0 + c1 * c1 + c2 * c2), a0 * d0 + a1 * d1 + a2 * d2)


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def _direction(kind, R, p, pt, aux, u):
    """u (3,) = a pointing goal's wanted unit direction (pt, or from p towards the point pt; on the point, the
    opposite of its axis, so the goal is unmet there); returns the distance (m) to the point (1 for a direction)."""
    if kind == AXIS_ALONG:
        u[0], u[1], u[2] = pt[0], pt[1], pt[2]
        return 1.0
    u0, u1, u2 = pt[0] - p[0], pt[1] - p[1], pt[2] - p[2]
    rho = math.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
    if rho < _NEAR_POINT:
        for i in range(3):
            u[i] = -(R[i, 0] * aux[AUX_AXIS] + R[i, 1] * aux[AUX_AXIS + 1] + R[i, 2] * aux[AUX_AXIS + 2])
        return 0.0
    u[0], u[1], u[2] = u0 / rho, u1 / rho, u2 / rho
    return rho


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def axes_error(kind, R, p, pt, Rt, aux, M, rv, e):
    """One goal's error rows e (its ``G_ROWS``) of this module's kinds; returns (|e|^2 unweighted, position error m,
    orientation error rad), the errors its tolerances judge. M (3, 3), rv (3,) scratch."""
    if kind == AXIS_ALONG or kind == AXIS_AT:
        _direction(kind, R, p, pt, aux, rv)
        c = 0.0
        for i in range(3):
            e[i] = R[i, 0] * aux[AUX_AXIS] + R[i, 1] * aux[AUX_AXIS + 1] + R[i, 2] * aux[AUX_AXIS + 2] - rv[i]
            c += e[i] * e[i]
        return c, 0.0, _angle(e[0] + rv[0], e[1] + rv[1], e[2] + rv[2], rv[0], rv[1], rv[2])
    c = 0.0
    pos2 = 0.0
    o = 0  # first rotation row
    if kind == BANDED_POINT or kind == BANDED_LOG6:
        d0, d1, d2 = p[0] - pt[0], p[1] - pt[1], p[2] - pt[2]
        for i in range(3):
            v = Rt[0, i] * d0 + Rt[1, i] * d1 + Rt[2, i] * d2 if kind == BANDED_LOG6 else p[i] - pt[i]
            e[i] = _dead(v, aux[AUX_INNER + i])
            c += e[i] * e[i]
            x = _excess(v, aux[AUX_BAND + i])
            pos2 += x * x
        if kind == BANDED_POINT:
            return c, math.sqrt(pos2), 0.0
        o = 3
    j = int(aux[AUX_SWING])
    if j >= 0:  # the swing of the target's axis j: R a - R_t a (base frame)
        for i in range(3):
            e[o + i] = R[i, j] - Rt[i, j]
            c += e[o + i] * e[o + i]
        return c, math.sqrt(pos2), _angle(R[0, j], R[1, j], R[2, j], Rt[0, j], Rt[1, j], Rt[2, j])
    for i in range(3):
        for k in range(3):
            M[i, k] = Rt[0, i] * R[0, k] + Rt[1, i] * R[1, k] + Rt[2, i] * R[2, k]  # R_t^T R
    log3(M, rv)
    rot2 = 0.0
    for i in range(3):
        e[o + i] = _dead(rv[i], aux[AUX_INNER + 3 + i])
        c += e[o + i] * e[o + i]
        x = _excess(rv[i], aux[AUX_BAND + 3 + i])
        rot2 += x * x
    return c, math.sqrt(pos2), math.sqrt(rot2)


@njit(cache=True, nogil=True, forceinline=True, **BORROWING)
def axes_jacobian(kind, R, p, J, pt, Rt, aux, rv, A, B, E, r):
    """One goal's rows r.. of the task Jacobian E (unweighted) from its frame's base-frame Jacobian J (6, n) at the
    pose (R, p) :func:`axes_error` saw. rv (3,), A, B (3, 3) scratch."""
    n = J.shape[1]
    if kind == AXIS_ALONG or kind == AXIS_AT:
        rho = _direction(kind, R, p, pt, aux, rv)
        a0 = R[0, 0] * aux[AUX_AXIS] + R[0, 1] * aux[AUX_AXIS + 1] + R[0, 2] * aux[AUX_AXIS + 2]  # R a
        a1 = R[1, 0] * aux[AUX_AXIS] + R[1, 1] * aux[AUX_AXIS + 1] + R[1, 2] * aux[AUX_AXIS + 2]
        a2 = R[2, 0] * aux[AUX_AXIS] + R[2, 1] * aux[AUX_AXIS + 1] + R[2, 2] * aux[AUX_AXIS + 2]
        for k in range(n):  # d(R a) = w x R a
            w0, w1, w2 = J[3, k], J[4, k], J[5, k]
            E[r, k] = w1 * a2 - w2 * a1
            E[r + 1, k] = w2 * a0 - w0 * a2
            E[r + 2, k] = w0 * a1 - w1 * a0
            if kind == AXIS_AT and rho > 0.0:  # -d(u) = (I - u u^T) J_v / rho
                s = rv[0] * J[0, k] + rv[1] * J[1, k] + rv[2] * J[2, k]
                for i in range(3):
                    E[r + i, k] += (J[i, k] - rv[i] * s) / rho
        return
    o = 0
    if kind == BANDED_POINT or kind == BANDED_LOG6:
        d0, d1, d2 = p[0] - pt[0], p[1] - pt[1], p[2] - pt[2]
        for i in range(3):
            if kind == BANDED_LOG6:
                v = Rt[0, i] * d0 + Rt[1, i] * d1 + Rt[2, i] * d2
                live = aux[AUX_INNER + i] == 0.0 or abs(v) > aux[AUX_INNER + i]  # h = 0: no dead zone
                for k in range(n):
                    E[r + i, k] = Rt[0, i] * J[0, k] + Rt[1, i] * J[1, k] + Rt[2, i] * J[2, k] if live else 0.0
            else:
                live = aux[AUX_INNER + i] == 0.0 or abs(p[i] - pt[i]) > aux[AUX_INNER + i]
                for k in range(n):
                    E[r + i, k] = J[i, k] if live else 0.0
        if kind == BANDED_POINT:
            return
        o = 3
    j = int(aux[AUX_SWING])
    if j >= 0:
        a0, a1, a2 = R[0, j], R[1, j], R[2, j]
        for k in range(n):
            w0, w1, w2 = J[3, k], J[4, k], J[5, k]
            E[r + o, k] = w1 * a2 - w2 * a1
            E[r + o + 1, k] = w2 * a0 - w0 * a2
            E[r + o + 2, k] = w0 * a1 - w1 * a0
        return
    for i in range(3):
        for k in range(3):
            A[i, k] = Rt[0, i] * R[0, k] + Rt[1, i] * R[1, k] + Rt[2, i] * R[2, k]  # R_t^T R
    theta = log3(A, rv)
    jlog3(theta, rv, B)
    for i in range(3):
        if not (aux[AUX_INNER + 3 + i] == 0.0 or abs(rv[i]) > aux[AUX_INNER + 3 + i]):
            for k in range(n):
                E[r + o + i, k] = 0.0
            continue
        for k in range(n):
            w0 = R[0, 0] * J[3, k] + R[1, 0] * J[4, k] + R[2, 0] * J[5, k]  # R^T J_w
            w1 = R[0, 1] * J[3, k] + R[1, 1] * J[4, k] + R[2, 1] * J[5, k]
            w2 = R[0, 2] * J[3, k] + R[1, 2] * J[4, k] + R[2, 2] * J[5, k]
            E[r + o + i, k] = B[i, 0] * w0 + B[i, 1] * w1 + B[i, 2] * w2
