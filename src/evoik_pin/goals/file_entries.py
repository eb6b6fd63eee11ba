"""The pieces goal kinds declare their goals-file entries (:mod:`evoik_pin.io.goals_file`) with: a kind's
:meth:`~evoik_pin.goals.goal.Goal.file_kind` is a :class:`FileKind` built from the readers and writers here. Every
error is a GoalsFileError naming the field; :mod:`evoik_pin.io.goals_file` adds the file and the goal."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np

from ..errors import GoalsFileError
from ..io import datafile
from ..io.datafile import Flow, floats
from ..target import Target
from .bands import DEFAULT_GOAL_TOLERANCE

__all__ = ["FIELD_READERS", "FileKind", "field_entries", "matrix_text", "name_entry", "number", "numbers",
           "orientation_target", "pointing", "pose_target", "position_target", "position_text",
           "unknown_keys", "vector_target"]

#: The data files' field readers raising GoalsFileError.
number = partial(datafile.number, error=GoalsFileError)
numbers = partial(datafile.numbers, error=GoalsFileError)
unknown_keys = partial(datafile.unknown_keys, error=GoalsFileError)


def pose_target(target: dict) -> Target:
    """A pose's target: ``matrix`` alone, or ``position`` with ``rpy`` (degrees) or ``rpy_rad``."""
    unknown_keys(target, ("position", "rpy", "rpy_rad", "matrix"), "target")
    if "matrix" in target:
        if len(target) > 1:
            raise GoalsFileError(f"target: matrix is the whole pose; give it alone, not with "
                                 f"{', '.join(k for k in target if k != 'matrix')}")
        rows = target["matrix"]
        if not isinstance(rows, list) or len(rows) != 4:
            raise GoalsFileError(f"target.matrix must be 4 rows of 4 numbers (a homogeneous pose, m), got {rows!r}")
        return Target.coerce(np.array([numbers(row, 4, f"target.matrix row {k}") for k, row in enumerate(rows)]))
    if "position" not in target:
        raise GoalsFileError("target of a pose needs position: [x, y, z] (m) with rpy: [r, p, y] (degrees) or "
                             "rpy_rad: (rad), or matrix: a 4 x 4 pose")
    angles = [k for k in ("rpy", "rpy_rad") if k in target]
    if len(angles) != 1:
        raise GoalsFileError("target of a pose needs one of rpy: [r, p, y] (degrees) and rpy_rad: (rad) with its "
                             f"position, got {'both' if angles else 'neither'}; for a position alone use kind: "
                             "position")
    rpy = numbers(target[angles[0]], 3, f"target.{angles[0]}")
    return Target.from_rpy(numbers(target["position"], 3, "target.position (m)"),
                           np.radians(rpy) if angles[0] == "rpy" else rpy)


def position_target(target: dict) -> np.ndarray:
    """A position's target: ``position`` (m), no orientation."""
    if any(k in target for k in ("rpy", "rpy_rad", "matrix")):
        raise GoalsFileError("target: a position goal has no orientation (rpy, rpy_rad, matrix); use kind: pose "
                             "for one")
    return vector_target("position", " (m)")(target)


def orientation_target(target: dict) -> np.ndarray:
    """An orientation's target: ``rpy`` (degrees) or ``rpy_rad`` alone, or a 3 x 3 (or 4 x 4) ``matrix``."""
    unknown_keys(target, ("rpy", "rpy_rad", "matrix"), "target")
    if len(target) != 1:
        raise GoalsFileError("target of an orientation needs one of rpy: [r, p, y] (degrees), rpy_rad: (rad) and "
                             f"matrix: a 3 x 3 rotation, got {', '.join(target) or 'none'}")
    if "matrix" in target:
        rows = target["matrix"]
        if not isinstance(rows, list) or len(rows) not in (3, 4):
            raise GoalsFileError(f"target.matrix must be 3 rows of 3 numbers (a rotation), got {rows!r}")
        return np.array([numbers(row, len(rows), f"target.matrix row {k}") for k, row in enumerate(rows)])
    key = next(iter(target))
    rpy = numbers(target[key], 3, f"target.{key}")
    return Target.from_rpy(np.zeros(3), np.radians(rpy) if key == "rpy" else rpy).rotation


