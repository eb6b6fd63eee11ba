#!/usr/bin/env python
"""The methods that return several answers or a front, on whole-robot goal lists: memetic-all and nsga2 beside
memetic (the default), every answer judged by Pinocchio forward kinematics.

    python scripts/bench_goal_methods.py                       # Baxter and Talos, 20 problems each
    python scripts/bench_goal_methods.py --n 50 --robots baxter --docs   # and append the table to docs/BENCHMARKS.md

Problems: ``goal_problems.make_problems`` (targets by forward kinematics of random configurations within limits; a
floating base within a 0.5 m cube and 30 degrees of upright), the same as ``bench_goals.py``. Judge:
``judge_goals.judge`` (every goal within 1e-6 m and rad, joints within limits) on ``Result.q``, and for
``memetic-all`` on every returned solution too. Times are wall clock per problem, in one process, the methods
interleaved problem by problem so the machine's load falls on all of them alike.
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

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_goals as bg  # noqa: E402
import goal_problems as gp  # noqa: E402
import judge_goals as jg  # noqa: E402

import evoik_pin as ek  # noqa: E402

DOCS = Path(__file__).resolve().parents[1] / "docs" / "BENCHMARKS.md"
#: The methods compared, with their options (small NSGA-II: its default 200 x 100 takes seconds per problem).
METHODS = {"memetic": {}, "memetic-all": {"count": 4}, "nsga2": {"population": 40, "max_generations": 20}}


def run(robot, problems: dict, model) -> dict:
    """Every method on every problem (interleaved): judged answers, wall times (s), solution counts."""
    goal_lists = [bg.goals_of(p) for p in problems["problems"]]
    for method, options in METHODS.items():  # one-time set-up (kernel, seed table) out of the times
        ek.solve(robot, goal_lists[0], method=method, seed=10**6, **options)
    out = {m: {"q": [], "wall_s": [], "count": [], "all_ok": [], "spread": []} for m in METHODS}
    for i, goals in enumerate(goal_lists):
        for method, options in METHODS.items():
            t0 = time.perf_counter()
            r = ek.solve(robot, goals, method=method, seed=i, **options)
            side = out[method]
            side["wall_s"].append(time.perf_counter() - t0)
            side["q"].append(robot.full_configuration(r.q))
            many = r.solutions if method == "memetic-all" else (None if r.front is None else list(r.front.q))
            if many is not None:
                Q = [s.q if method == "memetic-all" else s for s in many]
                side["count"].append(len(Q))
                if Q:
                    single = {**problems, "problems": [problems["problems"][i]] * len(Q)}
                    rows = jg.judge(single, [robot.full_configuration(q) for q in Q], model=model)
                    side["all_ok"].append(bool(jg.solved_at(rows, jg.TOLERANCES[0]).all()))
                if method == "memetic-all" and r.history.get("min_pairwise_distance") is not None:
                    side["spread"].append(float(r.history["min_pairwise_distance"][0]))
    return out


def table(problems: dict, out: dict, model) -> str:
    base = float(np.median(out["memetic"]["wall_s"]))
    lines = [f"{problems['robot']} ({len(problems['problems'])} problems; load average "
             f"{' '.join(f'{x:.2f}' for x in os.getloadavg())} after)", "",
             "| method | options | q solves (1e-6) | median ms | x memetic | answers per problem | all answers "
             "solve | median min pairwise distance (rad) |", "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for method, options in METHODS.items():
        side = out[method]
        ok = jg.solved_at(jg.judge(problems, side["q"], model=model), jg.TOLERANCES[0])
        med = float(np.median(side["wall_s"]))
        count = f"{np.mean(side['count']):.2f}" if side["count"] else "1"
        all_ok = (f"{sum(side['all_ok'])}/{len(side['all_ok'])}" if side["all_ok"] else "-")
        spread = f"{np.median(side['spread']):.2f}" if side["spread"] else "-"
        opts = ", ".join(f"{k}={v}" for k, v in options.items()) or "defaults"
        lines.append(f"| {method} | {opts} | {100 * ok.mean():.1f} % | {med * 1e3:.1f} | {med / base:.2f} | {count} | "
                     f"{all_ok} | {spread} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=20, help="problems per robot (default 20)")
    ap.add_argument("--seed", type=int, default=0, help="problem set's seed (default 0)")
    ap.add_argument("--robots", nargs="+", choices=["baxter", "talos", "go2", "allegro", "pr2"],
                    default=["baxter", "talos"])
    ap.add_argument("--docs", action="store_true", help="append the tables to docs/BENCHMARKS.md")
    args = ap.parse_args(argv)
    if args.n < 1:
        ap.error("--n must be at least 1")
    cmd = "python scripts/bench_goal_methods.py" + ("" if not argv else " " + " ".join(argv))
    parts = [f"Date: {datetime.date.today()}. Command: `{cmd}`. Machine: {platform.machine()}, {os.cpu_count()} "
             f"cores, Python {platform.python_version()}, shared with other work (load averages below). Success: "
             "every goal within 1e-6 m and rad by Pinocchio forward kinematics, joints within limits "
             "(`scripts/judge_goals.py`); 'all answers solve': problems whose every returned solution (memetic-all) "
             "or front member (nsga2) passes that judge. Times: wall clock per problem, methods interleaved; "
             "'x memetic' is each method's median over memetic's, which returns one answer where memetic-all "
             "returns `count` (a whole robot's solutions are a continuum) and nsga2 a front."]
    for name in args.robots:
        problems = gp.make_problems(name, args.n, args.seed)
        model = gp.model_of(problems)
        robot = bg.load_evoik_robot(problems)
        bg.check_same_model(robot, problems, model)
        parts.append(table(problems, run(robot, problems, model), model))
        print(parts[-1], flush=True)
    text = "\n\n".join(parts)
    if args.docs:
        doc = DOCS.read_text(encoding="utf-8").rstrip()
        DOCS.write_text(doc + "\n\n## Goal lists in memetic-all and nsga2 (scripts/bench_goal_methods.py)\n\n" + text
                        + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
