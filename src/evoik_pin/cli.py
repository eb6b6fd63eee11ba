"""The ``evoik`` command line: robots, fk, solve, reproduce, view.

Degrees (and metres) at the command line by default; ``--rad`` switches joint values to radians.
Each sub-command is one ``_cmd_*`` function registered in :func:`build_parser`.
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from .errors import EvoikError
from .robot import BUNDLED_ROBOTS, EXAMPLE_ARMS, load_robot


def _add_robot_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("robot", help="bundled or example-robot-data name, or a URDF path")
    p.add_argument("--tip", help="tip frame (default: the arm's tool frame)")
    p.add_argument("--base", help="base frame (default: the URDF root)")


def _load(args: argparse.Namespace):
    return load_robot(args.robot, tip=args.tip, base=args.base)


def _joint_values(values: list[float], rad: bool) -> np.ndarray:
    q = np.asarray(values, dtype=float)
    return q if rad else np.radians(q)


def _cmd_robots(args: argparse.Namespace) -> int:
    print("Bundled paper arms:")
    for name, what in BUNDLED_ROBOTS.items():
        print(f"  {name:12s} {what}")
    print("example-robot-data arms (default tip frame):")
    for name, arm in EXAMPLE_ARMS.items():
        print(f"  {name:12s} {arm.urdf} (tip {arm.tip})")
    return 0


def _pose_dict(robot, q) -> dict:
    import pinocchio as pin

    T = robot.fk(q)
    return {
        "robot": robot.name,
        "tip": robot.tip,
        "base": robot.base,
        "q_rad": [float(v) for v in q],
        "position_m": [float(v) for v in T.translation],
        "rpy_rad": [float(v) for v in pin.rpy.matrixToRpy(T.rotation)],
        "rotation": np.asarray(T.rotation).tolist(),
    }


def _cmd_fk(args: argparse.Namespace) -> int:
    robot = _load(args)
    q = robot.check_q(_joint_values(args.q, args.rad)) if args.q else np.zeros(robot.n)
    info = _pose_dict(robot, q)
    if args.json:
        print(json.dumps(info, indent=2))
        return 0
    print(f"{robot.name}: {robot.n} joints, base {robot.base!r} -> tip {robot.tip!r}")
    unit = "rad" if args.rad else "deg"
    shown = q if args.rad else np.degrees(q)
    print(f"q ({unit}):        " + " ".join(f"{v:.4f}" for v in shown))
    print("position (m):   " + " ".join(f"{v:.6f}" for v in info["position_m"]))
    print("rpy (deg):      " + " ".join(f"{np.degrees(v):.4f}" for v in info["rpy_rad"]))
    print("rotation:\n" + "\n".join("  " + " ".join(f"{v:+.6f}" for v in row) for row in info["rotation"]))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="evoik", description="Inverse kinematics by evolutionary computation on Pinocchio."
    )
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("robots", help="list the robots that load by name")
    p.set_defaults(func=_cmd_robots)

    p = sub.add_parser("fk", help="forward kinematics: tip pose at a joint vector")
    _add_robot_args(p)
    p.add_argument("--q", type=float, nargs="+", help="joint values (degrees, or radians with --rad)")
    p.add_argument("--rad", action="store_true", help="joint values in radians")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=_cmd_fk)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except EvoikError as exc:
        print(f"evoik {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
