"""Closed-form IK of the papers' small arms (m, rad), as references and as the ``algebraic`` method (the bundled
robots only, their kinematics checked; of goal lists one tip ``Pose`` or ``Position``, :func:`tip_target_problem`):
paper 001's planar 2R (:func:`planar2r_ik`) and PUMA wrist point (:func:`puma_ik`), paper 000's AX-18 for a tool
pitch (:func:`ax18_ik`) and its "algebraic method" searching the pitch (:func:`ax18_algebraic`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ... import lie
from ...errors import MethodError, TargetError
from ...problem import IKProblem
from ...result import Result
from .. import register
from ..options import check_positive
from .clustering import leader_rows
from .common import SolverRun

__all__ = ["AX18", "PLANAR2R", "PUMA3R", "AX18Solution", "ax18_algebraic", "ax18_fk", "ax18_ik", "planar2r_fk",
           "planar2r_ik", "puma_fk", "puma_ik", "solution_results", "tip_target_problem"]

_CM = 0.01
#: Paper 000, Table 1 (m): d1, a1, a2, a3, d2, a4 of the Crustcrawler AX-18.
AX18 = {"d1": 4.36 * _CM, "a1": 6.75 * _CM, "a2": 17.23 * _CM, "a3": 6.3 * _CM, "d2": 2.0 * _CM, "a4": 11.7 * _CM}
#: Paper 000's AX-18 joint limits (rad): t1 [-150, 150] deg, t2 [-60, 240], t3, t4 [-150, 150].
AX18_LIMITS = (np.radians([-150.0, -60.0, -150.0, -150.0]), np.radians([150.0, 240.0, 150.0, 150.0]))
#: Paper 001's planar 2R link lengths (m).
PLANAR2R = {"a1": 25 * _CM, "a2": 16 * _CM}
#: Paper 001's PUMA positioning-chain lengths (m), eq. 20 (a3 = 2.03 cm as in its Table 2).
PUMA3R = {"a2": 43.18 * _CM, "d": 14.90 * _CM, "a3": 2.03 * _CM, "d4": 43.30 * _CM}

_SAME = 1e-9  # rad: closed-form branches closer than this are one solution (singular configurations)


def _distinct(candidates: list[np.ndarray]) -> list[np.ndarray]:
    out: list[np.ndarray] = []
    for q in candidates:
        if all(np.abs(lie.wrap_angle(q - p)).max() > _SAME for p in out):
            out.append(q)
    return out


def _snap(c: float) -> float:
    """``c`` clipped into [-1, 1] and snapped onto +-1 within 1e-12 (one boundary solution, not two 1e-8 rad apart)."""
    c = float(np.clip(c, -1.0, 1.0))
    return float(np.sign(c)) if abs(c) > 1.0 - 1e-12 else c


def _point(p, size: int, name: str) -> np.ndarray:
    arr = np.asarray(p, dtype=float).reshape(-1)
    if arr.shape != (size,) or not np.all(np.isfinite(arr)):
        raise TargetError(f"{name} needs a finite position of {size} numbers (m), got {p!r}")
    return arr


def planar2r_fk(Q, a1: float = PLANAR2R["a1"], a2: float = PLANAR2R["a2"]) -> np.ndarray:
    """Paper 001 eqs. 16-17: tip (x, y) in m of joint vectors ``Q`` (..., 2) in rad, shape (..., 2)."""
    Q = np.asarray(Q, float)
    t1, t12 = Q[..., 0], Q[..., 0] + Q[..., 1]
    return np.stack([a1 * np.cos(t1) + a2 * np.cos(t12), a1 * np.sin(t1) + a2 * np.sin(t12)], axis=-1)


def _planar2r_candidates(x: float, y: float, a1: float, a2: float, clamp: bool) -> tuple[list[np.ndarray], bool]:
    c2 = (x * x + y * y - a1 * a1 - a2 * a2) / (2 * a1 * a2)
    exact = abs(c2) <= 1.0 + 1e-12
    if not exact and not clamp:
        return [], False
    c2 = _snap(c2)
    out = []
    for sign in (1.0, -1.0):
        s2 = sign * np.sqrt(max(0.0, 1.0 - c2 * c2))
        t2 = np.arctan2(s2, c2)
        t1 = np.arctan2(y, x) - np.arctan2(a2 * s2, a1 + a2 * c2)
        out.append(lie.wrap_angle([t1, t2]))
    return _distinct(out), exact


def planar2r_ik(x: float, y: float, a1: float = PLANAR2R["a1"], a2: float = PLANAR2R["a2"]) -> list[np.ndarray]:
    """The IK solutions (t1, t2) in rad, wrapped into [-pi, pi), of the planar 2R arm for tip (x, y) m: elbow
    ``t2 > 0`` first; one on the workspace boundary, none outside it."""
    x, y = _point([x, y], 2, "planar2r_ik")
    return _planar2r_candidates(x, y, a1, a2, clamp=False)[0]


def puma_fk(Q, a2: float = PUMA3R["a2"], d: float = PUMA3R["d"], a3: float = PUMA3R["a3"],
            d4: float = PUMA3R["d4"]) -> np.ndarray:
    """Paper 001 eq. 20: PUMA wrist point (..., 3) in m of joint vectors ``Q`` (..., 3) in rad."""
    Q = np.asarray(Q, float)
    t1, t2, t23 = Q[..., 0], Q[..., 1], Q[..., 1] + Q[..., 2]
    reach = np.sin(t23) * d4 + a3 * np.cos(t23) + a2 * np.cos(t2)
    return np.stack([np.cos(t1) * reach - d * np.sin(t1), np.sin(t1) * reach + d * np.cos(t1),
                     d4 * np.cos(t23) - a3 * np.sin(t23) - a2 * np.sin(t2)], axis=-1)


def _puma_candidates(p: np.ndarray, a2: float, d: float, a3: float, d4: float,
                     clamp: bool) -> tuple[list[np.ndarray], bool]:
    px, py, pz = p
    # px^2 + py^2 = r^2 + d^2 with r = S23 d4 + a3 C23 + a2 C2 (the in-plane reach, either sign).
    r2 = px * px + py * py - d * d
    # r^2 + pz^2 = a2^2 + a3^2 + d4^2 + 2 a2 (d4 S3 + a3 C3) = ... + 2 a2 rho sin(t3 + gamma).
    rho, gamma = np.hypot(a3, d4), np.arctan2(a3, d4)
    exact = r2 >= -1e-15
    out = []
    for r in (np.sqrt(max(r2, 0.0)), -np.sqrt(max(r2, 0.0))):
        t1 = np.arctan2(py, px) - np.arctan2(d, r)
        k = (r * r + pz * pz - a2 * a2 - a3 * a3 - d4 * d4) / (2 * a2 * rho)
        ok = abs(k) <= 1.0 + 1e-12
        exact = exact and ok
        if not ok and not clamp:
            continue
        k = _snap(k)
        for t3_plus_gamma in (np.arcsin(k), np.pi - np.arcsin(k)):
            t3 = t3_plus_gamma - gamma
            s3, c3 = np.sin(t3), np.cos(t3)
            # r = u C2 + v S2 and pz = v C2 - u S2 with u = a2 + d4 S3 + a3 C3, v = d4 C3 - a3 S3.
            u, v = a2 + d4 * s3 + a3 * c3, d4 * c3 - a3 * s3
            t2 = np.arctan2(v * r - u * pz, u * r + v * pz)
            out.append(lie.wrap_angle([t1, t2, t3]))
    if not exact and not clamp:
        return [], False
    return _distinct(out), bool(exact)


def puma_ik(p, a2: float = PUMA3R["a2"], d: float = PUMA3R["d"], a3: float = PUMA3R["a3"],
            d4: float = PUMA3R["d4"]) -> list[np.ndarray]:
    """All IK solutions (t1, t2, t3) in rad, wrapped into [-pi, pi), of paper 001's PUMA wrist point ``p`` (3,) m:
    up to four (two shoulders x two elbows), none out of reach."""
    return _puma_candidates(_point(p, 3, "puma_ik"), a2, d, a3, d4, clamp=False)[0]


def ax18_fk(Q, d1: float = AX18["d1"], a1: float = AX18["a1"], a2: float = AX18["a2"], a3: float = AX18["a3"],
            d2: float = AX18["d2"], a4: float = AX18["a4"]) -> np.ndarray:
    """Paper 000, section III-A: AX-18 tool position (..., 3) in m of joint vectors ``Q`` (..., 4) in rad."""
    Q = np.asarray(Q, float)
    t1, t2 = Q[..., 0], Q[..., 1]
    t23, phi = t2 + Q[..., 2], t2 + Q[..., 2] + Q[..., 3]
    r = (a3 + a4) * np.cos(phi) + d2 * np.sin(phi) + a1 * np.cos(t2) + a2 * np.cos(t23)
    z = d1 + a1 * np.sin(t2) + a2 * np.sin(t23) + (a3 + a4) * np.sin(phi) - d2 * np.cos(phi)
    return np.stack([np.cos(t1) * r, np.sin(t1) * r, z], axis=-1)


def _ax18_branches(p: np.ndarray, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form candidates (4, G, 4) for tool pitches ``phi`` (G,): shoulder (front, back: the branch the
    paper's atan leaves out) x elbow (+, -), cos t3 clamped into [-1, 1], and a (4, G) mask of the exact ones."""
    d1, a1, a2, a3, d2, a4 = (AX18[k] for k in ("d1", "a1", "a2", "a3", "d2", "a4"))
    px, py, pz = p
    rho = np.hypot(px, py)
    cphi, sphi = np.cos(phi), np.sin(phi)
    C = pz - d1 - (a3 + a4) * sphi + d2 * cphi
    out, exact = [], []
    for t1, r in ((np.arctan2(py, px), rho), (np.arctan2(py, px) + np.pi, -rho)):
        B = r - (a3 + a4) * cphi - d2 * sphi
        c3 = (B * B + C * C - a1 * a1 - a2 * a2) / (2 * a1 * a2)
        ok = np.abs(c3) <= 1.0 + 1e-12
        c3 = np.clip(c3, -1.0, 1.0)
        for sign in (1.0, -1.0):
            t3 = sign * np.arccos(c3)
            t2 = np.arctan2(C, B) - np.arctan2(a2 * np.sin(t3), a1 + a2 * np.cos(t3))
            t4 = phi - t2 - t3
            out.append(np.stack([np.full_like(phi, t1), t2, t3, t4], axis=-1))
            exact.append(ok)
    return np.array(out), np.array(exact)


