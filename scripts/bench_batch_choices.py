#!/usr/bin/env python
"""solve_many with ``prefer=`` (issue 23, gap e), measured (docs/BENCHMARKS.md, "solve_many with prefer").

    python scripts/bench_batch_choices.py            # 60 Panda poses, 2 rounds, stdout
    python scripts/bench_batch_choices.py --n 20     # quick

Why ``solve_many(prefer=...)`` solves its targets one by one in the calling thread (``backend="local"``): the same
targets (forward kinematics of configurations drawn uniformly in the limits, q0 zero), ``prefer="nearest"`` at its
default budget, solved (a) by ``solve_many(workers=1)``, (b) by a loop of ``solve`` and (c) by a loop of ``solve``
on two threads, each with its own copy of the robot (a pickled copy: the robot's Pinocchio Data is not shared
between threads), half the targets each: the wall time per target of each, after one warm-up round (the copy's seed
table built). Prints one markdown section with the command, the date, the machine and its load.
"""

from __future__ import annotations

import argparse
import datetime
import os
import pickle
import platform
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

import evoik_pin as ev


def run(args) -> str:
    panda = ev.load_robot("panda")
    ev.prepare(panda)
    twin = pickle.loads(pickle.dumps(panda))
    ev.prepare(twin)
    Q = panda.random_configurations(args.n, np.random.default_rng(args.seed))
    targets = [panda.fk(q) for q in Q]
    q0 = np.zeros(panda.n)

    def loop(robot, rows):
        return [ev.solve(robot, targets[i], q0=q0, prefer="nearest", seed=i).success for i in rows]

    def per_target(fn) -> float:
        t = time.perf_counter()
        fn()
        return (time.perf_counter() - t) / args.n * 1e3

    rows = []
    for r in range(args.rounds + 1):  # round 0: warm-up
        many = per_target(lambda r=r: ev.solve_many(panda, targets, q0=q0, prefer="nearest", seed=r, workers=1))
        serial = per_target(lambda: loop(panda, range(args.n)))
        with ThreadPoolExecutor(2) as pool:
            threads = per_target(lambda: list(pool.map(loop, (panda, twin),
                                                       (range(0, args.n, 2), range(1, args.n, 2)))))
        if r:
            rows.append(f"| {r} | {many:.2f} | {serial:.2f} | {threads:.2f} | {serial / threads:.2f} |")
    load = open("/proc/loadavg").read().split()[:3] if os.path.exists("/proc/loadavg") else ["?"]
    machine = platform.processor() or platform.machine()
    return "\n".join([
        f"## solve_many with prefer (issue 23, gap e; scripts/bench_batch_choices.py, {datetime.date.today()})",
        "",
        f"`python scripts/bench_batch_choices.py --n {args.n} --rounds {args.rounds}`; {machine}, {os.cpu_count()} "
        f"cores, load average {' '.join(load)} (after the run). Panda, {args.n} poses, prefer='nearest' at its "
        "default budget (0.4-0.6 ms), q0 zero; ms per target (wall time).",
        "",
        "| round | solve_many, workers=1 | loop of solve | loop of solve, 2 threads (robot copies) | loop / threads |",
        "|---|---|---|---|---|",
        *rows,
    ])


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=60)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    print(run(parser.parse_args()))
