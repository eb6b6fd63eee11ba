#!/usr/bin/env python
"""Benchmark collision-aware IK: a Panda reaching into a shelf on a table, against TRAC-IK + reject-and-retry.

Targets: the tip poses of random collision-free configurations with the tip inside the shelf
(``evoik_pin.scene.examples``). Per target, in a fresh random order (so machine load hits all alike):

* ``evoik (scene)``: ``evoik_pin.solve(robot, T, scene=scene)`` (memetic, default 5 ms budget);
* ``evoik (no scene)``: the same without the scene: how often a collision-blind answer collides;
* ``TRAC-IK + reject/retry``: TRAC-IK from random seeds, each answer checked with the same exact mesh check,
  retried from a new random seed until one is collision-free or 5 ms have passed (each call keeps TRAC-IK's own
  5 ms timeout; its epsilon is set to 5e-7 so that its answers can meet the 1e-6 threshold below).

Success: position error <= 1e-6 m and rotation angle <= 1e-6 rad by our FK, joints within limits, and
collision-free by the exact mesh check (``Scene.in_collision``). Also self-collision-only success on Panda,
UR5 and Kinova (random reachable poses of collision-free configurations), and ``solve_many`` throughput with
and without the scene.

    python scripts/bench_collision.py                 # 500 shelf targets; writes docs/BENCHMARKS.md
    python scripts/bench_collision.py --targets 100 --no-docs
"""

from __future__ import annotations

import argparse
import datetime
import sys
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

import evoik_pin as ev
from evoik_pin.scene import Scene
from evoik_pin.scene.examples import SHELF_INTERIOR, add_table_and_shelf, free_configurations

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_ik import TracIK, cpu_model, quiet_output  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs" / "BENCHMARKS.md"
BEGIN, END = "<!-- bench_collision:begin -->", "<!-- bench_collision:end -->"
TOL = 1e-6
BUDGET = 0.005


def judge(robot, scene, T: pin.SE3, q) -> tuple[bool, bool]:
    """(pose within TOL and limits, collision-free) of an answer by our FK and the exact mesh check."""
    if q is None:
        return False, False
    Tq = robot.fk(q)
    pos = np.linalg.norm(Tq.translation - T.translation)
    rot = np.linalg.norm(pin.log3(T.rotation.T @ Tq.rotation))
    return bool(pos <= TOL and rot <= TOL and robot.within_bounds(q, 1e-9)), not scene.in_collision(q)


class TracIKRetry:
    """TRAC-IK from random seeds, rejecting colliding answers until one is free or the budget is spent."""

    name = "TRAC-IK + reject/retry"

    def __init__(self, robot, scene):
        self.robot, self.scene = robot, scene
        self.trac = TracIK(robot, timeout=BUDGET, epsilon=5e-7)
        self.available, self.why = self.trac.available, self.trac.why

    def __call__(self, T, rng):
        t_end = time.perf_counter() + BUDGET
        last = None
        while time.perf_counter() < t_end:
            q = self.trac(T, self.robot.random_configurations(1, rng)[0], 0)
            if q is not None:
                last = q
                if not self.scene.in_collision(q):
                    return q
        return last


