#!/usr/bin/env python
"""Whole-robot IK (several goals in one solve): evoik_pin's memetic against pink and PlaCo, judged alike.

    python scripts/bench_goals.py                          # 200 problems per robot, every robot, stdout
    python scripts/bench_goals.py --n 20 --robots talos go2
    python scripts/bench_goals.py --docs                   # also writes docs/BENCHMARKS.md's bench_goals block
    python scripts/bench_goals.py --no-peers --n 50        # evoik alone (profiling)

For each robot of ``goal_problems.ROBOT_SETS`` (talos, baxter, go2, allegro, pr2, tiago_dual (TIAGo++), g1,
solo12: their frames and kinds) it generates ``--n`` problems (``goal_problems.make_problems``: targets by forward
kinematics of random configurations within the limits, a free-flyer base within a 0.5 m cube and 30 deg of
upright), then, interleaved robot by robot so that both sides see the same machine state:

1. evoik_pin: ``evoik_pin.solve(robot, goals, seed=i)`` with the library's defaults (memetic, its 5 ms budget per
   problem), the robot loaded by name with the goal frames as its tips (active joints: the union of their chains,
   as the peers' reduced models) and ``floating_base`` as the problem set says. One solve before the timed ones
   builds the seed table and loads the compiled kernel (one-time set-up, reported apart). Answers become the
   problems file's Pinocchio configurations by ``robot.full_configuration``; that our model and the file's agree
   on the joint order and on the free-flyer's 7 numbers is checked first (forward kinematics of every goal frame
   at random configurations, both ways, to 1e-12).
2. the peers, in their own virtual environment (``peers_runner.py`` under ``--peers-python``): pink and PlaCo
   from the neutral configuration with their documented best settings (printed with the results) and 0.2 s of
   their own wall time per problem.
3. every answer judged by ``judge_goals.judge`` (Pinocchio forward kinematics of the answer, joints in limits):
   success means every goal within 1e-6 m and rad.

Per robot it prints success at 1e-6 (and 1e-5, 1e-4), median and p90 wall time per problem, and the median time
on the problems that evoik and the faster peer both solve, with the ratio (peer / evoik). The faster peer is the
one with the smaller median time on the problems it and evoik both solve. The load average is read before and
after each robot.
"""

from __future__ import annotations

import argparse
import datetime
import importlib.metadata as md
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

import evoik_pin as ek
from evoik_pin.goals import Pose, Position

SCRIPTS = Path(__file__).resolve().parent
sys.path.insert(0, str(SCRIPTS))
import goal_problems as gp  # noqa: E402
import judge_goals as jg  # noqa: E402
from docs_block import write_block  # noqa: E402

ROOT = SCRIPTS.parent
DOCS = ROOT / "docs" / "BENCHMARKS.md"
BEGIN, END = "<!-- bench_goals:begin -->", "<!-- bench_goals:end -->"
#: The benchmark's robots (goal_problems' names) and the names evoik_pin loads them by.
EVOIK_NAMES = {"talos": "talos", "baxter": "baxter", "go2": "go2", "allegro": "allegro_right", "pr2": "pr2",
               "tiago_dual": "tiago_dual", "g1": "g1", "solo12": "solo12"}
PEERS_PYTHON = Path(os.environ.get("PEERS_VENV", "/work/peers-venv")) / "bin" / "python"
TOL = jg.TOLERANCES[0]


def load_evoik_robot(problems: dict) -> ek.Robot:
    """The problems file's robot loaded by evoik_pin: by name, tips = the goal frames, its floating base."""
    name = EVOIK_NAMES[problems["robot"]]
    robot = ek.load_robot(name, tips=[g["frame"] for g in problems["goals"]],
                          floating_base=problems["floating_base"])
    if Path(robot.urdf_path).resolve() != Path(problems["urdf"]).resolve():
        raise ValueError(f"evoik_pin's {name!r} is {robot.urdf_path}, the problems file's {problems['urdf']}")
    return robot


