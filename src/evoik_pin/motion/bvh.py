"""BVH motion files read into a :class:`~evoik_pin.motion.Motion` of every joint's world position (m, z up).

Our own small parser (NumPy only): BVH is a simple text format, and a joint-position reader needs a fraction of
what the BVH libraries on PyPI carry (``bvhio`` builds a transform tree object per joint and frame). It reads any
hierarchy (several roots too) with any channel order: each joint has 3 rotation channels, or 3 position and
3 rotation channels (6), or any subset of the six, in the order its ``CHANNELS`` line gives. Rotation channels are
Euler angles in degrees applied in the listed order about the joint's moving axes (``Zrotation Xrotation
Yrotation`` means ``R = Rz(a) Rx(b) Ry(c)``), as every BVH writer means them. A joint's position channels are its
translation from its parent, in place of its ``OFFSET`` (LAFAN1's root holds its world position there, with a
rest offset beside it). ``End Site`` blocks become keypoints named ``<parent>_end``.

Forward kinematics runs over all frames at once: per joint a stack of (N, 3, 3) rotations.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ..errors import BvhError
from ..lie import exp3
from .motion import Motion
from .units import infer_unit, unit_scale

__all__ = ["Y_UP_TO_Z_UP", "BvhSkeleton", "load_bvh", "parse_bvh"]

#: Rotation taking a Y-up file's coordinates to evoik_pin's Z-up world: (x, y, z) -> (z, x, y), a cyclic
#: permutation (det +1, nothing mirrored). A Y-up character facing +z with its left on +x (CMU's, LAFAN's and
#: Xsens' convention) then faces +x with its left on +y: a robot's base frame (x forward, y left, z up).
Y_UP_TO_Z_UP = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])

_AXES = {"X": 0, "Y": 1, "Z": 2}
_CHANNELS = {f"{a}{kind}" for a in "XYZ" for kind in ("position", "rotation")}


@dataclass
class _Node:
    name: str
    parent: int  # index into the node list, -1 for a root
    offset: np.ndarray  # (3,) file units, in the parent's frame
    channels: list[str] = field(default_factory=list)
    first_channel: int = 0  # column of its first channel in a frame line
    end_site: bool = False


@dataclass(frozen=True)
class BvhSkeleton:
    """A parsed BVH file: its nodes (joints and end sites, parents first) and its frames of channel values.

    ``names`` (K,), ``parents`` (K,) with -1 for a root, ``offsets`` (K, 3) file units, ``channels`` (K lists of
    channel names), ``first_channel`` (K,) column of each node's first channel in ``values`` (N, C), ``frame_time``
    s per frame.
    """

    names: tuple[str, ...]
    parents: np.ndarray
    offsets: np.ndarray
    channels: tuple[tuple[str, ...], ...]
    first_channel: np.ndarray
    values: np.ndarray
    frame_time: float

    def positions(self) -> np.ndarray:
        """World positions (N, K, 3) of every node in file units and file axes (forward kinematics)."""
        n = self.values.shape[0]
        K = len(self.names)
        pos = np.zeros((n, K, 3))
        rot = np.zeros((n, K, 3, 3))
        for k in range(K):
            translation = np.broadcast_to(self.offsets[k], (n, 3)).copy()
            local = None
            for j, channel in enumerate(self.channels[k]):
                column = self.values[:, self.first_channel[k] + j]
                axis = _AXES[channel[0]]
                if channel.endswith("position"):
                    translation[:, axis] = column
                else:
                    phi = np.zeros((n, 3))
                    phi[:, axis] = np.deg2rad(column)
                    turn = exp3(phi)
                    local = turn if local is None else local @ turn
            parent = self.parents[k]
            if parent < 0:
                pos[:, k] = translation
                rot[:, k] = np.eye(3) if local is None else local
            else:
                pos[:, k] = pos[:, parent] + np.einsum("nij,nj->ni", rot[:, parent], translation)
                rot[:, k] = rot[:, parent] if local is None else rot[:, parent] @ local
        return pos


def parse_bvh(text: str, source: str = "<text>") -> BvhSkeleton:
    """Parse BVH ``text`` (``source`` names it in errors) into a :class:`BvhSkeleton`; every defect raises
    :class:`~evoik_pin.errors.BvhError` naming ``source`` and the line (from 1)."""
    lines = text.splitlines()
    tokens: list[tuple[str, int]] = []
    motion_line = None
    for number, line in enumerate(lines, start=1):
        words = line.split()
        if words and words[0].upper() == "MOTION":
            motion_line = number
            break
        tokens.extend((w, number) for w in words)
    if not tokens or tokens[0][0].upper() != "HIERARCHY":
        raise BvhError(f"{source}: not a BVH file: it must start with HIERARCHY (found "
                       f"{tokens[0][0]!r} on line {tokens[0][1]})" if tokens else f"{source}: empty BVH file")
    nodes = _parse_hierarchy(tokens, source)
    if motion_line is None:
        raise BvhError(f"{source}: no MOTION section after the hierarchy (a BVH file needs MOTION, Frames:, "
                       f"Frame Time: and one line of values per frame)")
    values, frame_time = _parse_motion(lines, motion_line, sum(len(n.channels) for n in nodes), source)
    return BvhSkeleton(
        names=tuple(n.name for n in nodes),
        parents=np.array([n.parent for n in nodes], dtype=int),
        offsets=np.array([n.offset for n in nodes], dtype=float).reshape(-1, 3),
        channels=tuple(tuple(n.channels) for n in nodes),
        first_channel=np.array([n.first_channel for n in nodes], dtype=int),
        values=values,
        frame_time=frame_time,
    )


def _parse_hierarchy(tokens: list[tuple[str, int]], source: str) -> list[_Node]:
    """Nodes in file order (parents first) from the hierarchy's tokens (after HIERARCHY)."""
    nodes: list[_Node] = []
    stack: list[int] = []  # open blocks: node indices
    channel_count = 0
    i = 1
    pending: _Node | None = None  # a ROOT/JOINT/End Site whose "{" is next

    def need(count: int, what: str) -> list[tuple[str, int]]:
        if i + count > len(tokens):
            raise BvhError(f"{source}: line {tokens[-1][1]}: the hierarchy ends inside {what}")
        return tokens[i:i + count]

    while i < len(tokens):
        word, line = tokens[i]
        key = word.upper()
        if key in ("ROOT", "JOINT"):
            (name, _), = need(2, f"{word}")[1:]
            if key == "JOINT" and not stack:
                raise BvhError(f"{source}: line {line}: JOINT {name} outside any ROOT block")
            if key == "ROOT" and stack:
                raise BvhError(f"{source}: line {line}: ROOT {name} inside another joint's block")
            pending = _Node(name, stack[-1] if stack else -1, np.zeros(3))
            i += 2
        elif key == "END":
            if i + 1 >= len(tokens) or tokens[i + 1][0].upper() != "SITE":
                raise BvhError(f"{source}: line {line}: 'End' must be followed by 'Site'")
            if not stack:
                raise BvhError(f"{source}: line {line}: End Site outside any joint block")
            parent = nodes[stack[-1]]
            pending = _Node(f"{parent.name}_end", stack[-1], np.zeros(3), end_site=True)
            i += 2  # "End Site"
        elif word == "{":
            if pending is None:
                raise BvhError(f"{source}: line {line}: '{{' without a ROOT, JOINT or End Site before it")
            nodes.append(pending)
            stack.append(len(nodes) - 1)
            pending = None
            i += 1
        elif word == "}":
            if not stack:
                raise BvhError(f"{source}: line {line}: '}}' closes no block")
            stack.pop()
            i += 1
        elif key == "OFFSET":
            if not stack:
                raise BvhError(f"{source}: line {line}: OFFSET outside any joint block")
            nodes[stack[-1]].offset = np.array([_number(w, ln, source) for w, ln in need(4, "OFFSET")[1:]])
            i += 4
        elif key == "CHANNELS":
            if not stack:
                raise BvhError(f"{source}: line {line}: CHANNELS outside any joint block")
            count_word = need(2, "CHANNELS")[1][0]
            if not count_word.isdigit() or not 1 <= int(count_word) <= 6:
                raise BvhError(f"{source}: line {line}: CHANNELS must be followed by a count from 1 to 6; got "
                               f"{count_word!r}")
            count = int(count_word)
            names = [w for w, _ in need(2 + count, "CHANNELS")[2:]]
            wrong = [c for c in names if c.capitalize() not in _CHANNELS] + [
                c for c, ln in tokens[i + 2:i + 2 + count] if ln != line]
            if wrong or len({c.lower() for c in names}) != count:
                raise BvhError(f"{source}: line {line}: CHANNELS {count} must list {count} different channels "
                               f"among Xposition Yposition Zposition Xrotation Yrotation Zrotation on its line; "
                               f"got {names}")
            node = nodes[stack[-1]]
            if node.end_site:
                raise BvhError(f"{source}: line {line}: an End Site has no channels")
            node.channels = [c.capitalize() for c in names]
            node.first_channel = channel_count
            channel_count += count
            i += 2 + count
        else:
            raise BvhError(f"{source}: line {line}: unexpected {word!r} in the hierarchy (accepted: ROOT, JOINT, "
                           f"End Site, OFFSET, CHANNELS, braces)")
    if stack or pending is not None:
        raise BvhError(f"{source}: the hierarchy ends with {len(stack)} block(s) still open (a missing '}}')")
    if not nodes:
        raise BvhError(f"{source}: the hierarchy has no ROOT joint")
    seen: dict[str, int] = {}
    for node in nodes:
        if node.name in seen:
            raise BvhError(f"{source}: joint name {node.name!r} appears twice; names must be unique")
        seen[node.name] = 1
    return nodes


