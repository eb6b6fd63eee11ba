"""RelativePosition: one frame's origin placed relative to another's (two hands holding a box; a limb vector when
retargeting a motion) (see :mod:`evoik_pin.goals`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import OptionError
from .file_entries import FileKind, pair_kind, position_target, position_text
from .goal import BOTH, DEFAULT_GOAL_TOLERANCE, FramePair, Goal, point3
from .registry import FAMILY_BEYOND_FRAME, RELATIVE_POINT_IN_A, RELATIVE_POINT_WORLD, KindCode

__all__ = ["EXPRESSED_IN", "KIND_RELATIVE_POSITION", "KIND_RELATIVE_POSITION_IN_A", "RelativePosition"]

#: Its kernel codes (3 rows each, the compiled ``solvers/lm/balance.py``): ``p_b - p_a - p`` in the world's axes,
#: and ``R_a^T (p_b - p_a) - p`` in frame a's. Their ``aux`` row: ``goal.A_REL_*``.
KIND_RELATIVE_POSITION, KIND_RELATIVE_POSITION_IN_A = RELATIVE_POINT_WORLD, RELATIVE_POINT_IN_A
#: The axes ``p`` may be given in: frame a's, or the world's (the robot's base frame).
EXPRESSED_IN = ("a", "world")


@dataclass(frozen=True, eq=False, repr=False)
class RelativePosition(FramePair, Goal):
    """Frame ``frame_b``'s origin at ``p`` (3 numbers, m) from frame ``frame_a``'s origin, wherever the two frames
    are: ``p_b - p_a = p`` in the world's axes (``expressed_in="world"``: the robot's base frame; the vector keeps its
    direction in space), or ``R_a^T (p_b - p_a) = p`` in frame a's axes (``expressed_in="a"``, the default: the
    vector turns with frame a). Two hands holding a box 0.3 m wide: ``RelativePosition("left_hand", "right_hand",
    [0, -0.3, 0])``; a limb vector when retargeting a motion: ``expressed_in="world"``. Orientation free.

    Its error is ``|e|`` (m) of that equation's residual e; met when within ``tolerance`` (m, > 0, default 1e-6).

    Args: frame_a, frame_b, p, then ``expressed_in`` ("a" or "world"), ``weight`` (> 0, default 1) and ``tolerance``.
    """

    frame_a: str = ""
    target: object = None
    expressed_in: str = "a"
    KIND_CODES = (KindCode(KIND_RELATIVE_POSITION, (0, 1, 2), FAMILY_BEYOND_FRAME),
                  KindCode(KIND_RELATIVE_POSITION_IN_A, (0, 1, 2), FAMILY_BEYOND_FRAME))
    #: The optional fields of its goals-file entry.
    FILE_FIELDS = ("expressed_in", "weight", "tolerance")

    def __init__(self, frame_a: str, frame_b: str, p, expressed_in: str = "a", weight: float = 1.0,
                 tolerance: float = DEFAULT_GOAL_TOLERANCE) -> None:
        if expressed_in not in EXPRESSED_IN:
            raise OptionError(f"RelativePosition's expressed_in must be one of {', '.join(map(repr, EXPRESSED_IN))} "
                              f"(frame a's axes or the world's), got {expressed_in!r}")
        kind = KIND_RELATIVE_POSITION_IN_A if expressed_in == "a" else KIND_RELATIVE_POSITION
        self._init_common(frame_b, weight, tolerance, None, kind, False)
        self._init_pair(frame_a, frame_b, "RelativePosition")
        if not self.tolerance > 0:
            raise OptionError(f"tolerance (m) of the RelativePosition of {frame_b!r} from {frame_a!r} must be > 0, "
                              f"got {tolerance!r}")
        self._set(expressed_in=expressed_in, target=point3(p, f"RelativePosition of {frame_b!r} from {frame_a!r}: p"))

    @property
    def p(self) -> np.ndarray:
        """The wanted position (3,) (m) of frame b's origin from frame a's, in the axes ``expressed_in`` names."""
        return self.target

    def encode(self) -> tuple[np.ndarray, np.ndarray]:
        return self.target.copy(), np.eye(3)

    @property
    def both(self) -> float:
        """In the world's axes a joint moving both frames turns the vector (:data:`.goal.BOTH`); in frame a's it
        moves them together (0)."""
        return BOTH if self.expressed_in == "world" else 0.0

    def placement_errors(self, Ra, d, Rb) -> tuple[np.ndarray, np.ndarray]:
        """(|e| (N,) m, zeros (N,)): e the vector p_b - p_a, in the axes ``expressed_in`` names, minus ``p``."""
        v = np.einsum("nji,nj->ni", Ra, d) if self.expressed_in == "a" else d
        return np.linalg.norm(v - self.target, axis=1), np.zeros(len(d))

    @classmethod
    def file_kind(cls) -> FileKind:
        """``kind: relative_position``: ``frame_a``, ``frame`` (frame b) and ``target: {position: [x, y, z]}`` (m),
        with optional ``expressed_in`` (a | world), ``weight`` and ``tolerance``."""
        return pair_kind(cls, "relative_position", position_target, position_text)

    def __repr__(self) -> str:
        return (f"RelativePosition({self.frame_a!r}, {self.frame!r}, {np.round(self.target, 6).tolist()}, "
                f"expressed_in={self.expressed_in!r}, weight={self.weight:g}, tolerance={self.tolerance:g})")
