"""Distinct IK solutions among converged LM runs (for :mod:`.all_solutions`): classes modulo 2 pi, their
representatives, their spread. Distances are wrapped joint distances (rad, m on prismatic joints), joints whose
range spans a full turn compared modulo 2 pi.

A configuration within ``radius`` of one met joins its class; otherwise, unless already below
:data:`EXACT_ERROR`, a patient LM run refines it (near a singularity LM stops anywhere along a flat valley) and it
is matched again; one whose refinement stays above :data:`EXACT_ERROR` joins a class joined to it by a joint-space
segment within :data:`VALLEY_ERROR` of the target instead of opening its own. Exact solutions are never merged."""

from __future__ import annotations

import numpy as np

from ...problem import IKProblem
from ..lm import LevenbergMarquardt
from ..paper.clustering import joint_differences, leader_clusters

__all__ = ["EXACT_ERROR", "REFINE_ITERATIONS", "VALLEY_ERROR", "SolutionClasses", "class_representatives",
           "farthest_point_selection", "min_pairwise_distance"]

#: Steps of the refinement run of a configuration that opens a class.
REFINE_ITERATIONS = 100
#: A refined configuration whose error (m + rad) is at most this is an exact (isolated) solution.
EXACT_ERROR = 1e-10
#: Valley merge of a configuration that is not exact: largest error (m + rad) allowed at the sampled points of
#: the segment to a configuration of a class, the longest such segment (wrapped joint distance, rad), the
#: points sampled on it, and how many of the configurations met nearest are tried.
VALLEY_ERROR, VALLEY_LENGTH, VALLEY_SAMPLES, VALLEY_TRIES = 1e-3, 1.0, 7, 8


def class_representatives(Q: np.ndarray, reference: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                          wrap: np.ndarray) -> np.ndarray:
    """Each row of ``Q`` (N, n) moved, on the wrapping joints ``wrap`` (n,) bool, to the multiple of 2 pi
    inside [lower, upper] nearest to ``reference`` (n,); other joints unchanged. Same tip pose, same class."""
    Q = np.array(Q, dtype=float, ndmin=2)
    two_pi = 2.0 * np.pi
    base = lower + np.mod(Q - lower, two_pi)  # the lowest copy inside the box: [lower, lower + 2 pi)
    best = base.copy()
    for k in range(1, int(np.max(np.floor((upper - lower) / two_pi), initial=0)) + 1):
        copy = base + k * two_pi
        better = (copy <= upper) & (np.abs(copy - reference) < np.abs(best - reference))
        best = np.where(better, copy, best)
    return np.where(wrap, np.minimum(np.maximum(best, lower), upper), Q)


def _distances(Q: np.ndarray, q: np.ndarray, wrap: np.ndarray) -> np.ndarray:
    return np.linalg.norm(joint_differences(Q, q, wrap), axis=-1)


def farthest_point_selection(Q: np.ndarray, count: int, first: int, wrap: np.ndarray) -> np.ndarray:
    """Indices of ``min(count, N)`` rows of ``Q`` (N, n) spread apart: ``first``, then each time the row whose
    smallest wrapped joint distance to those already chosen is largest (greedy farthest-point selection)."""
    chosen = [int(first)]
    nearest = _distances(Q, Q[first], wrap)
    while len(chosen) < min(count, Q.shape[0]):
        k = int(nearest.argmax())
        chosen.append(k)
        nearest = np.minimum(nearest, _distances(Q, Q[k], wrap))
    return np.array(chosen, dtype=int)


def min_pairwise_distance(Q: np.ndarray, wrap: np.ndarray) -> float:
    """Smallest wrapped joint distance between two rows of ``Q`` (N, n) (inf for fewer than two rows)."""
    best = np.inf
    for i in range(Q.shape[0] - 1):
        best = min(best, float(_distances(Q[i + 1:], Q[i], wrap).min()))
    return best


