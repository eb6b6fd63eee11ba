"""What a URDF must be before Pinocchio reads it (urdfdom accepts files giving NaN or wrong kinematics, or rejects
them with a generic message): :func:`check_urdf`."""

from __future__ import annotations

import math
import warnings
import xml.etree.ElementTree as ET
from dataclasses import dataclass

from ..errors import RobotLoadError, RobotLoadWarning

__all__ = ["JOINT_TYPES", "Mimic", "check_urdf"]

#: The joint types of the URDF specification.
JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")
_MOVING = ("revolute", "continuous", "prismatic")  # 1-DOF joints: the only ones a mimic can couple


@dataclass(frozen=True)
class Mimic:
    """A mimic joint's value: ``multiplier * q[joint] + offset`` (rad or m), ``joint`` a joint no mimic drives."""

    joint: str
    multiplier: float
    offset: float


def check_urdf(root: ET.Element, where: str) -> dict[str, Mimic]:
    """Check the parsed URDF ``root`` (read from ``where``) and return its mimic couplings ``{joint: Mimic}``, each
    resolved to the joint driving its chain of mimics; a RobotLoadError naming ``where``, the joint or link and what
    is accepted. A ``<mimic>`` naming no 1-DOF joint is ignored with a RobotLoadWarning."""
    if root.tag != "robot":
        raise RobotLoadError(f"{where} is not a URDF: its root element is <{root.tag}>, expected <robot>")
    if not root.get("name"):
        raise RobotLoadError(f"{where}: the <robot> element has no name attribute (<robot name=\"...\">)")
    links = _names(root.findall("link"), "link", where)
    if not links:
        raise RobotLoadError(f"{where} has no <link> element: a URDF needs at least one link")
    joints = root.findall("joint")
    _names(joints, "joint", where)
    types: dict[str, str] = {}
    parent_of: dict[str, tuple[str, str]] = {}  # child link -> (parent link, joint)
    for j in joints:
        jname, jtype = j.get("name"), j.get("type")
        types[jname] = jtype
        if jtype not in JOINT_TYPES:
            raise RobotLoadError(f"{where}: joint {jname!r} has type {jtype!r}; URDF joint types are "
                                 f"{', '.join(JOINT_TYPES)}")
        ends = []
        for tag in ("parent", "child"):
            el = j.find(tag)
            link = el.get("link") if el is not None else None
            if not link:
                raise RobotLoadError(f"{where}: joint {jname!r} has no <{tag} link=\"...\"/> element")
            if link not in links:
                raise RobotLoadError(f"{where}: joint {jname!r} names {tag} link {link!r}, which the file does not "
                                     "define")
            ends.append(link)
        parent, child = ends
        if parent == child:
            raise RobotLoadError(f"{where}: joint {jname!r} joins link {parent!r} to itself")
        if child in parent_of:
            other = parent_of[child][1]
            raise RobotLoadError(f"{where}: link {child!r} is the child of two joints, {other!r} and {jname!r} (a "
                                 "closed loop); a URDF must be a tree: every link has at most one parent joint. Model "
                                 "a closed chain by cutting it open (drop one joint)")
        parent_of[child] = (parent, jname)
        _check_joint(j, jname, jtype, where)
    _check_tree(links, parent_of, where)
    return _mimic(joints, types, where)


def _names(elements: list[ET.Element], kind: str, where: str) -> list[str]:
    """The ``name`` of each element; a RobotLoadError for a missing or repeated one."""
    names: dict[str, None] = {}
    for i, el in enumerate(elements):
        n = el.get("name")
        if not n:
            raise RobotLoadError(f"{where}: <{kind}> number {i + 1} has no name attribute")
        if n in names:
            raise RobotLoadError(f"{where}: two {kind}s are named {n!r}; {kind} names must be unique")
        names[n] = None
    return list(names)


def _floats(text: str | None, count: int, what: str, where: str, default: tuple[float, ...],
            finite: bool = True) -> tuple[float, ...]:
    """``count`` numbers of a space-separated attribute; ``default`` when it is absent."""
    if text is None:
        return default
    parts = text.split()
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != count or any(math.isnan(v) or (finite and math.isinf(v)) for v in values):
        kind = "finite numbers" if finite else "numbers"
        raise RobotLoadError(f"{where}: {what} is {text!r}; expected {count} {kind} separated by spaces")
    return values


