#!/usr/bin/env python
"""Preferences never cost success (issue 23): every goal-kind benchmark's problems solved three ways, interleaved
problem by problem: the goals alone, with ``Posture(q_ref, 1)`` added, with ``JointLimitMargin(0.1 rad)`` added.

    python scripts/bench_goal_kinds_preferences.py                  # 100 problems per benchmark, stdout
    python scripts/bench_goal_kinds_preferences.py --n 5            # quick
    python scripts/bench_goal_kinds_preferences.py --only talos baxter --docs

The benchmarks are the other parts' problems, made by their own functions with their own seeds (the same targets
as there for the same ``--n``): UR5 ``free="rz"`` and the +-2 mm / +-5 deg band, Romeo's ``LookAt`` with a wrist
pose (scripts/bench_goal_kinds_axes.py), Talos standing and Baxter holding a box (bench_goal_kinds_balance.py),
``prefer="nearest"`` / ``"manipulability"`` on Panda and UR10 from q0 and goal sets of 10 Panda grasps of which 7
are out of reach (bench_goal_kinds_prefer.py). Every problem is a goal list (the prefer benchmarks' single targets
as ``[Pose(tip, T)]``, so that the three ways differ by the preference only). Each answer is judged by its
benchmark's own geometry (Pinocchio's kinematics of the answer: within 1e-6 m and rad, the band's half-widths,
Talos's CoM inside its shrunk polygon, a goal set's reachable member) as well as by ``Result.success``.

``q_ref`` is the middle of the joint limits (Talos's floating base at the benchmark's standing stance instead of the
middle of its +-1 m box). Two budgets, each over all the problems:

* ``time``: each benchmark's own wall-clock budget (memetic's default 5 ms; Talos 20 ms and Baxter 50 ms as in
  bench_goal_kinds_balance.py; ``prefer``'s default budget, 0.4-0.6 ms);
* ``fixed``: ``timeout=None, max_restarts=K`` (``--restarts``, default 5), no clock: the same work whatever the
  machine's load, so that a difference in success is the algorithm's.

Reported per benchmark and budget: success of each way, the problems the preference lost and gained against the
goals alone, median wall time of each and its ratio to the goals alone, and the preference's own effect on the
problems all three solved: mean over the joints of ``|q - q_ref|`` (joints whose range spans a full turn at the
nearest turn), the goals alone against ``+ Posture``; the smallest distance of any joint to its limits (median over
the problems) and the summed shortfall ``sum max(0, 0.1 - distance)`` over the joints (mean over the problems), the
goals alone against ``+ JointLimitMargin`` (joints whose range spans a full turn have no limit: UR arms have none).
Then the problems a preference lost, with its message.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import evoik_pin as ek
from evoik_pin.goals import JointLimitMargin, Pose, Posture, RelativePose
from evoik_pin.goals.preferences import turn_difference
from evoik_pin.solvers.lm import wrapping_joints

SCRIPTS = Path(__file__).resolve().parent
sys.path.insert(0, str(SCRIPTS))
import bench_goal_kinds_axes as axes  # noqa: E402
import bench_goal_kinds_balance as balance  # noqa: E402
import bench_goal_kinds_prefer as prefer  # noqa: E402
from bench_ik import cpu_model  # noqa: E402
from docs_block import write_block  # noqa: E402

DOCS = SCRIPTS.parent / "docs" / "BENCHMARKS.md"
BEGIN, END = "<!-- bench_goal_kinds_preferences:begin -->", "<!-- bench_goal_kinds_preferences:end -->"
TITLE = "## Preferences on every goal-kind benchmark (issue 23; scripts/bench_goal_kinds_preferences.py)"
TOL = 1e-6
MARGIN = 0.1
WAYS = ("goals alone", "+ Posture", "+ JointLimitMargin")
#: The problems a preference lost (solved alone, not with it): "benchmark [budget] way, problem i: message".
LOST: list[str] = []


@dataclass
class Problem:
    """One problem: its goal list, solve's options for it (seed, q0, prefer, ...) and its judge (q -> solved)."""

    goals: list
    options: dict
    judge: object


@dataclass
class Bench:
    """One benchmark: a robot, its problems, its own time budget (solve's options), the Posture's ``q_ref`` (n,)
    (default the middle of the limits), the robot's full-turn joints ``wrap`` (n,) bool, and once run, ``rows``
    (:func:`run_bench`)."""

    name: str
    robot: object
    problems: list[Problem]
    budget: dict
    q_ref: np.ndarray = None
    wrap: np.ndarray = field(init=False)
    rows: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.q_ref is None:
            self.q_ref = (self.robot.lower + self.robot.upper) / 2
        self.wrap = wrapping_joints(self.robot, self.robot.lower, self.robot.upper)


