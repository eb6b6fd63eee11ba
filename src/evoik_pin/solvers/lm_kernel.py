"""Compiled Levenberg-Marquardt run (numba): the hot path of :class:`~evoik_pin.solvers.polish.LevenbergMarquardt`.

One call runs a whole LM iteration from one start for a pose or position target, with the forward kinematics
and the Jacobian computed by the chain recursion the robot layer exports (``Robot.chain_constants``: every
joint axis turned onto z and folded into the fixed placements, ``T(q) = F_0 Z(q_1) F_1 ... Z(q_n) F_n``).
The algorithm is the one of :meth:`LevenbergMarquardt.run_python` line for line (same error, damping rule,
trust region, active-set joint limits, wrapping, stall test, geodesic acceleration and finishing step); only
the per-step cost differs: about 1-2 us compiled against 30-40 us of NumPy and Pinocchio calls, which is
most of a solve's time (docs/BENCHMARKS.md). Tests check the kinematics against Pinocchio's and the runs
against the Python loop.

Task error as in the Python loop: ``e = log6(T_t^-1 T(q))`` (Pinocchio's formula, m and rad) for a pose target,
with ``E = Jlog6(T_t^-1 T(q)) J_local``, and ``e = p(q) - p_t`` with the base-frame translational Jacobian
rows for a position target. ``log3``, ``log6``, ``Jlog3`` and ``Jlog6`` are Pinocchio's closed forms written
out, with ``1 - cos(theta)`` computed as ``2 sin^2(theta / 2)`` (no cancellation for small angles: the
round trip through ``pin.exp6`` holds to 1e-12 where the textbook form loses 1e-8 near theta = 1e-4); tests
compare them with ``pin.log3`` etc. near 0, near pi and at random.

Everything here is plain float arithmetic on small arrays; numba compiles it on first use (about 2-4 s, then
cached on disk next to this file, or in numba's user cache directory when that is not writable).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# One definition of the iteration's constants and of lm_run's params / box layouts: polish.py's.
from .polish import _B_CHI as B_CHI
from .polish import _B_CLO as B_CLO
from .polish import _B_HI as B_HI
from .polish import _B_LO as B_LO
from .polish import _B_WRAP as B_WRAP
from .polish import _FINISHED as FINISHED
from .polish import _GEO_ALPHA as GEO_ALPHA
from .polish import _GEO_H as GEO_H
from .polish import _GEO_NEAR as GEO_NEAR
from .polish import _GEO_SLOW as GEO_SLOW
from .polish import _GROW as GROW
from .polish import _LAMBDA_MAX as LAMBDA_MAX
from .polish import _LAMBDA_MIN as LAMBDA_MIN
from .polish import _P_DAMPING as P_DAMPING
from .polish import _P_FINISH as P_FINISH
from .polish import _P_ITERATIONS as P_ITERATIONS
from .polish import _P_MAX_STEP as P_MAX_STEP
from .polish import _P_POSE as P_POSE
from .polish import _P_RTOL as P_RTOL
from .polish import _P_STALL_RATIO as P_STALL_RATIO
from .polish import _P_STALL_WINDOW as P_STALL_WINDOW
from .polish import _P_TOL as P_TOL
from .polish import _SHRINK as SHRINK

TWO_PI = 2.0 * math.pi


@njit(cache=True, nogil=True)
def forward(FR, Fp, rev, q, R, p, Z, O):
    """Tip rotation R (3, 3) and position p (3,) at q (n,), and each joint's axis Z (n, 3) and origin O (n, 3),
    all in the base frame (written in place)."""
    n = q.shape[0]
    for i in range(3):
        p[i] = Fp[0, i]
        for j in range(3):
            R[i, j] = FR[0, i, j]
    for k in range(n):
        for i in range(3):
            Z[k, i] = R[i, 2]
            O[k, i] = p[i]
        if rev[k]:
            c, s = math.cos(q[k]), math.sin(q[k])
            for i in range(3):
                a, b = R[i, 0], R[i, 1]
                R[i, 0] = c * a + s * b
                R[i, 1] = c * b - s * a
        else:
            for i in range(3):
                p[i] += q[k] * R[i, 2]
        f0, f1, f2 = Fp[k + 1, 0], Fp[k + 1, 1], Fp[k + 1, 2]
        for i in range(3):
            r0, r1, r2 = R[i, 0], R[i, 1], R[i, 2]
            p[i] += r0 * f0 + r1 * f1 + r2 * f2
            R[i, 0] = r0 * FR[k + 1, 0, 0] + r1 * FR[k + 1, 1, 0] + r2 * FR[k + 1, 2, 0]
            R[i, 1] = r0 * FR[k + 1, 0, 1] + r1 * FR[k + 1, 1, 1] + r2 * FR[k + 1, 2, 1]
            R[i, 2] = r0 * FR[k + 1, 0, 2] + r1 * FR[k + 1, 1, 2] + r2 * FR[k + 1, 2, 2]


@njit(cache=True, nogil=True)
def jacobian(rev, p, Z, O, J):
    """Base-frame Jacobian J (6, n) of the tip point p (3,) from the joint axes Z and origins O (n, 3)."""
    n = Z.shape[0]
    for k in range(n):
        z0, z1, z2 = Z[k, 0], Z[k, 1], Z[k, 2]
        if rev[k]:
            l0, l1, l2 = p[0] - O[k, 0], p[1] - O[k, 1], p[2] - O[k, 2]
            J[0, k] = z1 * l2 - z2 * l1
            J[1, k] = z2 * l0 - z0 * l2
            J[2, k] = z0 * l1 - z1 * l0
            J[3, k], J[4, k], J[5, k] = z0, z1, z2
        else:
            J[0, k], J[1, k], J[2, k] = z0, z1, z2
            J[3, k] = J[4, k] = J[5, k] = 0.0


@njit(cache=True, nogil=True)
def log3(M, phi):
    """Rotation vector phi (3,) (rad) of the rotation M (3, 3), stable near 0 and near pi; returns the angle."""
    ax0, ax1, ax2 = M[2, 1] - M[1, 2], M[0, 2] - M[2, 0], M[1, 0] - M[0, 1]
    s = 0.5 * math.sqrt(ax0 * ax0 + ax1 * ax1 + ax2 * ax2)
    c = 0.5 * (M[0, 0] + M[1, 1] + M[2, 2] - 1.0)
    theta = math.atan2(s, c)
    if theta < math.pi - 1e-3:
        # theta / (2 sin theta), with its series near 0
        coef = 0.5 + theta * theta / 12.0 if s < 1e-8 else theta / (2.0 * s)
        phi[0], phi[1], phi[2] = coef * ax0, coef * ax1, coef * ax2
        return theta
    # near pi the antisymmetric part vanishes: the axis comes from the symmetric part,
    # a a^T = ((M + M^T) / 2 - cos I) / (1 - cos), its sign from the antisymmetric part
    omc = 1.0 - c
    d0, d1, d2 = (M[0, 0] - c) / omc, (M[1, 1] - c) / omc, (M[2, 2] - c) / omc
    if d0 >= d1 and d0 >= d2:
        a0 = math.sqrt(max(d0, 0.0))
        a1 = (M[0, 1] + M[1, 0]) / (2.0 * omc * a0)
        a2 = (M[0, 2] + M[2, 0]) / (2.0 * omc * a0)
    elif d1 >= d2:
        a1 = math.sqrt(max(d1, 0.0))
        a0 = (M[0, 1] + M[1, 0]) / (2.0 * omc * a1)
        a2 = (M[1, 2] + M[2, 1]) / (2.0 * omc * a1)
    else:
        a2 = math.sqrt(max(d2, 0.0))
        a0 = (M[0, 2] + M[2, 0]) / (2.0 * omc * a2)
        a1 = (M[1, 2] + M[2, 1]) / (2.0 * omc * a2)
    norm = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
    if a0 * ax0 + a1 * ax1 + a2 * ax2 < 0.0:
        norm = -norm
    k = theta / norm
    phi[0], phi[1], phi[2] = k * a0, k * a1, k * a2
    return theta


#: Pinocchio's series thresholds (TaylorSeriesExpansion precision<3> and <2>: eps^(1/3), eps^(1/2)).
_PREC3, _PREC2 = np.finfo(np.float64).eps ** (1.0 / 3.0), np.finfo(np.float64).eps ** 0.5


@njit(cache=True, nogil=True)
def _add_half_skew(v, A):
    """A (3, 3) += [v / 2]x, the skew matrix of v / 2 (Pinocchio's ``addSkew(0.5 * v, A)``)."""
    A[0, 1] -= 0.5 * v[2]
    A[1, 0] += 0.5 * v[2]
    A[0, 2] += 0.5 * v[1]
    A[2, 0] -= 0.5 * v[1]
    A[1, 2] -= 0.5 * v[0]
    A[2, 1] += 0.5 * v[0]


@njit(cache=True, nogil=True)
def jlog3(theta, w, A):
    """``pin.Jlog3``: A (3, 3), the derivative of ``log3(R exp(dw))`` at dw = 0, from ``w = log3(R)`` (angle
    theta): ``alpha w w^T + d I + [w]x / 2``."""
    if theta < _PREC3:
        alpha = 1.0 / 12.0 + theta * theta / 720.0
        d = 0.5 * (2.0 - theta * theta / 6.0)
    else:
        st_1mct = 1.0 / math.tan(0.5 * theta)  # sin / (1 - cos), without the cancellation of 1 - cos
        alpha = 1.0 / (theta * theta) - st_1mct / (2.0 * theta)
        d = 0.5 * theta * st_1mct
    for i in range(3):
        for j in range(3):
            A[i, j] = alpha * w[i] * w[j]
        A[i, i] += d
    _add_half_skew(w, A)


@njit(cache=True, nogil=True)
def log6(M, t, e):
    """``pin.log6`` of the pose (M (3, 3), t (3,)): e (6,) = (v, w) with ``w = log3(M)``; returns the angle."""
    theta = log3(M, e[3:])
    w0, w1, w2 = e[3], e[4], e[5]
    if M[0, 0] + M[1, 1] + M[2, 2] >= 3.0 - _PREC2:
        # Pinocchio's switch and series variable: the squared norm of the antisymmetric part (sin^2 theta)
        a0, a1, a2 = 0.5 * (M[2, 1] - M[1, 2]), 0.5 * (M[0, 2] - M[2, 0]), 0.5 * (M[1, 0] - M[0, 1])
        t2 = a0 * a0 + a1 * a1 + a2 * a2
        alpha = 1.0 - t2 / 12.0 - t2 * t2 / 720.0
        beta = 1.0 / 12.0 + t2 / 720.0
    else:
        st, sh = math.sin(theta), math.sin(0.5 * theta)
        omc = 2.0 * sh * sh  # 1 - cos(theta) without its cancellation near 0
        alpha = theta * st / (2.0 * omc)
        beta = 1.0 / (theta * theta) - st / (2.0 * theta * omc)
    wp = beta * (w0 * t[0] + w1 * t[1] + w2 * t[2])
    e[0] = alpha * t[0] - 0.5 * (w1 * t[2] - w2 * t[1]) + wp * w0
    e[1] = alpha * t[1] - 0.5 * (w2 * t[0] - w0 * t[2]) + wp * w1
    e[2] = alpha * t[2] - 0.5 * (w0 * t[1] - w1 * t[0]) + wp * w2
    return theta


@njit(cache=True, nogil=True)
def jlog6(theta, w, t, A, B):
    """``pin.Jlog6`` of the pose whose log is (., w) (angle theta) and translation t (3,): the (6, 6) matrix
    ``[[A, B], [0, A]]`` as its blocks A = ``Jlog3`` and B (3, 3) (Pinocchio's formula)."""
    jlog3(theta, w, A)
    t2 = theta * theta
    if theta < _PREC3:
        beta = 1.0 / 12.0 + t2 / 720.0
        beta_dot_over_theta = 1.0 / 360.0
    else:
        tinv = 1.0 / theta
        t2inv = tinv * tinv
        st, sh = math.sin(theta), math.sin(0.5 * theta)
        inv_2_2ct = 1.0 / (4.0 * sh * sh)  # 1 / (2 (1 - cos theta))
        beta = t2inv - st * tinv * inv_2_2ct
        beta_dot_over_theta = -2.0 * t2inv * t2inv + (1.0 + st * tinv) * t2inv * inv_2_2ct
    wTp = w[0] * t[0] + w[1] * t[1] + w[2] * t[2]
    C = np.empty((3, 3))
    for i in range(3):
        vi = beta_dot_over_theta * wTp * w[i] - (t2 * beta_dot_over_theta + 2.0 * beta) * t[i]
        for j in range(3):
            C[i, j] = vi * w[j] + beta * w[i] * t[j]
        C[i, i] += wTp * beta
    _add_half_skew(t, C)
    for i in range(3):
        for j in range(3):
            B[i, j] = C[i, 0] * A[0, j] + C[i, 1] * A[1, j] + C[i, 2] * A[2, j]


@njit(cache=True, nogil=True)
def task_error(FR, Fp, rev, q, pt, Rt, pose, R, p, Z, O, M, t, e):
    """Task error e (m,) at q; returns (|e|^2, position error m, orientation error rad or 0).

    Fills the kinematics buffers R, p, Z, O (see :func:`forward`), and for pose targets the tip pose seen from
    the target, ``T_t^-1 T(q)`` = (M (3, 3), t (3,)), which :func:`task_jacobian` needs.
    """
    forward(FR, Fp, rev, q, R, p, Z, O)
    d0, d1, d2 = p[0] - pt[0], p[1] - pt[1], p[2] - pt[2]
    pos = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    if not pose:
        e[0], e[1], e[2] = d0, d1, d2
        return pos * pos, pos, 0.0
    for i in range(3):
        t[i] = Rt[0, i] * d0 + Rt[1, i] * d1 + Rt[2, i] * d2  # R_t^T (p - p_t)
        for j in range(3):
            M[i, j] = Rt[0, i] * R[0, j] + Rt[1, i] * R[1, j] + Rt[2, i] * R[2, j]  # R_t^T R
    rot = log6(M, t, e)
    c = 0.0
    for i in range(6):
        c += e[i] * e[i]
    return c, pos, rot


@njit(cache=True, nogil=True)
def task_jacobian(rev, R, p, Z, O, t, e, pose, J, A, B, E):
    """Task Jacobian E (m, n) from the buffers :func:`task_error` filled for the same configuration.

    Position: the base-frame translational rows. Pose: ``Jlog6(T_t^-1 T) J_local`` with ``J_local = (R^T J_v,
    R^T J_w)``. J (6, n), A, B (3, 3) are scratch.
    """
    jacobian(rev, p, Z, O, J)
    n = J.shape[1]
    if not pose:
        for i in range(3):
            for k in range(n):
                E[i, k] = J[i, k]
        return
    theta = math.sqrt(e[3] * e[3] + e[4] * e[4] + e[5] * e[5])
    jlog6(theta, e[3:], t, A, B)
    for k in range(n):
        v0 = R[0, 0] * J[0, k] + R[1, 0] * J[1, k] + R[2, 0] * J[2, k]  # R^T J_v
        v1 = R[0, 1] * J[0, k] + R[1, 1] * J[1, k] + R[2, 1] * J[2, k]
        v2 = R[0, 2] * J[0, k] + R[1, 2] * J[1, k] + R[2, 2] * J[2, k]
        w0 = R[0, 0] * J[3, k] + R[1, 0] * J[4, k] + R[2, 0] * J[5, k]  # R^T J_w
        w1 = R[0, 1] * J[3, k] + R[1, 1] * J[4, k] + R[2, 1] * J[5, k]
        w2 = R[0, 2] * J[3, k] + R[1, 2] * J[4, k] + R[2, 2] * J[5, k]
        for i in range(3):
            E[i, k] = A[i, 0] * v0 + A[i, 1] * v1 + A[i, 2] * v2 + B[i, 0] * w0 + B[i, 1] * w1 + B[i, 2] * w2
            E[3 + i, k] = A[i, 0] * w0 + A[i, 1] * w1 + A[i, 2] * w2


@njit(cache=True, nogil=True)
def damped_solve(E, lam, rhs, L, y, dq):
    """dq (n,) = E^T (E E^T + lam I)^-1 rhs by Cholesky (L (m, m), y (m,) scratch); False when not positive."""
    m, n = E.shape
    for i in range(m):
        for j in range(i + 1):
            s = 0.0
            for k in range(n):
                s += E[i, k] * E[j, k]
            if i == j:
                s += lam
            for k in range(j):
                s -= L[i, k] * L[j, k]
            if i == j:
                if s <= 0.0:
                    return False
                L[i, i] = math.sqrt(s)
            else:
                L[i, j] = s / L[j, j]
    for i in range(m):  # L z = rhs
        s = rhs[i]
        for k in range(i):
            s -= L[i, k] * y[k]
        y[i] = s / L[i, i]
    for i in range(m - 1, -1, -1):  # L^T y = z
        s = y[i]
        for k in range(i + 1, m):
            s -= L[k, i] * y[k]
        y[i] = s / L[i, i]
    for k in range(n):
        s = 0.0
        for i in range(m):
            s += E[i, k] * y[i]
        dq[k] = s
    return True


@njit(cache=True, nogil=True)
def into_box(q, box, any_wrap, out):
    """out (n,) = q clipped into the box, wrapping joints shifted by 2 pi into [lower, lower + 2 pi)."""
    for k in range(q.shape[0]):
        x = min(max(q[k], box[B_CLO, k]), box[B_CHI, k])
        if any_wrap and box[B_WRAP, k] != 0.0 and (x < box[B_LO, k] or x > box[B_HI, k]):
            lo = box[B_LO, k]
            x = lo + ((x - lo) % TWO_PI)
        out[k] = x


@njit(cache=True, nogil=True)
def _scaled_to(dq, max_step):
    """Scale dq (n,) down to length max_step when longer (the trust region)."""
    s2 = 0.0
    for k in range(dq.shape[0]):
        s2 += dq[k] * dq[k]
    if s2 > max_step * max_step:
        f = max_step / math.sqrt(s2)
        for k in range(dq.shape[0]):
            dq[k] *= f


@njit(cache=True, nogil=True)
def lm_step(q, on_bound, E, e, lam, box, any_wrap, max_step, W, L, y, dq, dfix, rhs, held, qn):
    """The next configuration qn (n,) (written in place) and whether a joint hit a bound: the damped step,
    trust region, active-set limits and wrapping of ``LevenbergMarquardt._step`` (its docstring says why).
    W (m, n), L (m, m), y, rhs (m,), dq, dfix (n,) and held (n,) bool are scratch."""
    m, n = E.shape
    W[:, :] = E
    held[:] = False
    if on_bound:  # joints on a bound that the descent direction -E^T e pushes outward are held there
        for k in range(n):
            g = 0.0
            for i in range(m):
                g += E[i, k] * e[i]
            if (q[k] <= box[B_CLO, k] and g > 0.0) or (q[k] >= box[B_CHI, k] and g < 0.0):
                held[k] = True
                for i in range(m):
                    W[i, k] = 0.0
    if not damped_solve(W, lam, e, L, y, dq):
        qn[:] = q
        return False
    _scaled_to(dq, max_step)
    clipped = False
    for k in range(n):
        x = q[k] - dq[k]
        xc = min(max(x, box[B_CLO, k]), box[B_CHI, k])
        qn[k] = xc
        if xc != x:
            clipped = True
            held[k] = True  # from here on: fixed at the bound it hit
    if clipped:
        # the fixed joints move to their bound (dfix); the others re-solve for the error that move leaves
        for k in range(n):
            dfix[k] = qn[k] - q[k] if held[k] else 0.0
        for i in range(m):
            s = e[i]
            for k in range(n):
                s += W[i, k] * dfix[k]
            rhs[i] = s
        for k in range(n):
            if held[k]:
                for i in range(m):
                    W[i, k] = 0.0
        if not damped_solve(W, lam, rhs, L, y, dq):
            qn[:] = q
            return False
        _scaled_to(dq, max_step)
        for k in range(n):
            qn[k] = min(max(q[k] + dfix[k] - dq[k], box[B_CLO, k]), box[B_CHI, k])
    if any_wrap:
        into_box(qn, box, any_wrap, qn)
    return clipped


@njit(cache=True, nogil=True)
def _copy_kinematics(R, p, Z, O, R2, p2, Z2, O2):
    R2[:, :] = R
    p2[:] = p
    Z2[:, :] = Z
    O2[:, :] = O


@njit(cache=True, nogil=True)
def lm_run(q_start, FR, Fp, rev, box, any_wrap, pt, Rt, params, q_out):
    """One LM run from ``q_start`` (n,); the end configuration goes to ``q_out`` (n,).

    Args:
        FR (n+1, 3, 3), Fp (n+1, 3), rev (n,) bool: the folded chain (``Robot.chain_constants``).
        box (5, n): rows B_LO, B_HI, B_CLO, B_CHI, B_WRAP. any_wrap: some joint wraps.
        pt (3,), Rt (3, 3): target position (m) and rotation (ignored for position targets).
        params (9,): tolerance (m), rotation tolerance (rad), initial damping, max step, stall window,
            stall ratio, finish (0/1), max iterations, pose target (0/1).

    Returns:
        (position error m, orientation error rad (nan for position targets), converged, iterations,
        forward-kinematics evaluations), as ``LevenbergMarquardt.run_python`` counts them.
    """
    n = q_start.shape[0]
    pose = params[P_POSE] != 0.0
    m = 6 if pose else 3
    tol_p, tol_r = params[P_TOL], params[P_RTOL]
    max_step = params[P_MAX_STEP]
    window = int(params[P_STALL_WINDOW])
    stall = params[P_STALL_RATIO] * params[P_STALL_RATIO]
    finish = params[P_FINISH] != 0.0
    max_it = int(params[P_ITERATIONS])
    # buffers: current configuration (R, p, Z, O, e), candidate (R2, ..., en), scratch
    q, qn, qh = np.empty(n), np.empty(n), np.empty(n)
    v, dq, dfix = np.empty(n), np.empty(n), np.empty(n)
    held = np.empty(n, dtype=np.bool_)
    R, R2, R3 = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    p, p2, p3 = np.empty(3), np.empty(3), np.empty(3)
    Z, Z2, Z3 = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
    O, O2, O3 = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
    e, en, eh = np.empty(m), np.empty(m), np.empty(m)
    E, W, J = np.empty((m, n)), np.empty((m, n)), np.empty((6, n))
    tx, tx2, tx3 = np.empty(3), np.empty(3), np.empty(3)
    A, Bm, M, L = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3)), np.empty((m, m))
    y, rhs = np.empty(m), np.empty(m)
    history = np.empty(max_it + 1)

    into_box(q_start, box, any_wrap, q)
    on_bound = False
    for k in range(n):
        if q[k] <= box[B_CLO, k] or q[k] >= box[B_CHI, k]:
            on_bound = True
    c, pos, rot = task_error(FR, Fp, rev, q, pt, Rt, pose, R, p, Z, O, M, tx, e)
    evaluations = 1
    if pos <= tol_p and (not pose or rot <= tol_r):
        q_out[:] = q
        return pos, rot if pose else np.nan, True, 0, evaluations
    lam = params[P_DAMPING]
    have_E = False
    history[0] = c
    hlen = 1
    it = 0
    creeping = False  # the last accepted step did not halve |e| near the target: accelerate the next
    converged = False
    while it < max_it:
        it += 1
        if not have_E:
            task_jacobian(rev, R, p, Z, O, tx, e, pose, J, A, Bm, E)
            have_E = True
        on_bound_n = lm_step(q, on_bound, E, e, lam, box, any_wrap, max_step, W, L, y, dq, dfix, rhs, held, qn)
        if creeping and not (on_bound or on_bound_n):
            # geodesic acceleration (LevenbergMarquardt._geodesic): r'' from one extra FK at q + h v
            for k in range(n):
                d = qn[k] - q[k]
                if any_wrap and box[B_WRAP, k] != 0.0:
                    d = (d + math.pi) % TWO_PI - math.pi
                v[k] = d
                qh[k] = q[k] + GEO_H * d
            task_error(FR, Fp, rev, qh, pt, Rt, pose, R3, p3, Z3, O3, M, tx3, eh)
            evaluations += 1
            for i in range(m):
                s = 0.0
                for k in range(n):
                    s += E[i, k] * v[k]
                rhs[i] = (2.0 / GEO_H) * ((eh[i] - e[i]) / GEO_H - s)
            if damped_solve(E, lam, rhs, L, y, dq):  # dq = -a
                a2 = 0.0
                v2 = 0.0
                for k in range(n):
                    a2 += dq[k] * dq[k]
                    v2 += v[k] * v[k]
                if 2.0 * math.sqrt(a2) <= GEO_ALPHA * math.sqrt(v2):
                    for k in range(n):
                        qh[k] = q[k] + v[k] - 0.5 * dq[k]
                    into_box(qh, box, any_wrap, qn)
        cn, pos_n, rot_n = task_error(FR, Fp, rev, qn, pt, Rt, pose, R2, p2, Z2, O2, M, tx2, en)
        evaluations += 1
        if cn < c:
            creeping = GEO_SLOW * c < cn < GEO_NEAR
            q[:] = qn
            e[:] = en
            _copy_kinematics(R2, p2, Z2, O2, R, p, Z, O)
            tx[:] = tx2
            on_bound, pos, rot, c = on_bound_n, pos_n, rot_n, cn
            if pos <= tol_p and (not pose or rot <= tol_r):
                converged = True
                break
            have_E = False
            lam = max(lam * SHRINK, LAMBDA_MIN)
            history[hlen] = c
            hlen += 1
            if hlen > window and c > stall * history[hlen - 1 - window]:
                break
        else:
            lam *= GROW
            if lam > LAMBDA_MAX:
                break
    if converged and finish and c > FINISHED:
        # one more, (almost) undamped step: quadratic convergence takes ~1e-6 to ~1e-12 (kept if better)
        task_jacobian(rev, R, p, Z, O, tx, e, pose, J, A, Bm, E)
        lm_step(q, False, E, e, LAMBDA_MIN, box, any_wrap, max_step, W, L, y, dq, dfix, rhs, held, qn)
        cn, pos_n, rot_n = task_error(FR, Fp, rev, qn, pt, Rt, pose, R2, p2, Z2, O2, M, tx2, en)
        it += 1
        evaluations += 1
        if cn < c:
            q[:] = qn
            pos, rot = pos_n, rot_n
    q_out[:] = q
    return pos, rot if pose else np.nan, converged, it, evaluations


@njit(cache=True, nogil=True)
def lm_run_pairs(Q, FR, Fp, rev, box, any_wrap, P, Rts, params, Q_out, stats):
    """:func:`lm_run` on M (start, target) pairs: starts Q (M, n), target positions P (M, 3) and rotations
    Rts (M, 3, 3); end configurations to Q_out (M, n) and, per pair, (position error, orientation error,
    converged, iterations, evaluations) to the rows of stats (M, 5). For ``solve_many``."""
    for i in range(Q.shape[0]):
        pos, rot, converged, it, evaluations = lm_run(Q[i], FR, Fp, rev, box, any_wrap, P[i], Rts[i], params,
                                                      Q_out[i])
        stats[i, 0], stats[i, 1] = pos, rot
        stats[i, 2] = 1.0 if converged else 0.0
        stats[i, 3], stats[i, 4] = it, evaluations