def check_same_model(robot: ek.Robot, problems: dict, model: pin.Model, trials: int = 5) -> float:
    """Check that ``robot.full_configuration`` gives the problems file's model (``model``) configurations that
    place every goal frame where ``robot.fk`` does (joint order, free-flyer position and quaternion), at
    ``trials`` random configurations; returns the largest difference (m or rotation-matrix entry).

    Raises:
        ValueError: a difference above 1e-12, or a configuration of the wrong size.
    """
    data = model.createData()
    worst = 0.0
    rng = np.random.default_rng(12345)
    frames = [g["frame"] for g in problems["goals"]]
    for q in robot.random_configurations(trials, rng):
        qf = robot.full_configuration(q)
        if qf.shape != (model.nq,):
            raise ValueError(f"full_configuration gives {qf.shape[0]} numbers, the file's model has nq={model.nq}")
        pin.framesForwardKinematics(model, data, qf)
        for f in frames:
            ours, theirs = robot.fk(q, f), data.oMf[model.getFrameId(f)]
            worst = max(worst, float(np.abs(ours.translation - theirs.translation).max()),
                        float(np.abs(ours.rotation - theirs.rotation).max()))
    if worst > 1e-12:
        raise ValueError(f"{problems['robot']}: evoik_pin's model and the problems file's differ by {worst:.2e}")
    return worst


def goals_of(problem: dict) -> list:
    """evoik_pin goals of one problem (targets in the world frame: the URDF root or the free-flyer's world)."""
    return [Pose(g["frame"], np.asarray(g["target"])) if g["kind"] == "pose"
            else Position(g["frame"], np.asarray(g["target"])) for g in problem["goals"]]


def run_evoik(robot: ek.Robot, problems: dict, options: dict) -> dict:
    """Solve every problem; answers (Pinocchio configurations of the file's model), wall times (s), messages."""
    goal_lists = [goals_of(p) for p in problems["problems"]]
    warm = ek.solve(robot, goal_lists[0], seed=10**6, **options)  # seed table and kernel: one-time set-up
    answers, times, messages = [], [], []
    for i, goals in enumerate(goal_lists):
        t0 = time.perf_counter()
        r = ek.solve(robot, goals, seed=i, **options)
        times.append(time.perf_counter() - t0)
        answers.append(robot.full_configuration(r.q))
        messages.append(r.message)
    return {"q": answers, "wall_s": times, "messages": messages, "setup_s": warm.setup_s}


def run_peers(problems_path: Path, out_path: Path, peers_python: Path, budget: float) -> dict:
    """``peers_runner.py`` on a problems file in the peers' environment; its results (JSON)."""
    cmd = [str(peers_python), str(SCRIPTS / "peers_runner.py"), str(problems_path), "-o", str(out_path),
           "--budget", str(budget)]
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    done = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if done.returncode != 0:
        raise RuntimeError(f"peers_runner failed ({done.returncode}): {done.stderr.strip()[-2000:]}")
    return json.loads(out_path.read_text(encoding="utf-8"))


def _stats(rows: list[dict], times_s) -> dict:
    t = np.asarray(times_s, dtype=float)
    return {"ok": jg.solved_at(rows, TOL), "rates": [float(jg.solved_at(rows, x).mean()) for x in jg.TOLERANCES],
            "median_ms": 1e3 * float(np.median(t)), "p90_ms": 1e3 * float(np.percentile(t, 90)), "t": t,
            "out_of_limits": sum(not r["within_limits"] for r in rows if r["answered"])}


