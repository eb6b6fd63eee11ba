"""Taking answers along the goals' self-motion: ``prefer="nearest" | "manipulability"`` (TRAC-IK's Distance and Manip1)
and preferences summed into one :class:`Criterion`, lowered in the goals' null space by :func:`refine` (projected steps
restored by LM) or the compiled :func:`descend`. Nearness is ``|q - q0|``, full-turn joints taken to their turn nearest
``q0`` inside the box (:func:`nearest_turn`)."""

from __future__ import annotations

import time
import weakref

import numpy as np
import pinocchio as pin

from ...errors import MethodError, OptionError
from ...goals.preferences import Manipulability, Posture
from ...goals.registry import TASK_ROWS
from ..lm import LevenbergMarquardt, wrapping_joints
from ..lm.nullspace import nullspace_kernel
from ..options import check_choice

__all__ = ["BRANCHES_PREFER_TIMEOUT", "DEFAULT_PREFER_TIMEOUT", "PREFER", "REFINE_COUNT", "Criterion", "Nearness",
           "bind_preferences", "check_prefer", "check_prefer_method", "default_prefer_timeout", "euler_flips",
           "flipped", "has_null_space", "make_criterion", "nearest_turn", "refine"]

#: The answers ``prefer`` picks among: the first found, the nearest q0, the most dexterous.
PREFER = ("first", "nearest", "manipulability")
#: Default budget (s) of ``prefer="nearest" | "manipulability"`` on goals with a null space (a redundant arm on a
#: pose): the work done whatever the clock says (the first batch of LM runs, the descent's trial and the best answer's
#: first round) about fills it.
DEFAULT_PREFER_TIMEOUT = 0.0004
#: The default budgets (s) on goals without a null space (a 6-joint arm on a pose), where the whole budget collects IK
#: branches (nothing to descend along): the share of answers nearest q0 grows with it; the most dexterous branch is
#: found sooner.
BRANCHES_PREFER_TIMEOUT = {"nearest": 0.0006, "manipulability": 0.00045}
#: Answers refined in the null space (best first; two closer than 1e-3 rad count once).
REFINE_COUNT = 4
#: Null-space steps of one refinement at most (the winner's; each of the best answers first gets TRIAL_STEPS); LM
#: steps restoring the goals after each.
REFINE_STEPS, TRIAL_STEPS, RESTORE_ITERATIONS = 12, 3, 10
#: Largest null-space step (rad or m, Euclidean).
MAX_REFINE_STEP = 0.5


def check_prefer(prefer, q0_given: bool = True) -> str:
    """``prefer`` checked: one of :data:`PREFER`; OptionError naming them otherwise, or for "nearest" without a q0
    (``q0_given`` False)."""
    prefer = check_choice("prefer", prefer, PREFER)
    if prefer == "nearest" and not q0_given:
        raise OptionError("prefer='nearest' picks the answer nearest q0: give q0 (the current joints)")
    return prefer


def check_prefer_method(prefer: str, method: str) -> None:
    """MethodError for ``prefer`` other than ``"first"`` with a method other than memetic: it gives one answer,
    nothing to choose among."""
    if prefer != "first" and method != "memetic":
        raise MethodError(f"prefer={prefer!r} collects answers with method 'memetic'; {method!r} gives one "
                          "(use prefer='first', the default)")


def nearest_turn(q: np.ndarray, q0: np.ndarray, lower: np.ndarray, upper: np.ndarray, wrap: np.ndarray) -> np.ndarray:
    """``q`` (n,) with each ``wrap`` joint (its range spans a full turn) moved by a multiple of 2 pi to the value
    nearest ``q0`` that stays inside [lower, upper] (the same pose: a full turn)."""
    if not wrap.any():
        return q
    two_pi = 2.0 * np.pi
    shifted = q + two_pi * np.round((q0 - q) / two_pi)
    shifted = np.where(shifted > upper, shifted - two_pi, shifted)
    shifted = np.where(shifted < lower, shifted + two_pi, shifted)
    ok = wrap & (shifted >= lower) & (shifted <= upper)
    return np.where(ok, shifted, q)


