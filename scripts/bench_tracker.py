#!/usr/bin/env python
"""Motions within velocity limits: evoik_pin's trajectories and Tracker against pink's and PlaCo's differential-IK
step.

    python scripts/bench_tracker.py                        # Panda, Talos, G1; writes docs/BENCHMARKS.md's section
    python scripts/bench_tracker.py --no-peers --no-docs   # evoik_pin alone, printed

Targets: the forward kinematics of smooth random joint paths (a sine per joint, each joint's speed at most half its
velocity limit, inside its bounds), so every target is reachable within the limits by construction. Goals: Panda's
tool frame (pose); Talos's and G1's feet and wrists (four poses, ``goal_problems.ROBOT_SETS``), floating base.

1. Trajectories (``evoik_pin.solve_trajectory(robot, goal_lists, dt=0.01, velocity_limits=True, q0=path[0])``),
   Panda and Talos, with and without an infeasible stretch (targets of 15 points moved 0.5 m): velocity-limit
   violations (steps beyond ``v_max dt`` on any entry, 1e-12 for rounding), the largest step as a fraction of its
   limit (a branch flip would be far above 1), reachable points solved (outside the stretch and the points after it
   until the robot is back on the path: every point once the first success after the stretch came).
2. Tracking (1 kHz for Panda, 500 Hz for the humanoids, ``--steps`` steps): per-step wall time (median, p99) of
   ``Tracker.step`` (evoik_pin), of pink's ``solve_ik`` + ``integrate_inplace`` (FrameTasks on the same frames, daqp,
   its ``ConfigurationLimit`` and ``VelocityLimit`` with the same dt) and of PlaCo's ``solve(True)`` +
   ``update_kinematics`` (frame tasks, joint and velocity limits, the same dt), each from the path's first
   configuration following the same targets; the tracking error each leaves (the largest goal position error m and
   rotation angle rad after the step, by Pinocchio forward kinematics on the problems file's model, the same judge
   for all): steps with every goal within 1e-6 (m, rad), median and largest error. The peers run in their own
   environment (``/work/peers-venv``, ``--peers-python``) as a subprocess of this script (``--peer-side``), with
   ``peers_runner.py``'s models and tasks, on the same problems file.
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

SCRIPTS = Path(__file__).resolve().parent
sys.path.insert(0, str(SCRIPTS))
import goal_problems as gp  # noqa: E402
from docs_block import write_block  # noqa: E402

DOCS = SCRIPTS.parent / "docs" / "BENCHMARKS.md"
BEGIN, END = "<!-- bench_tracker:begin -->", "<!-- bench_tracker:end -->"
PEERS_PYTHON = Path(os.environ.get("PEERS_VENV", "/work/peers-venv")) / "bin" / "python"
#: m and rad: a goal "met" by any method.
MET = 1e-6
#: The benchmark's robots: (goal_problems' set, evoik_pin's name, control period s).
ROBOTS = {"panda": ("panda", 0.001), "talos": ("talos", 0.002), "g1": ("g1", 0.002)}
gp.ROBOT_SETS.setdefault("panda", gp.RobotSet("panda_description/urdf/panda.urdf", False,
                                              (("panda_hand_tcp", "pose"),), "Franka Panda; the tool frame, pose"))


# ------------------------------------------------------------------------------------------------ the peers' side
def peer_side(problems_path: Path, out_path: Path) -> None:
    """In the peers' environment: each peer follows the file's steps from its start, one QP step per target."""
    import logging

    import peers_runner as pr

    logging.getLogger().setLevel(logging.ERROR)  # pink warns whenever a joint touches its limit
    problems = gp.load_problems(problems_path)
    dt = problems["dt"]
    steps = [gp.parse_goals(s) for s in problems["steps"]]
    q_start = np.array(problems["q_start"])
    model = gp.model_of(problems)
    data = model.createData()
    frame_ids = [model.getFrameId(g["frame"]) for g in problems["goals"]]
    out = {"versions": pr._versions(), "peers": {}}
    for name in ("pink", "placo"):
        cls, settings_cls = pr.PEERS[name]
        settings = settings_cls()
        settings.dt = dt
        settings.velocity_limit = 1
        peer = cls(problems, settings, pr.Common())
        times, errors, qs = [], [], []
        if name == "pink":
            configuration = peer.pink.Configuration(peer.model, peer.data, pr._from_full(peer.q0, q_start, peer.maps))
            for goals in steps:
                for task, goal in zip(peer.tasks, goals, strict=True):
                    task.set_target(pr._se3(goal))
                t0 = time.perf_counter()
                v = peer.pink.solve_ik(configuration, peer.tasks, dt, solver="daqp", damping=settings.damping,
                                       limits=peer.limits, safety_break=False)
                configuration.integrate_inplace(v, dt)
                times.append(time.perf_counter() - t0)
                qs.append(pr._to_full(peer.q_full0, configuration.q, peer.maps))
        else:
            peer.robot.state.q = pr._from_full(peer.q0, q_start, peer.maps)
            peer.robot.update_kinematics()
            for goals in steps:
                for task, goal in zip(peer.tasks, goals, strict=True):
                    if goal["kind"] == "pose":
                        task.T_world_frame = goal["target"]
                    else:
                        task.target_world = goal["target"]
                t0 = time.perf_counter()
                peer.solver.solve(True)
                peer.robot.update_kinematics()
                times.append(time.perf_counter() - t0)
                qs.append(pr._to_full(peer.q_full0, np.array(peer.robot.state.q), peer.maps))
        for q, goals in zip(qs, steps, strict=True):
            pin.framesForwardKinematics(model, data, q)
            errors.append(gp.goal_errors(data, frame_ids, goals).max(axis=0).tolist())
        out["peers"][name] = {"wall_s": times, "errors": errors}
    out_path.write_text(json.dumps(out), encoding="utf-8")


# ------------------------------------------------------------------------------------------------ evoik_pin's side
#: The paths' centres (rad; the others: zero, clipped into the bounds): Panda's "ready" pose (franka_ros), away
#: from its shoulder singularity (joint 2 at 0, joints 1 and 3 aligned), where a path's own self-motion is not
#: followed by a velocity-limited answer and it falls behind when the joints come apart (see the docs' section).
CENTRES = {"panda": np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])}


def smooth_path(robot, steps: int, dt: float, seed: int, fraction: float = 0.5) -> np.ndarray:
    """(steps, n) q(t) = c + A sin(2 pi f t + phase): each entry's speed at most ``fraction`` of its limit (rad/s,
    m/s), every row inside the bounds (amplitude at most 0.3 of the half range and 0.3 rad or m), c the robot's
    centre (:data:`CENTRES`, else zero) moved inside the bounds."""
    from evoik_pin.robot.velocity_limits import urdf_velocity_limits

    rng = np.random.default_rng(seed)
    lo, hi = robot.lower, robot.upper
    f = rng.uniform(0.2, 0.5, robot.n)
    A = np.minimum(np.minimum((hi - lo) / 2, 1.0) * 0.3, fraction * urdf_velocity_limits(robot) / (2 * np.pi * f))
    c = np.clip(CENTRES.get(robot.name, np.zeros(robot.n)), lo + 1.01 * A, hi - 1.01 * A)
    t = np.arange(steps)[:, None] * dt
    return c + A * np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi, robot.n))


def load_robot(name: str):
    import evoik_pin as ek

    spec = gp.ROBOT_SETS[name]
    robot = ek.load_robot(name, tips=[f for f, _ in spec.goals], floating_base=spec.floating_base)
    return robot, [f for f, _ in spec.goals]


def goal_lists(robot, frames, Q):
    from evoik_pin.goals import Pose

    return [[Pose(f, robot.fk(q, frame=f)) for f in frames] for q in Q]


def judge(model, data, frame_ids, frames, configurations, targets) -> np.ndarray:
    """(N, 2) the largest goal position error (m) and rotation angle (rad) of each configuration (Pinocchio FK)."""
    out = np.empty((len(configurations), 2))
    for i, (q, goals) in enumerate(zip(configurations, targets, strict=True)):
        pin.framesForwardKinematics(model, data, q)
        out[i] = gp.goal_errors(data, frame_ids, goals).max(axis=0)
    return out


def trajectories(steps: int) -> list[str]:
    """Part 1: solve_trajectory on Panda and Talos, with and without an infeasible stretch; table rows."""
    import evoik_pin as ek
    from evoik_pin.robot.velocity_limits import urdf_velocity_limits

    rows = []
    dt = 0.01
    for name in ("panda", "talos"):
        robot, frames = load_robot(name)
        limit = urdf_velocity_limits(robot) * dt
        warm = smooth_path(robot, 3, dt, seed=99)  # the kernels loaded and the seed table built before any clock
        ek.solve_trajectory(robot, goal_lists(robot, frames, warm), dt=dt, velocity_limits=True, seed=0)
        for seed in range(3):
            Q = smooth_path(robot, steps, dt, seed=seed)
            lists = goal_lists(robot, frames, Q)
            for stretch in (False, True):
                targets = lists
                if stretch:
                    from evoik_pin.goals import Pose

                    targets = list(lists)
                    for i in range(steps // 3, steps // 3 + 15):
                        targets[i] = [Pose(g.frame, pin.SE3(g.target.rotation, g.target.translation + [0.5, 0, 0]))
                                      for g in lists[i]]
                t0 = time.perf_counter()
                rs = ek.solve_trajectory(robot, targets, dt=dt, velocity_limits=True, q0=Q[0], seed=seed)
                wall = time.perf_counter() - t0
                answers = np.array([r.q for r in rs])
                moves = np.abs(np.diff(np.vstack([Q[0], answers]), axis=0)) / limit
                violations = int((moves > 1 + 1e-12 / limit.min()).any(axis=1).sum())
                ok = np.array([r.success for r in rs])
                reachable = np.ones(steps, dtype=bool)
                if stretch:  # the stretch and the points until the first success after it: out of the box's reach
                    start = steps // 3
                    back = start + 15 + int(np.argmax(ok[start + 15:])) if ok[start + 15:].any() else steps
                    reachable[start:back] = False
                worst = max([r.position_error for r, m in zip(rs, reachable, strict=True) if m], default=0.0)
                rows.append(f"| {name} | {seed} | {'yes' if stretch else 'no'} | {steps} | {violations} | "
                            f"{moves.max():.3f} | {int(ok[reachable].sum())} / {int(reachable.sum())} | "
                            f"{int((~ok[reachable]).sum())} | {worst:.1e} | {1e6 * wall / steps:.0f} |")
                print(rows[-1], flush=True)
    return rows


def tracking(name: str, steps: int, peers_python: Path | None, tmp: Path) -> dict:
    """Part 2 for one robot: evoik_pin's Tracker and (optionally) the peers on the same targets."""
    import evoik_pin as ek

    robot, frames = load_robot(name)
    dt = ROBOTS[name][1]
    Q = smooth_path(robot, steps + 1, dt, seed=7)
    problems = gp.make_problems(name, 1, 0)  # the file's model, joints, neutral and goals
    model = gp.model_of(problems)
    data = model.createData()
    frame_ids = [model.getFrameId(f) for f in frames]
    configurations = [robot.full_configuration(q) for q in Q]
    step_goals = [gp.frame_goals(model, data, q, gp.ROBOT_SETS[name].goals) for q in configurations[1:]]
    problems.update(dt=dt, q_start=configurations[0].tolist(), steps=step_goals, problems=[])
    lists = goal_lists(robot, frames, Q[1:])
    tracker = ek.Tracker(robot, dt=dt, q0=Q[0], seed=0)
    warm = ek.Tracker(robot, dt=dt, q0=Q[0], seed=0)
    warm.step(lists[0])  # the kernel loaded and the engines made outside the clock
    times, answers = [], []
    for goals in lists:
        t0 = time.perf_counter()
        r = tracker.step(goals)
        times.append(time.perf_counter() - t0)
        answers.append(r.q)
    parsed = [gp.parse_goals(s) for s in step_goals]
    out = {"evoik": {"wall_s": times, "errors": judge(model, data, frame_ids, frames,
                                                         [robot.full_configuration(q) for q in answers], parsed)}}
    if peers_python is not None:
        path, result = tmp / f"{name}.steps.json", tmp / f"{name}.peers.json"
        path.write_text(json.dumps(problems), encoding="utf-8")
        env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
        done = subprocess.run([str(peers_python), str(Path(__file__).resolve()), "--peer-side", str(path), "-o",
                               str(result)], capture_output=True, text=True, env=env)
        if done.returncode != 0:
            raise RuntimeError(f"peer side failed ({done.returncode}): {done.stderr.strip()[-2000:]}")
        peers = json.loads(result.read_text(encoding="utf-8"))
        out["versions"] = peers["versions"]
        for peer, entry in peers["peers"].items():
            out[peer] = {"wall_s": entry["wall_s"], "errors": np.array(entry["errors"])}
    return out


