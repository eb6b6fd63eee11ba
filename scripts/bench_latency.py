#!/usr/bin/env python
"""Single-solve latency (issue 24): IKSolver.solve and evoik_pin.solve against TRAC-IK, one pose at a time.

For every robot, ``--targets`` random reachable poses (the tip poses of configurations drawn uniformly within the
joint limits, a fixed seed), each with a random start configuration q0 (TRAC-IK's seed, our ``q0``). Per target the
solvers run in a fresh random order, in one process, so machine load hits them alike:

* ``IKSolver.solve``: ``solver = evoik_pin.IKSolver(robot)`` made once, ``solver.solve(T, q0=q0, seed=i)``;
* ``IKSolver.solve (no q0)``: the same without q0 (the seed table's nearest entries first);
* ``evoik_pin.solve``: ``evoik_pin.solve(robot, T, q0=q0, seed=i)``;
* TRAC-IK (``pytracik``, 5 ms, epsilon 1e-5, Distance mode; joint limits from our model, targets in its base frame,
  as in ``scripts/bench_ik.py``): its C++ call alone is timed (the quaternion conversion is not).

Each answer is judged by our forward kinematics (Pinocchio): success at 1e-6 means position error <= 1e-6 m,
rotation angle <= 1e-6 rad and the joints within limits (continuous joints wrapped first); success at 2e-5 (what
TRAC-IK's epsilon 1e-5 per component gives) is reported too. Times are wall-clock per call, median and p99, and the
ratio of each median to TRAC-IK's in the same run.

Then: where a call's microseconds go (``--profile-robot``: each stage of IKSolver.solve timed by wrapping it, mean
per call), and a whole-robot problem: Talos with a floating base, both soles and both wrists (poses), through
IKSolver.solve and evoik_pin.solve.

    python scripts/bench_latency.py                        # 2,000 poses per robot, writes docs/BENCHMARKS.md
    python scripts/bench_latency.py --targets 200 --no-docs --json /tmp/lat.json
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

import evoik_pin as ek

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_ik import ROBOTS, TracIK, cpu_model, judge  # noqa: E402
from docs_block import write_block  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs" / "BENCHMARKS.md"
BEGIN, END = "<!-- bench_latency:begin -->", "<!-- bench_latency:end -->"

#: name -> (load_robot source, base, tip): bench_ik's where it has the arm.
ARMS = {"panda": ROBOTS["panda"], "ur10": ("ur10", None, None), "kinova": ROBOTS["kinova"],
        "baxter_left": ROBOTS["baxter_left"], "tiago_dual_left": ROBOTS["tiago_dual_left"]}


def load(name: str) -> ek.Robot:
    source, base, tip = ARMS[name]
    if source.endswith(".urdf"):
        from evoik_pin.robot import example_robot_data_dir

        source = str(example_robot_data_dir() / source)
    return ek.load_robot(source, base=base, tip=tip)


def bench_arm(name: str, n: int, seed: int) -> dict:
    robot = load(name)
    rng = np.random.default_rng([seed, sum(map(ord, name))])
    Qt, Qs = robot.random_configurations(n, rng), robot.random_configurations(n, rng)
    targets = [robot.fk(q) for q in Qt]
    solver = ek.IKSolver(robot)
    trac = TracIK(robot)
    ek.solve(robot, targets[0], seed=0)  # one-time set-up (kernel, seed table) outside the timed calls
    solver.solve(targets[0], seed=0)
    calls = {
        "IKSolver.solve": lambda T, q0, i: solver.solve(T, q0=q0, seed=i).q,
        "IKSolver.solve (no q0)": lambda T, q0, i: solver.solve(T, seed=i).q,
        "evoik_pin.solve": lambda T, q0, i: ek.solve(robot, T, q0=q0, seed=i).q,
    }
    if trac.available:
        calls["TRAC-IK"] = trac
    names = list(calls)
    rows = {k: {"t": [], "pos": [], "rot": [], "ok": []} for k in names}
    order = np.random.default_rng([seed, 99])
    for i, T in enumerate(targets):
        for j in order.permutation(len(names)):
            k = names[j]
            t0 = time.perf_counter()
            q = calls[k](T, Qs[i], i)
            dt = time.perf_counter() - t0
            if k == "TRAC-IK":
                dt = trac.elapsed
            pos, rot, inside = judge(robot, T, q)
            row = rows[k]
            row["t"].append(dt)
            row["pos"].append(pos)
            row["rot"].append(rot)
            row["ok"].append(inside)
    out = {}
    for k in names:
        row = rows[k]
        t = np.array(row["t"]) * 1e6
        pos, rot, inside = np.array(row["pos"]), np.array(row["rot"]), np.array(row["ok"])
        out[k] = {"n": int(t.size), "median_us": float(np.median(t)), "p99_us": float(np.percentile(t, 99)),
                  "mean_us": float(t.mean()),
                  "success_1e-6": float(np.mean((pos <= 1e-6) & (rot <= 1e-6) & inside)),
                  "success_2e-5": float(np.mean((pos <= 2e-5) & (rot <= 2e-5) & inside))}
    if "TRAC-IK" in out:
        ref = out["TRAC-IK"]["median_us"]
        for k in names:
            out[k]["ratio_to_tracik"] = out[k]["median_us"] / ref
    if not trac.available:
        out["TRAC-IK skipped"] = trac.why
    return out


# ---------------------------------------------------------------------- where the microseconds go
class _Clock:
    """Accumulates the time spent in wrapped functions (perf_counter_ns), per stage name, exclusive: the time a
    wrapped function spends in other wrapped functions is theirs (a Result made inside guaranteed_runs_result counts
    once, the checks inside IKSolver.problem are the checks')."""

    def __init__(self) -> None:
        self.ns: dict[str, int] = {}
        self._inner = [0]  # per open wrapped call: the time spent in wrapped calls inside it

    def wrap(self, owner, attr: str, stage: str):
        original = getattr(owner, attr)
        setattr(owner, attr, self.timed(original, stage))
        return original

    def timed(self, function, stage: str):
        """``function`` wrapped: its exclusive time added to ``stage``."""
        ns, inner = self.ns, self._inner
        ns.setdefault(stage, 0)
        clock = time.perf_counter_ns

        def timed(*args, **kwargs):
            inner.append(0)
            t0 = clock()
            try:
                return function(*args, **kwargs)
            finally:
                spent = clock() - t0
                ns[stage] += spent - inner.pop()
                inner[-1] += spent

        return timed


#: (stage label, what it covers), in the order of a call.
STAGES = [
    ("target's checks", "a single target's on its lane: pose_arrays (finite, a rotation matrix, within reach of the "
     "base); else Target.coerce, or a goal list's bind (the goals' checks and packing)"),
    ("q0's check", "IKSolver's q0 check: shape and finite"),
    ("problem", "the general path only: the template problem copied with the target and q0 (IKProblem)"),
    ("set-up look-ups", "the general path only: the memetic plan's cached seed table and LM engine (retargeted)"),
    ("guaranteed runs (compiled)", "one numba call: the table's distances to the target and the nearest entries, "
     "q0's tip pose and nearness, the guaranteed LM runs (the repeat call's compiled entry, or "
     "MemeticSetup.guaranteed_runs)"),
    ("memetic's later stages", "when no guaranteed run converged: the search going on (LM runs one by one, DE "
     "restarts), rare but long"),
    ("cost and Result", "the cost from the errors (the objective's from_errors; problem.assess) and the Result"),
    ("the rest (Python)", "IKSolver.solve and the lane's own logic: the target written into the engine's arrays, "
     "q0's copy, the compiled call's arguments, the tolerances' test, the clock"),
]


def profile_stages(robot: ek.Robot, targets, Qs, use_q0: bool) -> dict:
    """Mean microseconds per IKSolver.solve call spent in each stage of :data:`STAGES` (each stage's functions
    wrapped with an exclusive clock; the wrappers' own cost, about 0.15 us each, lands in their stages). Single
    targets take the solver's lane (solvers/search/repeat_call.py) from the second of their kind; ``targets``
    may be goal lists (scripts/bench_one_goal_latency.py), which take the general path: their checks and packing
    (bind) are the target's checks, their summary (IKProblem.goal_summary) part of the cost and Result."""
    from evoik_pin import ik_solver
    from evoik_pin.solvers.search import memetic, repeat_call

    solver = ek.IKSolver(robot)
    n = len(targets)
    for i in range(min(n, 200)):  # warm: caches, branch predictors; the lanes made
        solver.solve(targets[i], q0=Qs[i] if use_q0 else None, seed=i)
    t0 = time.perf_counter()
    for i in range(n):
        solver.solve(targets[i], q0=Qs[i] if use_q0 else None, seed=i)
    plain = (time.perf_counter() - t0) / n * 1e6
    clock = _Clock()
    saved = [
        (ik_solver, "pose_arrays", clock.wrap(ik_solver, "pose_arrays", "target")),
        (ek.Target, "coerce", clock.wrap(ek.Target, "coerce", "target")),
        (ik_solver, "bind", clock.wrap(ik_solver, "bind", "target")),
        (ik_solver.IKSolver, "_checked_q0", clock.wrap(ik_solver.IKSolver, "_checked_q0", "q0")),
        (ik_solver.IKSolver, "problem", clock.wrap(ik_solver.IKSolver, "problem", "problem")),
        (memetic.MemeticSetup, "_prepare", clock.wrap(memetic.MemeticSetup, "_prepare", "setup")),
        (memetic.MemeticSetup, "_engine", clock.wrap(memetic.MemeticSetup, "_engine", "setup")),
        (memetic.MemeticSetup, "guaranteed_runs", clock.wrap(memetic.MemeticSetup, "guaranteed_runs", "first")),
        (memetic.MemeticSetup, "resume", clock.wrap(memetic.MemeticSetup, "resume", "later")),
        (ek.IKProblem, "assess", clock.wrap(ek.IKProblem, "assess", "result")),
        (ek.IKProblem, "goal_summary", clock.wrap(ek.IKProblem, "goal_summary", "result")),  # a goal list's
        (memetic, "Result", clock.wrap(memetic, "Result", "result")),
        (repeat_call, "guaranteed_runs_result", clock.wrap(repeat_call, "guaranteed_runs_result", "result")),
    ]
    lanes = list(solver._repeat_calls.values())
    entries = [lane._entry for lane in lanes]
    for lane in lanes:  # the lane's own compiled entry and objective
        lane._entry = clock.timed(lane._entry, "first")
        lane._objective.from_errors = clock.timed(lane._objective.from_errors, "result")
    ns = clock.ns
    ns["later"] = ns.get("later", 0)
    # the general path's later stages: a _solve whose guaranteed runs did not converge, less the wrapped stages inside
    # it
    guaranteed_runs, solve = memetic._guaranteed_runs, memetic._solve
    fell_back = [False]

    def first_timed(*args):
        out = guaranteed_runs(*args)
        fell_back[0] = out[0] is None
        return out

    def solve_timed(*args):
        before, t = sum(ns.values()), time.perf_counter_ns()
        fell_back[0] = False
        out = solve(*args)
        if fell_back[0]:
            ns["later"] += time.perf_counter_ns() - t - (sum(ns.values()) - before)
        return out

    memetic._guaranteed_runs, memetic._solve = first_timed, solve_timed
    try:
        t0 = time.perf_counter()
        for i in range(n):
            solver.solve(targets[i], q0=Qs[i] if use_q0 else None, seed=i)
        wrapped = (time.perf_counter() - t0) / n * 1e6
    finally:
        memetic._guaranteed_runs, memetic._solve = guaranteed_runs, solve
        for owner, attr, original in saved:
            setattr(owner, attr, original)
        for lane, entry in zip(lanes, entries, strict=True):
            lane._entry = entry
            del lane._objective.from_errors
    us = {k: v / n / 1e3 for k, v in ns.items()}
    stages = {"target's checks": us["target"], "q0's check": us["q0"], "problem": us["problem"],
              "set-up look-ups": us["setup"], "guaranteed runs (compiled)": us["first"],
              "memetic's later stages": us["later"], "cost and Result": us["result"]}
    stages["the rest (Python)"] = wrapped - sum(stages.values())
    return {"stages_us": stages, "wrapped_mean_us": wrapped, "plain_mean_us": plain, "q0": use_q0, "n": n,
            "lane": bool(lanes)}


def bench_talos(n: int, seed: int) -> dict:
    from bench_goals_scale import problems

    talos = ek.load_robot("talos", floating_base=True)
    goal_lists = problems(talos, n, seed)
    solver = ek.IKSolver(talos)
    solver.solve(goal_lists[0], seed=0)
    ek.solve(talos, goal_lists[0], seed=0)
    calls = {"IKSolver.solve": lambda g, i: solver.solve(g, seed=i),
             "evoik_pin.solve": lambda g, i: ek.solve(talos, g, seed=i)}
    names = list(calls)
    t = {k: [] for k in names}
    ok = {k: [] for k in names}
    order = np.random.default_rng([seed, 7])
    for i, g in enumerate(goal_lists):
        for j in order.permutation(len(names)):
            k = names[j]
            t0 = time.perf_counter()
            r = calls[k](g, i)
            t[k].append(time.perf_counter() - t0)
            ok[k].append(r.success)
    return {k: {"n": n, "median_us": float(np.median(t[k]) * 1e6), "p99_us": float(np.percentile(t[k], 99) * 1e6),
                "success": float(np.mean(ok[k]))} for k in names}


def bench_trajectory(name: str, n: int, seed: int, rounds: int = 3) -> dict:
    """``evoik_pin.solve_trajectory`` along a smooth path of ``n`` poses (a random walk in joint space, steps of 0.01
    rad per joint, from a random configuration; q0 zeros), against TRAC-IK seeded with its previous answer: the
    whole call's wall time per point (the least of ``rounds``), success within 1e-6 (ours) and of TRAC-IK's calls."""
    robot = load(name)
    rng = np.random.default_rng([seed, 11])
    q = robot.random_configurations(1, rng)[0]
    path = []
    for _ in range(n):
        q = np.clip(q + 0.01 * rng.standard_normal(robot.n), robot.lower, robot.upper)
        path.append(robot.fk(q))
    ek.solve_trajectory(robot, path[:10], seed=0)  # one-time set-up outside the clock
    times, out = [], None
    for _ in range(rounds):
        t0 = time.perf_counter()
        out = ek.solve_trajectory(robot, path, seed=1, q0=np.zeros(robot.n))
        times.append(time.perf_counter() - t0)
    ok = []
    for T, r in zip(path, out, strict=True):
        pos, rot, inside = judge(robot, T, r.q)
        ok.append(pos <= 1e-6 and rot <= 1e-6 and inside)
    row = {"n": n, "us_per_point": min(times) / n * 1e6, "rounds_ms": [t * 1e3 for t in times],
           "success_1e-6": float(np.mean(ok))}
    trac = TracIK(robot)
    if trac.available:
        spent, solved, previous = [], [], np.zeros(robot.n)
        for T in path:
            answer = trac(T, previous, 0)
            spent.append(trac.elapsed)
            solved.append(answer is not None)
            previous = answer if answer is not None else previous
        row["tracik_us_per_point"] = float(np.sum(spent)) / n * 1e6
        row["tracik_success"] = float(np.mean(solved))
    return row


# ---------------------------------------------------------------------- report
def markdown(arms: dict, profile: dict | None, talos: dict | None, command: str, load: tuple,
             trajectory: dict | None = None) -> str:
    lines = [f"### Single-solve latency (issue 24), {datetime.date.today().isoformat()}", "",
             f"`{command}` on {cpu_model()} ({os.cpu_count()} cores), Python {platform.python_version()}; load "
             f"average {load[0]} before, {load[1]} after (the machine is shared by about six sessions: every "
             "figure is a loaded one; compare the ratios, measured in the same run, interleaved target by target).",
             "", "Per robot: random reachable poses, a random q0 (TRAC-IK's seed) each; success within 1e-6 m and "
             "rad by our FK (2e-5 too); wall time per call (TRAC-IK: its C++ call alone).", "",
             "| robot | solver | poses | success 1e-6 | success 2e-5 | median us | p99 us | median / TRAC-IK's |",
             "|---|---|---:|---:|---:|---:|---:|---:|"]
    for name, rows in arms.items():
        for k, r in rows.items():
            if not isinstance(r, dict):
                lines.append(f"| {name} | {k} | | | | | | {r} |")
                continue
            ratio = f"{r['ratio_to_tracik']:.3f}" if "ratio_to_tracik" in r else "-"
            lines.append(f"| {name} | {k} | {r['n']} | {100 * r['success_1e-6']:.2f}% | "
                         f"{100 * r['success_2e-5']:.2f}% | {r['median_us']:.1f} | {r['p99_us']:.0f} | {ratio} |")
    if profile:
        p = profile
        lines += ["", f"Where a call's microseconds go: IKSolver.solve on {p['robot']}"
                  f"{' with q0' if p['q0'] else ''}, {p['n']} poses, mean per call, each stage's functions wrapped "
                  f"with a clock (mean {p['wrapped_mean_us']:.1f} us wrapped, {p['plain_mean_us']:.1f} us without "
                  "the wrappers; the least loaded of three passes, whose wrapped means were "
                  f"{', '.join(f'{x:.1f}' for x in p['passes_wrapped_mean_us'])} us):", "",
                  "| stage | us per call | what |", "|---|---:|---|"]
        what = dict(STAGES)
        for k, v in p["stages_us"].items():
            lines.append(f"| {k} | {v:.1f} | {what[k]} |")
    if trajectory:
        t = trajectory
        peer = "" if "tracik_us_per_point" not in t else (
            f"; TRAC-IK seeded with its previous answer: {t['tracik_us_per_point']:.1f} us a point (its calls alone), "
            f"{100 * t['tracik_success']:.1f} % of its calls solved (1e-5)")
        lines += ["", f"`evoik_pin.solve_trajectory` on {t['robot']}, {t['n']} poses along a smooth path (joint steps "
                  f"of 0.01 rad), the whole call: {t['us_per_point']:.1f} us a point (the least of rounds of "
                  f"{', '.join(f'{x:.1f}' for x in t['rounds_ms'])} ms), {100 * t['success_1e-6']:.1f} % within "
                  f"1e-6{peer}."]
    if talos:
        lines += ["", f"Talos, floating base, four pose goals (both soles, both wrists; bench_goals_scale.py's "
                  f"problems), {next(iter(talos.values()))['n']} problems, interleaved:", "",
                  "| solver | success | median us | p99 us |", "|---|---:|---:|---:|"]
        for k, r in talos.items():
            lines.append(f"| {k} | {100 * r['success']:.1f}% | {r['median_us']:.0f} | {r['p99_us']:.0f} |")
    return "\n".join(lines) + "\n"


def write_docs(text: str) -> None:
    """Replace this script's own section of docs/BENCHMARKS.md (between its markers), or append it."""
    write_block(DOCS, BEGIN, END, text, None)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--targets", type=int, default=2000, help="poses per robot (default 2000)")
    ap.add_argument("--robots", nargs="+", choices=list(ARMS), default=list(ARMS))
    ap.add_argument("--profile-robot", default="panda", choices=list(ARMS), help="robot of the profile table")
    ap.add_argument("--profile-targets", type=int, default=1000, help="poses of the profile table (0: none)")
    ap.add_argument("--talos", type=int, default=200, help="Talos problems (0: none)")
    ap.add_argument("--trajectory", type=int, default=1000, help="solve_trajectory points on Panda (0: none)")
    ap.add_argument("--json", type=Path, help="write the numbers here")
    ap.add_argument("--no-docs", action="store_true", help="do not write docs/BENCHMARKS.md")
    ap.add_argument("--seed", type=int, default=2026)
    args = ap.parse_args(argv)
    load0 = os.getloadavg()
    arms = {}
    for name in args.robots:
        arms[name] = bench_arm(name, args.targets, args.seed)
        for k, r in arms[name].items():
            if isinstance(r, dict):
                print(f"{name:16s} {k:24s} success {r['success_1e-6']:.4f} median {r['median_us']:7.1f} us "
                      f"p99 {r['p99_us']:7.0f} us ratio {r.get('ratio_to_tracik', float('nan')):.3f}", flush=True)
    profile = None
    if args.profile_targets:
        robot = load(args.profile_robot)
        rng = np.random.default_rng([args.seed, 5])
        Qt = robot.random_configurations(args.profile_targets, rng)
        Qs = robot.random_configurations(args.profile_targets, rng)
        targets = [robot.fk(q) for q in Qt]
        # three passes, the least loaded one kept (the machine is shared: a pass that another process slowed down
        # inflates every stage)
        passes = [profile_stages(robot, targets, Qs, use_q0=True) for _ in range(3)]
        profile = min(passes, key=lambda p: p["wrapped_mean_us"])
        profile["robot"] = args.profile_robot
        profile["passes_wrapped_mean_us"] = [p["wrapped_mean_us"] for p in passes]
        print(json.dumps(profile, indent=1), flush=True)
    trajectory = None
    if args.trajectory:
        trajectory = bench_trajectory("panda", args.trajectory, args.seed)
        trajectory["robot"] = "panda"
        print(json.dumps(trajectory, indent=1), flush=True)
    talos = bench_talos(args.talos, args.seed) if args.talos else None
    if talos:
        print(json.dumps(talos, indent=1))
    load1 = os.getloadavg()
    loads = (f"{load0[0]:.2f}", f"{load1[0]:.2f}")
    command = "python scripts/bench_latency.py " + " ".join(argv if argv is not None else sys.argv[1:])
    text = markdown(arms, profile, talos, command.strip(), loads, trajectory)
    print(text)
    if args.json:
        args.json.write_text(json.dumps({"arms": arms, "profile": profile, "talos": talos, "trajectory": trajectory,
                                         "load": loads}, indent=1))
    if not args.no_docs:
        write_docs(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
