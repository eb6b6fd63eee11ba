#!/usr/bin/env python
"""Retargeting (issue 31): the bundled CMU clips onto G1 and Talos, judged by ``judge_retarget.py``.

    python scripts/bench_retarget.py                          # every clip x (g1, talos), pink baseline (+ evoik)
    python scripts/bench_retarget.py --clips walk --robots g1 --sweep 1,2,3,5,10,20   # pink's tracking vs K

For each clip (``evoik_pin.motion.load_clip``) and robot:

1. scale: one factor per clip and robot, the robot's leg length over the source's. The robot's leg length is
   hip-to-knee plus knee-to-ankle of its mapped frames at its neutral configuration, averaged over both legs;
   the source's is the same sum over its keypoints, averaged over both legs and all frames (a BVH's bones are
   rigid, so the bend of the knee does not change it). Positions are scaled about the origin, then shifted
   vertically so that the source ankles' floor level (``ground_height``) lands at the robot's ankle height above
   its soles at neutral (the lowest point of its foot collision geometry): the judged floor is z = 0.
2. targets: the mapped keypoints (``mapping_preset("cmu", robot)``) of the scaled motion, one per mapped frame;
   the base frame also gets the source pelvis's orientation (x forward = the hips' left-right axis crossed with the
   spine's up axis, y = left hip minus right hip, z completing), which GMR also tracks. With
   ``--feet-orientation`` the ankle frames get the source feet's orientations too (:func:`foot_rotations`), as
   GMR's configurations do; off by default (the brief's baseline: positions and the pelvis's orientation).
3. pink, GMR's method (``retarget_pink.py`` in the peers' venv, subprocess): from the neutral configuration with
   the base at the first pelvis target, ``--steps`` QP steps per frame (default 5, the fewest that keep its
   tracking: see the K sweep in docs/BENCHMARKS.md).
4. evoik_pin: :func:`retarget_evoik` (the hook the lead fills in when ``evoik_pin.retarget`` lands).
5. each answer judged by ``judge_retarget.judge_clip`` with the source contacts (``detect_contacts``) on the
   robot's ankle frames, the limbs of ``limb_pairs("cmu")`` and the SRDF where the robot has one (Talos).
   evoik_pin retargets the unscaled clip in the source's world, whose floor is ``ground_height(motion)``: its
   clips are judged against that floor (its tracking mm are against keypoints of another world: not compared).

Frames per second are the steady rate for both: frames 2..N over their wall time (pink: its own per-frame clock in
its subprocess, process start and model loading excluded; evoik_pin: its clip report's ``steady_fps``, the clip's
set-up and the first frame excluded, the whole call's rate in the JSON). The first frame, which starts from the neutral
configuration (pink settles it with 50 extra steps), is reported apart in ms.
"""

from __future__ import annotations

import argparse
import datetime
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

from evoik_pin.motion import detect_contacts, ground_height, limb_pairs, list_clips, load_clip, mapping_preset

SCRIPTS = Path(__file__).resolve().parent
sys.path.insert(0, str(SCRIPTS))
import goal_problems as gp  # noqa: E402
import judge_retarget as jr  # noqa: E402

PEERS_PYTHON = Path(os.environ.get("PEERS_VENV", "/work/peers-venv")) / "bin" / "python"
#: The robots: URDF and SRDF below example-robot-data's robots/ (as evoik_pin's catalog loads them).
ROBOTS = {
    "g1": ("g1_description/urdf/g1_29dof_rev_1_0.urdf", None),
    "talos": ("talos_data/robots/talos_reduced.urdf", "talos_data/srdf/talos.srdf"),
}
FEET = {"LeftFoot": "LeftFoot", "RightFoot": "RightFoot"}  # CMU's ankle keypoints (contacts)


def robot_files(robot_name: str) -> tuple[Path, Path | None]:
    """(URDF, SRDF or None) of a benchmark robot."""
    root = gp.example_robot_data_dir()
    urdf, srdf = ROBOTS[robot_name]
    return root / urdf, (root / srdf if srdf else None)


def _legs(mapping: dict[str, str]) -> list[tuple[str, str, str]]:
    """(hip, knee, ankle) robot frames per leg, from the preset's CMU keypoints."""
    by_key = {k: f for f, k in mapping.items()}
    return [(by_key[f"{side}UpLeg"], by_key[f"{side}Leg"], by_key[f"{side}Foot"]) for side in ("Left", "Right")]


