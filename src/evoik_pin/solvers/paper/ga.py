"""Genetic algorithms: paper 001's real-coded niching GA (``ga``, section 3.1: niching binary tournaments, SBX,
polynomial mutation; one solution per niche of the final population) and paper 000's binary GA (``ga-binary``,
section III-B: sign + magnitude bit strings, roulette wheel, single-point crossover, bit flips, elitism).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...errors import OptionError
from ...problem import IKProblem
from ...result import Result
from .. import register
from ..options import check_callback, check_choice, check_fraction, check_int, check_nonnegative, check_positive
from .analytic import solution_results
from .clustering import leader_rows
from .common import SolverRun, initial_population

__all__ = ["ENCODINGS", "basic_polynomial_mutation", "decode_bits", "decode_bounds", "decode_sign_magnitude",
           "niche_counts", "niching_tournament", "run_niching_ga", "sbx_pairs", "sharing_radius"]

#: ``ga-binary`` encodings: the paper's sign + magnitude in degrees, or unsigned bits over the bounds.
ENCODINGS = ("sign-magnitude", "bounds")


def sharing_radius(n: int, niches: int) -> float:
    """Paper 001 eq. 8: ``sigma_share = sqrt(n) / (2 r^(1/n))`` in the unit hypercube of n variables."""
    return float(np.sqrt(n) / (2.0 * niches ** (1.0 / n)))


def niche_counts(Z: np.ndarray, sigma: float) -> np.ndarray:
    """Paper 001 eqs. 6-7: ``nc_i = sum_j Sh(d_ij)`` (j = i included), ``Sh(d) = 1 - d / sigma`` for d < sigma,
    of normalized individuals ``Z`` (N, n)."""
    sq = np.einsum("ij,ij->i", Z, Z)
    d2 = np.maximum(sq[:, None] + sq[None, :] - 2.0 * (Z @ Z.T), 0.0)
    return np.maximum(1.0 - np.sqrt(d2) / sigma, 0.0).sum(axis=1)


def niching_tournament(cost: np.ndarray, nc: np.ndarray, niche_size: float, pairs: np.ndarray,
                       niching: bool = True) -> np.ndarray:
    """Winners (M,) of binary tournaments ``pairs`` (M, 2) under paper 001's niching rule: the lower cost when
    both niche counts are below ``niche_size`` (n*), else the smaller niche count (``niching=False``: cost
    only). Ties go to the first contestant."""
    a, b = pairs[:, 0], pairs[:, 1]
    by_cost = np.where(cost[b] < cost[a], b, a)
    if not niching:
        return by_cost
    return np.where((nc[a] < niche_size) & (nc[b] < niche_size), by_cost, np.where(nc[b] < nc[a], b, a))


def sbx_pairs(P1: np.ndarray, P2: np.ndarray, eta: float, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Paper 001 eqs. 9-10, unbounded simulated binary crossover of parents (M, n) with uniform draws ``u``
    (M, n): children ``0.5 [(p1 + p2) -+ beta |p2 - p1|]``."""
    beta = np.where(u < 0.5, (2.0 * u) ** (1.0 / (eta + 1.0)),
                    (1.0 / np.maximum(2.0 - 2.0 * u, 1e-300)) ** (1.0 / (eta + 1.0)))
    mean, half = 0.5 * (P1 + P2), 0.5 * beta * np.abs(P2 - P1)
    return mean - half, mean + half


def basic_polynomial_mutation(X: np.ndarray, lower: np.ndarray, upper: np.ndarray, eta: float, mask: np.ndarray,
                              u: np.ndarray) -> np.ndarray:
    """Paper 001 eq. 11: the basic polynomial mutation (Deb 2000) of the entries of ``X`` (N, n) where ``mask``
    is True, with uniform draws ``u`` (N, n): ``x += delta (upper - lower)``. Its spread ignores the bounds,
    unlike :func:`~.nsga2_minimizer.bounded_polynomial_mutation`."""
    delta = np.where(u < 0.5, (2.0 * u) ** (1.0 / (eta + 1.0)) - 1.0, 1.0 - (2.0 * (1.0 - u)) ** (1.0 / (eta + 1.0)))
    return np.where(mask, X + delta * (upper - lower), X)