#: How close (m, rad) a frame's pose must stay under a joint-triple flip for :func:`euler_flips` to take it as exact
#: (URDFs round their angles: xArm's shoulder flip moves the tip by ~1e-5); LM meets the goals again from there.
FLIP_TOLERANCE = 1e-4
#: Configurations :func:`euler_flips` tests a flip at (fixed draws in the limits).
FLIP_TRIALS = 3
_FLIPS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def euler_flips(robot, frame: str | None) -> tuple[tuple[int, float], ...]:
    """The joint triples (i, i+1, i+2) whose flip ``(q_i + pi, m - q_{i+1}, q_{i+2} + pi)`` leaves the pose of
    ``frame`` unchanged, as (i, m) with m 0 or pi: the two Euler-angle solutions of a spherical joint group (a
    7-joint arm's shoulder), other IK branches of the same pose whose self-motion prefer="nearest" also searches
    (:func:`flipped`). Tested at :data:`FLIP_TRIALS` configurations within :data:`FLIP_TOLERANCE`, each of the three
    joints moving the frame; cached per robot and frame."""
    cache = _FLIPS.setdefault(robot, {})
    if frame in cache:
        return cache[frame]
    fid = robot.frame_id(frame)
    Q = robot.random_configurations(FLIP_TRIALS, np.random.default_rng(0))
    poses = [robot.frame_poses_unchecked(q, [fid])[0] for q in Q]
    moving = np.any(np.abs(robot.jacobian_world_unchecked(Q[0], fid)) > 1e-9, axis=0)
    flips = []
    for i in range(robot.n - 2):
        if not moving[i:i + 3].all():
            continue
        for m in (0.0, np.pi):
            moved = (robot.frame_poses_unchecked(q, [fid])[0] for q in flipped(Q, ((i, m),)))
            if not any(np.linalg.norm(F.translation - T.translation) > FLIP_TOLERANCE
                       or np.linalg.norm(pin.log3(T.rotation.T @ F.rotation)) > FLIP_TOLERANCE
                       for F, T in zip(moved, poses, strict=True)):
                flips.append((i, m))
                break
    cache[frame] = tuple(flips)
    return cache[frame]


def flipped(Q: np.ndarray, flips) -> np.ndarray:
    """Each row of ``Q`` (N, n) under each flip of ``flips`` (:func:`euler_flips`) in turn: (N x len(flips), n),
    not taken into any box."""
    out = []
    for i, m in flips:
        F = Q.copy()
        F[:, i] += np.pi
        F[:, i + 1] = m - Q[:, i + 1]
        F[:, i + 2] += np.pi
        out.append(F)
    return np.concatenate(out) if out else Q[:0]


class Nearness(Posture):
    """prefer="nearest"'s term: ``Posture(q0)`` over every joint with plain differences (answers are taken to their
    turn nearest q0 first, :func:`nearest_turn`): the same numbers without Posture's joint mask and turn wrapping."""

    def costs(self, Q):
        d = Q - self._ref
        return 0.5 * self.weight * (d * d).sum(axis=-1)

    def cost(self, q):
        return float(self.costs(q))

    def gradient(self, q):
        return self.weight * (q - self._ref)


class Criterion:
    """The sum of bound preferences (``prefer``'s term first), what answers are ranked and refined by."""

    def __init__(self, terms: list) -> None:
        self.terms = terms
        self.curvature = sum(t.curvature for t in terms)

    def __bool__(self) -> bool:
        return bool(self.terms)

    def cost(self, q: np.ndarray) -> float:
        return float(sum(t.cost(q) for t in self.terms))

    def costs(self, Q: np.ndarray) -> np.ndarray:
        """:meth:`cost` of each row of ``Q`` (N, n)."""
        return sum((t.costs(Q) for t in self.terms), np.zeros(Q.shape[0]))

    def analytic_gradient(self, q: np.ndarray) -> np.ndarray | None:
        """d cost / dq (n,) when every term has it in closed form, else None."""
        total = np.zeros(q.shape[0])
        for t in self.terms:
            g = t.gradient(q)
            if g is None:
                return None
            total += g
        return total

    def null_gradient(self, q: np.ndarray, N: np.ndarray) -> np.ndarray:
        """The cost's gradient in the null-space basis ``N`` (r, n) (orthonormal rows): analytic terms exactly,
        the others (manipulability) by forward differences along each basis vector."""
        c = np.zeros(N.shape[0])
        numeric = []
        for t in self.terms:
            g = t.gradient(q)
            if g is None:
                numeric.append(t)
            else:
                c += N @ g
        if numeric:
            h = 1e-6
            f0 = sum(t.cost(q) for t in numeric)
            for i in range(N.shape[0]):
                c[i] += (sum(t.cost(q + h * N[i]) for t in numeric) - f0) / h
        return c


def _frame_rows(problem) -> list[tuple]:
    """(frame, its task rows) of each goal."""
    return [(g.frame, TASK_ROWS.get(g.kind, range(6))) for g in problem.goals]


def has_null_space(problem) -> bool:
    """Whether the goals leave a null space to refine in: fewer task rows than joints."""
    return sum(len(rows) for _, rows in _frame_rows(problem)) < problem.robot.n


def default_prefer_timeout(problem, prefer: str) -> float:
    """The default budget (s) of ``prefer`` ("nearest" or "manipulability") for ``problem``:
    :data:`DEFAULT_PREFER_TIMEOUT` with a null space to descend along, :data:`BRANCHES_PREFER_TIMEOUT`'s without."""
    return DEFAULT_PREFER_TIMEOUT if has_null_space(problem) else BRANCHES_PREFER_TIMEOUT[prefer]