# ------------------------------------------------------------------ the benchmarks (each part's problems)
def axes_benches(n: int, seed: int) -> list[Bench]:
    """UR5 free="rz", UR5 band, Romeo LookAt + wrist: bench_goal_kinds_axes.py's targets, drawn as it draws them."""
    rng = np.random.default_rng(seed)
    ur5 = ek.load_robot("ur5")
    tip = ur5.tip

    def free_judge(Tt):
        return lambda q: max(axes.free_axis_errors(ur5, Tt, q, True)) <= TOL

    def band_judge(Tt):
        return lambda q: axes.band_ratio(ur5, Tt, q) <= 1.0

    free = [Problem([Pose(tip, Tt, free="rz")], {"seed": i}, free_judge(Tt))
            for i, (Tt, _) in enumerate(axes.free_axis_targets(ur5, n, rng))]
    band = [Problem([Pose(tip, Tt, tolerance=axes.HALF)], {"seed": i}, band_judge(Tt))
            for i, Tt in enumerate(axes.band_targets(ur5, n, rng))]
    romeo = axes.load_romeo()

    def look_judge(W, point):
        return lambda q: max(axes.look_at_errors(romeo, W, point, q)) <= TOL

    look = [Problem(axes.look_at_goals(W, point), {"seed": i}, look_judge(W, point))
            for i, (W, point) in enumerate(axes.look_at_problems(romeo, n, rng))]
    return [Bench("UR5 `free=\"rz\"`", ur5, free, {}), Bench("UR5 band +-2 mm, +-5 deg", ur5, band, {}),
            Bench("Romeo `LookAt` + wrist `Pose`", romeo, look, {})]


def balance_benches(n: int, seed: int) -> list[Bench]:
    """Talos standing (soles, CoM over them, both wrists) and Baxter holding the box: bench_goal_kinds_balance.py's
    problems and budgets (20 ms, 50 ms)."""
    talos = ek.load_robot("talos", floating_base=True)
    stance = balance.stance_goals(talos)

    def talos_judge(wrists):
        return lambda q: balance.talos_judged(talos, q, stance, wrists)[1]

    standing = [Problem(stance + wrists, {"seed": i}, talos_judge(wrists))
                for i, wrists in enumerate(balance.talos_problems(talos, n, seed))]
    q_ref = (talos.lower + talos.upper) / 2
    q_ref[:6] = balance.STANCE_BASE  # the base where it stands, not at the middle of its +-1 m box (underground)
    baxter = ek.load_robot("baxter", tips=["left_gripper", "right_gripper"])
    rel = RelativePose("left_gripper", "right_gripper", balance.BOX)

    def box_judge(T):
        return lambda q: balance.box_held(baxter, q, T)

    box = [Problem([rel, Pose("left_gripper", T)], {"seed": i}, box_judge(T))
           for i, T in enumerate(balance.baxter_problems(baxter, n, seed))]
    return [Bench("Talos standing (soles, CoM, wrists)", talos, standing, {"timeout": 0.02}, q_ref),
            Bench("Baxter holding a 0.3 m box", baxter, box, {"timeout": 0.05})]


def prefer_benches(n: int, seed: int) -> list[Bench]:
    """prefer="nearest" / "manipulability" on Panda and UR10 (bench_goal_kinds_prefer.py's targets and q0, its
    default budget) and its goal sets of 10 Panda grasps, 7 unreachable."""
    out = []
    for name in ("panda", "ur10"):
        robot = ek.load_robot(name)
        targets, Q0 = prefer.problems(robot, n, seed)

        def pose_judge(T, robot=robot):
            return lambda q: prefer.met(robot, T, q, TOL)

        for how in ("nearest", "manipulability"):
            problems = [Problem([Pose(robot.tip, T)], {"seed": i, "q0": q0, "prefer": how}, pose_judge(T))
                        for i, (T, q0) in enumerate(zip(targets, Q0, strict=True))]
            out.append(Bench(f"{name} `prefer=\"{how}\"`", robot, problems, {}))
    panda = ek.load_robot("panda")
    sets, _ = prefer.goal_set_problems(panda, n, seed + 1)

    def set_judge(members):
        return lambda q: any(prefer.met(panda, T, q, TOL) for T in members)

    problems = [Problem(goals, {"seed": i}, set_judge([m.target for m in goals[0].alternatives]))
                for i, goals in enumerate(sets)]
    out.append(Bench("Panda goal sets (10 grasps, 7 unreachable)", panda, problems, {}))
    return out


