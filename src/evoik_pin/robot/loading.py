"""Finding and reading a robot (:func:`load_robot`, :func:`list_robots`). Bad input raises RobotLoadError or
RobotNotFoundError naming the file."""

from __future__ import annotations

import importlib.metadata
import os
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import BoundsError, FrameError, RobotLoadError, RobotNotFoundError
from .catalog import BUNDLED_ROBOTS, EXAMPLE_ARMS, WHOLE_ROBOTS
from .frames import is_branched
from .joints import couplings
from .packages import PackageResolver, check_package_aliases, check_package_dirs, package_uris
from .robot import Robot
from .urdf_checks import Mimic, check_urdf
from .urdf_text import captured_stderr, decode_xml, expand_xacro, is_xacro

__all__ = ["bundled_robots_dir", "example_robot_data_dir", "list_robots", "load_robot"]


def example_robot_data_dir() -> Path:
    """The ``robots/`` directory of the installed ``example-robot-data`` wheel."""
    dist = importlib.metadata.distribution("example-robot-data")
    for f in dist.files or []:
        parts = Path(str(f)).parts
        if "example-robot-data" in parts and "robots" in parts and str(f).endswith(".urdf"):
            k = parts.index("robots")
            return Path(dist.locate_file(Path(*parts[: k + 1]))).resolve()
    raise RobotNotFoundError("the installed 'example-robot-data' package ships no robots/ directory")


def bundled_robots_dir() -> Path:
    """Directory of the bundled paper arms: ``evoik_pin/robots`` in a wheel, ``robots/`` atop a source checkout."""
    package = Path(__file__).resolve().parents[1]  # evoik_pin/
    for candidate in (package / "robots", package.parents[1] / "robots"):
        if (candidate / "ax18.urdf").is_file():
            return candidate
    raise RobotNotFoundError(f"bundled robots not found next to {package} (looked for robots/ax18.urdf)")


def list_robots(whole: bool = False, describe: bool = False) -> list[str] | dict[str, str]:
    """Names :func:`load_robot` takes: the bundled paper arms, the example-robot-data arms, and with ``whole=True``
    its whole robots. ``describe=True``: a dict of those names to what each is."""
    what = {**BUNDLED_ROBOTS, **{k: f"example-robot-data arm, tip {a.tip}" for k, a in EXAMPLE_ARMS.items()}}
    if whole:
        what.update({k: f"example-robot-data whole robot: {w.what}" for k, w in WHOLE_ROBOTS.items()})
    return what if describe else list(what)