def _task_jacobian(problem, q: np.ndarray, lm: LevenbergMarquardt) -> np.ndarray:
    """The goals' stacked task Jacobian (rows, n) at ``q``, whose null space leaves every goal met to first order: on
    the compiled engine the rows LM's own step reads (right for every kind: free axes, bands, relative poses, centres
    of mass, LookAt); on the Python engine (pose, position, planar goals) the frames' base-frame rows."""
    if lm.engine == "compiled":
        stack = lm.goals
        e, E, ge = np.empty(stack.rows), np.empty((stack.rows, lm.n)), np.empty((len(stack.kinds), 2))
        nullspace_kernel()["task_rows"](np.ascontiguousarray(q, dtype=float), *lm._tree, *lm._goal_arrays, lm._pt,
                                        lm._Rt, e, E, ge)
        return E
    robot = problem.robot
    return np.vstack([robot.jacobian_world_unchecked(q, None if f is None else robot.frame_id(f))[list(rows)]
                      for f, rows in _frame_rows(problem)])


def _null_basis(E: np.ndarray) -> np.ndarray:
    """Orthonormal basis (r, n) of the null space of ``E`` (rows, n)."""
    _, s, Vt = np.linalg.svd(E)
    rank = int(np.count_nonzero(s > 1e-9 * max(s[0], 1e-300))) if s.size else 0
    return Vt[rank:]


#: Smallest pivot of the Cholesky factor of E E^T, relative to its largest, for which :func:`_null_projection` trusts
#: it (a condition number of E E^T up to 1e8); below it, the SVD.
GRAM_PIVOT = 1e-4


def _null_projection(E: np.ndarray, g: np.ndarray) -> np.ndarray:
    """``g`` (n,) projected on the null space of ``E`` (rows, n), zero rows dropped: ``g - E^T (E E^T)^-1 E g`` when
    the rows are well independent (Cholesky pivots within :data:`GRAM_PIVOT`), else by the SVD's null basis."""
    E = E[np.any(E != 0.0, axis=1)]
    if E.shape[0] == 0:
        return g
    if E.shape[0] < E.shape[1]:
        A = E @ E.T
        try:
            pivots = np.diagonal(np.linalg.cholesky(A))
            if pivots.min() > GRAM_PIVOT * pivots.max():
                return g - E.T @ np.linalg.solve(A, E @ g)
        except np.linalg.LinAlgError:  # not positive definite: dependent rows
            pass
    N = _null_basis(E)
    return N.T @ (N @ g)


def refine(problem, lm: LevenbergMarquardt, q: np.ndarray, criterion: Criterion, deadline: float | None,
           steps: int = REFINE_STEPS) -> tuple[np.ndarray, float, int]:
    """Lower ``criterion`` from an answer ``q`` (every goal met) by projected gradient steps in the goals' null space
    (scaled by the criterion's curvature, at most :data:`MAX_REFINE_STEP`), each restored by an LM run and kept only
    when it converges, the cost drops and, with a scene, it is collision-free; else halved. Returns (q, cost, LM
    evaluations)."""
    f = criterion.cost(q)
    scale, evaluations = 1.0, 0
    scene = problem.scene
    for _ in range(steps):
        if deadline is not None and time.perf_counter() >= deadline:
            break
        E = _task_jacobian(problem, q, lm)
        g = criterion.analytic_gradient(q)
        if g is not None:
            proj = _null_projection(E, g)
        else:
            N = _null_basis(E)
            if N.shape[0] == 0:
                break
            proj = N.T @ criterion.null_gradient(q, N)
        norm = float(np.linalg.norm(proj))
        if norm < 1e-12:
            break
        step = -proj / criterion.curvature if criterion.curvature > 0 else -proj * (0.2 / norm)
        length = float(np.linalg.norm(step)) * scale
        step *= scale * min(1.0, MAX_REFINE_STEP / max(length, 1e-300))
        out = lm.run(q + step, RESTORE_ITERATIONS)
        evaluations += out.evaluations
        f_new = criterion.cost(out.q) if out.converged else np.inf
        if f_new < f - 1e-15 * max(1.0, abs(f)) and (scene is None or not scene.in_collision(out.q, problem.margin)):
            q, f, scale = out.q, f_new, min(1.0, 2.0 * scale)
        else:
            scale *= 0.5
            if scale < 1e-3:
                break
    return q, f, evaluations


def make_criterion(problem, prefer: str, preferences, wrap: np.ndarray) -> Criterion:
    """prefer's term and the bound preferences. OptionError: prefer="nearest" without q0."""
    robot = problem.robot
    first_frame = problem.goals[0].frame
    terms = []
    if prefer == "nearest":
        check_prefer(prefer, problem.q0 is not None)
        # plain differences: answers are taken to their turn nearest q0 inside the box first (nearest_turn), and
        # a difference modulo 2 pi would count turns the limits forbid
        terms.append(Nearness(problem.q0).bind(robot, problem.q0, problem.lower, problem.upper, np.zeros_like(wrap)))
    elif prefer == "manipulability":
        terms.append(Manipulability(first_frame).bind(robot, problem.q0, problem.lower, problem.upper, wrap))
    for p in preferences:
        frame = (first_frame,) if isinstance(p, Manipulability) else ()
        terms.append(p.bind(robot, problem.q0, problem.lower, problem.upper, wrap, *frame))
    return Criterion(terms)


def bind_preferences(problem, preferences) -> Criterion:
    """The preferences checked against the problem's robot (errors naming the joint or frame), as a criterion."""
    return make_criterion(problem, "first", preferences, wrapping_joints(problem.robot, problem.lower, problem.upper))
