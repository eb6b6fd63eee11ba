"""A motion: named 3-D keypoints over frames (m, z up), the input a retargeter reads.

A :class:`Motion` is made from keypoint arrays (SMPL joint positions, a mocap marker set) or read from a BVH file
(:func:`evoik_pin.motion.load_bvh`). It is checked once when made and read-only after: NaN/inf keypoints, an
empty motion, duplicate names or an fps that is not a finite number > 0 raise :class:`~evoik_pin.errors.MotionError`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import MotionError
from ..robot.frames import closest_names

__all__ = ["Motion"]



def positive_number(value, message: str, error: type[Exception] = MotionError) -> float:
    """``value`` as a float when it is a finite number > 0 (a numeric string too), else ``error(message)``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise error(message) from None
    if not np.isfinite(v) or v <= 0.0:
        raise error(message)
    return v

class Motion:
    """Keypoint trajectories: ``positions`` (N, K, 3) in m in a z-up world frame, ``names`` (K,) and ``fps`` (Hz).

    Frame ``i`` is at time ``i / fps`` s. The arrays are copies made read-only, so a Motion can be shared.
    """

    __slots__ = ("_index", "fps", "names", "positions")

    def __init__(self, positions, names: Sequence[str], fps: float = 30.0):
        p = np.asarray(positions)
        if p.dtype == object or not (np.issubdtype(p.dtype, np.floating) or np.issubdtype(p.dtype, np.integer)):
            raise MotionError(f"Motion positions must be numbers, an (N, K, 3) array in m; got dtype {p.dtype}")
        if p.ndim != 3 or p.shape[2] != 3:
            raise MotionError(f"Motion positions must be an (N frames, K keypoints, 3) array in m; got shape "
                              f"{p.shape}")
        if p.shape[0] == 0 or p.shape[1] == 0:
            raise MotionError(f"Motion is empty: {p.shape[0]} frames of {p.shape[1]} keypoints (at least 1 frame "
                              f"of 1 keypoint is accepted)")
        p = np.array(p, dtype=float)
        bad = ~np.isfinite(p)
        if bad.any():
            frame, key = np.argwhere(bad)[0][:2]
            raise MotionError(f"Motion positions have {int(bad.any(axis=2).sum())} non-finite keypoint(s) (NaN or "
                              f"inf), the first at frame {frame}, keypoint {key}; only finite positions (m) are "
                              f"accepted: fill or drop the missing frames first")
        if isinstance(names, str):
            raise MotionError(f"Motion names must be a sequence of K = {p.shape[1]} strings, not one string")
        names = tuple(names)
        if len(names) != p.shape[1] or not all(isinstance(n, str) and n for n in names):
            raise MotionError(f"Motion names must be {p.shape[1]} non-empty strings (one per keypoint of positions "
                              f"{p.shape}); got {len(names)}: {list(names)[:8]}")
        index = {n: k for k, n in enumerate(names)}
        if len(index) != len(names):
            twice = sorted({n for n in names if names.count(n) > 1})
            raise MotionError(f"Motion names must be unique; repeated: {twice}")
        rate = positive_number(fps, f"Motion fps must be a finite number > 0 (frames per second); got {fps!r}")
        p.setflags(write=False)
        self.positions = p
        self.names = names
        self.fps = rate
        self._index = index

    def __setattr__(self, name, value):
        if hasattr(self, "_index"):  # set once in __init__, read-only after
            raise AttributeError(f"Motion is read-only: make a new Motion instead of setting {name}")
        object.__setattr__(self, name, value)

    def __reduce__(self):  # pickle and deepcopy through the checked constructor (the attributes are read-only)
        return (Motion, (self.positions, self.names, self.fps))

    def __repr__(self) -> str:
        return f"Motion({self.frames} frames x {len(self.names)} keypoints at {self.fps:g} fps, {self.duration:.2f} s)"

    def __len__(self) -> int:
        return self.frames

    @property
    def frames(self) -> int:
        """Number of frames N."""
        return self.positions.shape[0]

    @property
    def duration(self) -> float:
        """Time from the first frame to the last, s: ``(N - 1) / fps`` (0 for one frame)."""
        return (self.frames - 1) / self.fps

    @property
    def times(self) -> np.ndarray:
        """Frame times (N,) in s, from 0."""
        return np.arange(self.frames) / self.fps

    def index(self, name: str) -> int:
        """Column k of keypoint ``name`` in ``positions[:, k]``; an unknown name raises
        :class:`~evoik_pin.errors.MotionError` listing the closest names."""
        try:
            return self._index[name]
        except (KeyError, TypeError):
            close = closest_names(str(name), list(self.names))
            hint = f"; closest: {close}" if close else f"; names: {list(self.names)}"
            raise MotionError(f"motion has no keypoint {name!r}{hint}") from None

    def trajectory(self, name: str) -> np.ndarray:
        """Positions (N, 3) in m of keypoint ``name`` over the frames (read-only view)."""
        return self.positions[:, self.index(name)]

    def slice(self, start: int = 0, stop: int | None = None) -> Motion:
        """Frames ``start`` to ``stop`` (exclusive; Python's negative indices allowed) as a new Motion at the same
        fps; an empty range raises :class:`~evoik_pin.errors.MotionError`."""
        picked = range(self.frames)[slice(start, stop)]
        if len(picked) == 0:
            raise MotionError(f"Motion.slice({start}, {stop}) selects no frame of {self.frames}; accepted: a range "
                              f"holding at least one of frames 0..{self.frames - 1}")
        return Motion(self.positions[picked.start:picked.stop], self.names, self.fps)

    def resampled(self, fps: float) -> Motion:
        """The motion at ``fps`` (Hz) by linear interpolation between frames, over the same time span: frame j at
        ``j / fps`` s for every j with ``j / fps <= duration``."""
        rate = Motion(self.positions[:1], self.names, fps).fps  # the same fps check as the constructor
        t_new = np.arange(int(np.floor(self.duration * rate + 1e-9)) + 1) / rate
        s = t_new * self.fps  # position in source frames
        i0 = np.minimum(np.floor(s).astype(int), self.frames - 1)
        i1 = np.minimum(i0 + 1, self.frames - 1)
        w = (s - i0)[:, None, None]
        return Motion((1.0 - w) * self.positions[i0] + w * self.positions[i1], self.names, rate)

    def height(self) -> float:
        """Standing height estimate, m: the median over frames of the keypoints' vertical extent (highest z minus
        lowest z). Meant for a clip upright most of the time (walking, dancing); a clip spent lying or in the air
        upside down reads lower or higher. Keypoints are joints, so this is joint height (a head joint or end
        site, not the top of the skull)."""
        z = self.positions[:, :, 2]
        return float(np.median(z.max(axis=1) - z.min(axis=1)))
