#!/usr/bin/env python
"""Whole-robot IK problems (several goals in one solve) for the benchmark against pink and PlaCo.

    python scripts/goal_problems.py talos -n 20 --seed 0 -o /tmp/talos.json
    python scripts/goal_problems.py --all -n 20 --seed 0 --out-dir /tmp/goals   # one file per robot
    python scripts/goal_problems.py --show pr2                                   # frames, active joints, neutral

A problem is the list of a robot's goals (a frame and a kind: "pose", a 4x4 homogeneous target, or "position", a
3-vector in m), every target the forward kinematics of one random configuration within the joint limits, so every
problem is reachable by construction. Only the *active* joints (those on the paths from the root to the goal
frames) are drawn; the others stay at the neutral configuration. Continuous joints take any angle; a free-flyer
base is drawn with its translation uniform in a 0.5 m cube centred on the neutral base position and its
orientation within 30 degrees of upright (a uniformly random axis, an angle uniform in [0, 30] deg). Targets are
in Pinocchio's world frame: the URDF root for a fixed base, the world for a free-flyer.

The file holds everything a solver in another environment needs (no evoik_pin import there): the URDF path,
package directories, the base kind, joint names, the active joints, the neutral configuration (``pin.neutral``
clipped into the joint limits where it lies outside them; the clipped joints are listed), the joint limits (null
where a coordinate is unbounded: free-flyer, continuous joints) and, per problem, the goals and the configuration
that generated them (for checking). Configurations are Pinocchio's ``q`` (``nq`` numbers).

This module uses plain Pinocchio and numpy only: ``peers_runner.py`` imports it inside the peers' virtual
environment (another Pinocchio version), and ``judge_goals.py`` imports it in evoik_pin's.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

FORMAT = "evoik-goal-problems/1"
KINDS = ("pose", "position")
#: Side of the cube (m) the free-flyer base translation is drawn in, centred on the neutral base position.
BASE_BOX_M = 0.5
#: Largest tilt (deg) of a free-flyer base from upright (its neutral orientation).
BASE_TILT_DEG = 30.0
#: Limits at or beyond this magnitude are no limits (Pinocchio writes +-max double for the free-flyer).
_UNBOUNDED = 1e20


@dataclass(frozen=True)
class RobotSet:
    """One robot of the benchmark: its URDF below example-robot-data's ``robots/`` and its goals."""

    urdf: str
    floating_base: bool
    goals: tuple[tuple[str, str], ...]  # (frame, kind)
    note: str


#: The benchmark's robots. Frame names were chosen by inspecting the models (``--show ROBOT`` prints them).
ROBOT_SETS: dict[str, RobotSet] = {
    "talos": RobotSet(
        "talos_data/robots/talos_reduced.urdf", True,
        (("left_sole_link", "pose"), ("right_sole_link", "pose"),
         ("arm_left_7_link", "pose"), ("arm_right_7_link", "pose")),
        "free-flyer; both soles and both wrists (last arm links), poses",
    ),
    "baxter": RobotSet(
        "baxter_description/urdf/baxter.urdf", False,
        (("left_gripper", "pose"), ("right_gripper", "pose")),
        "fixed base; both grippers, poses",
    ),
    "go2": RobotSet(
        "go2_description/urdf/go2.urdf", True,
        (("base", "pose"), ("FL_foot", "position"), ("FR_foot", "position"),
         ("RL_foot", "position"), ("RR_foot", "position")),
        "free-flyer; base pose and four feet positions",
    ),
    "allegro": RobotSet(
        "allegro_hand_description/urdf/allegro_right_hand.urdf", False,
        (("link_3.0_tip", "position"), ("link_7.0_tip", "position"),
         ("link_11.0_tip", "position"), ("link_15.0_tip", "position")),
        "Allegro right hand, fixed palm; four fingertip positions (link_15.0 is the thumb)",
    ),
    "pr2": RobotSet(
        "pr2_description/urdf/pr2.urdf", False,
        (("l_gripper_tool_frame", "pose"), ("r_gripper_tool_frame", "pose")),
        "fixed base; both gripper tool frames, poses; the torso lift is shared by both arms",
    ),
    "tiago_dual": RobotSet(
        "tiago_description/robots/tiago_dual.urdf", False,
        (("arm_left_tool_link", "pose"), ("arm_right_tool_link", "pose")),
        "TIAGo++, fixed base; both arms' tool frames, poses; the torso lift is shared by both arms",
    ),
    "g1": RobotSet(
        "g1_description/urdf/g1_29dof_rev_1_0.urdf", True,
        (("left_ankle_roll_link", "pose"), ("right_ankle_roll_link", "pose"),
         ("left_wrist_yaw_link", "pose"), ("right_wrist_yaw_link", "pose")),
        "Unitree G1, free-flyer; both feet (ankle roll links) and both wrists (last arm links), poses",
    ),
    "solo12": RobotSet(
        "solo_description/robots/solo12.urdf", True,
        (("base_link", "pose"), ("FL_FOOT", "position"), ("FR_FOOT", "position"),
         ("HL_FOOT", "position"), ("HR_FOOT", "position")),
        "ODRI Solo12, free-flyer; base pose and four feet positions",
    ),
}


