#!/usr/bin/env python
"""Benchmark ``solve_all`` (default method ``memetic-all``): every IK solution of random reachable 6-D poses.

* UR5 and UR10: recall of the closed-form set (the UR analytic solution of tests/test_all_solutions.py,
  verified there against our FK; solutions compared modulo 2 pi on the +-2 pi joints, class radius 1e-3 rad),
  answers that match no closed-form solution ("extra"), time per pose;
* 6R arms without a closed form (Kinova Jaco2 6-DOF; a general 6R from a DH table, up to 12 real solutions):
  the same against a brute-force oracle (LM from 3000 random starts, refined to 1e-12 and clustered); poses
  where the oracle cannot isolate the solutions (refined error above 1e-10: a degenerate pose) are counted
  apart;
* Panda (7 DOF): distinct converged solutions found per pose and per ms, and the spread (smallest pairwise
  joint distance) of the 8 returned;
* ``hga`` (paper 001) on a few UR5 poses, for contrast.

Targets are the FK of configurations drawn uniformly within the joint limits (fixed seeds). Times are
``Result.time_s`` (the search alone; the one-time set-up is done first) and the wall time of the whole
``solve_all`` call.

    python scripts/bench_all_solutions.py             # 500 UR poses each, writes docs/BENCHMARKS.md
    python scripts/bench_all_solutions.py --quick     # 50 poses, stdout only
    python scripts/bench_all_solutions.py --ur-poses 200 --oracle-poses 50 --no-docs --json out.json
"""

from __future__ import annotations

import argparse
import datetime
import importlib.util
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

import evoik_pin as ev

sys.path.insert(0, str(Path(__file__).resolve().parent))
from docs_block import write_block  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs" / "BENCHMARKS.md"
BEGIN, END = "<!-- bench_all_solutions:begin -->", "<!-- bench_all_solutions:end -->"
TITLE = "## All IK solutions: solve_all (memetic-all) against closed forms and an oracle"


def _load_module(name: str, path: Path):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# The closed form, the oracle and the arms live with the tests that verify them.
T_ALL = _load_module("test_all_solutions", ROOT / "tests" / "test_all_solutions.py")
cpu_model = _load_module("bench_ik", ROOT / "scripts" / "bench_ik.py").cpu_model


def poses(robot, count: int, seed: int) -> list[pin.SE3]:
    rng = np.random.default_rng(seed)
    return [robot.fk(q) for q in robot.random_configurations(count, rng)]


def timed_solve_all(robot, T, **options):
    t0 = time.perf_counter()
    sols = ev.solve_all(robot, T, **options)
    return sols, time.perf_counter() - t0


def summary(times: list[float], walls: list[float]) -> dict:
    t, w = np.array(times) * 1e3, np.array(walls) * 1e3
    return {"median_ms": float(np.median(t)), "p90_ms": float(np.percentile(t, 90)),
            "p99_ms": float(np.percentile(t, 99)), "max_ms": float(t.max()), "wall_median_ms": float(np.median(w))}


def bench_reference(name: str, robot, count: int, seed: int, reference, method: str = "memetic-all",
                    options: dict | None = None, log=print) -> dict:
    """Recall of ``reference(robot, T) -> (classes, degenerate)`` over ``count`` random poses."""
    options = options or {}
    hit = total = extra = timeouts = degenerate = 0
    missed: list[int] = []
    times, walls, sizes = [], [], []
    for i, T in enumerate(poses(robot, count, seed)):
        ref, singular = reference(robot, T)
        sols, wall = timed_solve_all(robot, T, method=method, seed=i, **options)
        if singular:
            degenerate += 1
            continue
        h, e = T_ALL.matched(robot, ref, [s.q for s in sols])
        hit, total, extra = hit + h, total + len(ref), extra + e
        if h < len(ref):
            missed.append(i)
        timeouts += "time budget" in sols.message
        times.append(sols.result.time_s)
        walls.append(wall)
        sizes.append(len(ref))
        if (i + 1) % 100 == 0:
            log(f"  {name} {method}: {i + 1}/{count} poses, recall {hit}/{total}")
    out = {"robot": name, "method": method, "poses": len(times), "degenerate_poses": degenerate,
           "solutions": total, "found": hit, "recall": hit / max(total, 1), "extra": extra,
           "timeouts": timeouts, "missed_poses": missed, "mean_solutions": float(np.mean(sizes)),
           "max_solutions": int(max(sizes)), **summary(times, walls)}
    log(f"{name} {method}: recall {hit}/{total} = {out['recall']:.4%}, extra {extra}, median {out['median_ms']:.2f} "
        f"ms, p99 {out['p99_ms']:.2f} ms, {degenerate} degenerate pose(s)")
    return out


def closed_form(robot, T):
    return T_ALL.ur_solutions(robot, T), False


def oracle(robot, T):
    ref, worst = T_ALL.oracle_solutions(robot, T)
    return ref, worst > 1e-10


def bench_redundant(name: str, count: int, seed: int, log=print) -> dict:
    robot = ev.load_robot(name)
    ev.solve_all(robot, robot.fk(np.zeros(robot.n)), seed=0)  # one-time set-up
    pooled, returned, spread, times, walls, ok = [], [], [], [], [], 0
    for i, T in enumerate(poses(robot, count, seed)):
        sols, wall = timed_solve_all(robot, T, seed=i)
        ok += all(robot.within_bounds(s.q) and s.success for s in sols)
        pooled.append(sols.result.history["solutions"][-1])
        returned.append(len(sols))
        spread.append(sols.result.history["min_pairwise_distance"][0] if len(sols) > 1 else np.nan)
        times.append(sols.result.time_s)
        walls.append(wall)
    t_ms = np.array(times) * 1e3
    out = {"robot": name, "poses": count, "all_valid_poses": ok, "pooled_median": float(np.median(pooled)),
           "pooled_per_ms": float(np.median(np.array(pooled) / t_ms)), "returned_median": float(np.median(returned)),
           "min_pairwise_median_rad": float(np.nanmedian(spread)), "min_pairwise_p10_rad": float(
               np.nanpercentile(spread, 10)), **summary(times, walls)}
    log(f"{name}: {out['pooled_median']:.0f} distinct solutions per pose ({out['pooled_per_ms']:.1f} per ms), "
        f"{out['returned_median']:.0f} returned, spread {out['min_pairwise_median_rad']:.2f} rad, median "
        f"{out['median_ms']:.2f} ms")
    return out


