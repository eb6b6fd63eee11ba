#!/usr/bin/env python
"""The single-pose chain case of the compiled LM kernel: a fingerprint of its answers and its time per run, to
compare two checkouts (a branch that adds goal kinds must leave this case bit for bit and as fast).

    PYTHONPATH=/path/to/checkout/src python scripts/bench_chain_kernel.py      # run it under each checkout, alternating

Runs ``lm_runs`` (one kernel call) on ``--n`` Panda pose targets (forward kinematics of random configurations,
fixed seed) from random starts (another fixed seed), 30 iterations, ``--reps`` times; prints the md5 of the end
configurations, statistics and per-goal errors (equal digests: the same floating-point results), the best and the
median time per run (us), the convergence rate and the mean number of kinematics evaluations.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import time

import numpy as np

import evoik_pin as ek
from evoik_pin.goals.pose import KIND_POSE
from evoik_pin.goals.stack import GoalStack
from evoik_pin.solvers.lm import kernel as K
from evoik_pin.solvers.lm.layout import STATS_SIZE, box_constants, kernel_params


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=4000)
    parser.add_argument("--reps", type=int, default=7)
    args = parser.parse_args(argv)
    robot = ek.load_robot("panda")
    targets = robot.random_configurations(args.n, np.random.default_rng(0))
    P, R = np.empty((args.n, 1, 3)), np.empty((args.n, 1, 3, 3))
    for i, q in enumerate(targets):
        T = robot.fk(q)
        P[i, 0], R[i, 0] = T.translation, T.rotation
    Q0 = robot.random_configurations(args.n, np.random.default_rng(1))
    stack = GoalStack.single(robot, KIND_POSE, 1e-6, 1e-6)
    _, any_wrap, _, _, box = box_constants(robot, robot.lower, robot.upper)
    Q_out, stats, g_stats = np.empty_like(Q0), np.empty((args.n, STATS_SIZE)), np.empty((args.n, 1, 2))
    kin, goals = tuple(robot.tree_constants()), tuple(stack.arrays)
    call = (Q0, kin, box, any_wrap, goals, P, R, kernel_params(30), Q_out, stats, g_stats)
    K.lm_runs(*call)  # compiled (or loaded from numba's cache) outside the timing
    times = []
    for _ in range(args.reps):
        t0 = time.perf_counter()
        K.lm_runs(*call)
        times.append((time.perf_counter() - t0) / args.n * 1e6)
    digest = hashlib.md5(Q_out.tobytes() + stats.tobytes() + g_stats.tobytes()).hexdigest()
    print(f"{ek.__file__}: md5 {digest}; us per run best {min(times):.2f}, median {np.median(times):.2f}; converged "
          f"{stats[:, 2].mean():.3f}; evaluations {stats[:, 4].mean():.2f}; load average {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
