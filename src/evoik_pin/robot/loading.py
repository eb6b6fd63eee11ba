"""Finding and reading a robot: bundled paper arms, ``example-robot-data`` arms, URDF files and strings.

:func:`load_robot` resolves a source (a URDF path, a URDF XML string, a bundled paper arm or an
``example-robot-data`` arm by name) to URDF text, builds the Pinocchio model of the whole URDF, picks the
arm's default tip frame and the directories its ``package://`` mesh URIs resolve against, and hands all
of it to :class:`~evoik_pin.robot.kinematics.Robot`, which extracts the chain.
"""

from __future__ import annotations

import importlib.metadata
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import RobotLoadError, RobotNotFoundError
from .kinematics import Robot

__all__ = [
    "BUNDLED_ROBOTS",
    "EXAMPLE_ARMS",
    "bundled_robots_dir",
    "example_robot_data_dir",
    "list_robots",
    "load_robot",
]

#: The papers' arms shipped with evoik_pin (``robots/<name>.urdf``), with the paper each comes from.
BUNDLED_ROBOTS: dict[str, str] = {
    "ax18": "000: Crustcrawler AX-18, 4R + tool (standard DH, Table 1)",
    "planar2r": "001: planar 2R elbow arm, a1 = 0.25 m, a2 = 0.16 m",
    "puma3r": "001: PUMA 560 positioning chain (wrist point, eq. 20)",
    "redundant7r": "002: redundant 7R arm (standard DH, eqs. 3-9)",
    "vehicle_arm": "003: planar vehicle (prismatic x, y) carrying a 3R arm",
    "aerial6r": "004: 6R human-like arm of an aerial manipulator (Table 1, standard DH)",
}


@dataclass(frozen=True)
class _ExampleArm:
    urdf: str  # path below example-robot-data's robots/ directory
    tip: str
    base: str | None = None


#: Arms of the ``example-robot-data`` wheel reachable by name, with their default tip frames.
EXAMPLE_ARMS: dict[str, _ExampleArm] = {
    "panda": _ExampleArm("panda_description/urdf/panda.urdf", "panda_hand_tcp"),
    "ur3": _ExampleArm("ur_description/urdf/ur3_robot.urdf", "tool0"),
    "ur5": _ExampleArm("ur_description/urdf/ur5_robot.urdf", "tool0"),
    "ur10": _ExampleArm("ur_description/urdf/ur10_robot.urdf", "tool0"),
    "kinova": _ExampleArm("kinova_description/robots/kinova.urdf", "j2s6s200_end_effector"),
    "z1": _ExampleArm("z1_description/urdf/z1.urdf", "gripperStator"),
    "xarm": _ExampleArm("xarm_description/urdf/xarm7.urdf", "link_eef"),
    "so_arm": _ExampleArm("so_arm_description/urdf/so101.urdf", "gripper_frame_link"),
}


def example_robot_data_dir() -> Path:
    """The ``robots/`` directory of the installed ``example-robot-data`` wheel.

    Found from the installed distribution's file list, so it works in any virtual environment.
    """
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError as exc:  # pragma: no cover - it is a dependency
        raise RobotNotFoundError(
            "the 'example-robot-data' package is not installed; install it (pip install example-robot-data) "
            "to load arms such as panda or ur5 by name"
        ) from exc
    for f in dist.files or []:
        parts = Path(str(f)).parts
        if "example-robot-data" in parts and "robots" in parts and str(f).endswith(".urdf"):
            k = parts.index("robots")
            return Path(dist.locate_file(Path(*parts[: k + 1]))).resolve()
    raise RobotNotFoundError("the installed 'example-robot-data' package ships no robots/ directory")


def bundled_robots_dir() -> Path:
    """Directory holding the bundled paper arms: ``evoik_pin/robots`` in an installed wheel (pyproject's
    ``force-include``), ``robots/`` at the top of a source checkout (``src/evoik_pin`` two levels below)."""
    package = Path(__file__).resolve().parents[1]  # evoik_pin/ (this file is evoik_pin/robot/loading.py)
    for candidate in (package / "robots", package.parents[1] / "robots"):
        if (candidate / "ax18.urdf").is_file():
            return candidate
    raise RobotNotFoundError(f"bundled robots not found next to {package} (looked for robots/ax18.urdf)")


def list_robots() -> list[str]:
    """Names accepted by :func:`load_robot`: the bundled paper arms, then the example-robot-data arms."""
    return list(BUNDLED_ROBOTS) + list(EXAMPLE_ARMS)