def shelf_run(n: int, seed: int, log) -> dict:
    robot = ev.load_robot("panda")
    scene = add_table_and_shelf(Scene(robot))
    rng = np.random.default_rng(seed)
    Q = free_configurations(scene, n, rng, SHELF_INTERIOR)
    targets = [robot.fk(q) for q in Q]
    log(f"{len(targets)} shelf targets")
    with quiet_output():
        trac = TracIKRetry(robot, scene)
    ev.solve(robot, targets[0], scene=scene, seed=0)  # one-time set-up (kernel, seed table, its free entries)
    ev.solve(robot, targets[0], seed=0)
    solvers = {
        "evoik (scene)": lambda T, i, r: ev.solve(robot, T, scene=scene, seed=i).q,
        "evoik (no scene)": lambda T, i, r: ev.solve(robot, T, seed=i).q,
    }
    if trac.available:
        solvers[trac.name] = lambda T, i, r: trac(T, r)
    rows = {name: {"t": [], "ok": 0, "free": 0, "ok_free": 0, "false_success": 0} for name in solvers}
    order_rng = np.random.default_rng(seed + 1)
    for i, T in enumerate(targets):
        for name in order_rng.permutation(list(solvers)):
            t0 = time.perf_counter()
            q = solvers[name](T, i, np.random.default_rng(seed + 100 + i))
            rows[name]["t"].append(time.perf_counter() - t0)
            ok, free = judge(robot, scene, T, q)
            rows[name]["ok"] += ok
            rows[name]["free"] += free
            rows[name]["ok_free"] += ok and free
    # success=True answers that collide (must be none): re-solve with the scene and re-check
    false_success = sum(r.success and scene.in_collision(r.q) for r in
                        (ev.solve(robot, T, scene=scene, seed=i) for i, T in enumerate(targets)))
    rows["evoik (scene)"]["false_success"] = false_success
    H = np.array([T.homogeneous for T in targets])
    reps = max(1, 10_000 // len(targets))
    Hm = np.concatenate([H] * reps)
    tp = {}
    for label, kw in (("solve_many (scene)", {"scene": scene}), ("solve_many (no scene)", {})):
        ev.solve_many(robot, Hm[:10], seed=0, **kw)
        t0 = time.perf_counter()
        res = ev.solve_many(robot, Hm, seed=0, **kw)
        el = time.perf_counter() - t0
        free = sum(not scene.in_collision(r.q) for r in res[:: max(1, len(res) // 1000)])
        tp[label] = {"n": len(Hm), "per_s": len(Hm) / el, "success": res.stats["success_rate"],
                     "free_sampled": free / len(res[:: max(1, len(res) // 1000)])}
    return {"n": len(targets), "rows": rows, "throughput": tp}


def self_collision_run(names, n: int, seed: int) -> dict:
    out = {}
    for name in names:
        robot = ev.load_robot(name)
        scene = Scene(robot)
        Q = free_configurations(scene, n, np.random.default_rng(seed))
        ok, t = 0, []
        ev.solve(robot, robot.fk(Q[0]), scene=scene, seed=0)
        for i, q in enumerate(Q):
            T = robot.fk(q)
            r = ev.solve(robot, T, scene=scene, seed=i)
            t.append(r.time_s)
            good, free = judge(robot, scene, T, r.q)
            ok += good and free and r.success
        out[name] = {"n": len(Q), "success": ok / len(Q), "median_ms": 1e3 * float(np.median(t)),
                     "pairs": scene.pair_count}
    return out


def markdown(shelf: dict, selfc: dict, command: str) -> str:
    lines = [BEGIN, "", f"## Collision-aware IK: Panda into a shelf, against TRAC-IK + reject/retry "
             f"({datetime.date.today()})", "",
             f"Command: `{command}`. Machine: {cpu_model()}, 2 cores. Scene: a table and an open shelf "
             "(`evoik_pin.scene.examples.add_table_and_shelf`), Panda collision meshes with its SRDF. "
             f"{shelf['n']} targets: tip poses of random collision-free configurations with the tip inside the "
             "shelf. Success: pose within 1e-6 (m, rad), joints within limits, collision-free by the exact mesh "
             "check. Times are wall-clock per call, solvers interleaved per target in random order.", "",
             "| solver | success | pose ok | collision-free | median ms | p95 ms |",
             "| --- | ---: | ---: | ---: | ---: | ---: |"]
    n = shelf["n"]
    for name, r in shelf["rows"].items():
        t = 1e3 * np.array(r["t"])
        lines.append(f"| {name} | {100 * r['ok_free'] / n:.1f}% | {100 * r['ok'] / n:.1f}% | "
                     f"{100 * r['free'] / n:.1f}% | {np.median(t):.3f} | {np.percentile(t, 95):.3f} |")
    lines += ["", f"`success=True` answers of `evoik (scene)` that collide: "
              f"{shelf['rows']['evoik (scene)']['false_success']} of {n}.", "",
              "| throughput | targets | targets/s | success | collision-free (1,000 sampled) |",
              "| --- | ---: | ---: | ---: | ---: |"]
    for label, r in shelf["throughput"].items():
        lines.append(f"| {label} | {r['n']} | {r['per_s']:.0f} | {100 * r['success']:.1f}% | "
                     f"{100 * r['free_sampled']:.1f}% |")
    lines += ["", "Self-collision only (random reachable poses of collision-free configurations, default 5 ms "
              "budget):", "", "| robot | poses | checked pairs | success | median ms |",
              "| --- | ---: | ---: | ---: | ---: |"]
    for name, r in selfc.items():
        lines.append(f"| {name} | {r['n']} | {r['pairs']} | {100 * r['success']:.1f}% | {r['median_ms']:.3f} |")
    lines += ["", END]
    return "\n".join(lines)


def write_docs(text: str) -> None:
    doc = DOCS.read_text() if DOCS.exists() else "# Benchmarks\n"
    if BEGIN in doc and END in doc:
        doc = doc[: doc.index(BEGIN)] + text + doc[doc.index(END) + len(END):]
    else:
        doc = doc.rstrip() + "\n\n" + text + "\n"
    DOCS.write_text(doc)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--targets", type=int, default=500, help="shelf targets (default 500)")
    ap.add_argument("--self-poses", type=int, default=300, help="self-collision poses per robot (default 300)")
    ap.add_argument("--no-docs", action="store_true", help="do not write docs/BENCHMARKS.md")
    ap.add_argument("--seed", type=int, default=2026)
    args = ap.parse_args(argv)
    command = "python scripts/bench_collision.py " + " ".join(argv if argv is not None else sys.argv[1:])

    def log(msg):
        print(msg, file=sys.stderr, flush=True)

    shelf = shelf_run(args.targets, args.seed, log)
    selfc = self_collision_run(["panda", "ur5", "kinova"], args.self_poses, args.seed)
    text = markdown(shelf, selfc, command.strip())
    print(text)
    if not args.no_docs:
        write_docs(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
