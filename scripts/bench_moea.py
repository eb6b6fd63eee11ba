"""Benchmark: our NSGA-II against pymoo's NSGA2, and paper 000's MODE variants on the AX-18.

Part 1 (peers): same population, generations and seeds for both libraries, on
  * ZDT1 (30 variables), hypervolume with reference point (1.1, 1.1);
  * paper 003's vehicle-arm IK (target (1.5, 0.5) m, yaw 0; objectives 1/(Y+1) and S with gains
    (10, 10, 1, 1, 1); constraint: position and yaw errors within 1e-3 m / rad), hypervolume of the
    feasible first front with reference point (1.0, 10.0). Our plain algorithm (``repair_steps=0``) is
    the like-for-like peer; our default (with the damped-least-squares repair) is shown beside it.
Part 2: ``mode`` on paper 000's five Table 2 targets, its three configurations, several seeds: share of
runs within 1 mm, median error and time.

Run: ``python scripts/bench_moea.py`` (about 3 minutes on 2 cores) or ``--quick`` (a smoke run).
pymoo is a bench-only dependency: ``pip install -e '.[bench]'``.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

import evoik_pin
from evoik_pin import Target, load_robot
from evoik_pin.objectives import (
    Manipulability,
    PopulationKinematics,
    WeightedJointDisplacement,
    orientation_errors,
    position_errors,
)
from evoik_pin.solvers.nsga2 import nsga2_minimize

GAINS = np.array([10.0, 10.0, 1.0, 1.0, 1.0])
VEHICLE_TARGET = Target.planar_target(1.5, 0.5, 0.0)
VEHICLE_TOL = 1e-3
ZDT1_REF = np.array([1.1, 1.1])
VEHICLE_REF = np.array([1.0, 10.0])
TABLE2 = np.array([(10, 10, 10), (0, 7.5, 12), (2, 13, -5), (-6, 9.5, 4.3), (3, -7, 13)]) * 0.01


def zdt1(X):
    f1 = X[:, 0]
    g = 1.0 + 9.0 * X[:, 1:].mean(axis=1)
    return np.column_stack([f1, g * (1.0 - np.sqrt(f1 / g))])


def vehicle_functions():
    """(f(X) -> (F, CV), lower, upper) of the vehicle-arm problem, shared by both libraries."""
    robot = load_robot("vehicle_arm")
    objectives = [Manipulability("planar", "inverse"), WeightedJointDisplacement(np.zeros(5), GAINS)]

    def f(X):
        kin = PopulationKinematics(robot, X)
        F = np.column_stack([o(X, kin) for o in objectives])
        G = np.column_stack([position_errors(VEHICLE_TARGET, kin) - VEHICLE_TOL,
                             orientation_errors(VEHICLE_TARGET, kin) - VEHICLE_TOL])
        return F, G

    return f, robot.lower, robot.upper


def hypervolume(F, ref):
    from pymoo.indicators.hv import HV

    F = F[np.all(F < ref, axis=1)]
    return float(HV(ref_point=ref)(F)) if len(F) else 0.0


def run_pymoo(f, lower, upper, n_obj, n_constr, pop, gens, seed):
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

    t0 = time.perf_counter()
    res = minimize(P(), NSGA2(pop_size=pop), ("n_gen", gens + 1), seed=seed, verbose=False)  # gen 1 = initial
    elapsed = time.perf_counter() - t0
    pop_F = res.pop.get("F")
    cv = res.pop.get("CV").reshape(-1) if n_constr else np.zeros(len(pop_F))
    front = res.pop.get("rank") == 0 if res.pop.get("rank")[0] is not None else np.ones(len(pop_F), bool)
    keep = front & (cv <= 0)
    return pop_F[keep], elapsed


def run_ours_zdt1(pop, gens, seed):
    t0 = time.perf_counter()
    res = nsga2_minimize(zdt1, np.zeros(30), np.ones(30), 2, np.random.default_rng(seed), population=pop,
                         generations=gens)
    return res.F[res.front], time.perf_counter() - t0


def run_ours_vehicle(pop, gens, seed, repair_steps):
    res = evoik_pin.solve("vehicle_arm", VEHICLE_TARGET, method="nsga2", seed=seed, population=pop,
                          max_generations=gens, gains=GAINS, repair_steps=repair_steps, tolerance=VEHICLE_TOL,
                          rotation_tolerance=VEHICLE_TOL)
    F = res.front.objectives[res.front.violation <= 0]
    return F, res.time_s


def table(rows, header):
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(lines)


def peers(seeds, zdt_gens, veh_gens):
    rows = []
    f_veh, lo, hi = vehicle_functions()

    def pymoo_vehicle(X):
        F, G = f_veh(X)
        return F, G

    cases = [
        ("ZDT1", "pymoo NSGA2", 100, zdt_gens, lambda s: run_pymoo(zdt1, np.zeros(30), np.ones(30), 2, 0, 100,
                                                                    zdt_gens, s), ZDT1_REF),
        ("ZDT1", "evoik nsga2_minimize", 100, zdt_gens, lambda s: run_ours_zdt1(100, zdt_gens, s), ZDT1_REF),
        ("vehicle arm", "pymoo NSGA2", 200, veh_gens, lambda s: run_pymoo(pymoo_vehicle, lo, hi, 2, 2, 200,
                                                                          veh_gens, s), VEHICLE_REF),
        ("vehicle arm", "evoik nsga2, repair_steps=0", 200, veh_gens, lambda s: run_ours_vehicle(200, veh_gens, s, 0),
         VEHICLE_REF),
        ("vehicle arm", "evoik nsga2 (default, DLS repair)", 200, veh_gens,
         lambda s: run_ours_vehicle(200, veh_gens, s, 3), VEHICLE_REF),
    ]
    base = {}
    for problem, name, pop, gens, fn, ref in cases:
        hvs, times, sizes = [], [], []
        for s in seeds:
            F, t = fn(s)
            hvs.append(hypervolume(F, ref))
            times.append(t)
            sizes.append(len(F))
        key = problem
        if name.startswith("pymoo"):
            base[key] = (np.mean(hvs), np.mean(times))
        b_hv, b_t = base[key]
        rows.append([problem, name, pop, gens, f"{np.mean(hvs):.4f} +- {np.std(hvs):.4f}",
                     f"{np.mean(hvs) / b_hv:.3f}" if b_hv > 0 else "n/a", f"{np.mean(times):.3f}",
                     f"{np.mean(times) / b_t:.2f}", f"{np.mean(sizes):.0f}"])
        print(rows[-1], flush=True)
    return table(rows, ["problem", "algorithm", "population", "generations", "hypervolume (mean +- sd)",
                        "HV / pymoo", "time s (mean)", "time / pymoo", "feasible front size"])


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
    args = ap.parse_args()
    seeds = [0, 1] if args.quick else [0, 1, 2, 3, 4]
    zdt_gens, veh_gens, mode_gens = (40, 10, 40) if args.quick else (250, 100, 200)
    cpu = next((line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if "model name" in line),
               platform.processor()) if os.path.exists("/proc/cpuinfo") else platform.processor()
    print(f"machine: {cpu}, {os.cpu_count()} cores; Python {platform.python_version()}, numpy {np.__version__}")
    print(peers(seeds, zdt_gens, veh_gens))
    print(mode_variants(seeds[:3] if not args.quick else seeds[:1], mode_gens))


if __name__ == "__main__":
    main()
