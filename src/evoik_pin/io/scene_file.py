"""Scene files: a :class:`~evoik_pin.scene.Scene`'s obstacles as YAML or JSON by the extension: :func:`read_scene`
checks a file into plain data (:class:`SceneFile`), :func:`write_scene` writes a scene. Lengths in m, angles in rad,
poses in the robot's base frame::

    units: m                 # optional; m is the only unit accepted
    self_collision: true     # optional (default true): also check the robot against itself
    srdf: panda.srdf         # optional: SRDF whose disabled pairs are not checked (default: the robot's own)
    obstacles:
      - name: table          # unique, not the name of one of the robot's links
        kind: box
        size: [1.6, 1.6, 0.04]                           # edge lengths x, y, z
        pose: {xyz: [0.3, 0.0, -0.03], rpy: [0, 0, 0]}   # centre; rpy optional (R = Rz(y) Ry(p) Rx(r))
      - {name: ball, kind: sphere, radius: 0.08, pose: {xyz: [0.5, 0.2, 0.4]}}
      - {name: post, kind: cylinder, radius: 0.03, length: 0.8, pose: {xyz: [0.4, -0.4, 0.4]}}   # axis: pose z
      - {name: bar, kind: capsule, radius: 0.02, length: 0.5, pose: {xyz: [0.5, 0, 0.7], rpy: [0, 1.5708, 0]}}
      - name: bin
        kind: mesh
        path: meshes/bin.stl   # relative paths resolve against this file's folder; anything assimp reads
        scale: 0.001           # optional (default 1): one factor or three (a mesh in mm -> m)
        pose: [[1, 0, 0, 0.5], [0, 1, 0, -0.3], [0, 0, 1, 0.0], [0, 0, 0, 1]]   # or a 4 x 4 homogeneous matrix

Unknown keys are errors; every error is a :class:`~evoik_pin.errors.SceneError` naming the file, the obstacle
(index from 0 and name) and what is wrong.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import SceneError
from ..scene.geometry import as_placement
from .datafile import Flow, floats, naming, number, numbers, read_mapping, unknown_keys, write_data

__all__ = ["SceneFile", "read_scene", "write_scene"]

#: Keys an obstacle entry takes besides ``name``, ``kind`` and ``pose``, per kind (required, optional).
KIND_KEYS = {"box": (("size",), ()), "sphere": (("radius",), ()), "cylinder": (("radius", "length"), ()),
             "capsule": (("radius", "length"), ()), "mesh": (("path",), ("scale",))}
_TOP_KEYS = ("units", "self_collision", "srdf", "obstacles")
_POSE_HELP = "pose: {xyz: [x, y, z] (m), rpy: [roll, pitch, yaw] (rad, optional)} or a 4 x 4 homogeneous matrix"


@dataclass(frozen=True)
class SceneFile:
    """A scene file, checked: ``self_collision``, ``srdf`` (resolved against the file's folder, or None) and
    ``obstacles``, each ``(name, kind, Scene.add_<kind> keyword arguments, pose (pin.SE3))`` in file order."""

    path: Path
    self_collision: bool
    srdf: Path | None
    obstacles: list[tuple[str, str, dict, pin.SE3]]


#: The data files' field readers raising SceneError.
_number = partial(number, error=SceneError)
_numbers = partial(numbers, error=SceneError)
_unknown_keys = partial(unknown_keys, error=SceneError)


def _pose(value, what: str) -> pin.SE3:
    """A base-frame placement from ``{xyz, rpy}`` or a 4 x 4 matrix (list of four rows)."""
    if isinstance(value, dict):
        _unknown_keys(value, ("xyz", "rpy"), f"{what}: pose")
        if "xyz" not in value:
            raise SceneError(f"{what}: pose needs xyz ({_POSE_HELP})")
        xyz = _numbers(value["xyz"], 3, f"{what}: pose xyz (m)")
        rpy = _numbers(value.get("rpy", [0, 0, 0]), 3, f"{what}: pose rpy (rad)")
        return pin.SE3(pin.rpy.rpyToMatrix(*rpy), np.array(xyz))
    if isinstance(value, list) and len(value) == 4 and all(isinstance(row, list) for row in value):
        H = np.array([_numbers(row, 4, f"{what}: pose row {k}") for k, row in enumerate(value)])
        return as_placement(H, what)
    raise SceneError(f"{what}: bad pose {value!r}; expected {_POSE_HELP}")


def _obstacle(entry, k: int, folder: Path, seen: dict[str, int]) -> tuple[str, str, dict, pin.SE3]:
    """(name, kind, Scene.add_* keyword arguments, pose) of obstacle ``k``, checked."""
    if not isinstance(entry, dict):
        raise SceneError(f"obstacle {k}: expected a mapping with name, kind, pose and the kind's sizes, got {entry!r}")
    name = entry.get("name")
    what = f"obstacle {k}" + (f" ({name!r})" if name is not None else "")
    if not isinstance(name, str) or not name.strip():
        raise SceneError(f"{what}: missing or empty name (a unique string)")
    if name in seen:
        raise SceneError(f"{what}: the name {name!r} is already obstacle {seen[name]}'s; names must be unique")
    kind = entry.get("kind")
    if kind not in KIND_KEYS:
        raise SceneError(f"{what}: " + ("missing kind" if kind is None else f"unknown kind {kind!r}")
                         + f"; accepted kinds: {', '.join(KIND_KEYS)}")
    required, optional = KIND_KEYS[kind]
    _unknown_keys(entry, ("name", "kind", *required, *optional, "pose"), f"{what}, a {kind}")
    for key in (*required, "pose"):
        if key not in entry:
            hint = _POSE_HELP if key == "pose" else f"a {kind} needs {', '.join(required)}"
            raise SceneError(f"{what}: missing field {key!r} ({hint})")
    kw: dict = {}
    if kind == "box":
        kw["size"] = _numbers(entry["size"], 3, f"{what}: size (m)", positive=True)
    elif kind == "mesh":
        kw["path"] = _file_in(folder, entry["path"], f"{what}: path must be a mesh file name")
        scale, label = entry.get("scale", 1.0), f"{what}: scale (one factor or three)"
        kw["scale"] = _numbers(scale, 3, label, True) if isinstance(scale, list) else _number(scale, label, True)
    else:
        kw.update({key: _number(entry[key], f"{what}: {key} (m)", positive=True) for key in required})
    seen[name] = k
    return name, kind, kw, _pose(entry["pose"], what)


def read_scene(path: str | os.PathLike) -> SceneFile:
    """The scene file ``path`` (format: the module docstring), checked; SceneError."""
    path = Path(os.fspath(path)).expanduser()
    where = f"scene file {str(path)!r}"
    data = read_mapping(path, where, SceneError, _TOP_KEYS, "a mapping with an 'obstacles:' list")
    with naming(where, SceneError):
        units = data.get("units", "m")
        if units != "m":
            raise SceneError(f"units: only 'm' is accepted (lengths in metres, angles in radians), got {units!r}")
        self_collision = data.get("self_collision", True)
        if not isinstance(self_collision, bool):
            raise SceneError(f"self_collision must be true or false, got {self_collision!r}")
        srdf = data.get("srdf")
        srdf = None if srdf is None else _file_in(path.parent, srdf, "srdf must be a file name")
        entries = data.get("obstacles") or []
        if not isinstance(entries, list):
            raise SceneError(f"obstacles must be a list of obstacles, got {entries!r}")
        seen: dict[str, int] = {}
        obstacles = [_obstacle(entry, k, path.parent, seen) for k, entry in enumerate(entries)]
    return SceneFile(path, self_collision, srdf, obstacles)


def _file_in(folder: Path, name, what: str) -> Path:
    """The file ``name`` (a non-empty string; relative to ``folder`` unless absolute); SceneError "``what``, got
    ..." otherwise."""
    if not isinstance(name, str) or not name:
        raise SceneError(f"{what}, got {name!r}")
    return folder / Path(name).expanduser()  # an absolute path replaces the folder


def write_scene(scene, path: str | os.PathLike) -> Path:
    """Write ``scene`` to ``path`` (YAML or JSON; mesh paths relative to its folder when below it); return the path."""
    path = Path(os.fspath(path)).expanduser()
    data: dict = {"units": "m", "self_collision": scene.self_collision}
    if scene.srdf is not None and scene.srdf != getattr(scene.robot, "srdf", None):
        data["srdf"] = _relative(Path(scene.srdf), path.parent)
    data["obstacles"] = []
    for ob in scene.obstacles.values():
        entry = {"name": ob.name, "kind": ob.kind, **ob.params}  # a sphere's, cylinder's, capsule's lengths (m)
        if ob.kind == "box":
            entry["size"] = floats(ob.params["size"])
        elif ob.kind == "mesh":
            scale = floats(ob.params["scale"])
            entry["path"] = _relative(Path(ob.params["path"]), path.parent)
            entry["scale"] = scale[0] if len(set(scale)) == 1 else scale
        entry["pose"] = Flow(xyz=floats(ob.pose.translation), rpy=floats(pin.rpy.matrixToRpy(ob.pose.rotation)))
        data["obstacles"].append(entry)
    header = f"# evoik_pin scene of {scene.robot.name} (m, rad, robot base frame)\n"
    return write_data(path, data, header, "scene file", SceneError)


def _relative(file: Path, folder: Path) -> str:
    """``file`` relative to ``folder`` when it lies below it, else absolute."""
    file = file.resolve()
    try:
        return file.relative_to(folder.resolve()).as_posix()
    except ValueError:
        return str(file)