def run_niching_ga(problem: IKProblem, rng: np.random.Generator, population: int, max_generations: int,
                   niches: int, niche_size: float | None, eta: float, crossover_probability: float,
                   niching: bool = True, archive: list | None = None, callback: Callable | None = None
                   ) -> tuple[SolverRun, np.ndarray, np.ndarray]:
    """Paper 001's real-coded GA for exactly ``max_generations`` generations (stopping at the first solution
    would cut the other families short), options as in :func:`ga` and checked here; ``archive`` (a list) receives
    ``(Q, cost)`` of every generation. Returns the run (history adds ``mutation_probability``, p_m of eq. 11, and
    ``mean_niche_count``) and the final population (N, n) with its costs (N,)."""
    population = check_int("population", population, 4)
    run = SolverRun(problem, max_generations)
    niches = check_int("niches", niches, 1)
    niche_size = check_positive("niche_size (n*)", 200.0 * population / 750.0 if niche_size is None else niche_size)
    eta = check_nonnegative("eta (SBX distribution index)", eta)
    crossover_probability = check_fraction("crossover_probability", crossover_probability)
    callback = check_callback(callback)
    n, lo, hi = problem.n, problem.lower, problem.upper
    scale = np.where(hi > lo, hi - lo, 1.0)
    sigma = sharing_radius(n, niches)
    Q, p_m, half = initial_population(problem, rng, population), 1.0 / n, (population + 1) // 2
    while True:
        ev = problem.evaluate(Q)
        nc = niche_counts(Q / scale, sigma)
        run.record(Q, ev, mutation_probability=p_m, mean_niche_count=float(nc.mean()))
        if archive is not None:
            archive.append((Q, ev.cost))
        if callback is not None:
            callback(run.generation, Q.copy())
        if run.generation >= run.max_generations:
            break
        t = run.generation
        winners = niching_tournament(ev.cost, nc, niche_size, rng.integers(0, population, (2 * half, 2)), niching)
        P1, P2 = Q[winners[:half]], Q[winners[half:]]
        C1, C2 = sbx_pairs(P1, P2, eta, rng.random(P1.shape))
        cross = (rng.random(half) < crossover_probability)[:, None]
        children = np.concatenate([np.where(cross, C1, P1), np.where(cross, C2, P2)])[:population]
        # Eq. 11 (Deb 2000): p_m grows from 1/n to 1 while eta_m = 100 + t shrinks the perturbation.
        p_m = 1.0 / n + (t / max(run.max_generations, 1)) * (1.0 - 1.0 / n)
        mask = rng.random(children.shape) < p_m
        Q = np.clip(basic_polynomial_mutation(children, lo, hi, 100.0 + t, mask, rng.random(children.shape)), lo, hi)
        run.generation += 1
    return run, Q, ev.cost


@register("ga", "paper 001: real-coded GA with SBX and niching binary tournament; the final population's "
          "niches give several IK solutions", multi_solution=True)
def ga(problem: IKProblem, rng: np.random.Generator, *, population: int = 750, max_generations: int = 12,
       niches: int = 2, niche_size: float | None = None, eta: float = 5.0, crossover_probability: float = 0.9,
       niching: bool = True, cluster_radius: float = 0.35, min_niche_fraction: float = 0.005,
       max_solutions: int = 8, callback: Callable | None = None) -> Result:
    """Paper 001's real-coded niching GA (section 3.1; defaults: its planar 2R settings, Table 1).

    Options:
        max_generations: always all run. niches: expected number of solutions r, sets sigma_share (eq. 8).
        niche_size: n*, niche-count threshold of the tournament (default 200 x population / 750).
        eta: SBX distribution index. crossover_probability: per pair of parents.
        niching: False gives a plain binary tournament.
        cluster_radius: joint-space radius (rad, wrapped) grouping the final population into solutions.
        min_niche_fraction: share of the population a cluster needs to count as a solution.
        max_solutions: at most this many niche leaders are returned, best first.
        callback: ``callback(generation, population)`` after every generation (0 = initial), a copy of the
            (N, n) population; its return value is ignored.

    Returns:
        :class:`Result` with ``q`` the best individual and ``solutions`` one Result per populated niche, best
        first (``success=False`` unless within tolerance: the GA alone is approximate; ``hga`` polishes).
    """
    min_niche_fraction = check_fraction("min_niche_fraction", min_niche_fraction)
    max_solutions = check_int("max_solutions", max_solutions)
    run, Q, cost = run_niching_ga(problem, rng, population, max_generations, niches, niche_size, eta,
                                  crossover_probability, bool(niching), callback=callback)
    leaders = leader_rows(Q, cost, cluster_radius, problem.robot.revolute,
                          min_members=max(1, int(np.ceil(min_niche_fraction * population))))[:max_solutions]
    result = run.result("ga", f"max_generations ({max_generations}) run; {len(leaders)} niche(s) found")
    result.solutions = solution_results(problem, leaders, "ga", result.generations, result.evaluations,
                                        result.time_s, only_successful=False)
    return result


def _unsigned(bits) -> np.ndarray:
    """The unsigned integers (...) of bit strings ``bits`` (..., B), most significant bit first."""
    bits = np.asarray(bits).astype(np.int64)
    return bits @ (1 << np.arange(bits.shape[-1] - 1, -1, -1, dtype=np.int64))


def decode_sign_magnitude(bits: np.ndarray) -> np.ndarray:
    """Paper 000's decoding: angles (rad) of sign + magnitude bit strings ``bits`` (..., B): ``bits[..., 0]`` the sign
    (1 = positive), the rest the magnitude, most significant first, ``theta = +-m * 180 / (2^(B-1) - 1)`` deg."""
    bits = np.asarray(bits)
    m = bits.shape[-1] - 1
    sign = np.where(bits[..., 0] == 1, 1.0, -1.0)
    return np.radians(sign * _unsigned(bits[..., 1:]) * 180.0 / (2 ** m - 1))


