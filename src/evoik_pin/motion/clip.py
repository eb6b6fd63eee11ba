"""A retargeted clip: a robot's joint trajectory at a frame rate, its quality report, and its files.

:func:`evoik_pin.retarget` returns a :class:`Clip`. Its rows are the robot's configurations frame by frame:
``q`` (N, robot.n) in evoik_pin's layout (a floating base as x, y, z m and yaw, pitch, roll rad, then the joints),
and ``configurations`` (N, nq) in Pinocchio's free-flyer layout, that of
``pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer())``: root position (m), root quaternion (x, y, z, w), then
the URDF's joints (rad or m). :meth:`Clip.save` writes ``.npz``, ``.csv`` or ``.pkl`` (GMR's layout).
"""

from __future__ import annotations

import csv
import pickle
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import OutputError

__all__ = ["SAVE_FORMATS", "Clip"]

#: File suffixes :meth:`Clip.save` writes.
SAVE_FORMATS = (".npz", ".csv", ".pkl")


@dataclass(frozen=True, eq=False)
class Clip:
    """A robot motion, one configuration per frame.

    Attributes:
        q: (N, n) joint vectors of the robot (its ``Robot.q`` layout; rad, m).
        configurations: (N, nq) Pinocchio free-flyer configurations: root xyz (m), quaternion xyzw, joints.
        fps: frames per second (Hz); frame i is at i / fps s.
        robot_name: the robot's name (``Robot.name``).
        joint_names: (nq - 7,) names of the columns after the root in ``configurations``.
        frames: the robot frames that followed motion keypoints (the mapping's frames).
        report: quality figures of the retargeting (see :func:`evoik_pin.motion.retarget.retarget`).
        keypoints: (N, K, 3) the source keypoints as the robot followed them (scaled, in the robot's world, m),
            and ``keypoint_names`` (K,): what a viewer draws beside the robot.
    """

    q: np.ndarray
    configurations: np.ndarray
    fps: float
    robot_name: str
    joint_names: tuple[str, ...]
    frames: tuple[str, ...] = ()
    report: dict = field(default_factory=dict)
    keypoints: np.ndarray | None = None
    keypoint_names: tuple[str, ...] = ()

    def __len__(self) -> int:
        return int(self.q.shape[0])

    def __repr__(self) -> str:
        return (f"Clip({self.robot_name!r}, {len(self)} frames at {self.fps:g} fps, "
                f"success rate {self.report.get('success_rate', float('nan')):.2f})")

    @property
    def root_pos(self) -> np.ndarray:
        """(N, 3) root link positions, m."""
        return self.configurations[:, :3]

    @property
    def root_rot(self) -> np.ndarray:
        """(N, 4) root link quaternions (x, y, z, w)."""
        return self.configurations[:, 3:7]

    @property
    def dof_pos(self) -> np.ndarray:
        """(N, nq - 7) the URDF's joint values (rad or m), columns :attr:`joint_names`."""
        return self.configurations[:, 7:]

    def save(self, path) -> Path:
        """Write the clip to ``path`` by its suffix and return the path:

        * ``.npz``: ``q`` (N, n), ``configurations`` (N, nq), ``fps``, ``joint_names``, ``robot_name``;
        * ``.csv``: a header row, then per frame root x, y, z (m), quaternion x, y, z, w, the joints (rad or m);
        * ``.pkl``: a dict ``fps``, ``root_pos`` (N, 3), ``root_rot`` (N, 4) xyzw, ``dof_pos`` (N, joints) (the
          layout GMR writes), plus ``joint_names``.

        Another suffix raises :class:`~evoik_pin.errors.OutputError`; so does a folder that cannot be written.
        """
        path = Path(path)
        suffix = path.suffix.lower()
        if suffix not in SAVE_FORMATS:
            raise OutputError(f"Clip.save: unknown file type {path.suffix!r} of {str(path)!r}; accepted: "
                              f"{', '.join(SAVE_FORMATS)}")
        try:
            if suffix == ".npz":
                np.savez(path, q=self.q, configurations=self.configurations, fps=np.float64(self.fps),
                         joint_names=np.array(self.joint_names), robot_name=np.array(self.robot_name))
            elif suffix == ".csv":
                header = ["root_x", "root_y", "root_z", "root_qx", "root_qy", "root_qz", "root_qw",
                          *self.joint_names]
                with path.open("w", newline="") as f:
                    writer = csv.writer(f)
                    writer.writerow(header)
                    writer.writerows([[repr(float(v)) for v in row] for row in self.configurations])
            else:
                data = {"fps": float(self.fps), "root_pos": np.array(self.root_pos),
                        "root_rot": np.array(self.root_rot), "dof_pos": np.array(self.dof_pos),
                        "joint_names": list(self.joint_names)}
                with path.open("wb") as f:
                    pickle.dump(data, f)
        except OSError as exc:
            raise OutputError(f"Clip.save could not write {str(path)!r}: {exc}") from exc
        return path