def _check_joint(j: ET.Element, jname: str, jtype: str, where: str) -> None:
    """Origin, axis and limits of one joint."""
    origin = j.find("origin")
    for attr in ("xyz", "rpy") if origin is not None else ():
        _floats(origin.get(attr), 3, f"the origin {attr} of joint {jname!r}", where, (0.0, 0.0, 0.0))
    if jtype in ("fixed", "floating"):
        return
    axis_el = j.find("axis")
    if axis_el is not None:
        axis = _floats(axis_el.get("xyz"), 3, f"the axis of joint {jname!r}", where, (1.0, 0.0, 0.0))
        if math.sqrt(sum(a * a for a in axis)) < 1e-12:
            raise RobotLoadError(f"{where}: joint {jname!r} has a zero-length axis {axis_el.get('xyz')!r}; give its "
                                 "direction, e.g. <axis xyz=\"0 0 1\"/> (omitting <axis> means 1 0 0)")
    limit = j.find("limit")
    if jtype in ("revolute", "prismatic"):
        if limit is None:
            hint = " (an unlimited revolute joint is type=\"continuous\")" if jtype == "revolute" else ""
            raise RobotLoadError(f"{where}: {jtype} joint {jname!r} has no <limit> element; URDF requires <limit lower="
                                 f"\"...\" upper=\"...\" effort=\"...\" velocity=\"...\"/> for {jtype} joints{hint}")
        for attr in ("effort", "velocity"):
            if limit.get(attr) is None:
                raise RobotLoadError(f"{where}: the <limit> of joint {jname!r} has no {attr} attribute; URDF "
                                     "requires effort and velocity (lower and upper default to 0)")
    if limit is None:
        return
    values = {attr: _floats(limit.get(attr), 1, f"the {attr} limit of joint {jname!r}", where, (0.0,), finite=False)[0]
              for attr in ("lower", "upper", "effort", "velocity")}
    if jtype in ("revolute", "prismatic") and values["lower"] > values["upper"]:
        raise RobotLoadError(f"{where}: joint {jname!r} has inverted limits: lower {values['lower']:g} > upper "
                             f"{values['upper']:g} (lower must not exceed upper)")


def _check_tree(links: list[str], parent_of: dict[str, tuple[str, str]], where: str) -> None:
    """One root, every link reachable from it (no cycle)."""
    roots = [link for link in links if link not in parent_of]
    if not roots:
        raise RobotLoadError(f"{where}: every link has a parent joint, so its joints form a cycle; a URDF must be a "
                             "tree with one root link")
    if len(roots) > 1:
        shown = ", ".join(repr(r) for r in roots[:5]) + (", ..." if len(roots) > 5 else "")
        raise RobotLoadError(f"{where} has {len(roots)} root links (links no joint has as child): {shown}; a URDF must "
                             "be one tree: join them with joints")
    loop = []
    for link in links:  # a link whose parents never reach the root sits on a cycle (or hangs from one)
        up, steps = link, 0
        while up in parent_of and steps <= len(links):
            up, steps = parent_of[up][0], steps + 1
        if up != roots[0]:
            loop.append(link)
    if loop:
        shown = ", ".join(repr(x) for x in loop[:5]) + (", ..." if len(loop) > 5 else "")
        raise RobotLoadError(f"{where}: links {shown} are not connected to the root link {roots[0]!r}: their joints "
                             "form a cycle; a URDF must be a tree")


def _mimic(joints: list[ET.Element], types: dict[str, str], where: str) -> dict[str, Mimic]:
    """The mimic couplings, each resolved to the joint that drives its chain of mimics."""
    direct: dict[str, Mimic] = {}
    for j in joints:
        el = j.find("mimic")
        if el is None:
            continue
        jname, jtype = j.get("name"), j.get("type")
        target = el.get("joint")
        if not target:
            raise RobotLoadError(f"{where}: the <mimic> of joint {jname!r} has no joint attribute "
                                 "(<mimic joint=\"...\" multiplier=\"1\" offset=\"0\"/>)")
        m = _floats(el.get("multiplier"), 1, f"the mimic multiplier of joint {jname!r}", where, (1.0,))[0]
        c = _floats(el.get("offset"), 1, f"the mimic offset of joint {jname!r}", where, (0.0,))[0]
        if jtype not in _MOVING:
            continue  # a fixed (or floating, planar) joint has no value to couple; urdfdom ignores it too
        if target == jname:
            raise RobotLoadError(f"{where}: joint {jname!r} mimics itself")
        if types.get(target) not in _MOVING:
            what = "no joint of the file" if target not in types else f"a {types[target]} joint"
            warnings.warn(f"{where}: joint {jname!r} mimics {target!r}, which is {what}; the <mimic> is ignored "
                          f"and {jname!r} loads as an independent joint", RobotLoadWarning, stacklevel=5)
            continue
        direct[jname] = Mimic(target, m, c)
    resolved: dict[str, Mimic] = {}
    for jname in direct:
        path = [jname]
        mim = direct[jname]
        while mim.joint in direct:  # j = m1 (m2 q + c2) + c1 = (m1 m2) q + (m1 c2 + c1)
            if mim.joint in path:
                raise RobotLoadError(f"{where}: mimic joints form a cycle: {' -> '.join(path + [mim.joint])}; one "
                                     "of them must be driven by an independent joint")
            path.append(mim.joint)
            nxt = direct[mim.joint]
            mim = Mimic(nxt.joint, mim.multiplier * nxt.multiplier, mim.multiplier * nxt.offset + mim.offset)
        resolved[jname] = mim
    return resolved