def run(args, log=print) -> dict:
    results: dict = {"reference": [], "redundant": []}
    for name in ("ur5", "ur10"):
        robot = ev.load_robot(name)
        ev.solve_all(robot, robot.fk(np.zeros(6)), seed=0)  # one-time set-up: kernel, seed table
        results["reference"].append(bench_reference(name, robot, args.ur_poses, 1, closed_form, log=log))
    for name in ("kinova", "general6r"):
        robot = ev.load_robot("kinova") if name == "kinova" else T_ALL.dh_arm(name)
        ev.solve_all(robot, robot.fk(np.zeros(6)), seed=0)
        results["reference"].append(bench_reference(name, robot, args.oracle_poses, 2, oracle, log=log))
    results["redundant"].append(bench_redundant("panda", args.panda_poses, 3, log=log))
    if args.hga_poses:
        robot = ev.load_robot("ur5")
        results["reference"].append(bench_reference("ur5", robot, args.hga_poses, 1, closed_form, method="hga",
                                                     log=log))
    return results


def markdown(results: dict, command: str) -> str:
    lines = [
        f"Date: {datetime.date.today().isoformat()}. Command: `{command}`.",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores ({cpu_model()}), Python {platform.python_version()}, "
        f"numpy {np.__version__}, pin {pin.__version__}; shared with other work while it ran (times are noisy).",
        "",
        "Random reachable poses (FK of uniform configurations in the joint limits). Recall: reference solutions "
        "(classes modulo 2 pi on full-turn joints, radius 1e-3 rad) that some returned solution matches; "
        "extra: returned solutions matching none (an invalid or duplicate answer would count here). Times: the "
        "search (`Result.time_s`; the one-time set-up done first) and the whole call (wall). Degenerate: poses "
        "where the oracle itself cannot isolate the solutions (left out of the recall).",
        "",
        "| arm | method | reference | poses | solutions (mean / max per pose) | recall | extra | median ms | "
        "p90 ms | p99 ms | max ms | wall median ms | time budget hit | degenerate |",
        "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for r in results["reference"]:
        ref = "closed form" if r["robot"].startswith("ur") else "oracle (3000 LM starts)"
        lines.append(
            f"| {r['robot']} | {r['method']} | {ref} | {r['poses']} | {r['solutions']} ({r['mean_solutions']:.2f} / "
            f"{r['max_solutions']}) | {r['found']}/{r['solutions']} = {r['recall']:.2%} | {r['extra']} | "
            f"{r['median_ms']:.2f} | {r['p90_ms']:.2f} | {r['p99_ms']:.2f} | {r['max_ms']:.1f} | "
            f"{r['wall_median_ms']:.2f} | {r['timeouts']} | {r['degenerate_poses']} |")
    lines += ["", "| arm | poses | distinct solutions per pose (median) | per ms | returned | smallest pairwise "
              "distance of the returned, median (p10) rad | median ms | p90 ms | wall median ms | poses all valid |",
              "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in results["redundant"]:
        lines.append(
            f"| {r['robot']} | {r['poses']} | {r['pooled_median']:.0f} | {r['pooled_per_ms']:.1f} | "
            f"{r['returned_median']:.0f} | {r['min_pairwise_median_rad']:.2f} ({r['min_pairwise_p10_rad']:.2f}) | "
            f"{r['median_ms']:.2f} | {r['p90_ms']:.2f} | {r['wall_median_ms']:.2f} | {r['all_valid_poses']} |")
    return "\n".join(lines)


def write_docs(text: str) -> None:
    """Replace this script's own section of docs/BENCHMARKS.md (between its markers), or append it."""
    write_block(DOCS, BEGIN, END, text, TITLE)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ur-poses", type=int, default=500, help="random poses per UR arm (default 500)")
    ap.add_argument("--oracle-poses", type=int, default=100, help="random poses per oracle arm (default 100)")
    ap.add_argument("--panda-poses", type=int, default=200, help="random Panda poses (default 200)")
    ap.add_argument("--hga-poses", type=int, default=5, help="UR5 poses for hga (default 5; 0: none)")
    ap.add_argument("--quick", action="store_true", help="50 / 10 / 20 / 1 poses, stdout only")
    ap.add_argument("--no-docs", action="store_true", help="do not write docs/BENCHMARKS.md")
    ap.add_argument("--json", metavar="PATH", help="also write the numbers as JSON")
    args = ap.parse_args(argv)
    if args.quick:
        args.ur_poses, args.oracle_poses, args.panda_poses, args.hga_poses, args.no_docs = 50, 10, 20, 1, True
    command = "python scripts/bench_all_solutions.py" + ("" if argv is None and len(sys.argv) == 1
                                                         else " " + " ".join(argv or sys.argv[1:]))
    results = run(args, log=lambda text: print(text, flush=True))
    text = markdown(results, command)
    print(text)
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2))
    if not args.no_docs:
        write_docs(text)
        print(f"wrote {DOCS}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