def example_robot_data_dir() -> Path:
    """The ``robots/`` directory of the installed ``example-robot-data`` distribution (from its file list).

    Raises:
        FileNotFoundError: the distribution is not installed or ships no ``robots/`` directory.
    """
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError as exc:
        raise FileNotFoundError("the 'example-robot-data' package is not installed (pip install example-robot-data)") \
            from exc
    for f in dist.files or []:
        parts = Path(str(f)).parts
        if "example-robot-data" in parts and "robots" in parts and str(f).endswith(".urdf"):
            k = parts.index("robots")
            return Path(dist.locate_file(Path(*parts[: k + 1]))).resolve()
    raise FileNotFoundError("the installed 'example-robot-data' package ships no robots/ directory")


def build_model(urdf: str | Path, floating_base: bool) -> pin.Model:
    """Pinocchio model of a URDF, with a free-flyer root joint when ``floating_base``."""
    if floating_base:
        return pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer())
    return pin.buildModelFromUrdf(str(urdf))


def model_of(problems: dict) -> pin.Model:
    """The Pinocchio model a problems file describes, checked against the file's joint names and sizes.

    Raises:
        ValueError: the model built here differs from the one the file was written with.
    """
    model = build_model(problems["urdf"], problems["floating_base"])
    names = list(model.names)[1:]
    if names != problems["joint_names"] or model.nq != problems["nq"] or model.nv != problems["nv"]:
        raise ValueError(
            f"{problems['urdf']}: this Pinocchio ({pin.__version__}) builds a model (nq={model.nq}, nv={model.nv}, "
            f"{len(names)} joints) other than the problems file's (nq={problems['nq']}, nv={problems['nv']}, "
            f"{len(problems['joint_names'])} joints, Pinocchio {problems['pinocchio_version']})"
        )
    return model


def frame_id(model: pin.Model, frame: str) -> int:
    """Index of a frame of ``model``.

    Raises:
        KeyError: no frame of that name; the message lists the model's body frames.
    """
    if not model.existFrame(frame):
        bodies = [f.name for f in model.frames if f.type == pin.BODY]
        raise KeyError(f"no frame {frame!r} in the model; its body frames are: {', '.join(bodies)}")
    return model.getFrameId(frame)


def active_joint_ids(model: pin.Model, frames: list[str]) -> list[int]:
    """Joint indices (ascending, universe excluded) on the paths from the root to the given frames."""
    ids: set[int] = set()
    for name in frames:
        ids.update(j for j in model.supports[model.frames[frame_id(model, name)].parentJoint] if j > 0)
    return sorted(ids)