def decode_bounds(bits: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Unsigned bit strings ``bits`` (N, n, B), most significant first, mapped linearly onto the bounds:
    ``q = lower + k / (2^B - 1) (upper - lower)`` (rad or m)."""
    return lower + _unsigned(bits) / (2 ** np.shape(bits)[-1] - 1) * (upper - lower)


def decode_bits(chromosomes: np.ndarray, n: int, encoding: str, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Joint vectors (N, n) of chromosomes (N, n * B) under ``encoding``, clipped into the bounds."""
    bits = chromosomes.reshape(chromosomes.shape[0], n, -1)
    Q = decode_sign_magnitude(bits) if encoding == "sign-magnitude" else decode_bounds(bits, lower, upper)
    return np.clip(Q, lower, upper)


@register("ga-binary", "paper 000: binary GA (9-bit sign + magnitude angles), roulette wheel, single-point "
          "crossover, bit mutation, elitism")
def ga_binary(problem: IKProblem, rng: np.random.Generator, *, population: int = 200, elite: int = 100,
              max_generations: int = 400, bits: int = 9, encoding: str = "sign-magnitude",
              crossover_probability: float = 0.9, mutation_probability: float | None = None,
              fitness_scale: float = 0.01) -> Result:
    """Paper 000's binary GA (section III-B; defaults are its settings), stopped early when the best meets the
    tolerances. ``elite``: best chromosomes kept unchanged each generation; ``bits`` per joint; ``encoding``
    ``"sign-magnitude"`` (the paper's, revolute joints only) or ``"bounds"`` (unsigned, linear over each joint's
    bounds), decoded values clipped into the bounds; ``crossover_probability`` of single-point crossover per pair;
    ``mutation_probability`` per bit (default 1 / chromosome length); roulette fitness ``exp(-cost /
    fitness_scale)`` (0.01 m: the paper's error in cm)."""
    population = check_int("population", population, 2)
    elite = check_int("elite", elite, 0)
    if elite >= population:
        raise OptionError(f"elite must be smaller than population ({population}) so offspring are made, got {elite}")
    run = SolverRun(problem, max_generations)
    bits = check_int("bits (per joint)", bits, 2, 62)
    check_choice("encoding", encoding, ENCODINGS)
    if encoding == "sign-magnitude" and not problem.robot.revolute.all():
        raise OptionError(f"{problem.robot.name} has prismatic joints, which the sign-magnitude angle encoding "
                          "cannot represent; use encoding='bounds'")
    crossover_probability = check_fraction("crossover_probability", crossover_probability)
    n, lo, hi = problem.n, problem.lower, problem.upper
    length = n * bits
    p_bit = 1.0 / length if mutation_probability is None else check_fraction("mutation_probability",
                                                                              mutation_probability)
    fitness_scale = check_positive("fitness_scale", fitness_scale, unit="m")
    G = rng.integers(0, 2, size=(population, length), dtype=np.uint8)
    if problem.q0 is not None and encoding == "bounds":  # seed q0 as the other solvers do
        k = np.rint((np.clip(problem.q0, lo, hi) - lo) / np.where(hi > lo, hi - lo, 1.0) * (2 ** bits - 1))
        G[0] = ((k.astype(np.int64)[:, None] >> np.arange(bits - 1, -1, -1)) & 1).reshape(-1)
    Q = decode_bits(G, n, encoding, lo, hi)
    ev = problem.evaluate(Q)
    run.record(Q, ev)
    n_child = population - elite
    half = (n_child + 1) // 2
    while (reason := run.stop_reason()) is None:
        # Roulette wheel (paper: p_i = f_i / sum f): fitness relative to the best keeps exp() finite.
        fit = np.exp(-(ev.cost - ev.cost.min()) / fitness_scale)
        parents = rng.choice(population, size=2 * half, p=fit / fit.sum())
        A, B = G[parents[:half]], G[parents[half:]]
        cut = rng.integers(1, length, size=half)
        swap = (np.arange(length)[None, :] >= cut[:, None]) & (rng.random(half) < crossover_probability)[:, None]
        kids = np.concatenate([np.where(swap, B, A), np.where(swap, A, B)])[:n_child]
        kids ^= (rng.random(kids.shape) < p_bit).astype(np.uint8)
        Qk = decode_bits(kids, n, encoding, lo, hi)
        evk = problem.evaluate(Qk)
        keep = np.argsort(ev.cost, kind="stable")[:elite]
        G = np.concatenate([G[keep], kids])
        Q = np.concatenate([Q[keep], Qk])
        ev = type(ev)(*(None if a is None else np.concatenate([a[keep], b])
                        for a, b in zip((ev.cost, ev.position_error, ev.orientation_error),
                                        (evk.cost, evk.position_error, evk.orientation_error), strict=True)))
        run.generation += 1
        run.record(Q, ev)
    return run.result("ga-binary", reason)