def robot_geometry(robot_name: str) -> dict:
    """Neutral leg length (m) and ankle height above the soles (m) of the robot, from its mapped frames."""
    urdf, _ = robot_files(robot_name)
    model = jr.build_model(urdf)
    data = model.createData()
    geom = jr.collision_model(model, urdf)
    gdata = geom.createData()
    q = pin.neutral(model)
    pin.framesForwardKinematics(model, data, q)
    pin.updateGeometryPlacements(model, data, geom, gdata)
    mapping = mapping_preset("cmu", robot_name)
    p = {f: data.oMf[model.getFrameId(f)].translation.copy() for f in mapping}
    legs = _legs(mapping)
    length = np.mean([np.linalg.norm(p[h] - p[k]) + np.linalg.norm(p[k] - p[a]) for h, k, a in legs])
    heights = []
    for _, _, ankle in legs:
        joint = model.frames[model.getFrameId(ankle)].parentJoint
        lows = [jr.lowest_point_z(o.geometry, gdata.oMg[i]) for i, o in enumerate(geom.geometryObjects)
                if o.parentJoint == joint]
        heights.append(p[ankle][2] - min(lows))
    return {"leg_length": float(length), "ankle_height": float(np.mean(heights)), "mapping": mapping,
            "q_neutral": q, "model": model}


def source_leg_length(motion) -> float:
    """Mean over frames and legs of hip-knee plus knee-ankle, m."""
    total = []
    for side in ("Left", "Right"):
        h, k, a = (motion.trajectory(f"{side}{b}") for b in ("UpLeg", "Leg", "Foot"))
        total.append(np.linalg.norm(h - k, axis=1) + np.linalg.norm(k - a, axis=1))
    return float(np.mean(total))


def pelvis_rotations(keypoints: np.ndarray, names: list[str]) -> np.ndarray:
    """(N, 3, 3) source pelvis orientations: y = left hip - right hip, z = up along the spine, x = y x z."""
    ix = {n: i for i, n in enumerate(names)}
    y = keypoints[:, ix["LeftUpLeg"]] - keypoints[:, ix["RightUpLeg"]]
    up = keypoints[:, ix["Spine1"]] - keypoints[:, ix["Hips"]]
    y /= np.linalg.norm(y, axis=1, keepdims=True)
    x = np.cross(y, up)
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    z = np.cross(x, y)
    return np.stack([x, y, z], axis=2)  # columns: the pelvis axes in the world


def foot_rotations(keypoints: np.ndarray, names: list[str], side: str, contact: np.ndarray) -> np.ndarray:
    """(N, 3, 3) source foot orientations for a robot foot that is flat at rest: the heading of ankle -> toe
    (``{side}Foot`` -> ``{side}ToeBase``) and its pitch below the horizontal less the median pitch while in
    contact (a person's ankle stands above the toe: about 13 deg on the walk clip), no roll."""
    ix = {n: i for i, n in enumerate(names)}
    v = keypoints[:, ix[f"{side}ToeBase"]] - keypoints[:, ix[f"{side}Foot"]]
    yaw = np.arctan2(v[:, 1], v[:, 0])
    pitch = np.arctan2(-v[:, 2], np.linalg.norm(v[:, :2], axis=1))
    pitch = pitch - np.median(pitch[contact] if contact.any() else pitch)
    return np.array([pin.utils.rpyToMatrix(0.0, p, y) for p, y in zip(pitch, yaw, strict=True)])


def prepare(clip: str, robot_name: str, feet_orientation: bool = False) -> dict:
    """The clip scaled for the robot: keypoints, targets, contacts, limbs and the judge's arguments."""
    motion = load_clip(clip)
    robot = robot_geometry(robot_name)
    scale = robot["leg_length"] / source_leg_length(motion)
    keys = motion.positions * scale
    keys[:, :, 2] += robot["ankle_height"] - ground_height(motion) * scale
    mapping = robot["mapping"]
    frames = list(mapping)
    names = list(motion.names)
    targets = keys[:, [names.index(mapping[f]) for f in frames]]
    by_key = {k: f for f, k in mapping.items()}
    contacts = {by_key[k]: flags for k, flags in detect_contacts(motion, feet=tuple(FEET)).items()}
    limbs = {g: [(by_key[a], by_key[b], a, b) for a, b in pairs] for g, pairs in limb_pairs("cmu").items()}
    q_init = robot["q_neutral"].copy()
    q_init[:3] = targets[0, frames.index(by_key["Hips"])]
    oriented, rotations = [by_key["Hips"]], [pelvis_rotations(keys, names)]
    if feet_orientation:
        for side in ("Left", "Right"):
            foot = by_key[f"{side}Foot"]
            oriented.append(foot)
            rotations.append(foot_rotations(keys, names, side, contacts[foot]))
    return {"motion": motion, "scale": scale, "keypoints": keys, "names": names, "frames": frames,
            "targets": targets, "contacts": contacts, "limbs": limbs, "q_init": q_init,
            "oriented": oriented, "rotations": np.stack(rotations, axis=1),
            "mapping": [(f, mapping[f]) for f in frames]}


