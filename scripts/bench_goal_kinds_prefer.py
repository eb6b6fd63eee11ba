#!/usr/bin/env python
"""Issue 23's goal sets, ``prefer=`` and preferences, measured (docs/BENCHMARKS.md, "Goal sets, prefer and
preferences").

    python scripts/bench_goal_kinds_prefer.py              # 200 targets per part, stdout
    python scripts/bench_goal_kinds_prefer.py --n 20       # quick

Parts (every target from forward kinematics of a configuration drawn uniformly in the limits, q0 drawn
independently the same way; seeds fixed):

1. ``prefer="nearest"`` on Panda and UR10 against pytracik's TRAC-IK ``solver_type="Distance"`` (5 ms, epsilon
   1e-5; joint limits set from our model, targets in its base frame, as scripts/bench_ik.py drives it) from the
   same q0: success of each (ours: 1e-6 m and rad; TRAC-IK's answers judged by our forward kinematics at 1e-5, its
   own epsilon), the share of the targets both solve on which our answer is no farther from q0 than its answer
   (Euclidean norm of q - q0, joints whose range spans a full turn at their turn nearest q0 inside the limits for
   both, a 1e-6 rad slack; TRAC-IK's answer first taken by our LM from where it is to the exact solution (1e-12)
   of its branch, a move of about its epsilon, so that two answers of one branch compare equal), median wall time per
   target (all targets) and the ratio. ``prefer="manipulability"`` against ``"Manip1"`` likewise: the share of
   the targets both solve on which our answer's sqrt(det(J J^T)) (6 x n, LOCAL_WORLD_ALIGNED) is at least its
   own (1e-9 relative slack).
2. Goal sets on Panda: 10 grasps of which 3 are reachable (forward kinematics of random configurations) and 7 are
   not (positions 1.2 to 1.6 m from the base, beyond Panda's reach, random orientations), shuffled: the share that
   finds a reachable one, and its median wall time against single-pose solves (``[Pose(tip, T)]``, the reachable
   grasp) of the same targets.
3. Preferences never cost success: the single-pose Panda and UR10 problems with ``Posture(mid-range)`` or
   ``JointLimitMargin(0.1 rad)`` added: success with and without.

Prints one markdown section (``run(args)`` returns it) with the command, the date, the machine and its load.
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
import pinocchio as pin

import evoik_pin as ev
from evoik_pin.goals import JointLimitMargin, Pose, Posture
from evoik_pin.solvers.lm import LevenbergMarquardt, wrapping_joints
from evoik_pin.solvers.search.prefer import DEFAULT_PREFER_TIMEOUT, nearest_turn

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_ik import cpu_model, quiet_output  # noqa: E402

TOL = 1e-6
TRAC_EPS = 1e-5


class Trac:
    """pytracik's TRAC-IK in one solve type, driven as scripts/bench_ik.py drives it."""

    def __init__(self, robot, solver_type: str, timeout: float = 0.005) -> None:
        import pytracik
        from trac_ik import TracIK

        with quiet_output():
            solver = TracIK(robot.base, robot.tip, str(robot.urdf_path), timeout=timeout, epsilon=TRAC_EPS,
                            solver_type=solver_type)
        assert solver.dof == robot.n, (solver.dof, robot.n)
        solver.joint_limits = (robot.lower, robot.upper)
        self._ik, self._handle = pytracik.ik, solver._ik_solver
        q = (robot.lower + robot.upper) / 2
        p, R = solver.fk(q)
        T = robot.fk(q)
        assert np.abs(p - T.translation).max() < 1e-9 and np.abs(R - T.rotation).max() < 1e-9, "frames differ"

    def __call__(self, T: pin.SE3, q0: np.ndarray):
        quat = pin.Quaternion(T.rotation)
        x, y, z = T.translation
        r = self._ik(self._handle, q0, x, y, z, quat.x, quat.y, quat.z, quat.w)
        return np.array(r[1:]) if r[0] >= 0 else None


def met(robot, T: pin.SE3, q, tol: float) -> bool:
    if q is None or not robot.within_bounds(q, 1e-9):
        return False
    Tq = robot.fk(q)
    return (np.linalg.norm(Tq.translation - T.translation) <= tol
            and np.linalg.norm(pin.log3(T.rotation.T @ Tq.rotation)) <= tol)