def load_robot(source: str | bytes | os.PathLike, tip: str | None = None, base: str | None = None,
               joints: list[str] | None = None, bounds: tuple[np.ndarray, np.ndarray] | None = None,
               xacro_args: dict | None = None, srdf: str | os.PathLike | None = None,
               package_dirs: str | os.PathLike | list | None = None, tips: list[str] | str | None = None,
               floating_base: bool = False, base_box=None, package_aliases: dict[str, str] | None = None) -> Robot:
    """Load a robot: one serial chain of a URDF, the chains to several frames, or the whole tree.

    Args:
        source: a URDF or xacro path, URDF (or xacro) XML text or bytes, or a name of ``list_robots(whole=True)``.
            Files are decoded as their XML declaration says (UTF-8 by default).
        tip: end-effector frame (default a named arm's tool frame, else the deepest link): the active joints are
            the chain from the base to it. Without ``tip`` and ``tips``, a whole robot by name and a branching URDF
            activate the whole tree (``tips="all"``).
        base: frame the chain starts from and poses are expressed in (default: the URDF's root).
        joints: names of the active joints to keep free; the rest is locked.
        bounds: ``(lower, upper)`` search bounds, each (n,) (rad or m).
        xacro_args: ``{name: value}`` of a xacro file's ``<xacro:arg>`` (xacro sources only).
        srdf: an SRDF file whose ``<disable_collisions>`` pairs collision scenes skip (named robots find theirs).
        package_dirs: folders holding the ROS packages the file names, searched first (:mod:`.packages`). A
            ``$(find pkg)`` nothing finds is a RobotLoadError; a missing mesh package only matters to meshes.
        package_aliases: ``{package named in the file: the name it is shipped under}``.
        tips: frames whose chains from the base make the active joints (their union; ``tip`` defaults to the
            first), or ``"all"``: every joint below the base.
        floating_base: a free-flying root in front of the URDF's root: six more entries at the front of q, x, y, z
            (m) and yaw, pitch, roll (rad; Rz Ry Rx) in the world frame, where poses are then expressed.
        base_box: the floating base's position box: a half-width h (m; default 1) or (lower (3,), upper (3,)).

    Returns a :class:`Robot`, the other joints locked at their neutral value (clipped into their limits).
    """
    name, path, xml, named = _resolve_source(source)
    where = str(path) if path is not None else "URDF string"
    resolver = PackageResolver(path, check_package_dirs(package_dirs), check_package_aliases(package_aliases))
    if is_xacro(path, xml):
        source_text, xml = xml, expand_xacro(xml, where, path, xacro_args, resolver)
        macros = re.findall(r"<xacro:macro\s+name\s*=\s*[\"']([^\"']+)", source_text)
        if macros and not re.search(r"<link\b", xml):  # a file of macros that calls none
            raise RobotLoadError(
                f"{where} defines the xacro macro(s) {', '.join(macros)} but calls none, so it has no <link>: load the "
                f"xacro file that includes it and calls them (e.g. <xacro:{macros[0]} .../>)")
    elif xacro_args:
        raise RobotLoadError(f"xacro_args given, but {where} is not a xacro file (*.xacro, or XML with <xacro:...> "
                             "elements or ${...} / $(...) expressions)")
    if tip is None and named:
        tip = EXAMPLE_ARMS[name].tip if name in EXAMPLE_ARMS else "tool" if name in BUNDLED_ROBOTS else None
    model, mimic = _parse_urdf(xml, path)
    if tip is None and tips is None and (named and name in WHOLE_ROBOTS
                                         or not named and is_branched(model, couplings(model, mimic))):
        tips = "all"  # a whole robot: never the chain to one arbitrary deepest link
    # the mesh URIs' packages (a missing one is an error only when meshes are loaded), and the folders Pinocchio
    # tries the others in (example-robot-data's URDFs name package://example-robot-data/robots/...)
    folders = {pkg: resolver.find(pkg) for pkg in package_uris(xml)}
    missing = {p: resolver.not_found(p, where, f"package://{p}/... in a mesh URI") for p, f in folders.items()
               if f is None}
    erd, own = example_robot_data_dir(), ([path.parent, path.parent.parent] if path is not None else [])
    dirs = [str(d) for d in (*resolver.user_dirs, *resolver.ros_dirs, *own, erd, erd.parents[1])]
    try:
        robot = Robot(model, tip=tip, base=base, joints=joints, name=name, urdf_path=path, urdf_xml=xml, mimic=mimic,
                      package_dirs=dirs, packages={p: str(f) for p, f in folders.items() if f is not None},
                      missing_packages=missing, tips=tips, floating_base=floating_base, base_box=base_box)
    except (RobotLoadError, FrameError, BoundsError) as exc:
        raise type(exc)(f"{where}: {exc}") from None
    if bounds is not None:
        robot.set_bounds(*bounds)
    robot.srdf = _srdf_path(srdf, name if named else None)
    return robot


def _srdf_path(srdf, name: str | None) -> str | None:
    """The SRDF file to use: ``srdf`` when given (it must exist), else a named example arm's own, else None."""
    if srdf is not None:
        p = Path(os.fspath(srdf)).expanduser()
        if not p.is_file():
            raise RobotNotFoundError(f"SRDF file not found: {str(srdf)!r}")
        return str(p.resolve())
    arm = (EXAMPLE_ARMS.get(name) or WHOLE_ROBOTS.get(name)) if name is not None else None
    if arm is not None and arm.srdf is not None:
        p = example_robot_data_dir() / arm.srdf
        return str(p) if p.is_file() else None
    return None