def run_pink(robot_name: str, case: dict, steps: int, extra: list[str] | None = None, timeout: float = 900.0) -> dict:
    """GMR's method in the peers' venv: configurations (N, nq), wall_s (N,), settings, failures."""
    urdf, _ = robot_files(robot_name)
    with tempfile.TemporaryDirectory() as tmp:
        src, out = Path(tmp) / "targets.npz", Path(tmp) / "out.npz"
        np.savez(src, urdf_path=str(urdf), frames=json.dumps(case["frames"]), targets=case["targets"],
                 fps=case["motion"].fps, q_init=case["q_init"], oriented=json.dumps(case["oriented"]),
                 rotations=case["rotations"])
        subprocess.run([str(PEERS_PYTHON), str(SCRIPTS / "retarget_pink.py"), str(src), "-o", str(out),
                        "--steps", str(steps), *(extra or [])], check=True, timeout=timeout)
        z = np.load(out, allow_pickle=False)
        names = json.loads(str(z["joint_names"]))
        model = jr.build_model(urdf)
        if names != list(model.names)[1:]:
            raise ValueError(f"the peers' Pinocchio orders {robot_name}'s joints otherwise than ours")
        return {"configurations": z["configurations"], "wall_s": z["wall_s"], "failures": int(z["failures"]),
                "settings": json.loads(str(z["settings"]))}


# ------------------------------------------------------------------------------------------------ evoik hook
def retarget_evoik(robot_name: str, motion, scale: float, report: dict | None = None):
    """evoik_pin's retargeter on ``motion`` at ``scale`` (the CMU preset: the mapped frames :func:`prepare` uses), as
    (configurations (N, nq) of ``pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer())``, wall seconds of the
    retargeting alone, the robot loaded before the clock), or None without ``evoik_pin.retarget``; the clip's
    report into ``report`` when given (its ``steady_fps``, ``first_frame_s``, ``setup_s``)."""
    import evoik_pin

    if not hasattr(evoik_pin, "retarget"):
        return None
    robot = evoik_pin.load_robot(robot_name, floating_base=True)
    start = time.perf_counter()
    clip = evoik_pin.retarget(robot, motion, mapping="cmu", scale=scale)
    seconds = time.perf_counter() - start
    if report is not None:
        report.update(clip.report)
    return np.asarray(clip.configurations), seconds


def judge(robot_name: str, case: dict, configurations: np.ndarray, ground: float = 0.0) -> dict:
    """The judge's verdict on a clip whose floor is z = ``ground`` (m): 0 for the targets of :func:`prepare`;
    evoik_pin retargets in the source's world, whose floor is ``ground_height(motion)``."""
    urdf, srdf = robot_files(robot_name)
    return jr.judge_clip(urdf, srdf, configurations, case["motion"].fps, case["keypoints"], case["mapping"],
                         case["contacts"], ground, case["limbs"], keypoint_names=case["names"])


HEADER = ("| clip | robot | method | frames | fps | first ms | limit | vel | coll | skate mm | pen mm "
          "| legs deg (worst) | trunk deg (worst) | arms deg (worst) | track mm |")


def steady_fps(wall_s: np.ndarray) -> float:
    """Frames per second over frames 2..N (the first one starts from neutral and is reported apart)."""
    wall_s = np.asarray(wall_s, dtype=float)
    return (len(wall_s) - 1) / wall_s[1:].sum() if len(wall_s) > 1 else float("nan")