def joint_kind(joint) -> str:
    """``free_flyer``, ``continuous`` (an unbounded revolute, nq 2) or ``bounded`` (one coordinate with limits)."""
    if joint.nq == 7 and joint.nv == 6:
        return "free_flyer"
    if joint.nq == 2 and joint.nv == 1:
        return "continuous"
    if joint.nq == 1 and joint.nv == 1:
        return "bounded"
    raise ValueError(f"joint {joint.shortname()} (nq={joint.nq}, nv={joint.nv}) is not supported here")


def position_limits(model: pin.Model) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper limits per coordinate of ``q`` (shape (nq,)), ``-inf``/``+inf`` where there is none:
    free-flyer coordinates, continuous joints' (cos, sin) pairs and URDF limits of +-1e20 or more."""
    lower = np.full(model.nq, -np.inf)
    upper = np.full(model.nq, np.inf)
    for joint in model.joints[1:]:
        if joint_kind(joint) == "bounded":
            lo, hi = model.lowerPositionLimit[joint.idx_q], model.upperPositionLimit[joint.idx_q]
            if abs(lo) < _UNBOUNDED and abs(hi) < _UNBOUNDED:
                lower[joint.idx_q], upper[joint.idx_q] = lo, hi
    return lower, upper


def neutral_configuration(model: pin.Model) -> tuple[np.ndarray, list[str]]:
    """``pin.neutral(model)`` with each bounded coordinate clipped into its limits (shape (nq,)), and the names
    of the joints whose neutral value had to be clipped."""
    q = pin.neutral(model)
    lower, upper = position_limits(model)
    clipped = np.clip(q, lower, upper)
    names = [model.names[j] for j in range(1, model.njoints)
             if model.joints[j].nq == 1 and clipped[model.joints[j].idx_q] != q[model.joints[j].idx_q]]
    return clipped, names


def random_configuration(model: pin.Model, active: list[int], q_neutral: np.ndarray,
                         rng: np.random.Generator) -> np.ndarray:
    """A configuration (nq,) with the ``active`` joints drawn at random and the others at ``q_neutral``.

    Bounded joints: uniform within their limits. Continuous joints: an angle uniform in [-pi, pi). A free-flyer:
    translation uniform in a ``BASE_BOX_M`` cube centred on the neutral translation, rotation of a uniformly
    random axis and an angle uniform in [0, ``BASE_TILT_DEG``] from the neutral orientation.
    """
    q = q_neutral.copy()
    lower, upper = position_limits(model)
    for j in active:
        joint = model.joints[j]
        i = joint.idx_q
        kind = joint_kind(joint)
        if kind == "bounded":
            if not (np.isfinite(lower[i]) and np.isfinite(upper[i])):
                raise ValueError(f"joint {model.names[j]} has no finite limits to draw within")
            q[i] = rng.uniform(lower[i], upper[i])
        elif kind == "continuous":
            angle = rng.uniform(-np.pi, np.pi)
            q[i:i + 2] = np.cos(angle), np.sin(angle)
        else:
            q[i:i + 3] = q_neutral[i:i + 3] + rng.uniform(-BASE_BOX_M / 2, BASE_BOX_M / 2, 3)
            axis = rng.normal(size=3)
            axis /= np.linalg.norm(axis)
            tilt = rng.uniform(0.0, np.radians(BASE_TILT_DEG))
            r0 = pin.Quaternion(q_neutral[i + 3:i + 7]).toRotationMatrix()
            q[i + 3:i + 7] = pin.Quaternion(r0 @ pin.exp3(axis * tilt)).coeffs()  # (x, y, z, w)
    return q