def _resolve_source(source: str | bytes | os.PathLike) -> tuple[str, Path | None, str, bool]:
    """(name, path or None, URDF or xacro text, whether it was a robot name) of a load_robot source."""
    if isinstance(source, (bytes, bytearray)):
        return "urdf", None, decode_xml(bytes(source), "URDF string"), False
    stripped = source.lstrip("\ufeff \t\r\n") if isinstance(source, str) else ""  # an XML declaration comes first
    if stripped.startswith("<") or "<?xml" in stripped or "<robot" in stripped:  # URDF text: no path or name has these
        return "urdf", None, stripped if stripped.startswith("<") else source, False
    if not isinstance(source, (str, os.PathLike)):
        raise RobotLoadError(f"robot source must be a URDF path, a URDF XML string or a robot name, got "
                             f"{type(source).__name__}")
    text = os.fspath(source)
    if not isinstance(text, str) or not text.strip():
        raise RobotLoadError(f"robot source {text!r} is empty: give a URDF path, a URDF XML string or one of "
                             f"{', '.join(list_robots(whole=True))}")
    shown = repr(text) if len(text) <= 200 else repr(text[:200]) + "..."
    named = isinstance(source, str) and (text in BUNDLED_ROBOTS or text in EXAMPLE_ARMS or text in WHOLE_ROBOTS)
    if named and text in BUNDLED_ROBOTS:
        path = bundled_robots_dir() / f"{text}.urdf"
    elif named:
        path = example_robot_data_dir() / (EXAMPLE_ARMS.get(text) or WHOLE_ROBOTS[text]).urdf
    else:
        path = Path(text).expanduser()
        try:
            is_dir, is_file, exists = path.is_dir(), path.is_file(), path.exists()
        except (OSError, ValueError) as exc:  # a name too long for the file system, a NUL character
            raise RobotNotFoundError(f"{shown} is not a usable path ({exc}): give a URDF path, a URDF XML string "
                                     "or a robot name") from None
        if is_dir:
            inside = sorted(str(f.relative_to(path)) for pattern in ("*.urdf", "*.xacro", "urdf/*.urdf", "urdf/*.xacro")
                            for f in path.glob(pattern))
            hint = f"; URDF files in it: {', '.join(inside[:6])}" if inside else ""
            raise RobotLoadError(f"{shown} is a directory, not a URDF file: give the path of a .urdf or .xacro "
                                 f"file{hint}")
        if not is_file:
            if path.suffix or os.sep in text or exists or not isinstance(source, str):
                raise RobotNotFoundError(f"URDF file not found: {shown} (no such file)")
            raise RobotNotFoundError(f"unknown robot {shown}: give a URDF path, a URDF XML string or one of "
                                     f"{', '.join(list_robots(whole=True))}")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise RobotNotFoundError(f"cannot read URDF file {str(path)!r}: {exc.strerror}") from exc
    stem = path.name
    for suffix in (".xacro", ".urdf"):
        stem = stem[: -len(suffix)] if stem.lower().endswith(suffix) and len(stem) > len(suffix) else stem
    return (text if named else stem), path.resolve(), decode_xml(data, str(path.resolve())), named


def _parse_urdf(xml: str, path: Path | None) -> tuple[pin.Model, dict[str, Mimic]]:
    """(Pinocchio model of the whole URDF ``xml`` read from ``path`` (None: a string), its mimics), or a
    RobotLoadError saying what is wrong with it."""
    where = str(path) if path is not None else "URDF string"
    try:
        root = ET.fromstring(xml)
    except (ET.ParseError, ValueError, RecursionError) as exc:  # ValueError: e.g. characters XML does not allow
        raise RobotLoadError(f"malformed URDF XML in {where}: {exc}") from exc
    mimic = check_urdf(root, where)
    failure: Exception | None = None
    with captured_stderr() as err:  # urdfdom prints its reasons on stderr
        try:
            model = pin.buildModelFromXML(xml)  # Robot folds the mimics in
        except Exception as exc:  # RuntimeError, ValueError, ... from the C++ parsers
            failure = exc
    if failure is not None:  # urdfdom's reasons, without its "at line N in joint.cpp" locations
        said = [line.strip().removeprefix("Error:").strip() for line in err[0].splitlines()]
        said = [line for line in said if line and not line.startswith("at line ")]
        detail = f" urdfdom said: {'; '.join(said)}" if said else ""
        raise RobotLoadError(f"Pinocchio could not build a model from {where}: {failure}{detail}") from None
    return model, mimic
