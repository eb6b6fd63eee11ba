#!/usr/bin/env python
"""NSGA-II's repair steps on goal lists with goal kinds beyond Pose and Position (issue 23, gap f).

    python scripts/bench_nsga2_repair.py                 # rows timing (Talos, N = 100) and success, 10 seeds each
    python scripts/bench_nsga2_repair.py --seeds 20 --population 40 --generations 20

Part 1, the kernel's task rows of a population (what each repair step reads): one compiled call for the whole
population (``lm.population_rows.task_rows_batch``, through ``IKProblem.goal_rows``) against a Python loop of N calls of
``lm.kernel.task_rows``, on Talos (floating base, 38 joints) with a goal list of both soles' poses, a LookAt and a
support polygon (N = 100; the median of repeated timings, interleaved).

Part 2, NSGA-II with ``repair_steps=0`` (the plain algorithm: before this change the only choice for these kinds)
and with the default repair (3 damped-least-squares steps per new individual, 12 for the initial population) on
goal lists met at a random configuration (Baxter; Talos's soles at a standing pose): success is every goal within
its tolerance (1e-6 m and rad) at ``Result.q`` by ``IKProblem.goal_errors`` (Pinocchio's forward kinematics and
centre of mass; tests/test_nsga2_repair.py checks the pointing goals by the frames' placements too).
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

import evoik_pin as ek
from evoik_pin.goals import CenterOfMass, Direction, LookAt, Orientation, Pose, Position, RelativePose
from evoik_pin.problem import IKProblem
from evoik_pin.solvers.lm.population_rows import task_rows

Z = np.array([0.0, 0.0, 1.0])
SOLES = ["left_sole_link", "right_sole_link"]


def talos_rows_list(talos):
    standing = np.zeros(talos.n)
    return ([Pose(f, talos.fk(standing, f)) for f in SOLES]
            + [LookAt("arm_left_7_link", Z, [0.6, 0.3, 0.2]), CenterOfMass(support=SOLES, margin=0.02)])


def rows_timing(talos, N: int, repeats: int) -> str:
    problem = IKProblem(talos, talos_rows_list(talos))
    stack, pt, Rt = problem.goal_stack()
    Q = talos.random_configurations(N, np.random.default_rng(0))
    consts = talos.tree_constants()
    e, E, ge = np.empty(stack.rows), np.empty((stack.rows, talos.n)), np.empty((len(problem.goals), 2))

    def loop():
        for q in Q:
            task_rows(q, *consts, *stack.arrays, pt, Rt, e, E, ge)

    loop(), problem.goal_rows(Q)  # compiled and loaded before timing
    batch_s, loop_s = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        problem.goal_rows(Q)
        batch_s.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        loop()
        loop_s.append(time.perf_counter() - t0)
    b, lo = float(np.median(batch_s)), float(np.median(loop_s))
    return (f"Task rows of N = {N} Talos configurations ({stack.rows} rows, {talos.n} joints; median of {repeats}): "
            f"one batch call {b * 1e3:.2f} ms, a loop of {N} task_rows calls {lo * 1e3:.2f} ms: the batch "
            f"{lo / b:.1f}x faster")


def goal_lists(baxter, talos, seed: int) -> dict:
    """Goal lists met at one random configuration (seed) of Baxter, and on Talos at the standing pose's soles."""
    q, q2 = baxter.random_configurations(2, np.random.default_rng(seed))
    Tl, Tr = baxter.fk(q, "left_gripper"), baxter.fk(q, "right_gripper")
    qt = talos.random_configurations(1, np.random.default_rng(seed))[0]
    standing = np.zeros(talos.n)
    soles = [Pose(f, talos.fk(standing, f)) for f in SOLES]
    A = talos.fk(qt, "arm_left_7_link")
    return {
        ("baxter", "Pose + Direction"): [Pose("left_gripper", Tl), Direction("right_gripper", Z, Tr.rotation @ Z)],
        ("baxter", "Position + LookAt"): [Position("left_gripper", Tl.translation),
                                          LookAt("right_gripper", Z, Tr.translation + 0.5 * Tr.rotation @ Z)],
        ("baxter", "Pose(free='rz') + Orientation"): [Pose("left_gripper", Tl, free="rz"),
                                                      Orientation("right_gripper", Tr.rotation)],
        ("baxter", "RelativePose"): [RelativePose("left_gripper", "right_gripper", (Tl.inverse() * Tr).homogeneous)],
        ("baxter", "Pose goal set (2 members) + Position"): [
            Pose("left_gripper", [baxter.fk(qk, "left_gripper") for qk in (q, q2)]),
            Position("right_gripper", Tr.translation)],
        ("talos", "2 sole Poses + CoM support"): soles + [CenterOfMass(support=SOLES, margin=0.02)],
        ("talos", "2 sole Poses + Direction"): soles + [Direction("arm_left_7_link", Z, A.rotation @ Z)],
    }


def success_table(baxter, talos, seeds: int, population: int, generations: int) -> str:
    robots = {"baxter": baxter, "talos": talos}
    keys = list(goal_lists(baxter, talos, 0))
    counts = {(k, r): [] for k in keys for r in (0, 3)}
    times = {(k, r): [] for k in keys for r in (0, 3)}
    for seed in range(seeds):
        lists = goal_lists(baxter, talos, 100 + seed)
        for key in keys:
            for steps in (0, 3):  # interleaved: the machine's load falls on both alike
                t0 = time.perf_counter()
                r = ek.solve(robots[key[0]], lists[key], method="nsga2", seed=seed, population=population,
                             max_generations=generations, repair_steps=steps)
                times[key, steps].append(time.perf_counter() - t0)
                counts[key, steps].append(bool(r.success))
    lines = [f"NSGA-II, population {population}, {generations} generations, {seeds} seeds per row:", "",
             "| robot | goal list | success, repair_steps=0 | success, default repair (3) | median ms, 0 | "
             "median ms, 3 |", "| --- | --- | --- | --- | --- | --- |"]
    for key in keys:
        lines.append(f"| {key[0]} | {key[1]} | {sum(counts[key, 0])}/{seeds} | {sum(counts[key, 3])}/{seeds} | "
                     f"{1e3 * np.median(times[key, 0]):.0f} | {1e3 * np.median(times[key, 3]):.0f} |")
    return "\n".join(lines)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--population", type=int, default=40)
    ap.add_argument("--generations", type=int, default=20)
    ap.add_argument("--n", type=int, default=100, help="configurations of the rows timing (default 100)")
    args = ap.parse_args()
    talos = ek.load_robot("talos", floating_base=True)
    baxter = ek.load_robot("baxter", tips=["left_gripper", "right_gripper"])
    print(f"Machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}; load "
          f"{' '.join(f'{x:.2f}' for x in os.getloadavg())} before", flush=True)
    print(rows_timing(talos, args.n, 30), flush=True)
    print(success_table(baxter, talos, args.seeds, args.population, args.generations), flush=True)
    print(f"load {' '.join(f'{x:.2f}' for x in os.getloadavg())} after")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