def _number(word: str, line: int, source: str) -> float:
    try:
        value = float(word)
    except ValueError:
        raise BvhError(f"{source}: line {line}: {word!r} is not a number") from None
    if not np.isfinite(value):
        raise BvhError(f"{source}: line {line}: {word!r} is not a finite number")
    return value


def _header_value(lines: list[str], index: int, label: str, source: str) -> str:
    """The text after ``label`` (e.g. ``Frames:``) on line ``index`` (0-based)."""
    if index >= len(lines) or not lines[index].strip().lower().startswith(label.lower()):
        found = lines[index].strip()[:40] if index < len(lines) else "the end of the file"
        raise BvhError(f"{source}: line {index + 1}: expected {label!r} after MOTION; found {found!r}")
    return lines[index].strip()[len(label):].strip()


def _parse_motion(lines: list[str], motion_line: int, channels: int, source: str) -> tuple[np.ndarray, float]:
    """Frame values (N, channels) and the frame time (s) from the lines after MOTION (on line ``motion_line``)."""
    frames_text = _header_value(lines, motion_line, "Frames:", source)
    if not frames_text.isdigit():
        raise BvhError(f"{source}: line {motion_line + 1}: Frames: must be followed by a whole number; got "
                       f"{frames_text!r}")
    frames = int(frames_text)
    time_text = _header_value(lines, motion_line + 1, "Frame Time:", source)
    frame_time = _number(time_text, motion_line + 2, source)
    if frame_time <= 0.0:
        raise BvhError(f"{source}: line {motion_line + 2}: Frame Time must be > 0 s; got {time_text}")
    first = motion_line + 2  # 0-based index of the first frame line
    rows = [(number, line.split()) for number, line in enumerate(lines[first:], start=first + 1) if line.strip()]
    if frames == 0:
        raise BvhError(f"{source}: line {motion_line + 1}: Frames: 0; a motion needs at least one frame")
    if len(rows) != frames:
        raise BvhError(f"{source}: line {motion_line + 1}: Frames: {frames} but the file has {len(rows)} frame "
                       f"line(s) after Frame Time")
    for number, words in rows:
        if len(words) != channels:
            raise BvhError(f"{source}: line {number}: {len(words)} values; the hierarchy has {channels} channels")
    try:
        values = np.array([words for _, words in rows], dtype=float)
    except ValueError:
        for number, words in rows:
            for w in words:
                _number(w, number, source)
        raise  # pragma: no cover (the loop above names the bad value)
    if not np.isfinite(values).all():
        number = rows[int(np.argwhere(~np.isfinite(values))[0][0])][0]
        raise BvhError(f"{source}: line {number}: a value is not a finite number")
    return values, frame_time


