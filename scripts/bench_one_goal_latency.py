#!/usr/bin/env python
"""Per-call time of one-goal lists against the single target (issues 23 gap a and 24), and where it goes.

    python scripts/bench_one_goal_latency.py                      # 2,000 UR5 targets, IKSolver and evoik_pin.solve
    python scripts/bench_one_goal_latency.py --n 500 --profile    # plus a cProfile of each kind (top functions)

UR5 targets from random configurations within the limits (reachable), each solved three ways, interleaved target by
target (so every kind sees the same machine state): the single target ``T``, the one-goal list ``[Pose(tool0, T)]``
and ``[Pose(tool0, T, free="rz")]`` (T turned about its own z by a random angle), each from the same random q0 and
seed, through one :class:`~evoik_pin.IKSolver` per kind and through :func:`evoik_pin.solve`. The goal lists are made
outside the timed call (a caller builds its goals once per target either way). Prints medians, p99, successes and
the ratios of the goal lists' medians to the single target's, with the load average before and after.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import os
import pstats
import time

import numpy as np
import pinocchio as pin

import evoik_pin as ek
from evoik_pin.goals import Pose

KINDS = ("single T", "[Pose(T)]", "[Pose(T, free=rz)]")


def _problems(robot, n: int, seed: int):
    rng = np.random.default_rng(seed)
    tip = robot.tip
    out = []
    for _ in range(n):
        T = robot.fk(rng.uniform(robot.lower, robot.upper))
        turned = T * pin.SE3(pin.utils.rotate("z", rng.uniform(-np.pi, np.pi)), np.zeros(3))
        q0 = rng.uniform(robot.lower, robot.upper)
        out.append(((T, [Pose(tip, T)], [Pose(tip, turned, free="rz")]), q0))
    return out


def _time(problems, call):
    times = {k: [] for k in KINDS}
    ok = {k: 0 for k in KINDS}
    for i, (targets, q0) in enumerate(problems):
        for kind, target in zip(KINDS, targets, strict=True):
            t0 = time.perf_counter()
            r = call(kind, target, q0, i)
            times[kind].append(time.perf_counter() - t0)
            ok[kind] += bool(r.success)
    return times, ok


def stage_table(robot, problems) -> None:
    """Print a markdown table: per stage of :func:`bench_latency.profile_stages`, the mean microseconds per
    IKSolver.solve call of each kind (the least loaded of three passes per kind, passes interleaved by kind)."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from bench_latency import STAGES, profile_stages

    Qs = [q0 for _, q0 in problems]
    best = {}
    for _ in range(3):
        for k, kind in enumerate(KINDS):
            p = profile_stages(robot, [targets[k] for targets, _ in problems], Qs, use_q0=True)
            if kind not in best or p["wrapped_mean_us"] < best[kind]["wrapped_mean_us"]:
                best[kind] = p
    print("| stage | " + " | ".join(KINDS) + " |\n|---|" + "---:|" * len(KINDS))
    for stage, _ in STAGES:
        print(f"| {stage} | " + " | ".join(f"{best[k]['stages_us'][stage]:.1f}" for k in KINDS) + " |")
    print("| mean per call, wrapped (plain) | " + " | ".join(
        f"{best[k]['wrapped_mean_us']:.1f} ({best[k]['plain_mean_us']:.1f})" for k in KINDS) + " |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=2000, help="targets (default 2000)")
    ap.add_argument("--seed", type=int, default=24)
    ap.add_argument("--profile", action="store_true", help="cProfile each kind through IKSolver (top 25 by tottime)")
    ap.add_argument("--stages", action="store_true", help="where each kind's microseconds go: bench_latency.py's "
                    "per-stage clocks, the least loaded of three passes")
    args = ap.parse_args()
    ur5 = ek.load_robot("ur5")
    problems = _problems(ur5, args.n, args.seed)
    solvers = {k: ek.IKSolver(ur5) for k in KINDS}
    for k, target in zip(KINDS, problems[0][0], strict=True):  # one-time set-up: kernel, seed table, engines
        solvers[k].solve(target, q0=problems[0][1], seed=0)
        ek.solve(ur5, target, q0=problems[0][1], seed=0)
    load0 = open("/proc/loadavg").read().split()[0] if os.path.exists("/proc/loadavg") else "?"
    runs = {
        "IKSolver.solve": lambda kind, target, q0, i: solvers[kind].solve(target, q0=q0, seed=i),
        "evoik_pin.solve": lambda kind, target, q0, i: ek.solve(ur5, target, q0=q0, seed=i),
    }
    for name, call in runs.items():
        times, ok = _time(problems, call)
        base = np.median(times[KINDS[0]])
        print(f"{name} (n={args.n}):")
        for k in KINDS:
            t = np.asarray(times[k]) * 1e6
            print(f"  {k:20s} median {np.median(t):7.1f} us  p99 {np.percentile(t, 99):7.1f} us  "
                  f"success {ok[k]}/{args.n}  ratio {np.median(times[k]) / base:.3f}")
    load1 = open("/proc/loadavg").read().split()[0] if os.path.exists("/proc/loadavg") else "?"
    print(f"load average {load0} -> {load1}")
    if args.stages:
        stage_table(ur5, problems)
    if args.profile:
        for k in KINDS:
            prof = cProfile.Profile()
            solver = solvers[k]
            idx = KINDS.index(k)
            prof.enable()
            for i, (targets, q0) in enumerate(problems):
                solver.solve(targets[idx], q0=q0, seed=i)
            prof.disable()
            s = io.StringIO()
            pstats.Stats(prof, stream=s).sort_stats("tottime").print_stats(25)
            print(f"===== profile {k} ({args.n} calls)\n{s.getvalue()}")


if __name__ == "__main__":
    main()