BENCHES = {"axes": axes_benches, "balance": balance_benches, "prefer": prefer_benches}
#: The benchmarks' short names (``--only``), in the order of BENCHES' groups.
NAMES = {"ur5_free": ("axes", 0), "ur5_band": ("axes", 1), "romeo": ("axes", 2), "talos": ("balance", 0),
         "baxter": ("balance", 1), "panda_nearest": ("prefer", 0), "panda_manip": ("prefer", 1),
         "ur10_nearest": ("prefer", 2), "ur10_manip": ("prefer", 3), "panda_sets": ("prefer", 4)}
#: Each group's seed in its own script's default (so the problems are those of its report).
SEEDS = {"axes": 23, "balance": 0, "prefer": 0}


# ------------------------------------------------------------------ measuring
def posture_distance(q: np.ndarray, q_ref: np.ndarray, wrap: np.ndarray) -> float:
    """Mean over the joints of ``|q - q_ref|`` (rad or m), full-turn joints at the nearest turn."""
    return float(np.mean(np.abs(turn_difference(q, q_ref, wrap))))


def limit_margins(q: np.ndarray, lower: np.ndarray, upper: np.ndarray, wrap: np.ndarray) -> tuple[float, float]:
    """(the smallest distance (rad or m) of a joint to its limits, the summed shortfall of the joints closer than
    :data:`MARGIN`: ``sum max(0, MARGIN - distance)``), the full-turn joints (no limit to keep off) left out;
    (nan, nan) when every joint turns fully."""
    d = np.minimum(q - lower, upper - q)[~wrap]
    if not d.size:
        return np.nan, np.nan
    return float(d.min()), float(np.maximum(0.0, MARGIN - d).sum())


def run_bench(bench: Bench, budgets: dict, log) -> None:
    """Solve every problem of ``bench`` the three ways under each budget (``{name: solve's options}``), the ways
    interleaved problem by problem; ``bench.rows[budget][way]`` = list of (solved, wall s, q)."""
    robot = bench.robot
    ek.prepare(robot)
    prefs = {WAYS[0]: [], WAYS[1]: [Posture(bench.q_ref, 1.0)], WAYS[2]: [JointLimitMargin(MARGIN)]}
    first = bench.problems[0]
    for way in WAYS:  # one-time set-up (seed tables, the null-space kernel) before any clock
        ek.solve(robot, first.goals + prefs[way], **{**first.options, "seed": 0})
    for budget, options in budgets.items():
        rows = bench.rows[budget] = {way: [] for way in WAYS}
        for p in bench.problems:
            for way in WAYS:
                t = time.perf_counter()
                r = ek.solve(robot, p.goals + prefs[way], **{**p.options, **options})
                dt = time.perf_counter() - t
                rows[way].append((bool(r.success and p.judge(r.q)), dt, r.q, r.message))
        log(f"{bench.name} [{budget}]: " + ", ".join(f"{w} {sum(r[0] for r in rows[w])}/{len(rows[w])}"
                                                    for w in WAYS))


def report_rows(bench: Bench) -> list[str]:
    """The benchmark's table rows, one per budget."""
    robot = bench.robot
    out = []
    for budget, rows in bench.rows.items():
        ok = {w: np.array([r[0] for r in rows[w]]) for w in WAYS}
        med = {w: float(np.median([r[1] for r in rows[w]])) * 1e3 for w in WAYS}
        n = ok[WAYS[0]].size
        lost = {w: int((ok[WAYS[0]] & ~ok[w]).sum()) for w in WAYS[1:]}
        gained = {w: int((~ok[WAYS[0]] & ok[w]).sum()) for w in WAYS[1:]}
        every = ok[WAYS[0]] & ok[WAYS[1]] & ok[WAYS[2]]
        idx = np.nonzero(every)[0]

        def qs(way, idx=idx, rows=rows):
            return [rows[way][i][2] for i in idx]

        dist = [np.mean([posture_distance(q, bench.q_ref, bench.wrap) for q in qs(w)]) if idx.size else np.nan
                for w in WAYS[:2]]
        marg = [np.array([limit_margins(q, robot.lower, robot.upper, bench.wrap) for q in qs(w)]).reshape(-1, 2)
                for w in (WAYS[0], WAYS[2])]
        medm = [float(np.median(m[:, 0])) if m.size else np.nan for m in marg]
        short = [float(np.mean(m[:, 1])) if m.size else np.nan for m in marg]
        effect = ("- (no joint with limits)" if np.isnan(medm[0]) and idx.size else
                  f"{medm[0]:.3f} -> {medm[1]:.3f} ({short[0]:.3f} -> {short[1]:.3f})")
        success = " / ".join(f"{100 * ok[w].mean():.1f}" for w in WAYS)
        changes = " / ".join(f"-{lost[w]} +{gained[w]}" for w in WAYS[1:])
        times = " / ".join(f"{med[w]:.2f}" for w in WAYS)
        ratios = " / ".join(f"{med[w] / med[WAYS[0]]:.2f}x" for w in WAYS[1:])
        out.append(f"| {bench.name} | {budget} | {n} | {success} | {changes} | {times} | {ratios} | "
                   f"{dist[0]:.3f} -> {dist[1]:.3f} | {effect} |")
        for w in WAYS[1:]:
            out_lost = [i for i in range(n) if rows[WAYS[0]][i][0] and not rows[w][i][0]]
            LOST.extend(f"{bench.name} [{budget}] {w}, problem {i}: {rows[w][i][3]}" for i in out_lost)
    return out