def lm_for(robot, T):
    return LevenbergMarquardt(ev.make_problem(robot, T, tolerance=1e-12)[0])


def exact(lm, q):
    """TRAC-IK's answer (within its epsilon, 1e-5) taken by our LM to the exact solution of its branch nearest it
    (a few steps, ~1e-5 rad), so that the two answers of one branch compare equal; the original when LM fails."""
    out = lm.run(np.clip(q, lm.problem.lower, lm.problem.upper), 30)
    return out.q if out.converged else q


def manip(robot, q) -> float:
    J = robot.jacobian(q, "world")
    return float(np.sqrt(max(np.linalg.det(J @ J.T), 0.0)))


def problems(robot, n: int, seed: int):
    rng = np.random.default_rng(seed)
    Q = robot.random_configurations(n, rng)
    Q0 = robot.random_configurations(n, rng)
    return [robot.fk(q) for q in Q], Q0


def bench_prefer(name: str, n: int, seed: int, log, timeout: float | None = None) -> list[str]:
    robot = ev.load_robot(name)
    ev.prepare(robot)
    targets, Q0 = problems(robot, n, seed)
    wrap = wrapping_joints(robot, robot.lower, robot.upper)
    extra = {} if timeout is None else {"timeout": timeout}
    rows = []
    for prefer, stype in (("nearest", "Distance"), ("manipulability", "Manip1")):
        trac = Trac(robot, stype)
        ev.solve(robot, targets[0], q0=Q0[0], prefer=prefer, seed=0, **extra)  # warm
        ours, theirs, t_ours, t_theirs = [], [], [], []
        for i, (T, q0) in enumerate(zip(targets, Q0, strict=True)):
            t = time.perf_counter()
            r = ev.solve(robot, T, q0=q0, prefer=prefer, seed=i, **extra)
            t_ours.append(time.perf_counter() - t)
            ours.append(r.q if r.success else None)
            t = time.perf_counter()
            q = trac(T, q0)
            t_theirs.append(time.perf_counter() - t)
            theirs.append(exact(lm_for(robot, T), q) if met(robot, T, q, TRAC_EPS) else None)
        both = [i for i in range(n) if ours[i] is not None and theirs[i] is not None]
        if prefer == "nearest":
            def dist(q, q0):
                return float(np.linalg.norm(nearest_turn(q, q0, robot.lower, robot.upper, wrap) - q0))
            better = [dist(ours[i], Q0[i]) <= dist(theirs[i], Q0[i]) + 1e-6 for i in both]
            med = (np.median([dist(ours[i], Q0[i]) for i in both]), np.median([dist(theirs[i], Q0[i]) for i in both]))
            what = "no farther from q0"
        else:
            better = [manip(robot, ours[i]) >= manip(robot, theirs[i]) * (1 - 1e-9) for i in both]
            med = (np.median([manip(robot, ours[i]) for i in both]), np.median([manip(robot, theirs[i]) for i in both]))
            what = "at least as dexterous"
        s_ours = sum(q is not None for q in ours) / n
        s_theirs = sum(q is not None for q in theirs) / n
        mo, mt = np.median(t_ours) * 1e3, np.median(t_theirs) * 1e3
        row = (f"| {name} | {prefer} vs {stype} | {100 * s_ours:.1f} % | {100 * s_theirs:.1f} % | "
               f"{100 * np.mean(better):.1f} % {what} ({len(both)} both solve) | {med[0]:.4g} / {med[1]:.4g} | "
               f"{mo:.3f} / {mt:.3f} ms | {mt / mo:.1f}x |")
        log(row)
        rows.append(row)
    return rows


def goal_set_problems(robot, n: int, seed: int) -> tuple[list, list]:
    """Part 2's problems: (``n`` goal lists ``[Pose(tip, [10 grasps])]``, 3 reachable and 7 not, shuffled; the
    single-pose lists ``[Pose(tip, T)]`` of each set's first reachable grasp)."""
    rng = np.random.default_rng(seed)
    sets, singles = [], []
    for _ in range(n):
        reach = [robot.fk(q) for q in robot.random_configurations(3, rng)]
        far = []
        for _ in range(7):
            d = rng.normal(size=3)
            d[2] = abs(d[2])
            p = d / np.linalg.norm(d) * rng.uniform(1.2, 1.6)
            far.append(pin.SE3(pin.exp3(rng.normal(size=3)), p))
        members = reach + far
        order = rng.permutation(10)
        sets.append([Pose(robot.tip, [members[k] for k in order])])
        singles.append([Pose(robot.tip, reach[0])])
    return sets, singles