def frame_goals(model: pin.Model, data: pin.Data, q: np.ndarray, goals) -> list[dict]:
    """The goals' targets at configuration ``q``: ``{"frame", "kind", "target"}`` with a 4x4 list (pose) or a
    3-list in m (position), in the world frame."""
    pin.framesForwardKinematics(model, data, q)
    out = []
    for frame, kind in goals:
        placement = data.oMf[frame_id(model, frame)]
        target = placement.homogeneous.tolist() if kind == "pose" else placement.translation.tolist()
        out.append({"frame": frame, "kind": kind, "target": target})
    return out


def placement_errors(placements, goals: list[dict]) -> np.ndarray:
    """Errors of the goals at the given frame placements (``pin.SE3``, one per goal, in the world frame): shape
    (n_goals, 2), each row the position error (m, Euclidean) and the rotation error (rad,
    ``||log3(R_target^T R)||``; 0 for position goals).

    ``goals`` are dicts with ``kind`` and a numpy ``target`` ((4, 4) or (3,)), as :func:`parse_goals` returns.
    """
    err = np.zeros((len(goals), 2))
    for k, (placement, goal) in enumerate(zip(placements, goals, strict=True)):
        target = goal["target"]
        if goal["kind"] == "pose":
            err[k, 0] = np.linalg.norm(placement.translation - target[:3, 3])
            err[k, 1] = np.linalg.norm(pin.log3(target[:3, :3].T @ placement.rotation))
        else:
            err[k, 0] = np.linalg.norm(placement.translation - target)
    return err


def goal_errors(data: pin.Data, frame_ids: list[int], goals: list[dict]) -> np.ndarray:
    """:func:`placement_errors` at the frame placements already in ``data.oMf`` (forward kinematics done)."""
    return placement_errors([data.oMf[i] for i in frame_ids], goals)


def parse_goals(goals: list[dict]) -> list[dict]:
    """A problem's goals with numpy targets, checked: kind "pose" with a 4x4 target, "position" with a 3-vector.

    Raises:
        ValueError: a goal of another kind or a target of the wrong shape (named by its index and frame).
    """
    out = []
    for k, goal in enumerate(goals):
        kind = goal.get("kind")
        if kind not in KINDS:
            raise ValueError(f"goal {k} ({goal.get('frame')!r}): kind {kind!r}; accepted: {', '.join(KINDS)}")
        target = np.asarray(goal["target"], dtype=float)
        shape = (4, 4) if kind == "pose" else (3,)
        if target.shape != shape or not np.all(np.isfinite(target)):
            raise ValueError(f"goal {k} ({goal['frame']!r}, {kind}): target of shape {target.shape}; "
                             f"accepted: finite numbers of shape {shape}")
        out.append({"frame": goal["frame"], "kind": kind, "target": target})
    return out


def _json_limits(values: np.ndarray) -> list[float | None]:
    return [float(v) if np.isfinite(v) else None for v in values]


def limits_of(problems: dict) -> tuple[np.ndarray, np.ndarray]:
    """The file's joint limits as arrays (nq,), ``-inf``/``+inf`` where it stores null."""
    lower = np.array([-np.inf if v is None else v for v in problems["lower"]])
    upper = np.array([np.inf if v is None else v for v in problems["upper"]])
    return lower, upper