def run(args) -> str:
    """Every selected benchmark under both budgets; the markdown section (without the docs markers)."""
    def log(msg: str) -> None:
        if args.verbose:
            print(msg, file=sys.stderr, flush=True)

    wanted = args.only or list(NAMES)
    fixed = {"timeout": None, "max_restarts": args.restarts}
    load0, t0 = os.getloadavg(), time.time()
    lines = []
    for group, make in BENCHES.items():
        picked = [k for name, (g, k) in NAMES.items() if g == group and name in wanted]
        if not picked:
            continue
        benches = make(args.n, SEEDS[group])
        for k in picked:
            bench = benches[k]
            run_bench(bench, {"time": bench.budget, "fixed": fixed}, log)
            lines += report_rows(bench)
    load1 = os.getloadavg()
    command = "python scripts/bench_goal_kinds_preferences.py" + ("" if not args.argv else " " + " ".join(args.argv))
    head = [f"Run {datetime.datetime.now().strftime('%Y-%m-%d %H:%M')}, `{command}`, {cpu_model()}, "
            f"{os.cpu_count()} cores, Python {platform.python_version()}; load average {load0[0]:.2f} before, "
            f"{load1[0]:.2f} after ({time.time() - t0:.0f} s; a shared machine: other engineers' jobs ran beside "
            "this, so times are noisy; the three ways ran interleaved, problem by problem, so their ratios are "
            f"fairer). Budgets: `time` is each benchmark's own, `fixed` is `timeout=None, max_restarts="
            f"{args.restarts}`. Posture: `Posture(q_ref, 1.0)`, q_ref the middle of the limits (Talos's base at "
            f"the stance); JointLimitMargin: `JointLimitMargin({MARGIN:g})`. Success: `Result.success` and the "
            "benchmark's own judge of the answer (see the script's docstring).", "",
            "| benchmark | budget | problems | success % (alone / + Posture / + JointLimitMargin) | lost, gained "
            "against alone (+ Posture / + JLM) | median ms (alone / + Posture / + JLM) | time ratio (+ Posture / "
            "+ JLM) | mean abs(q - q_ref), alone -> + Posture | min distance to a limit, alone -> + JLM (mean summed "
            "shortfall below 0.1) |",
            "|---|---|---|---|---|---|---|---|---|"]
    tail = ["", "Problems a preference lost (solved by the goals alone, not with it):"]
    tail += [f"- {text}" for text in LOST] or ["- none."]
    return "\n".join(head + lines + tail) + "\n"


def write_docs(text: str) -> None:
    """Replace this script's own section of docs/BENCHMARKS.md (between its markers), or append it."""
    write_block(DOCS, BEGIN, END, text, TITLE)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=100, help="problems per benchmark (default 100)")
    parser.add_argument("--restarts", type=int, default=5, help="max_restarts of the fixed budget (default 5)")
    parser.add_argument("--only", nargs="+", choices=list(NAMES), help="benchmarks to run (default all)")
    parser.add_argument("--verbose", action="store_true", help="each benchmark's counts on stderr as it ends")
    parser.add_argument("--docs", action="store_true", help="write the section into docs/BENCHMARKS.md")
    args = parser.parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)
    text = run(args)
    print(text)
    if args.docs:
        write_docs(text)
        print(f"wrote {DOCS}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
