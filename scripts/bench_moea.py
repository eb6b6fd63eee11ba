"""Benchmark: our NSGA-II against pymoo's NSGA2, and paper 000's MODE variants on the AX-18.

Part 1 (peers): for each seed both libraries start from the same initial population (uniform in the box,
the first draw of ``np.random.default_rng(seed)``, which is exactly what ours draws first) and run the same
population and number of offspring generations, so the same number of evaluations, on
  * ZDT1 (30 variables): hypervolume with reference point (1.1, 1.1), i.e. 1.1 x the true front's nadir
    (1, 1) (its ideal point is (0, 0));
  * paper 003's vehicle-arm IK (target (1.5, 0.5) m, yaw 0; objectives 1/(Y+1) and S with gains
    (10, 10, 1, 1, 1) from q_prev = 0; constraints: position and yaw errors within 1e-3 m / rad; one
    function feeds both libraries, and our fronts are re-evaluated through it as a check): hypervolume of
    the feasible first front after normalizing both objectives by a common ideal and nadir point, those of
    the union of every vehicle-arm run's feasible front (all rows, all seeds), reference point 1.1.
    Our plain algorithm (``repair_steps=0``) is the like-for-like peer; our default (with the
    damped-least-squares repair, whose FK/Jacobian passes count as evaluations) is shown beside it.
  Per row: mean +- sd over the seeds, the ratio to pymoo's mean, the seeds on which ours beats pymoo (same
  seed, same initial population) and a two-sided Wilcoxon signed-rank p-value over those pairs.
Part 2: ``mode`` on paper 000's five Table 2 targets, its three configurations, several seeds: share of
runs within 1 mm, median error and time.

Run: ``python scripts/bench_moea.py`` (about 10 minutes on 2 cores) or ``--quick`` (a smoke run).
pymoo is a bench-only dependency: ``pip install -e '.[bench]'``.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

import evoik_pin
from evoik_pin import Target, load_robot
from evoik_pin.objectives import (
    ManipulabilityCost,
    PopulationKinematics,
    WeightedJointDisplacement,
    orientation_errors,
    position_errors,
)
from evoik_pin.solvers.paper.nsga2 import nsga2_minimize

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_ik import cpu_model  # noqa: E402

GAINS = np.array([10.0, 10.0, 1.0, 1.0, 1.0])
VEHICLE_TARGET = Target.planar_target(1.5, 0.5, 0.0)
VEHICLE_TOL = 1e-3
ZDT1_IDEAL, ZDT1_NADIR = np.zeros(2), np.ones(2)
TABLE2 = np.array([(10, 10, 10), (0, 7.5, 12), (2, 13, -5), (-6, 9.5, 4.3), (3, -7, 13)]) * 0.01


def zdt1(X):
    f1 = X[:, 0]
    g = 1.0 + 9.0 * X[:, 1:].mean(axis=1)
    return np.column_stack([f1, g * (1.0 - np.sqrt(f1 / g))])


def vehicle_functions(robot):
    """f(X) -> (F, G) of the vehicle-arm problem, shared by both libraries (G <= 0 feasible)."""
    objectives = [ManipulabilityCost("planar", "inverse"), WeightedJointDisplacement(np.zeros(5), GAINS)]

    def f(X):
        kin = PopulationKinematics(robot, X)
        F = np.column_stack([o(X, kin) for o in objectives])
        G = np.column_stack([position_errors(VEHICLE_TARGET, kin) - VEHICLE_TOL,
                             orientation_errors(VEHICLE_TARGET, kin) - VEHICLE_TOL])
        return F, G

    return f


def initial_population(seed, lower, upper, size):
    """The seed's shared initial population: the first draw of ``np.random.default_rng(seed)``."""
    return np.random.default_rng(seed).uniform(lower, upper, size=(size, len(lower)))


def hypervolume(F, ideal, nadir):
    """Hypervolume of F normalized by (ideal, nadir), reference point 1.1 in every objective."""
    from pymoo.indicators.hv import HV

    span = np.where(nadir > ideal, nadir - ideal, 1.0)
    Fn = (np.asarray(F, float).reshape(-1, len(ideal)) - ideal) / span
    Fn = Fn[np.all(Fn < 1.1, axis=1)]
    return float(HV(ref_point=np.full(len(ideal), 1.1))(Fn)) if len(Fn) else 0.0