def robot_report(problems: dict, evoik: dict, peers: dict | None, model: pin.Model, loads: tuple,
                 extra: dict | None = None, agreement: float = 0.0) -> tuple[str, dict]:
    """Markdown lines for one robot and the numbers behind them (``extra``: evoik_pin runs with other budgets, by
    row name; ``agreement``: :func:`check_same_model`'s largest difference)."""
    n = len(problems["problems"])
    sides = {"evoik_pin (memetic)": _stats(jg.judge(problems, evoik["q"], model=model), evoik["wall_s"])}
    for name, run in (extra or {}).items():
        sides[name] = _stats(jg.judge(problems, run["q"], model=model), run["wall_s"])
    for name, entry in (peers or {}).get("peers", {}).items():
        answers = entry["answers"]
        sides[name] = _stats(jg.judge(problems, [a["q"] for a in answers], model=model),
                             [a["wall_s"] for a in answers])
    ev = sides["evoik_pin (memetic)"]
    both = {}
    for name, s in sides.items():
        if name.startswith("evoik_pin"):
            continue
        common = ev["ok"] & s["ok"]
        if common.any():
            both[name] = (int(common.sum()), 1e3 * float(np.median(ev["t"][common])),
                          1e3 * float(np.median(s["t"][common])))
    faster = min(both, key=lambda k: both[k][2]) if both else None
    spec = gp.ROBOT_SETS[problems["robot"]]
    lines = [f"### {problems['robot']} ({n} problems; {spec.note})", "",
             f"Load average {loads[0]:.2f} before, {loads[1]:.2f} after; evoik_pin's one-time set-up (seed table, "
             f"kernel load) {evoik['setup_s']:.2f} s, outside the times; its answers mapped by "
             f"`robot.full_configuration` onto the file's model (goal frames agree to {agreement:.0e} m).", "",
             "| solver | ok 1e-6 | ok 1e-5 | ok 1e-4 | median ms | p90 ms | out of limits |"
             " both solve: n | evoik ms | peer ms | peer / evoik |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for name, s in sides.items():
        rates = " | ".join(f"{100 * r:.1f}%" for r in s["rates"])
        tail = " | | | |"
        if name in both:
            k, te, tp = both[name]
            mark = " (faster peer)" if name == faster else ""
            tail = f" | {k} | {te:.2f} | {tp:.2f} | {tp / te:.1f}x{mark} |"
        lines.append(f"| {name} | {rates} | {s['median_ms']:.2f} | {s['p90_ms']:.2f} | {s['out_of_limits']}{tail}")
    fails = [m for m, ok in zip(evoik["messages"], ev["ok"], strict=True) if not ok]
    if fails:
        lines += ["", f"evoik_pin's failures ({len(fails)}): " + "; ".join(sorted(set(fails))[:3])]
    numbers = {name: {"success": s["rates"][0], "median_ms": s["median_ms"], "p90_ms": s["p90_ms"]}
               for name, s in sides.items()}
    numbers["faster_peer"] = faster
    if faster is not None:
        numbers["both"] = dict(zip(("n", "evoik_ms", "peer_ms"), both[faster], strict=True))
    return "\n".join(lines) + "\n", numbers


def peer_settings_text(peers: dict) -> str:
    """Lines naming the peers' settings, stopping rules and versions (from a results file)."""
    common = peers["common"]
    out = [f"Peers (`scripts/peers_runner.py`, its docstring says how the settings were chosen): from the neutral "
           f"configuration, stop when every goal is below {common['stop_tol']:g} m and rad, after "
           f"{common['stall_iters']} iterations without the best error shrinking below {common['stall_ratio']:g} of "
           f"its old value, or after {common['budget']:g} s of wall time."]
    for name, entry in peers["peers"].items():
        settings = ", ".join(f"{k}={v}" for k, v in entry["settings"].items())
        out.append(f"- {name}: {settings}")
    versions = ", ".join(f"{k} {v}" for k, v in peers["versions"].items() if v)
    out.append(f"- peers' environment: {versions}")
    return "\n".join(out)


def header(args, argv: list[str]) -> str:
    cmd = "python scripts/bench_goals.py" + ("" if not argv else " " + " ".join(argv))
    versions = ", ".join(f"{p} {md.version(p)}" for p in ("numpy", "pin", "numba", "example-robot-data"))
    budget = "its default 5 ms" if args.timeout is None else f"timeout={args.timeout:g} s"
    return (f"Date: {datetime.date.today()}. Command: `{cmd}`.\n"
            f"Machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, {versions}; "
            f"shared with other work (load averages per robot below).\n\n"
            f"evoik_pin: `evoik_pin.solve(robot, goals, seed=i)`, memetic with {budget} per problem, the robot "
            f"loaded by name with the goal frames as tips. Success: every goal within {TOL:g} m and rad by "
            f"Pinocchio forward kinematics of the answer, joints within limits (`scripts/judge_goals.py`, the same "
            f"judge for all). Times: wall clock per problem. 'both solve': the problems solved by evoik_pin and by "
            f"that peer, with each one's median time on them.\n")


def write_docs(text: str) -> None:
    """Replace this script's own section of docs/BENCHMARKS.md (between its markers), or append it."""
    write_block(DOCS, BEGIN, END, text, "## Whole robots: evoik_pin against pink and PlaCo (scripts/bench_goals.py)")


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=200, help="problems per robot (default 200)")
    ap.add_argument("--seed", type=int, default=0, help="problem set's seed (default 0)")
    ap.add_argument("--robots", nargs="+", choices=list(gp.ROBOT_SETS), default=list(gp.ROBOT_SETS))
    ap.add_argument("--timeout", type=float, help="evoik_pin's budget per problem, s (default: memetic's, 5 ms)")
    ap.add_argument("--also-timeout", type=float,
                    help="a second evoik_pin row with this budget per problem, s (e.g. 0.05 on a loaded machine)")
    ap.add_argument("--no-peers", action="store_true", help="evoik_pin alone")
    ap.add_argument("--peers-python", type=Path, default=PEERS_PYTHON, help=f"default {PEERS_PYTHON}")
    ap.add_argument("--peer-budget", type=float, default=0.2, help="s of wall time per problem (default 0.2)")
    ap.add_argument("--json", type=Path, help="write the numbers here")
    ap.add_argument("--docs", action="store_true", help="write the tables into docs/BENCHMARKS.md")
    args = ap.parse_args(argv)
    if args.n < 1:
        ap.error("--n must be at least 1")
    if not args.no_peers and not args.peers_python.is_file():
        ap.error(f"no {args.peers_python}: run scripts/peers_venv.sh, or pass --no-peers")
    options = {} if args.timeout is None else {"timeout": args.timeout}
    parts, numbers, settings = [], {}, None
    print(header(args, argv), flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.robots:
            problems = gp.make_problems(name, args.n, args.seed)
            path = Path(tmp) / f"{name}.json"
            path.write_text(json.dumps(problems), encoding="utf-8")
            problems = gp.load_problems(path)
            model = gp.model_of(problems)
            robot = load_evoik_robot(problems)
            agreement = check_same_model(robot, problems, model)
            load0 = os.getloadavg()[0]
            evoik = run_evoik(robot, problems, options)
            extra = {}
            if args.also_timeout is not None:
                extra[f"evoik_pin (timeout={args.also_timeout:g} s)"] = run_evoik(robot, problems,
                                                                                 {"timeout": args.also_timeout})
            peers = None if args.no_peers else run_peers(path, Path(tmp) / f"{name}.peers.json",
                                                        args.peers_python, args.peer_budget)
            text, numbers[name] = robot_report(problems, evoik, peers, model, (load0, os.getloadavg()[0]), extra,
                                               agreement)
            if peers is not None:
                settings = peers
            print(text, flush=True)
            parts.append(text)
    if settings:
        print(peer_settings_text(settings))
    out = header(args, argv) + "\n" + (peer_settings_text(settings) + "\n\n" if settings else "") + "\n".join(parts)
    if args.json:
        args.json.write_text(json.dumps(numbers, indent=1), encoding="utf-8")
    if args.docs:
        write_docs(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
