"""Solve one IK problem and look at it in the browser (meshcat), then save the scene as an HTML file.

    $ python examples/view_solution.py                      # Panda; open the printed URL, Ctrl-C to stop
    $ python examples/view_solution.py ax18 --html ax18.html --no-block

What it does:
1. loads a robot (a name from ``evoik robots`` or a URDF path);
2. picks a reachable target: the tip pose (``pin.SE3``, m) of a random configuration;
3. solves it with ``evoik_pin.solve`` (or, in a checkout that has no solver yet, takes that random
   configuration as "the solution");
4. shows the solution, the target as a coordinate triad, and an animation from the rest configuration to the
   solution with the tip's path, in a meshcat viewer;
5. writes a self-contained HTML file of the scene (open it in any browser, no server or network needed).
"""

from __future__ import annotations

import argparse

import numpy as np

import evoik_pin
from evoik_pin import load_robot
from evoik_pin.viz import Viewer


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("robot", nargs="?", default="panda", help="robot name or URDF path (default: panda)")
    parser.add_argument("--tip", help="tip frame (default: the arm's tool frame)")
    parser.add_argument("--seed", type=int, default=0, help="random seed of the target and the solver")
    parser.add_argument("--html", default="view_solution.html", help="where to write the HTML scene")
    parser.add_argument("--no-block", action="store_true", help="exit after writing the HTML file")
    args = parser.parse_args(argv)

    robot = load_robot(args.robot, tip=args.tip)
    rng = np.random.default_rng(args.seed)
    q_random = robot.random_configurations(1, rng)[0]
    target = robot.fk(q_random)  # pin.SE3: position (m) and rotation of the tip, in the base frame

    if hasattr(evoik_pin, "solve"):
        result = evoik_pin.solve(robot, target, seed=args.seed)
        print(result)
        q = result.q
    else:  # no solver in this checkout yet: the configuration the target came from is a solution
        q = q_random
    T = robot.fk(q)
    print(f"tip error {np.linalg.norm(T.translation - target.translation):.3g} m; q (deg) = "
          + " ".join(f"{v:.1f}" for v in np.degrees(q)))

    rest = robot.clip(np.zeros(robot.n))  # the zero configuration, moved into the joint bounds
    trajectory = np.linspace(rest, q, 60)  # (60, n): a straight line in joint space

    with Viewer(robot) as viewer:
        viewer.show_target(target.translation, target.rotation)
        viewer.animate(trajectory, dt=0.04)  # plays once in the browser, and draws the tip's path
        viewer.show(q)
        print(f"meshcat viewer: {viewer.url}")
        print(f"wrote {viewer.save_html(args.html)}")
        if not args.no_block:
            viewer.block("Press Ctrl-C to stop the viewer.")  # printed where Ctrl-C is already the clean stop
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