def run_pymoo(f, lower, upper, n_obj, n_constr, pop, gens, seed):
    """pymoo's NSGA2 with its defaults: (feasible first front F, seconds, evaluations)."""
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.core.problem import Problem
    from pymoo.optimize import minimize

    class P(Problem):
        def __init__(self):
            super().__init__(n_var=len(lower), n_obj=n_obj, n_ieq_constr=n_constr, xl=lower, xu=upper)

        def _evaluate(self, X, out, *args, **kwargs):
            if n_constr:
                out["F"], out["G"] = f(X)
            else:
                out["F"] = f(X)

    X0 = initial_population(seed, lower, upper, pop)
    t0 = time.perf_counter()
    res = minimize(P(), NSGA2(pop_size=pop, sampling=X0), ("n_gen", gens + 1), seed=seed,
                   verbose=False)  # generation 1 = the initial population
    elapsed = time.perf_counter() - t0
    pop_F = res.pop.get("F")
    cv = res.pop.get("CV").reshape(-1) if n_constr else np.zeros(len(pop_F))
    rank = res.pop.get("rank")
    front = np.array([r == 0 for r in rank]) if rank[0] is not None else np.ones(len(pop_F), bool)
    return pop_F[front & (cv <= 0)], elapsed, res.algorithm.evaluator.n_eval


def run_ours_zdt1(pop, gens, seed):
    X0 = initial_population(seed, np.zeros(30), np.ones(30), pop)
    t0 = time.perf_counter()
    res = nsga2_minimize(zdt1, np.zeros(30), np.ones(30), 2, np.random.default_rng(seed), population=pop,
                         generations=gens, initial=X0)
    return res.F[res.front], time.perf_counter() - t0, res.evaluations


def run_ours_vehicle(robot, pop, gens, seed, repair_steps, f_check):
    # q0 is None, so nsga2's first draw from default_rng(seed) is initial_population(seed, ...) above.
    t0 = time.perf_counter()
    res = evoik_pin.solve(robot, VEHICLE_TARGET, method="nsga2", seed=seed, population=pop,
                          max_generations=gens, gains=GAINS, repair_steps=repair_steps, tolerance=VEHICLE_TOL,
                          rotation_tolerance=VEHICLE_TOL)
    elapsed = time.perf_counter() - t0
    F_check, G = f_check(res.front.q)  # the same problem as pymoo's: objectives and violation agree
    assert np.allclose(F_check, res.front.objectives, rtol=1e-12, atol=1e-12)
    assert np.allclose(np.maximum(G, 0.0).sum(axis=1), res.front.violation, rtol=1e-9, atol=1e-12)
    return res.front.objectives[res.front.violation <= 0], elapsed, res.evaluations


def table(rows, header):
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(lines)


def paired_statistics(hv, hv_base):
    """'wins/n' (ties shown apart) and a two-sided Wilcoxon signed-rank p-value of the paired seeds."""
    from scipy.stats import wilcoxon

    d = np.asarray(hv) - np.asarray(hv_base)
    wins, ties = int(np.sum(d > 0)), int(np.sum(d == 0))
    p = float(wilcoxon(d).pvalue) if np.any(d != 0) and len(d) > 1 else 1.0
    return f"{wins}/{len(d)}" + (f" ({ties} tied)" if ties else ""), f"{p:.2g}"


