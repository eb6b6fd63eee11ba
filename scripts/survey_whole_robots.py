#!/usr/bin/env python
"""Every whole robot example-robot-data ships (evoik_pin's catalog, ``WHOLE_ROBOTS``): random reachable pose goals on
its chains' end links (up to four, the deepest first), solved by memetic at a given budget, as a user would try them.

    python scripts/survey_whole_robots.py                 # default budget (5 ms), 60 problems a robot
    python scripts/survey_whole_robots.py --timeout 0.05  # the same problems at 50 ms

Legged robots and humanoids get a floating base; the fixed-base ones (manipulators, hands) none. A problem: a random
configuration in the joint limits, a ``Pose`` goal on each chosen frame at its pose there; success by memetic's
verdict (every goal within 1e-6 m and rad). Prints one line per robot: joints, frames, success %, median solve ms
(the first solve, which builds the seed table, left out)."""

from __future__ import annotations

import argparse

import numpy as np
import pinocchio as pin

import evoik_pin as ek
from evoik_pin.goals import Pose
from evoik_pin.robot import WHOLE_ROBOTS

#: Whole robots without a floating base (manipulators on a fixed base, hands, toy arms).
FIXED = {"baxter", "pr2", "tiago", "tiago_dual", "tiago_no_hand", "tiago_pro", "allegro_right", "allegro_left",
         "finger_edu", "double_pendulum", "asr_twodof", "alex"}


def end_frames(robot, most: int = 4) -> list[str]:
    """The body frames of the robot's leaf joints, the deepest chains first, at most ``most``."""
    m = robot.model
    parents = {int(m.parents[j]) for j in range(1, m.njoints)}
    depth = [0] * m.njoints
    for j in range(1, m.njoints):
        depth[j] = depth[m.parents[j]] + 1
    leaves = sorted((j for j in range(1, m.njoints) if j not in parents), key=lambda j: -depth[j])
    frames = [next((f.name for f in m.frames if f.parentJoint == j and f.type == pin.FrameType.BODY), None)
              for j in leaves[:most]]
    return [f for f in frames if f is not None]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("robots", nargs="*", default=list(WHOLE_ROBOTS))
    ap.add_argument("--n", type=int, default=60, help="problems a robot (default 60)")
    ap.add_argument("--timeout", type=float, default=0.005, help="memetic's budget, s (default 0.005)")
    args = ap.parse_args()
    print(f"| robot | joints | frames | success | median ms | (budget {args.timeout * 1e3:g} ms, {args.n} problems) |")
    print("|---|---|---|---|---|---|")
    for name in args.robots:
        robot = ek.load_robot(name, floating_base=name not in FIXED)
        if robot.n <= (6 if robot.floating_base else 0):
            print(f"| {name} | {robot.n} | - | no joints beyond the base | | |")
            continue
        frames = end_frames(robot)
        solver = ek.IKSolver(robot, timeout=args.timeout)
        rng = np.random.default_rng(0)
        ok, times = 0, []
        for i in range(args.n):
            q = robot.random_configurations(1, rng)[0]
            r = solver.solve([Pose(f, robot.fk(q, f)) for f in frames], seed=i)
            ok += r.success
            times += [r.time_s] if i else []
        print(f"| {name} | {robot.n} | {len(frames)} | {100 * ok / args.n:.1f} % | {1e3 * np.median(times):.2f} | |",
              flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
