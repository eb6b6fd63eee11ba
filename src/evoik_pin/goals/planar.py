"""Planar: a frame's (x, y) in the base xy-plane and optionally its heading (also a planar Target of the tip)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .. import lie
from ..errors import TargetError
from .file_entries import number, unknown_keys
from .goal import DEFAULT_GOAL_TOLERANCE, Goal
from .registry import FAMILY_FRAME, PLANAR, PLANAR_YAW, KindCode

__all__ = ["KIND_PLANAR", "KIND_PLANAR_YAW", "Planar"]

#: A planar goal's kernel codes: x, y (2 rows), and x, y with the heading (3 rows).
KIND_PLANAR, KIND_PLANAR_YAW = PLANAR, PLANAR_YAW


def _planar_target(target: dict) -> tuple[float, float, float | None]:
    """A planar goal's target: ``x``, ``y`` (m) and optionally ``yaw_rad`` (rad)."""
    unknown_keys(target, ("x", "y", "yaw_rad"), "target")
    return (number(target.get("x"), "target x (m)"), number(target.get("y"), "target y (m)"),
            None if "yaw_rad" not in target else number(target["yaw_rad"], "target yaw_rad (rad)"))


@dataclass(frozen=True, eq=False, repr=False)
class Planar(Goal):
    """The frame's origin at (x, y) (m) in the robot's base xy-plane (its height free) and, with ``yaw`` (rad), its
    heading ``atan2(R[1, 0], R[0, 0])`` at ``yaw``.

    Args: frame, x, y, yaw (None: heading free), then ``weight`` (> 0, default 1), ``tolerance`` (m, default 1e-6,
    on the distance in the plane) and ``rotation_tolerance`` (rad, default ``tolerance``, on the wrapped heading
    difference).
    """

    #: (x, y, yaw or 0): the kernel's target row.
    target: object = None
    yaw: float | None = None
    KIND_CODES = (KindCode(KIND_PLANAR, (0, 1), FAMILY_FRAME),
                  KindCode(KIND_PLANAR_YAW, (0, 1, 5), FAMILY_FRAME, oriented=True, angle=True))
    #: ``kind: planar``: ``target: {x, y[, yaw_rad]}`` (m, rad); weight, tolerance, rotation_tolerance.
    FILE_ENTRY = ("planar", ("weight", "tolerance", "rotation_tolerance"), _planar_target,
                  lambda g: {"x": float(g.target[0]), "y": float(g.target[1])}
                  | ({} if g.yaw is None else {"yaw_rad": g.yaw}),
                  {"make": lambda frame, target, **fields: Planar(frame, *target, **fields)})

    def __init__(self, frame: str, x: float, y: float, yaw: float | None = None, weight: float = 1.0,
                 tolerance: float | None = DEFAULT_GOAL_TOLERANCE, rotation_tolerance: float | None = None) -> None:
        self._init_common(frame, weight, tolerance, rotation_tolerance,
                          KIND_PLANAR if yaw is None else KIND_PLANAR_YAW, yaw is not None)
        try:
            target = np.array([x, y, 0.0 if yaw is None else yaw], dtype=float)
        except (TypeError, ValueError):
            target = np.full(3, np.nan)
        if not np.isfinite(target).all():
            raise TargetError(f"Planar on {frame!r} takes finite numbers x, y (m) and yaw (rad) or None, got "
                              f"{x!r}, {y!r}, {yaw!r}")
        self._set(target=target, yaw=None if yaw is None else float(target[2]))

    def population_errors(self, P: np.ndarray, R: np.ndarray, pt, Rt) -> tuple[np.ndarray, np.ndarray]:
        """(distances (N,) m in the base xy-plane, |wrapped heading differences| (N,) rad, 0 without a yaw) of frame
        poses P (N, 3), R (N, 3, 3)."""
        d = P[:, :2] - self.target[:2]
        pos = np.sqrt((d * d).sum(axis=1))
        rot = (np.abs(lie.wrap_angle(lie.yaw(R) - self.yaw)) if self.yaw is not None else np.zeros_like(pos))
        return pos, rot

    def marker(self) -> tuple[str, np.ndarray, np.ndarray | None]:
        """A sphere at (x, y, 0), a triad turned by the yaw when it has one."""
        x, y, yaw = self.target
        R = pin.rpy.rpyToMatrix(0.0, 0.0, yaw) if self.yaw is not None else None
        return self.frame, np.array([x, y, 0.0]), R

    def __repr__(self) -> str:
        yaw = "" if self.yaw is None else f", yaw={self.yaw:g}"
        return (f"Planar({self.frame!r}, x={self.target[0]:g}, y={self.target[1]:g}{yaw}, weight={self.weight:g}, "
                f"tolerance={self.tolerance:g}, rotation_tolerance={self.rotation_tolerance:g})")