def bench_sets(n: int, seed: int, log) -> list[str]:
    robot = ev.load_robot("panda")
    ev.prepare(robot)
    sets, singles = goal_set_problems(robot, n, seed)
    ev.solve(robot, sets[0], seed=0)
    ok, t_set, t_one, ok_one = 0, [], [], 0
    for i, (gs, g1) in enumerate(zip(sets, singles, strict=True)):
        t = time.perf_counter()
        r = ev.solve(robot, gs, seed=i)
        t_set.append(time.perf_counter() - t)
        ok += r.success and r.chosen[0] is not None
        t = time.perf_counter()
        r1 = ev.solve(robot, g1, seed=i)
        t_one.append(time.perf_counter() - t)
        ok_one += r1.success
    ms, m1 = np.median(t_set) * 1e3, np.median(t_one) * 1e3
    row = (f"| panda | 10 grasps, 7 unreachable | {100 * ok / n:.1f} % | {ms:.3f} ms | single pose: "
           f"{100 * ok_one / n:.1f} %, {m1:.3f} ms | {ms / m1:.2f}x |")
    log(row)
    return [row]


def bench_preferences(name: str, n: int, seed: int, log) -> list[str]:
    robot = ev.load_robot(name)
    ev.prepare(robot)
    targets, _ = problems(robot, n, seed)
    mid = (robot.lower + robot.upper) / 2
    cases = {"goals alone": [], "+ Posture(mid-range, 0.1)": [Posture(mid, 0.1)],
             "+ JointLimitMargin(0.1 rad)": [JointLimitMargin(0.1)]}
    out = []
    for label, prefs in cases.items():
        ok, times = 0, []
        for i, T in enumerate(targets):
            t = time.perf_counter()
            r = ev.solve(robot, [Pose(robot.tip, T), *prefs], seed=i)
            times.append(time.perf_counter() - t)
            ok += r.success
        row = f"| {name} | {label} | {100 * ok / n:.1f} % | {np.median(times) * 1e3:.3f} ms |"
        log(row)
        out.append(row)
    return out


def run(args) -> str:
    def log(msg: str) -> None:
        if args.verbose:
            print(msg, file=sys.stderr, flush=True)

    load = os.getloadavg()
    lines = ["### Goal sets, prefer and preferences (issue 23)", "",
             f"{datetime.date.today().isoformat()}, `python scripts/bench_goal_kinds_prefer.py --n {args.n}"
             f"{f' --prefer-timeout {args.prefer_timeout:g}' if args.prefer_timeout else ''}`, "
             f"{cpu_model()}, {os.cpu_count()} cores, Python {platform.python_version()}; load average "
             f"{load[0]:.2f} at the start (a shared, loaded machine: times are indicative, ratios were taken in the "
             f"same run, target by target interleaved). prefer's budget: `timeout` "
             f"{(args.prefer_timeout or DEFAULT_PREFER_TIMEOUT) * 1e3:g} ms"
             f"{'' if args.prefer_timeout else ' (the default)'}.", "",
             "| robot | prefer vs TRAC-IK | our success | TRAC-IK success | our answer | median (ours / TRAC-IK) "
             "| median time (ours / TRAC-IK) | speed-up |", "|---|---|---|---|---|---|---|---|"]
    for name in ("panda", "ur10"):
        lines += bench_prefer(name, args.n, args.seed, log, args.prefer_timeout)
    lines += ["", "| robot | goal set | finds a reachable one | median time | single pose | ratio |",
              "|---|---|---|---|---|---|"]
    lines += bench_sets(args.n, args.seed + 1, log)
    lines += ["", "| robot | problems | success | median time |", "|---|---|---|---|"]
    for name in ("panda", "ur10"):
        lines += bench_preferences(name, args.n, args.seed + 2, log)
    load = os.getloadavg()
    lines += ["", f"Load average at the end: {load[0]:.2f}."]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=200, help="targets per part (default 200)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--verbose", action="store_true", help="rows on stderr as they come")
    parser.add_argument("--prefer-timeout", type=float, help="prefer's budget in s (default: the library's)")
    print(run(parser.parse_args(argv)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