def peers(zdt_seeds, veh_seeds, zdt_gens, veh_gens):
    robot = load_robot("vehicle_arm")
    f_veh, lo, hi = vehicle_functions(robot), robot.lower, robot.upper
    cases = [
        ("ZDT1", "pymoo NSGA2", 100, zdt_gens, zdt_seeds,
         lambda s: run_pymoo(zdt1, np.zeros(30), np.ones(30), 2, 0, 100, zdt_gens, s)),
        ("ZDT1", "evoik nsga2_minimize", 100, zdt_gens, zdt_seeds, lambda s: run_ours_zdt1(100, zdt_gens, s)),
        ("vehicle arm", "pymoo NSGA2", 200, veh_gens, veh_seeds,
         lambda s: run_pymoo(f_veh, lo, hi, 2, 2, 200, veh_gens, s)),
        ("vehicle arm", "evoik nsga2, repair_steps=0", 200, veh_gens, veh_seeds,
         lambda s: run_ours_vehicle(robot, 200, veh_gens, s, 0, f_veh)),
        ("vehicle arm", "evoik nsga2 (default, DLS repair)", 200, veh_gens, veh_seeds,
         lambda s: run_ours_vehicle(robot, 200, veh_gens, s, 3, f_veh)),
    ]
    runs = []
    for problem, name, pop, gens, seeds, fn in cases:
        fn(seeds[0])  # warm-up, untimed (first calls, caches)
        out = [fn(s) for s in seeds]
        runs.append((problem, name, pop, gens, seeds, out))
        print(f"{problem} / {name}: {len(seeds)} seeds, {np.mean([o[1] for o in out]):.3f} s per run", flush=True)
    union = np.vstack([F for r in runs if r[0] == "vehicle arm" for F, _, _ in r[5] if len(F)])
    veh_ideal, veh_nadir = union.min(axis=0), union.max(axis=0)
    norm = {"ZDT1": (ZDT1_IDEAL, ZDT1_NADIR), "vehicle arm": (veh_ideal, veh_nadir)}
    rows, base = [], {}
    for problem, name, pop, gens, seeds, out in runs:
        hvs = np.array([hypervolume(F, *norm[problem]) for F, _, _ in out])
        times = np.array([t for _, t, _ in out])
        if name.startswith("pymoo"):
            base[problem] = hvs, times
            wins, p = "-", "-"
        else:
            wins, p = paired_statistics(hvs, base[problem][0])
        b_hv, b_t = base[problem][0].mean(), base[problem][1].mean()
        rows.append([problem, name, len(seeds), pop, gens, f"{np.mean([e for _, _, e in out]):.0f}",
                     f"{hvs.mean():.4f} +- {hvs.std():.4f}", f"{hvs.mean() / b_hv:.3f}" if b_hv > 0 else "n/a",
                     wins, p, f"{times.mean():.3f}", f"{times.mean() / b_t:.2f}",
                     f"{np.mean([len(F) for F, _, _ in out]):.1f}"])
    span = veh_nadir - veh_ideal
    print(f"vehicle arm: common ideal {np.round(veh_ideal, 4).tolist()}, nadir {np.round(veh_nadir, 4).tolist()}, "
          f"reference point {np.round(veh_nadir + 0.1 * span, 4).tolist()} in objective units")
    return table(rows, ["problem", "algorithm", "seeds", "population", "generations", "evaluations (mean)",
                        "hypervolume (mean +- sd)", "HV / pymoo", "seeds won vs pymoo", "Wilcoxon p",
                        "time s (mean)", "time / pymoo", "feasible front size"])


def mode_variants(seeds, gens):
    rows = []
    for variant in ("fixed", "binomial", "binomial-trigonometric"):
        errs, times = [], []
        for s in seeds:
            for t in TABLE2:
                r = evoik_pin.solve("ax18", t, method="mode", seed=s, variant=variant, max_generations=gens)
                errs.append(r.position_error)
                times.append(r.time_s)
        errs = np.array(errs)
        rows.append([variant, len(errs), f"{np.mean(errs < 1e-3):.0%}", f"{np.median(errs) * 1e3:.3f}",
                     f"{errs.max() * 1e3:.3f}", f"{np.mean(times):.3f}"])
        print(rows[-1], flush=True)
    return table(rows, ["mode variant", "runs", "within 1 mm", "median error mm", "max error mm", "time s / run"])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="2 seeds, short runs (smoke test)")
    ap.add_argument("--zdt-seeds", type=int, default=20, help="ZDT1 seeds 0..N-1 (20)")
    ap.add_argument("--vehicle-seeds", type=int, default=100, help="vehicle-arm seeds 0..N-1 (100: its spread is wide)")
    args = ap.parse_args()
    zdt_seeds = list(range(2 if args.quick else args.zdt_seeds))
    veh_seeds = list(range(2 if args.quick else args.vehicle_seeds))
    zdt_gens, veh_gens, mode_gens = (40, 10, 40) if args.quick else (250, 100, 200)
    cpu = cpu_model()
    import pymoo

    print(f"machine: {cpu}, {os.cpu_count()} cores; Python {platform.python_version()}, numpy {np.__version__}, "
          f"pymoo {pymoo.__version__}")
    print(peers(zdt_seeds, veh_seeds, zdt_gens, veh_gens))
    print(mode_variants([0] if args.quick else [0, 1, 2], mode_gens))


if __name__ == "__main__":
    main()