def row(clip: str, robot: str, method: str, verdict: dict, fps: float, first_ms: float) -> str:
    def group(g):
        v = verdict["limbs"][g]
        return f"{v['mean_deg']:.1f} ({v['worst_limb_mean_deg']:.1f})"
    return (f"| {clip} | {robot} | {method} | {verdict['frames']} | {fps:.0f} | {first_ms:.1f} "
            f"| {verdict['joint_limit_frames']} "
            f"| {verdict['velocity_limit_frames']} | {verdict['self_collision_frames']} "
            f"| {verdict['foot_skating_mm_mean']:.1f} | {verdict['ground_penetration_mm_max']:.1f} "
            f"| {group('legs')} | {group('trunk')} | {group('arms')} | {verdict['tracking_mm_mean']:.1f} |")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--clips", nargs="+", default=list_clips())
    parser.add_argument("--robots", nargs="+", default=list(ROBOTS), choices=list(ROBOTS))
    parser.add_argument("--steps", type=int, default=5, help="pink's QP steps per frame (5: see the K sweep)")
    parser.add_argument("--pink-args", default="", help="more retarget_pink.py options, e.g. '--posture-cost 1e-3'")
    parser.add_argument("--sweep", default="", help="comma-separated K values: pink's tracking vs K instead")
    parser.add_argument("--feet-orientation", action="store_true",
                        help="pink also tracks the source feet's orientations (flat at rest; see foot_rotations)")
    parser.add_argument("--json", help="also write every verdict to this file")
    args = parser.parse_args(argv)
    now = datetime.datetime.now(datetime.UTC)
    print(f"# {now:%Y-%m-%d %H:%M} UTC, {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"load {os.getloadavg()[0]:.2f}")
    out = []
    if args.sweep:
        print("| clip | robot | K | fps | track mm mean | track mm max | legs | trunk | arms | vel | limit "
              "| QP fails |")
        print("|---|---|---|---|---|---|---|---|---|---|---|---|")
        for clip in args.clips:
            for robot in args.robots:
                case = prepare(clip, robot, args.feet_orientation)
                for k in (int(s) for s in args.sweep.split(",")):
                    run = run_pink(robot, case, k, args.pink_args.split())
                    v = judge(robot, case, run["configurations"])
                    fps = steady_fps(run["wall_s"])
                    print(f"| {clip} | {robot} | {k} | {fps:.0f} | {v['tracking_mm_mean']:.1f} "
                          f"| {v['tracking_mm_max']:.1f} | {v['limbs']['legs']['mean_deg']:.1f} "
                          f"| {v['limbs']['trunk']['mean_deg']:.1f} | {v['limbs']['arms']['mean_deg']:.1f} "
                          f"| {v['velocity_limit_frames']} | {v['joint_limit_frames']} | {run['failures']} |",
                          flush=True)
                    out.append({"clip": clip, "robot": robot, "steps": k, "fps": fps, "verdict": v})
    else:
        print(HEADER)
        print("|" + "---|" * (HEADER.count("|") - 1))
        settings = None
        for clip in args.clips:
            for robot in args.robots:
                case = prepare(clip, robot, args.feet_orientation)
                run = run_pink(robot, case, args.steps, args.pink_args.split())
                settings = run["settings"]
                v = judge(robot, case, run["configurations"])
                fps = steady_fps(run["wall_s"])
                method = f"pink K={args.steps}" + (" +feet" if args.feet_orientation else "")
                print(row(clip, robot, method, v, fps, run["wall_s"][0] * 1e3), flush=True)
                out.append({"clip": clip, "robot": robot, "method": "pink", "scale": case["scale"], "fps": fps,
                            "first_ms": run["wall_s"][0] * 1e3,
                            "failures": run["failures"], "verdict": v})
                clip_report: dict = {}
                ours = retarget_evoik(robot, case["motion"], case["scale"], clip_report)
                if ours is None:
                    print(f"| {clip} | {robot} | evoik_pin | not built yet | | | | | | | | | | | |", flush=True)
                else:
                    configurations, seconds = ours
                    v = judge(robot, case, configurations, ground_height(case["motion"]))
                    # the steady rate (frames 2..N) and the first frame apart, as pink's; the whole call (the
                    # clip's set-up, a robot's first scene hulls, the first frame's search) in the JSON
                    fps = clip_report["steady_fps"]
                    print(row(clip, robot, "evoik_pin", v, fps, clip_report["first_frame_s"] * 1e3), flush=True)
                    out.append({"clip": clip, "robot": robot, "method": "evoik_pin", "fps": fps,
                                "first_ms": clip_report["first_frame_s"] * 1e3, "setup_s": clip_report["setup_s"],
                                "whole_call_fps": len(configurations) / seconds, "verdict": v})
        print(f"# pink settings: {json.dumps(settings)}")
        print(f"# load after: {os.getloadavg()[0]:.2f}")
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1), encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
