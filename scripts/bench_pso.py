"""Benchmark: paper 002's PSO on 6-D pose targets of aerial6r and on position targets, by pose metric and r draws.

Part 1 (poses): random reachable poses of ``aerial6r`` (FK of uniform in-limit configurations; target k from
``np.random.default_rng(1000 + k)``, solver seed 6000 + k), tolerance 1e-6 m and 1e-6 rad, PSO defaults
(30 particles, 600 iterations, inertia 0.9 -> 0.4, c1 = c2 = 1.5, up to 10 runs) and each combination of
``pose_metric`` (``sum``: m + 1 m/rad x rad; ``euclidean``: the norm of the two) and ``random_factors``
(``per-coordinate``: r1, r2 per particle and joint; ``per-particle``: one each per particle), plus two
settings of the reliable combination. Part 2 (positions): paper 002's Scenario 2 style, random reachable
points of ``redundant7r`` and ``ax18`` solved from q = 0 to 1e-10 m (up to 4 runs), by ``random_factors``.

Run: ``python scripts/bench_pso.py`` (about 4 minutes on 2 cores) or ``--quick`` (a smoke run). Prints
markdown tables; ``--json PATH`` writes the same numbers.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time

import numpy as np

import evoik_pin as ek

POSE_CONFIGS = [
    ("sum", "per-coordinate", {}),
    ("euclidean", "per-coordinate", {}),
    ("sum", "per-particle", {}),
    ("euclidean", "per-particle", {}),
    ("euclidean", "per-particle", {"population": 40}),
    ("euclidean", "per-particle", {"orientation_weight": 0.2}),
]


def pose_rows(n: int) -> list[dict]:
    robot = ek.load_robot("aerial6r")
    targets = [robot.fk(robot.random_configurations(1, np.random.default_rng(1000 + k))[0]) for k in range(n)]
    rows = []
    for metric, factors, extra in POSE_CONFIGS:
        results = []
        for k, target in enumerate(targets):
            results.append(ek.solve(robot, target, method="pso", seed=6000 + k, tolerance=1e-6, pose_metric=metric,
                                    random_factors=factors, **extra))
        rows.append({
            "pose_metric": metric, "random_factors": factors, "options": extra, "n": n,
            "reached": sum(r.success for r in results),
            "mean_evaluations": float(np.mean([r.evaluations for r in results])),
            "mean_time_s": float(np.mean([r.time_s for r in results])),
            "median_pos_err_missed": float(np.median([r.position_error for r in results if not r.success]))
            if not all(r.success for r in results) else None,
        })
        print(f"  {metric:9s} {factors:14s} {extra}: {rows[-1]['reached']}/{n}", flush=True)
    return rows


def position_rows(n: int) -> list[dict]:
    rows = []
    for name in ("redundant7r", "ax18"):
        robot = ek.load_robot(name)
        Q = robot.random_configurations(n, np.random.default_rng(2026))
        for factors in ("per-coordinate", "per-particle"):
            results = [ek.solve(robot, robot.fk(q).translation, method="pso", seed=i, tolerance=1e-10,
                                q0=np.zeros(robot.n), random_factors=factors, runs=4) for i, q in enumerate(Q)]
            rows.append({
                "robot": name, "random_factors": factors, "n": n, "reached": sum(r.success for r in results),
                "mean_evaluations": float(np.mean([r.evaluations for r in results])),
                "mean_time_s": float(np.mean([r.time_s for r in results])),
            })
            print(f"  {name} {factors}: {rows[-1]['reached']}/{n}", flush=True)
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--poses", type=int, default=40, help="number of aerial6r pose targets (default 40)")
    parser.add_argument("--points", type=int, default=40, help="position targets per robot (default 40)")
    parser.add_argument("--quick", action="store_true", help="3 poses and 3 points (smoke run)")
    parser.add_argument("--json", metavar="PATH", help="write the rows as JSON")
    args = parser.parse_args(argv)
    if args.quick:
        args.poses, args.points = 3, 3
    t0 = time.perf_counter()
    print(f"# PSO benchmark, {time.strftime('%Y-%m-%d')}, {platform.machine()} x {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, numpy {np.__version__}", flush=True)
    poses = pose_rows(args.poses)
    points = position_rows(args.points)
    print("\n| pose_metric | random_factors | other options | reached (1e-6 m, 1e-6 rad) | mean evaluations | "
          "mean time / target (s) | median position error of the missed (m) |")
    print("|---|---|---|---|---|---|---|")
    for r in poses:
        missed = "" if r["median_pos_err_missed"] is None else f"{r['median_pos_err_missed']:.2g}"
        opts = ", ".join(f"{k} {v}" for k, v in r["options"].items()) or "defaults"
        print(f"| {r['pose_metric']} | {r['random_factors']} | {opts} | {r['reached']}/{r['n']} | "
              f"{r['mean_evaluations']:,.0f} | {r['mean_time_s']:.2f} | {missed} |")
    print("\n| robot (position targets, 1e-10 m) | random_factors | reached | mean evaluations | "
          "mean time / point (ms) |")
    print("|---|---|---|---|---|")
    for r in points:
        print(f"| {r['robot']} | {r['random_factors']} | {r['reached']}/{r['n']} | {r['mean_evaluations']:,.0f} | "
              f"{1e3 * r['mean_time_s']:.1f} |")
    print(f"\ntotal {time.perf_counter() - t0:.0f} s")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"poses": poses, "positions": points}, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
