#!/usr/bin/env python
"""Throughput of solve_many on whole-robot problems: Talos with a floating base, four pose goals (both soles, both
wrists), one worker against every core, in the same run.

    python scripts/bench_goals_scale.py                    # 2,000 problems, 3 repetitions, stdout
    python scripts/bench_goals_scale.py --problems 500 --reps 1

Problems: the goal frames' poses at Talos configurations drawn uniformly within the robot's bounds (the free-flyer's
six entries too: +-1 m, roll and yaw +-pi, pitch +-pi/2; a fixed seed), so every problem is reachable by
construction; solve_many's defaults (every goal within 1e-6 m and rad, memetic's 5 ms fallback budget). Runs of the
worker counts alternate, so machine load hits them alike; medians and bests of ``--reps`` runs are reported, with the
load average before and after.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

import evoik_pin as ek
from evoik_pin.goals import Pose
from evoik_pin.solvers.batch.threads import default_workers

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_ik import cpu_model  # noqa: E402

FRAMES = ("left_sole_link", "right_sole_link", "arm_left_7_link", "arm_right_7_link")


def problems(robot, count: int, seed: int) -> list[list[Pose]]:
    """``count`` goal lists: the four frames' poses at random configurations within the bounds."""
    Q = robot.random_configurations(count, np.random.default_rng(seed))
    return [[Pose(f, robot.fk(q, f)) for f in FRAMES] for q in Q]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--problems", type=int, default=2000)
    parser.add_argument("--reps", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    talos = ek.load_robot("talos", floating_base=True)
    lists = problems(talos, args.problems, args.seed)
    setup = ek.prepare(talos)
    ek.solve_many(talos, lists[:50], seed=0, workers=1)  # the goal stack's k-d tree and buffers: not timed
    cores = default_workers()
    counts = sorted({1, cores})
    load0 = os.getloadavg()
    runs: dict[int, list[dict]] = {w: [] for w in counts}
    for _ in range(args.reps):
        for w in counts:
            t0 = time.perf_counter()
            res = ek.solve_many(talos, lists, seed=0, workers=w)
            wall = time.perf_counter() - t0
            runs[w].append({**res.stats, "wall": wall})
    load1 = os.getloadavg()
    print(f"# solve_many on {args.problems} Talos problems (floating base, 4 pose goals), "
          f"{datetime.date.today().isoformat()}")
    print(f"machine: {cpu_model()}, {os.cpu_count()} cores ({cores} usable); Python {platform.python_version()}; "
          f"load average {load0[0]:.1f} before, {load1[0]:.1f} after; set-up (kernel, seed table) {setup:.1f} s")
    print("| workers | problems/s (median) | best | solved | batched rounds | one by one |")
    print("|---:|---:|---:|---:|---:|---:|")
    medians = {}
    for w in counts:
        tp = [r["throughput"] for r in runs[w]]
        medians[w] = float(np.median(tp))
        last = runs[w][-1]
        print(f"| {w} | {medians[w]:,.0f} | {max(tp):,.0f} | {last['solved']} / {last['n']} | {last['batched']} | "
              f"{last['fallback']} ({last['fallback_solved']} solved) |")
    if len(counts) > 1:
        print(f"speed-up {counts[-1]} workers / 1: {medians[counts[-1]] / medians[1]:.2f}x (medians)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