def vector_target(name: str, unit: str = "") -> Callable[[dict], np.ndarray]:
    """The reader of a target that is one 3-vector under the key ``name`` (direction, point, position)."""
    def read(target: dict) -> np.ndarray:
        unknown_keys(target, (name,), "target")
        if name not in target:
            raise GoalsFileError(f"target needs {name}: [x, y, z]{unit}")
        return numbers(target[name], 3, f"target.{name}{unit}")
    return read


def tolerance_entry(value, what: str):
    """A tolerance: one number, or a list of half-widths (``.inf`` or ``"inf"``: free)."""
    if not isinstance(value, list):
        return number(value, what)
    return [math.inf if isinstance(v, str) and v.strip().lower() in ("inf", ".inf") or v == math.inf
            else number(v, f"{what}[{k}]") for k, v in enumerate(value)]


def free_entry(value, what: str):
    if isinstance(value, str) or (isinstance(value, list) and all(isinstance(v, str) for v in value)):
        return value
    raise GoalsFileError(f"{what} must name axes (a string such as 'rz' or a list of names), got {value!r}")


def name_entry(value, what: str) -> str:
    """A name (a non-empty string), such as ``expressed_in: world``; the goal checks which names it accepts."""
    if not isinstance(value, str) or not value:
        raise GoalsFileError(f"{what} must be a name (a string), got {value!r}")
    return value


#: How the optional fields other than numbers are read (the others: :func:`number`).
FIELD_READERS = {"tolerance": tolerance_entry, "free": free_entry, "axis": lambda value, what: numbers(value, 3, what),
                 "expressed_in": name_entry}


def matrix_text(goal) -> dict:
    """A pose target as its 4 x 4 ``matrix`` (m), a rotation as its 3 x 3 one."""
    return {"matrix": [floats(row) for row in getattr(goal.target, "homogeneous", goal.target)]}


def position_text(goal) -> dict:
    """A position target as its ``position`` (m)."""
    return Flow(position=floats(goal.target))


@dataclass(frozen=True)
class FileKind:
    """One ``kind:`` of a goals file: its ``name``, its goal class, the optional fields it takes (besides frame, kind
    and target), how its ``target:`` mapping is read and how a goal's target is written; ``make`` (frame, target,
    **fields) -> goal where the class takes its arguments in another order (None: the class)."""

    name: str
    cls: type
    fields: tuple[str, ...]
    read_target: Callable[[dict], object]
    write_target: Callable[[object], dict]
    make: Callable | None = None
    #: Kinds whose entries are not (frame, target, numbers): the whole entry read (entry, what) -> Goal, and the
    #: whole entry written (goal) -> dict.
    read: Callable[[dict, str], object] | None = None
    write: Callable[[object], dict] | None = None
    #: How the targets a goal set's ``targets:`` reads become the class's members (None: as read).
    set_member: Callable | None = None
    #: A kind on two frames: ``frame_a`` and ``frame`` (frame b), read as ``cls(frame_a, frame, target, **fields)``.
    pair: bool = False


def pointing(cls) -> Callable:
    """``make`` of a pointing kind: its required ``axis`` field first."""
    def make(frame, target, axis=None, **options):
        if axis is None:
            raise GoalsFileError(f"missing field 'axis' (a {cls.__name__} goal points the frame's axis: [x, y, z])")
        return cls(frame, axis, target, **options)
    return make


def field_entries(goal, fields: tuple[str, ...]) -> dict:
    """The entries of ``goal``'s optional ``fields`` as a goals file writes them (numbers where they differ from
    their defaults)."""
    entry: dict = {}
    defaults = {"weight": 1.0, "tolerance": DEFAULT_GOAL_TOLERANCE, "rotation_tolerance": goal.tolerance}
    band = getattr(goal, "band", None)
    for key in fields:
        if key == "tolerance" and band is not None:  # per-axis half-widths (inf: free)
            entry[key] = [float(v) for v in band]
        elif key == "free":
            if goal.free:
                entry[key] = " ".join(goal.free)
        elif key == "axis":
            entry[key] = floats(goal.axis)
        elif key == "expressed_in":
            if goal.expressed_in != "a":
                entry[key] = goal.expressed_in
        elif getattr(goal, key) != defaults[key]:
            entry[key] = float(getattr(goal, key))
    return entry