def load_robot(
    source: str | os.PathLike,
    tip: str | None = None,
    base: str | None = None,
    joints: list[str] | None = None,
    bounds: tuple[np.ndarray, np.ndarray] | None = None,
) -> Robot:
    """Load one serial chain of a URDF.

    Args:
        source: a URDF path, a URDF XML string, the name of a bundled paper arm (``ax18``, ``planar2r``,
            ``puma3r``, ``redundant7r``, ``vehicle_arm``, ``aerial6r``) or of an example-robot-data arm
            (``panda``, ``ur3``, ``ur5``, ``ur10``, ``kinova``, ``z1``, ``xarm``, ``so_arm``).
        tip: end-effector frame (a link or frame name). Default: the arm's usual tool frame for named
            arms, otherwise the deepest link of the URDF.
        base: frame the chain starts from and poses are expressed in. Default: the URDF's root (world).
        joints: optional subset of the chain's joint names to keep free; the rest of the chain is locked.
        bounds: optional ``(lower, upper)`` search bounds, each of length ``n`` (rad or m).

    Returns:
        A :class:`Robot`. Joints outside the base->tip chain are locked at their neutral value
        (clipped into their limits).
    """
    name, path, xml = _resolve_source(source)
    if tip is None:
        tip = _default_tip(name)
    robot = Robot(_parse_urdf(xml, path), tip=tip, base=base, joints=joints, name=name, urdf_path=path,
                  urdf_xml=xml, package_dirs=_package_dirs(path))
    if bounds is not None:
        robot.set_bounds(*bounds)
    return robot


def _default_tip(name: str) -> str | None:
    """The usual tool frame of a named arm (``tool`` for the bundled paper arms); None for other URDFs."""
    if name in EXAMPLE_ARMS:
        return EXAMPLE_ARMS[name].tip
    if name in BUNDLED_ROBOTS:
        return "tool"
    return None


def _package_dirs(path: Path | None) -> list[str]:
    """Directories ``package://`` mesh URIs resolve against: the URDF's folder and its parent (when loaded
    from a file), then example-robot-data's."""
    erd = example_robot_data_dir()
    # example-robot-data URDFs name meshes both package://<pkg>/... and package://example-robot-data/robots/...
    package_dirs = [str(erd), str(erd.parents[1])]
    if path is not None:
        package_dirs = [str(path.parent), str(path.parent.parent), *package_dirs]
    return package_dirs


def _resolve_source(source: str | os.PathLike) -> tuple[str, Path | None, str]:
    """(name, path or None, URDF text) of a load_robot source."""
    if isinstance(source, str) and source.lstrip().startswith("<"):
        return "urdf", None, source
    if not isinstance(source, (str, os.PathLike)):
        raise RobotLoadError(
            f"robot source must be a URDF path, a URDF XML string or a robot name, got {type(source).__name__}"
        )
    text = os.fspath(source)
    if text in BUNDLED_ROBOTS:
        path = bundled_robots_dir() / f"{text}.urdf"
    elif text in EXAMPLE_ARMS:
        path = example_robot_data_dir() / EXAMPLE_ARMS[text].urdf
    else:
        path = Path(text).expanduser()
        if not path.is_file():
            if path.suffix or os.sep in text or path.exists():
                raise RobotNotFoundError(f"URDF file not found: {text!r} (no such file)")
            raise RobotNotFoundError(
                f"unknown robot {text!r}: give a URDF path, a URDF XML string or one of "
                f"{', '.join(list_robots())}"
            )
    try:
        xml = path.read_text()
    except OSError as exc:
        raise RobotNotFoundError(f"cannot read URDF file {str(path)!r}: {exc.strerror}") from exc
    name = text if (text in BUNDLED_ROBOTS or text in EXAMPLE_ARMS) else path.stem
    return name, path.resolve(), xml


def _parse_urdf(xml: str, path: Path | None) -> pin.Model:
    """Pinocchio model of the whole URDF ``xml`` (read from ``path``, or None for a string), or a
    RobotLoadError saying what is wrong with it."""
    where = str(path) if path is not None else "URDF string"
    try:
        root = ET.fromstring(xml)
    except ET.ParseError as exc:
        raise RobotLoadError(f"malformed URDF XML in {where}: {exc}") from exc
    if root.tag != "robot":
        raise RobotLoadError(f"{where} is not a URDF: its root element is <{root.tag}>, expected <robot>")
    try:
        return pin.buildModelFromXML(xml)
    except (RuntimeError, ValueError) as exc:
        raise RobotLoadError(f"Pinocchio could not build a model from {where}: {exc}") from exc