def ax18_ik(p, phi: float) -> list[np.ndarray]:
    """Exact AX-18 solutions (rad, wrapped into [-pi, pi), joint limits not applied) for tool position ``p`` (m)
    and pitch ``phi`` (rad): up to four, none when out of reach."""
    p = _point(p, 3, "ax18_ik")
    Q, ok = _ax18_branches(p, np.array([float(phi)]))
    return _distinct([lie.wrap_angle(Q[b, 0]) for b in range(4) if ok[b, 0]])


@dataclass(frozen=True)
class AX18Solution:
    """Result of :func:`ax18_algebraic`: joint vector ``q`` (4,) rad, pitch ``phi`` rad, error (m)."""

    q: np.ndarray
    phi: float
    position_error: float
    branch: int


def _into_limits(Q: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Each angle moved by a multiple of 2 pi into [lower, lower + 2 pi), then clamped onto the limits."""
    return np.clip(lower + np.mod(Q - lower, 2 * np.pi), lower, upper)


def ax18_algebraic(p, q0=None, phi_step: float = np.radians(0.5), lower=None, upper=None,
                   fk=ax18_fk) -> list[AX18Solution]:
    """Paper 000's algebraic method for tool position ``p`` (3,) m: the tool pitch phi of least position error.

    Every branch of :func:`ax18_ik` (clamped to its reach, joints moved into ``lower``, ``upper``: default the
    servo ranges) on a phi grid of step ``phi_step`` (rad), the best refined within one step; ties in error go
    to the least maximum displacement from ``q0`` (default zeros). ``fk``: vectorized ``(N, 4) -> (N, 3)``.
    Returns one :class:`AX18Solution` per branch, least error first.
    """
    p = _point(p, 3, "ax18_algebraic")
    phi_step = check_positive("phi_step (at most pi/4)", phi_step, np.pi / 4, unit="rad")
    lower = AX18_LIMITS[0] if lower is None else np.asarray(lower, float)
    upper = AX18_LIMITS[1] if upper is None else np.asarray(upper, float)
    q0 = np.zeros(4) if q0 is None else np.asarray(q0, float)

    def branch_q(phi: float, b: int) -> np.ndarray:
        return _into_limits(_ax18_branches(p, np.array([phi]))[0][b, 0], lower, upper)

    phis = np.arange(-np.pi, np.pi, phi_step)
    Q = _into_limits(_ax18_branches(p, phis)[0], lower, upper).reshape(-1, 4)
    err = np.linalg.norm(fk(Q) - p, axis=-1).reshape(4, -1)
    disp = np.abs(Q - q0).max(axis=-1).reshape(4, -1)
    out = []
    for b in range(4):
        # Least error first; among errors equal to 1e-12 m, least displacement.
        g = int(np.argmin(np.round(err[b] / 1e-12) * 1e3 + disp[b] / (2 * np.pi)))
        phi = float(phis[g])
        if err[b, g] > 1e-12:
            from scipy.optimize import minimize_scalar  # lazy: scipy.optimize is slow to import

            ref = minimize_scalar(lambda x, b=b: float(np.linalg.norm(fk(branch_q(x, b)[None])[0] - p)),
                                  bounds=(phi - phi_step, phi + phi_step), method="bounded", options={"xatol": 1e-10})
            if ref.fun < err[b, g]:
                phi = float(ref.x)
        q = branch_q(phi, b)
        out.append(AX18Solution(q=q, phi=phi, position_error=float(np.linalg.norm(fk(q[None])[0] - p)), branch=b))
    out.sort(key=lambda s: (round(s.position_error / 1e-12), float(np.abs(s.q - q0).max())))
    return out


#: Fixed joint vectors (rad) at which a loaded chain must match the closed form (to 1e-9 m) to be recognized.
_PROBES = np.array([[0.3, -0.7, 1.1, -0.4], [-1.2, 0.5, -0.2, 2.0], [2.5, 1.9, -2.2, 0.6]])


def _closed_form_for(robot):
    """The closed form matching ``robot`` (name and kinematics), or a MethodError."""
    forms = {"planar2r": (2, lambda Q: np.concatenate([planar2r_fk(Q), np.zeros(Q.shape[:-1] + (1,))], -1)),
             "puma3r": (3, puma_fk), "ax18": (4, ax18_fk)}
    if robot.name not in forms:
        raise MethodError(f"method 'algebraic' has closed forms for the bundled robots {', '.join(forms)} only, not "
                          f"for {robot.name!r}; use an evolutionary method (see evoik_pin.methods())")
    n, fk = forms[robot.name]
    if robot.n != n:
        raise MethodError(f"method 'algebraic': robot {robot.name!r} has {robot.n} joints, its closed form {n}")
    probes = _PROBES[:, :n]
    mismatch = np.abs(robot.positions_batch(probes) - fk(probes)).max()
    if mismatch > 1e-9:
        raise MethodError(
            f"method 'algebraic': the loaded {robot.name!r} chain (tip {robot.tip!r}) does not match the paper's "
            f"closed form (forward kinematics differ by {mismatch:.3g} m); load the bundled robot unchanged"
        )
    return robot.name


def solution_results(problem: IKProblem, Q: np.ndarray, method: str, generations: int, evaluations: int,
                     time_s: float, only_successful: bool = True) -> list[Result]:
    """One :class:`Result` per row of ``Q`` (M, n), best first (the errors' evaluation is not counted); with
    ``only_successful``, rows that miss the tolerances (a goal list: a goal's own) are left out."""
    if len(Q) == 0:
        return []
    Q = np.atleast_2d(np.asarray(Q, float))
    ev = problem.evaluate(Q, count=False)
    ok = problem.rows_met(Q)
    return [Result(q=Q[i].copy(), position_error=float(ev.position_error[i]),
                   orientation_error=None if ev.orientation_error is None else float(ev.orientation_error[i]),
                   cost=float(ev.cost[i]), success=bool(ok[i]), generations=generations, evaluations=evaluations,
                   time_s=time_s, message="distinct IK solution", method=method,
                   goal_errors=None if problem.target is not None else problem.goal_errors(Q[i]))
            for i in np.argsort(ev.cost, kind="stable") if ok[i] or not only_successful]


def tip_target_problem(problem: IKProblem) -> IKProblem | None:
    """The one-target problem a goal list stands for when it is one Pose or Position goal on the robot's tip (the
    closed forms' problem: the goal's target, tolerances and the problem's box), else None."""
    from dataclasses import replace

    from ...goals import Pose, Position
    from ...target import Target

    goals, robot = problem.goals, problem.robot
    if len(goals) != 1 or type(goals[0]) not in (Pose, Position):
        return None
    if robot.frame_id(goals[0].frame) != robot.frame_id(None):  # a goal on another frame than the tip
        return None
    goal = goals[0]
    pt, Rt = goal.encode()
    return replace(problem, target=Target(pt, Rt if goal.has_orientation else None), goals=None,
                   tolerance=goal.tolerance, rotation_tolerance=goal.rotation_tolerance, evaluations=0)


@register("algebraic", "closed-form IK: paper 000's algebraic method (ax18, phi search), planar2r (both "
          "elbows) and the puma3r wrist point (four solutions)", multi_solution=True)
def algebraic(problem: IKProblem, rng: np.random.Generator, *, phi_step: float = np.radians(0.5)) -> Result:
    """Closed-form IK of ``planar2r``, ``puma3r`` (every solution) and ``ax18`` (paper 000's AM, ``phi_step`` rad);
    ``rng`` is unused. Returns ``q`` the best candidate (an unreachable target: the clamped closed form,
    ``success=False``) and ``solutions`` every distinct exact one inside the bounds (moved by multiples of
    2 pi), best first, ties in cost broken by the least maximum displacement from ``q0``.
    """
    robot = problem.robot
    name = _closed_form_for(robot)
    run = SolverRun(problem, 0)
    t = problem.target
    if t.planar and name != "planar2r":
        raise TargetError(f"a planar target applies to planar arms; {name} needs a 3-D position (m)")
    p = np.array([t.position[0], t.position[1], 0.0]) if t.planar else t.position
    if name == "planar2r":
        cands, exact = _planar2r_candidates(p[0], p[1], **PLANAR2R, clamp=True)
        exact = exact and not abs(p[2]) > 0
    elif name == "puma3r":
        cands, exact = _puma_candidates(p, **PUMA3R, clamp=True)
    else:
        def counted_fk(Q):
            problem.evaluations += Q.shape[0]  # the phi search's forward kinematics are evaluations too
            return robot.positions_batch(Q)

        sols = ax18_algebraic(p, q0=problem.q0, phi_step=phi_step, lower=problem.lower, upper=problem.upper,
                              fk=counted_fk)
        cands, exact = [s.q for s in sols], sols[0].position_error <= problem.tolerance
    Q = np.array(cands)
    lo, hi = problem.lower, problem.upper
    Q = np.where(robot.revolute, lo + np.mod(Q - lo, 2 * np.pi), Q)
    inside = np.all((Q >= lo - 1e-12) & (Q <= hi + 1e-12), axis=1)
    ev = problem.evaluate(np.clip(Q, lo, hi))
    q0 = np.zeros(robot.n) if problem.q0 is None else problem.q0
    disp = np.abs(Q - q0).max(axis=1)
    order = np.lexsort((disp, np.round(ev.cost / 1e-12), ~inside))
    best = order[0]
    run.offer(np.clip(Q[best], lo, hi), ev, best)
    keep = Q[order][inside[order]]
    keep = leader_rows(keep, np.arange(len(keep), dtype=float), 1e-6, robot.revolute)  # order kept: cost = index
    solutions = solution_results(problem, keep, "algebraic", 0, problem.evaluations, 0.0) if exact else []
    if exact and solutions:
        message = f"closed form: {len(solutions)} solution(s) inside the bounds"
    elif exact:
        message = "closed form: every exact solution lies outside the search bounds"
    else:
        message = f"target out of reach of {name}: no exact closed-form solution (nearest approximation returned)"
    result = run.result("algebraic", message, solutions=solutions)
    for s in solutions:
        s.time_s = result.time_s
    return result