def tracking_rows(name: str, result: dict, steps: int) -> list[str]:
    rows = []
    for method in ("evoik", "pink", "placo"):
        if method not in result:
            continue
        t = 1e6 * np.array(result[method]["wall_s"])
        e = result[method]["errors"]
        met = int(((e[:, 0] <= MET) & (e[:, 1] <= MET)).sum())
        pos, rot = e[:, 0], e[:, 1]
        rows.append(f"| {name} | {method} | {np.median(t):.0f} | {np.percentile(t, 99):.0f} | {met} / {steps} | "
                    f"{np.median(pos):.1e} / {pos.max():.1e} | {np.median(rot):.1e} / {rot.max():.1e} |")
        print(rows[-1], flush=True)
    return rows


def write_docs(text: str) -> None:
    """Replace this script's own section of docs/BENCHMARKS.md (between its markers), or append it."""
    write_block(DOCS, BEGIN, END, text, "## Motions within velocity limits: trajectories and the Tracker against "
                "pink's and PlaCo's differential-IK step (scripts/bench_tracker.py)")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--peer-side", type=Path, help=argparse.SUPPRESS)
    ap.add_argument("-o", "--out", type=Path, help=argparse.SUPPRESS)
    ap.add_argument("--steps", type=int, default=300, help="tracking steps per robot (default 300)")
    ap.add_argument("--points", type=int, default=120, help="trajectory points per path (default 120)")
    ap.add_argument("--robots", default="panda,talos,g1", help="tracking robots (default panda,talos,g1)")
    ap.add_argument("--no-peers", action="store_true", help="evoik_pin alone")
    ap.add_argument("--no-docs", action="store_true", help="print only; do not write docs/BENCHMARKS.md")
    ap.add_argument("--peers-python", type=Path, default=PEERS_PYTHON, help=f"default {PEERS_PYTHON}")
    args = ap.parse_args(argv)
    if args.peer_side is not None:
        peer_side(args.peer_side, args.out)
        return 0
    if not args.no_peers and not args.peers_python.is_file():
        ap.error(f"no {args.peers_python}: run scripts/peers_venv.sh, or pass --no-peers")
    load0 = os.getloadavg()[0]
    print("| robot | path | infeasible stretch | points | velocity violations | largest step / limit | "
          "reachable points solved | reachable points failed | largest error there (m) | us per point |")
    traj = trajectories(args.points)
    track, versions = [], None
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.robots.split(","):
            result = tracking(name, args.steps, None if args.no_peers else args.peers_python, Path(tmp))
            versions = result.get("versions", versions)
            track += tracking_rows(name, result, args.steps)
    load1 = os.getloadavg()[0]
    cmd = "python scripts/bench_tracker.py" + ("" if not argv else " " + " ".join(argv))
    ours = ", ".join(f"{p} {md.version(p)}" for p in ("numpy", "pin", "numba"))
    theirs = "" if not versions else "; peers: " + ", ".join(f"{k} {v}" for k, v in versions.items() if v)
    text = "\n".join([
        f"Date: {datetime.date.today()}. Command: `{cmd}`. Machine: {platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, {ours}{theirs}; shared with other work (load average {load0:.1f} at "
        f"the start, {load1:.1f} at the end).",
        "",
        "Targets: forward kinematics of smooth random joint paths (each joint at most half its velocity limit), "
        "so every point is reachable within the limits; see the script's docstring for the definitions.",
        "",
        "Trajectories: `solve_trajectory(robot, goal_lists, dt=0.01, velocity_limits=True, q0=path[0])`; the "
        "infeasible stretch moves 15 points' targets 0.5 m; 'reachable' excludes the stretch and the points until "
        "the robot is back on the path.",
        "",
        "| robot | path | infeasible stretch | points | velocity violations | largest step / limit | "
        "reachable points solved | reachable points failed | largest error there (m) | us per point |",
        "|---|---|---|---|---|---|---|---|---|---|",
        *traj,
        "",
        f"Tracking: {args.steps} steps per robot (Panda at 1 kHz, Talos and G1 with four pose goals at 500 Hz); "
        f"per-step wall time in us; 'goals met': steps with every goal within {MET:g} m and rad after the step "
        "(Pinocchio FK, the same judge for all); errors median / largest over the steps.",
        "",
        "| robot | method | median us | p99 us | goals met | position error (m) | rotation error (rad) |",
        "|---|---|---|---|---|---|---|",
        *track,
    ])
    print(text)
    if not args.no_docs:
        write_docs(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
