"""Finding and reading a robot (:func:`load_robot`, :func:`list_robots`): a source resolved to URDF text
(:mod:`.urdf_text`), checked (:mod:`.urdf_checks`), built into the Pinocchio model of the whole URDF and handed,
with its default tip and mesh package folders, to :class:`~evoik_pin.robot.robot.Robot`. Bad input raises
:class:`~evoik_pin.errors.RobotLoadError` (or :class:`~evoik_pin.errors.RobotNotFoundError`) naming the file (or
"URDF string") and what is accepted."""

from __future__ import annotations

import importlib.metadata
import os
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import BoundsError, FrameError, RobotLoadError, RobotNotFoundError
from .catalog import WHOLE_ROBOTS
from .frames import is_branched
from .joints import couplings
from .packages import PackageResolver, check_package_aliases, check_package_dirs, package_uris
from .robot import Robot
from .urdf_checks import UrdfSummary, check_urdf
from .urdf_text import captured_stderr, decode_xml, expand_xacro, is_xacro_path, is_xacro_text

__all__ = [
    "BUNDLED_ROBOTS",
    "EXAMPLE_ARMS",
    "WHOLE_ROBOTS",
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
    srdf: str | None = None  # the SRDF (disabled collision pairs), below robots/ too


#: Arms of the ``example-robot-data`` wheel reachable by name, with their default tip frames.
EXAMPLE_ARMS: dict[str, _ExampleArm] = {
    "panda": _ExampleArm("panda_description/urdf/panda.urdf", "panda_hand_tcp",
                         srdf="panda_description/srdf/panda.srdf"),
    "ur3": _ExampleArm("ur_description/urdf/ur3_robot.urdf", "tool0"),
    "ur5": _ExampleArm("ur_description/urdf/ur5_robot.urdf", "tool0", srdf="ur_description/srdf/ur5.srdf"),
    "ur10": _ExampleArm("ur_description/urdf/ur10_robot.urdf", "tool0"),
    "kinova": _ExampleArm("kinova_description/robots/kinova.urdf", "j2s6s200_end_effector",
                          srdf="kinova_description/srdf/kinova.srdf"),
    "z1": _ExampleArm("z1_description/urdf/z1.urdf", "gripperStator", srdf="z1_description/srdf/z1.srdf"),
    "xarm": _ExampleArm("xarm_description/urdf/xarm7.urdf", "link_eef", srdf="xarm_description/srdf/xarm7.srdf"),
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


def list_robots(whole: bool = False, describe: bool = False) -> list[str] | dict[str, str]:
    """Names accepted by :func:`load_robot`: the bundled paper arms, then the example-robot-data arms (serial
    chains to a tool frame), then with ``whole=True`` the example-robot-data whole robots (humanoids, quadrupeds,
    dual-arm robots, hands: :data:`~evoik_pin.robot.catalog.WHOLE_ROBOTS`). ``describe=True``: a dict of those
    names to what each is."""
    what = {**BUNDLED_ROBOTS, **{k: f"example-robot-data arm, tip {a.tip}" for k, a in EXAMPLE_ARMS.items()}}
    if whole:
        what.update({k: f"example-robot-data whole robot: {w.what}" for k, w in WHOLE_ROBOTS.items()})
    return what if describe else list(what)


def load_robot(
    source: str | bytes | os.PathLike,
    tip: str | None = None,
    base: str | None = None,
    joints: list[str] | None = None,
    bounds: tuple[np.ndarray, np.ndarray] | None = None,
    xacro_args: dict | None = None,
    srdf: str | os.PathLike | None = None,
    package_dirs: str | os.PathLike | list | None = None,
    tips: list[str] | str | None = None,
    floating_base: bool = False,
    base_box=None,
    package_aliases: dict[str, str] | None = None,
) -> Robot:
    """Load a robot: one serial chain of a URDF, the chains to several frames, or the whole tree.

    Args:
        source: a URDF path, a xacro path (``*.xacro``, ``*.urdf.xacro``), a URDF XML string (or bytes;
            xacro text is expanded too), the name of a bundled paper arm (``ax18``, ``planar2r``,
            ``puma3r``, ``redundant7r``, ``vehicle_arm``, ``aerial6r``), of an example-robot-data arm
            (``panda``, ``ur3``, ``ur5``, ``ur10``, ``kinova``, ``z1``, ``xarm``, ``so_arm``) or of an
            example-robot-data whole robot (``talos``, ``g1``, ``go2``, ``baxter``, ``pr2``, ``tiago_dual``,
            ``allegro_right``, ...: ``list_robots(whole=True)``). Files are read as bytes and decoded as their XML
            declaration says (UTF-8 by default).
        tip: end-effector frame (a link or frame name). Default: the arm's usual tool frame for the named
            arms, otherwise the deepest link of the URDF (a file called ``panda.urdf`` is not the named arm).
            Given, the active joints are those of the chain from the base to the tip. Not given (nor ``tips``),
            a whole robot by name and a URDF whose movable joints branch (a tree: legs, arms, a head; a file or a
            string) activate the whole tree, as ``tips="all"``, and ``tip`` is only the default goal frame; a
            serial chain (a gripper whose fingers mimic one joint included) activates the chain to its tip.
        base: frame the chain starts from and poses are expressed in. Default: the URDF's root (world).
        joints: optional subset of the active joints' names (the chain's, or the whole tree's) to keep free; the
            rest is locked.
        bounds: optional ``(lower, upper)`` search bounds, each of length ``n`` (rad or m).
        xacro_args: values of a xacro file's ``<xacro:arg>`` (``{"name": value}``), as ``name:=value`` on
            xacro's command line; only for xacro sources.
        srdf: an SRDF file whose ``<disable_collisions>`` pairs collision scenes skip
            (:class:`~evoik_pin.scene.Scene`); the named example-robot-data robots find their own.
        package_dirs: folders (one, or a list) holding the ROS packages the file names (``$(find pkg)`` in
            xacro, ``package://pkg/...`` mesh URIs): ``pkg`` is ``DIR/pkg``, ``DIR`` itself, or a package.xml
            naming it below ``DIR``. Searched first, then ``ROS_PACKAGE_PATH``, then the file's own tree (a
            folder named ``pkg`` above the file or inside one of the folders above it), then a package.xml
            naming ``pkg`` above the file (:mod:`evoik_pin.robot.packages`). A ``$(find pkg)`` nothing finds is a
            RobotLoadError naming the package, the file naming it and the folders searched; a mesh package
            nothing finds only matters to meshes (viewer, collision scenes), which then raise that error.
        package_aliases: ``{package named in the file: the name it is shipped under}``, e.g.
            ``{"abb_irb140": "abb_irb140_description"}``: the package is looked for under that name by the rules
            above (a robot file copied out of its ROS workspace whose packages were renamed).
        tips: frames (names) whose chains from the base make the active joints (their union), e.g. both grippers
            of a dual-arm robot; ``tip`` defaults to the first. ``"all"``: every joint below the base (what a
            whole robot by name, or a URDF whose joints branch, gets when neither ``tip`` nor ``tips`` is given).
        floating_base: put a free-flying root in front of the URDF's root link: six more entries at the front of
            q, the root link's position x, y, z (m) and yaw, pitch, roll (rad; its rotation is Rz(yaw) Ry(pitch)
            Rx(roll)) in the world frame, where poses are then expressed. Bounds: ``base_box`` for the position,
            yaw and roll a full turn (they wrap), pitch [-pi/2, pi/2]; ``Robot.full_configuration`` gives the
            configuration of ``pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer())``. The base moves every
            frame, so a goal on a frame that only the base moves while joints between the root and that frame
            are locked (off the active joints) is an error naming them (:class:`~evoik_pin.errors.LockedJointsError`).
        base_box: the floating base's position box: a half-width h (m; the box [-h, h]^3, default 1 m) or a pair
            (lower (3,), upper (3,)) in m. (``robot.set_bounds`` changes it later: entries 0-2.)

    Returns:
        A :class:`Robot`. Joints outside the active ones (the base->tip chain, the tips' chains) are locked at their
        neutral value (clipped into their limits); mimic joints follow their joint (``q`` has one entry per
        independent degree of freedom).
    """
    name, path, xml, named = _resolve_source(source)
    where = str(path) if path is not None else "URDF string"
    user_dirs = check_package_dirs(package_dirs)
    resolver = PackageResolver(path, user_dirs, check_package_aliases(package_aliases))
    if (path is not None and is_xacro_path(path)) or is_xacro_text(xml):
        source_text = xml
        xml = expand_xacro(xml, where, path, xacro_args, resolver)
        _check_instantiated(source_text, xml, where)
    elif xacro_args:
        raise RobotLoadError(f"xacro_args given, but {where} is not a xacro file (*.xacro, or XML with <xacro:...> "
                             "elements or ${...} / $(...) expressions)")
    if tip is None and named:
        tip = _default_tip(name)
    model, summary = _parse_urdf(xml, path)
    if tip is None and tips is None and (named and name in WHOLE_ROBOTS
                                         or not named and is_branched(model, couplings(model, summary.mimic))):
        # a whole robot, by name or from a file or string whose joints branch: every joint, unless joints= says
        # less. Never the chain to one arbitrary deepest link: with a floating base, goals on the other branches
        # would bind to locked joints (the base moves every frame, so nothing else refuses them).
        tips = "all"
    mesh_packages, missing_packages = _mesh_packages(xml, resolver, where)
    try:
        robot = Robot(model, tip=tip, base=base, joints=joints, name=name, urdf_path=path, urdf_xml=xml,
                      package_dirs=_package_dirs(path, resolver), mimic=summary.mimic,
                      packages=mesh_packages, missing_packages=missing_packages, tips=tips,
                      floating_base=floating_base, base_box=base_box)
    except (RobotLoadError, FrameError, BoundsError) as exc:  # say which file the frames and joints were looked for in
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


def _default_tip(name: str) -> str | None:
    """The usual tool frame of a named arm (``tool`` for the bundled paper arms); None for other names."""
    if name in EXAMPLE_ARMS:
        return EXAMPLE_ARMS[name].tip
    if name in BUNDLED_ROBOTS:
        return "tool"
    return None


def _package_dirs(path: Path | None, resolver: PackageResolver) -> list[str]:
    """Directories Pinocchio tries ``package://pkg/...`` mesh URIs in (as ``DIR/pkg/...``) when
    :func:`_mesh_packages` did not find ``pkg``: the given folders, ``ROS_PACKAGE_PATH``'s, the URDF's folder
    and its parent (when loaded from a file), then example-robot-data's."""
    erd = example_robot_data_dir()
    # example-robot-data URDFs name meshes both package://<pkg>/... and package://example-robot-data/robots/...
    package_dirs = [str(erd), str(erd.parents[1])]
    if path is not None:
        package_dirs = [str(path.parent), str(path.parent.parent), *package_dirs]
    return [*(str(d) for d in (*resolver.user_dirs, *resolver.ros_dirs)), *package_dirs]


def _mesh_packages(xml: str, resolver: PackageResolver, where: str) -> tuple[dict[str, str], dict[str, str]]:
    """(``{pkg: folder}`` of the ``package://pkg/...`` URIs of the URDF that were found, ``{pkg: error
    message}`` of those that were not: raised only when meshes are loaded, as IK needs none)."""
    found: dict[str, str] = {}
    missing: dict[str, str] = {}
    for pkg in package_uris(xml):
        folder = resolver.find(pkg)
        if folder is not None:
            found[pkg] = str(folder)
        else:
            missing[pkg] = resolver.not_found(pkg, where, f"package://{pkg}/... in a mesh URI")
    return found, missing


def _check_instantiated(source_text: str, urdf: str, where: str) -> None:
    """A RobotLoadError for a xacro file that only defines macros (it has a robot name, but no link comes
    out): name the macros, so that the user loads the file calling them."""
    if re.search(r"<link\b", urdf):
        return
    macros = re.findall(r"<xacro:macro\s+name\s*=\s*[\"']([^\"']+)", source_text)
    if macros:
        raise RobotLoadError(
            f"{where} defines the xacro macro(s) {', '.join(macros)} but calls none, so it has no <link>: load the "
            f"xacro file that includes it and calls them (e.g. <xacro:{macros[0]} .../>)")


def _looks_like_xml(text: str) -> bool:
    """True for URDF (or xacro) text given as a string: it starts with "<" or holds an XML declaration or a
    <robot> element (a path or a name does neither)."""
    return text.lstrip("\ufeff \t\r\n").startswith("<") or "<?xml" in text or "<robot" in text


def _resolve_source(source: str | bytes | os.PathLike) -> tuple[str, Path | None, str, bool]:
    """(name, path or None, URDF or xacro text, whether the source was a robot name) of a load_robot source."""
    if isinstance(source, (bytes, bytearray)):
        return "urdf", None, decode_xml(bytes(source), "URDF string"), False
    if isinstance(source, str) and _looks_like_xml(source):
        stripped = source.lstrip("\ufeff \t\r\n")  # an XML declaration must come first
        return "urdf", None, stripped if stripped.startswith("<") else source, False
    if not isinstance(source, (str, os.PathLike)):
        raise RobotLoadError(
            f"robot source must be a URDF path, a URDF XML string or a robot name, got {type(source).__name__}"
        )
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
            raise RobotNotFoundError(
                f"unknown robot {shown}: give a URDF path, a URDF XML string or one of "
                f"{', '.join(list_robots(whole=True))}"
            )
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise RobotNotFoundError(f"cannot read URDF file {str(path)!r}: {exc.strerror}") from exc
    resolved = path.resolve()
    xml = decode_xml(data, str(resolved))
    stem = path.name
    for suffix in (".xacro", ".urdf"):
        stem = stem[: -len(suffix)] if stem.lower().endswith(suffix) and len(stem) > len(suffix) else stem
    return (text if named else stem), resolved, xml, named


def _parse_urdf(xml: str, path: Path | None) -> tuple[pin.Model, UrdfSummary]:
    """Pinocchio model of the whole URDF ``xml`` (read from ``path``, or None for a string) and what
    :func:`check_urdf` found in it, or a RobotLoadError saying what is wrong with it."""
    where = str(path) if path is not None else "URDF string"
    try:
        root = ET.fromstring(xml)
    except ET.ParseError as exc:
        raise RobotLoadError(f"malformed URDF XML in {where}: {exc}") from exc
    except (ValueError, RecursionError) as exc:  # e.g. characters XML does not allow
        raise RobotLoadError(f"malformed URDF XML in {where}: {exc}") from exc
    summary = check_urdf(root, where)
    failure: Exception | None = None
    with captured_stderr() as err:  # urdfdom prints its reasons on stderr
        try:
            model = pin.buildModelFromXML(xml)  # mimic couplings are folded in by Robot, not by Pinocchio
        except Exception as exc:  # RuntimeError, ValueError, ... from the C++ parsers
            failure = exc
    if failure is not None:  # urdfdom's reasons, without its "at line N in joint.cpp" locations
        said = [line.strip().removeprefix("Error:").strip() for line in err[0].splitlines()]
        said = [line for line in said if line and not line.startswith("at line ")]
        detail = f" urdfdom said: {'; '.join(said)}" if said else ""
        raise RobotLoadError(f"Pinocchio could not build a model from {where}: {failure}{detail}") from None
    return model, summary