class SolutionClasses:
    """Classes of distinct solutions met so far (see the module docstring).

    Attributes:
        reps: one configuration (n,) per class, the lowest-error met. errors: its error (m + rad).
        exact: whether it is an isolated solution. hits: runs that reached each class.
        evaluations: forward kinematics spent on refinements."""

    def __init__(self, problem: IKProblem, wrap: np.ndarray, radius: float, refine: LevenbergMarquardt | None
                 ) -> None:
        self.problem = problem
        self.wrap = wrap
        self.radius = radius
        self.refine = refine
        self.reps: list[np.ndarray] = []
        self.errors: list[float] = []
        self.exact: list[bool] = []
        self.hits: list[int] = []
        self.evaluations = 0
        self._known = np.empty((0, problem.n))  # every configuration matched so far, with its class
        self._label = np.empty(0, dtype=int)

    def __len__(self) -> int:
        return len(self.reps)

    def labels(self, Q: np.ndarray) -> np.ndarray:
        """Class of each row of ``Q`` (K, n): that of the nearest configuration met when within ``radius``,
        else -1."""
        if not self._label.size:
            return np.full(Q.shape[0], -1)
        d = _distances(Q[:, None, :], self._known[None], self.wrap)
        k = d.argmin(axis=1)
        return np.where(d[np.arange(Q.shape[0]), k] <= self.radius, self._label[k], -1)

    def _remember(self, q: np.ndarray, label: int) -> None:
        self._known = np.vstack([self._known, q])
        self._label = np.concatenate([self._label, np.array([label], dtype=int)])

    def _segment_error(self, a: np.ndarray, b: np.ndarray) -> float:
        """Largest error (m + rad) at VALLEY_SAMPLES interior points of the wrapped segment from a to b."""
        t = np.linspace(0.0, 1.0, VALLEY_SAMPLES + 2)[1:-1, None]
        P = a + t * joint_differences(b, a, self.wrap)
        ev = self.problem.evaluate(P, count=False)
        err = ev.position_error + (0.0 if ev.orientation_error is None else ev.orientation_error)
        return float(err.max())

    def _valley_class(self, q: np.ndarray, exact: bool) -> int:
        """A class joined to ``q`` by a low-error segment from one of the VALLEY_TRIES configurations met nearest
        to it (only where q or that class is not exact), or -1."""
        if not self._label.size:
            return -1
        d = _distances(self._known, q, self.wrap)
        tried: set[int] = set()
        for k in np.argsort(d)[:VALLEY_TRIES]:
            c = int(self._label[k])
            if d[k] > VALLEY_LENGTH:
                break
            if c in tried or (exact and self.exact[c]):
                continue
            if self._segment_error(q, self._known[k]) <= VALLEY_ERROR:
                return c
            tried.add(c)
        return -1

    def add(self, Q: np.ndarray, E: np.ndarray) -> list[int]:
        """Sort converged configurations ``Q`` (K, n), with their errors ``E`` (K,) (m + rad), into classes;
        returns the indices of the new classes."""
        new: list[int] = []
        if not Q.shape[0]:
            return new
        labels = self.labels(Q)
        for label in labels[labels >= 0]:
            self.hits[label] += 1
        # The rest (the guaranteed runs of each class, runs stopped along a flat near-singular valley), grouped around
        # leaders first so that one refinement serves a group.
        rest, rest_errors = Q[labels < 0], E[labels < 0]
        leaders, group = leader_clusters(rest, rest_errors, self.radius, self.wrap)
        sizes = np.bincount(group, minlength=leaders.size)
        for j, (q, error) in enumerate(zip(rest[leaders], rest_errors[leaders], strict=True)):
            members = int(sizes[j])
            # no refinement: every leader is a new class (leaders are radius apart)
            label = -1 if self.refine is None else int(self.labels(q[None])[0])
            if label >= 0:
                self.hits[label] += members
                continue
            raw, exact = q, self.refine is None or error <= EXACT_ERROR
            if not exact:  # most runs end near 1e-12 (LM's finishing step): nothing to refine
                out = self.refine.run(q, REFINE_ITERATIONS)
                self.evaluations += out.evaluations
                q, error = out.q, out.error
                exact = error <= EXACT_ERROR
                label = int(self.labels(q[None])[0])
            if label < 0 and self.refine is not None:
                label = self._valley_class(q, exact)
            if label < 0:
                label = len(self.reps)
                new.append(label)
                self.reps.append(q.copy())
                self.errors.append(error)
                self.exact.append(exact)
                self.hits.append(0)
            elif error < self.errors[label]:  # a better representative of a valley class
                self.reps[label], self.errors[label], self.exact[label] = q.copy(), error, exact
            if q is not raw:
                self._remember(raw, label)  # the raw run too: a run ending there is not refined again
            self._remember(q, label)
            self.hits[label] += members
        return new
