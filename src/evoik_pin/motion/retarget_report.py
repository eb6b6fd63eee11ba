"""The quality report of a retargeted clip (``Clip.report``), measured on the answers with Pinocchio's forward
kinematics and the scene's exact collision check, not taken from the solver's own figures."""

from __future__ import annotations

import numpy as np

__all__ = ["clip_report"]

#: Slack of the limit checks: rounding of the box arithmetic (rad, m).
LIMIT_SLACK = 1e-9


def _angle_deg(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Angles (deg) between the rows of u and v (..., 3)."""
    nu, nv = np.linalg.norm(u, axis=-1), np.linalg.norm(v, axis=-1)
    c = np.einsum("...i,...i->...", u, v) / np.maximum(nu * nv, 1e-12)
    return np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))


def clip_report(robot, plan, Q: np.ndarray, success: np.ndarray, errors: list, v_max: np.ndarray, dt: float,
                scene, lower: np.ndarray, upper: np.ndarray) -> dict:
    """The figures listed in :func:`evoik_pin.motion.retarget.retarget`'s docstring, for joint rows ``Q`` (N, n).

    ``errors``: per frame, ``[(goal kind name, position error m), ...]``; ``lower``/``upper``: the bounds the
    frames were solved in (the joints' are the robot's); ``collided``: the frames the solve left colliding.
    """
    n_frames = Q.shape[0]
    frames = sorted({f for f, _ in plan.pairs} | set(plan.contacts))
    ids = [robot.frame_id(f) for f in frames]
    P = np.array([[pose.translation for pose in robot.frame_poses_unchecked(q, ids)] for q in Q])  # (N, F, 3)
    at = {f: k for k, f in enumerate(frames)}

    joints = slice(6, None) if robot.floating_base else slice(None)
    outside = (Q[:, joints] < robot.lower[joints] - LIMIT_SLACK) | (Q[:, joints] > robot.upper[joints] + LIMIT_SLACK)
    step = np.abs(np.diff(Q, axis=0))
    too_fast = (step > v_max * dt * (1 + 1e-9) + LIMIT_SLACK).any(axis=1)

    skating = []
    penetration = [0.0]
    for frame, flags in plan.contacts.items():
        p = P[:, at[frame]]
        both = flags[1:] & flags[:-1]
        skating.extend((np.linalg.norm(p[1:] - p[:-1], axis=1)[both] * 1e3).tolist())
        if plan.ground is not None:
            penetration.append(float(np.max(plan.ground - (p[:, 2] - plan.sole[frame])) * 1e3))

    angles = {}
    for group, limbs in plan.limbs.items():
        if not limbs:
            continue
        a_robot = np.stack([P[:, at[b]] - P[:, at[a]] for a, b in limbs], axis=1)
        a_source = np.stack([plan.source_points[:, plan.src_index[b]] - plan.source_points[:, plan.src_index[a]]
                             for a, b in limbs], axis=1)
        ang = _angle_deg(a_robot, a_source)
        angles[group] = {"mean": float(ang.mean()), "max": float(ang.max())}

    worst: dict[str, float] = {}
    for frame_errors in errors:
        for kind, e in frame_errors:
            worst[kind] = max(worst.get(kind, 0.0), float(e))
    return {
        "frames": n_frames,
        "success_rate": float(success.mean()),
        "failed_frames": np.flatnonzero(~success).tolist(),
        "max_goal_error_m": worst,
        "collision_frames": [i for i, q in enumerate(Q) if scene.in_collision(q)],
        "joint_limit_frames": np.flatnonzero(outside.any(axis=1)).tolist(),
        "velocity_limit_frames": (np.flatnonzero(too_fast) + 1).tolist(),
        "foot_skating_mm": {"mean": float(np.mean(skating)) if skating else 0.0,
                            "max": float(np.max(skating)) if skating else 0.0},
        "ground_penetration_mm": max(0.0, max(penetration)),
        "limb_angle_deg": angles,
    }