def make_problems(robot: str, n: int, seed: int) -> dict:
    """A problems file (as a dict ready for JSON) of ``n`` problems of a robot of :data:`ROBOT_SETS`.

    Raises:
        KeyError: an unknown robot name (the message lists the known ones).
        ValueError: ``n`` below 1.
    """
    if robot not in ROBOT_SETS:
        raise KeyError(f"unknown robot {robot!r}; accepted: {', '.join(ROBOT_SETS)}")
    if n < 1:
        raise ValueError(f"number of problems {n}; accepted: 1 or more")
    spec = ROBOT_SETS[robot]
    robots_dir = example_robot_data_dir()
    urdf = robots_dir / spec.urdf
    model = build_model(urdf, spec.floating_base)
    data = model.createData()
    frames = [frame for frame, _ in spec.goals]
    active = active_joint_ids(model, frames)
    q_neutral, clipped = neutral_configuration(model)
    lower, upper = position_limits(model)
    rng = np.random.default_rng(seed)
    problems = []
    for _ in range(n):
        q = random_configuration(model, active, q_neutral, rng)
        problems.append({"goals": frame_goals(model, data, q, spec.goals), "q_generating": q.tolist()})
    return {
        "format": FORMAT,
        "robot": robot,
        "note": spec.note,
        "urdf": str(urdf),
        "package_dirs": [str(robots_dir)],
        "floating_base": spec.floating_base,
        "pinocchio_version": pin.__version__,
        "seed": seed,
        "nq": model.nq,
        "nv": model.nv,
        "joint_names": list(model.names)[1:],
        "goals": [{"frame": frame, "kind": kind} for frame, kind in spec.goals],
        "active_joints": [model.names[j] for j in active],
        "neutral": q_neutral.tolist(),
        "neutral_clipped": clipped,
        "lower": _json_limits(lower),
        "upper": _json_limits(upper),
        "base_box_m": BASE_BOX_M if spec.floating_base else None,
        "base_tilt_deg": BASE_TILT_DEG if spec.floating_base else None,
        "problems": problems,
    }


def load_problems(path: str | Path) -> dict:
    """Read a problems file written by :func:`make_problems`.

    Raises:
        ValueError: not a problems file of this format.
    """
    with open(path, encoding="utf-8") as fh:
        problems = json.load(fh)
    if not isinstance(problems, dict) or problems.get("format") != FORMAT:
        raise ValueError(f"{path}: not a goal problems file (expected format {FORMAT!r})")
    return problems


def describe(problems: dict) -> str:
    """Lines saying a problems file's robot, goals, active joints and neutral clipping."""
    goals = ", ".join(f"{g['frame']} ({g['kind']})" for g in problems["goals"])
    lines = [
        f"{problems['robot']}: {problems['urdf']}",
        f"  base: {'free-flyer' if problems['floating_base'] else 'fixed'}; nq={problems['nq']} nv={problems['nv']}",
        f"  goals: {goals}",
        f"  active joints ({len(problems['active_joints'])}): {', '.join(problems['active_joints'])}",
        f"  neutral clipped into the limits: {', '.join(problems['neutral_clipped']) or 'none'}",
        f"  problems: {len(problems['problems'])} (seed {problems['seed']})",
    ]
    return "\n".join(lines)


def _write(problems: dict, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(problems), encoding="utf-8")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("robot", nargs="?", help=f"one of: {', '.join(ROBOT_SETS)}")
    parser.add_argument("--all", action="store_true", help="every robot, one file each in --out-dir")
    parser.add_argument("-n", "--problems", type=int, default=20, help="problems per robot (default 20)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("-o", "--out", type=Path, help="output file (one robot)")
    parser.add_argument("--out-dir", type=Path, help="output directory: ROBOT.json per robot")
    parser.add_argument("--show", action="store_true", help="print the robot's goals and active joints only")
    args = parser.parse_args(argv)
    robots = list(ROBOT_SETS) if args.all else [args.robot]
    if robots == [None]:
        parser.error(f"name a robot ({', '.join(ROBOT_SETS)}) or pass --all")
    if not args.show and args.out is None and args.out_dir is None:
        parser.error("say where to write: -o FILE or --out-dir DIR")
    if args.out is not None and len(robots) > 1:
        parser.error("-o names one file; use --out-dir with --all")
    for robot in robots:
        try:
            problems = make_problems(robot, 1 if args.show else args.problems, args.seed)
        except (KeyError, ValueError, FileNotFoundError) as exc:
            parser.error(str(exc.args[0]))
        print(describe(problems))
        if not args.show:
            path = args.out if args.out is not None else args.out_dir / f"{robot}.json"
            _write(problems, path)
            print(f"  written: {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