def load_bvh(path: str | os.PathLike, unit=None, up: str = "y", fps: float | None = None) -> Motion:
    """Read a BVH file into a :class:`Motion` of every joint's and end site's world position (m, z up).

    ``unit``: the file's length unit, one of ``"m"``, ``"cm"``, ``"mm"``, ``"inch"``, ``"cmu"`` (CMU's 1/0.45 inch)
    or a number of m per file unit; by default inferred from the skeleton's size in the first frame (its largest
    extent along the file's axes: the standing height of an upright or lying body, the arm span in a T-pose) as
    the unit that makes it closest to 1.7 m. ``up``: the file's up axis, ``"y"`` (BVH's usual, CMU, LAFAN1,
    Xsens; turned to z by :data:`Y_UP_TO_Z_UP`) or ``"z"``. ``fps``: resample to this rate (Hz, linear
    interpolation); by default the file's own (1 / Frame Time). Keypoint names are the joint names, and
    ``<joint>_end`` for an End Site.
    """
    source = os.fspath(path)
    try:
        with open(source, encoding="utf-8", errors="replace") as f:
            text = f.read()
    except OSError as e:
        raise BvhError(f"cannot read BVH file {source}: {e.strerror or e}") from None
    if up not in ("y", "z", "Y", "Z"):
        raise BvhError(f"up must be 'y' (a Y-up file, BVH's usual) or 'z'; got {up!r}")
    skeleton = parse_bvh(text, source)
    positions = skeleton.positions()
    if up.lower() == "y":
        positions = positions @ Y_UP_TO_Z_UP.T
    if unit is None:
        first = positions[0]
        unit = infer_unit(float((first.max(axis=0) - first.min(axis=0)).max()))
    rate = 1.0 / skeleton.frame_time
    if abs(rate - round(rate)) < 1e-4 * rate:  # Frame Time's printed digits were cut: .0083333 is 120 fps
        rate = float(round(rate))
    motion = Motion(positions * unit_scale(unit), skeleton.names, rate)
    return motion if fps is None else motion.resampled(fps)
