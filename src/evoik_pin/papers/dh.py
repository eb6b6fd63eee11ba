"""Denavit-Hartenberg tables and serial chains written out as URDF (joint ``i`` moves like row ``i``, the frame
after the last row is the ``tool`` link; a box per link, a cylinder per joint axis, for meshcat). Lengths in m,
angles in rad. Standard DH, row (a_i, alpha_i, d_i, theta_i): ``A_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``;
modified (Craig), row (a_{i-1}, alpha_{i-1}, d_i, theta_i): ``A_i = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i) Tz(d_i)``.
The joint variable adds to ``theta`` (revolute) or ``d`` (prismatic).
"""

from __future__ import annotations

from dataclasses import dataclass
from xml.sax.saxutils import escape

import numpy as np

from .. import lie
from ..errors import RobotLoadError

__all__ = ["DHRow", "JointSpec", "chain_to_urdf", "dh_to_urdf", "dh_transform", "translation"]

_KINDS = ("revolute", "prismatic", "fixed")


def _rot(axis: str, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    T, i = np.eye(4), 1 if axis == "x" else 0  # the rotated plane: (y, z) about x, (x, y) about z
    T[i:i + 2, i:i + 2] = [[c, -s], [s, c]]
    return T


def translation(axis: str, dist: float) -> np.ndarray:
    """The (4, 4) transform moving ``dist`` (m) along ``axis`` (``"x"``, ``"y"`` or ``"z"``)."""
    T = np.eye(4)
    T["xyz".index(axis), 3] = dist
    return T


@dataclass(frozen=True)
class DHRow:
    """One row of a DH table: link length ``a`` (m), twist ``alpha`` (rad), offset ``d`` (m), angle ``theta`` (rad;
    both constants the joint variable adds to), ``kind`` (``"revolute"``, ``"prismatic"``, ``"fixed"``), the joint
    variable's limits ``lower``, ``upper`` (rad or m) and its ``name`` (default ``joint<i>``)."""

    a: float
    alpha: float
    d: float
    theta: float = 0.0
    kind: str = "revolute"
    lower: float = -np.pi
    upper: float = np.pi
    name: str | None = None

    def __post_init__(self) -> None:
        if self.kind not in _KINDS:
            raise RobotLoadError(f"DH row kind {self.kind!r} is not one of {_KINDS}")
        if self.kind != "fixed" and not (np.isfinite(self.lower) and np.isfinite(self.upper)):
            raise RobotLoadError(f"DH row limits must be finite, got [{self.lower}, {self.upper}]")
        if self.kind != "fixed" and self.lower > self.upper:
            raise RobotLoadError(f"DH row limits are inverted: lower {self.lower} > upper {self.upper}")


def _split(row: DHRow, q: float, convention: str) -> tuple[np.ndarray, np.ndarray]:
    """One DH row at joint value ``q`` as (transform up to the joint frame, transform after it), (4, 4) each."""
    theta = row.theta + (q if row.kind == "revolute" else 0.0)
    d = row.d + (q if row.kind == "prismatic" else 0.0)
    if convention == "standard":
        return _rot("z", theta) @ translation("z", d), translation("x", row.a) @ _rot("x", row.alpha)
    if convention == "modified":
        return _rot("x", row.alpha) @ translation("x", row.a) @ _rot("z", theta) @ translation("z", d), np.eye(4)
    raise RobotLoadError(f"DH convention {convention!r} is not 'standard' or 'modified'")


def dh_transform(row: DHRow, q: float = 0.0, convention: str = "standard") -> np.ndarray:
    """Homogeneous transform (4, 4) of one DH row at joint value ``q`` (rad or m)."""
    before, after = _split(row, q, convention)
    return before @ after


@dataclass(frozen=True)
class JointSpec:
    """A joint of a serial chain: ``name``, ``kind`` (``"revolute"``, ``"prismatic"``, ``"fixed"``), ``origin`` (4, 4)
    from the parent link frame at zero joint value, unit ``axis`` (3,) in the joint frame, limits (rad or m)."""

    name: str
    kind: str
    origin: np.ndarray
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    lower: float = -np.pi
    upper: float = np.pi


def dh_to_urdf(name: str, rows: list[DHRow], convention: str = "standard", link_radius: float = 0.01,
               comment: str = "") -> str:
    """URDF text of the arm ``name`` of DH ``rows`` (base to tool) in ``convention`` (``"standard"`` or
    ``"modified"``), first DH frame at ``base_link``; ``link_radius`` (m) of the visuals, ``comment`` on top."""
    if not rows:
        raise RobotLoadError("a DH table needs at least one row")
    pending = np.eye(4)
    joints: list[JointSpec] = []
    for row in rows:
        before, after = _split(row, 0.0, convention)  # the joint moves along / about z between the two
        if row.kind == "fixed":
            pending = pending @ before @ after
            continue
        joints.append(JointSpec(row.name or f"joint{len(joints) + 1}", row.kind, pending @ before, lower=row.lower,
                                upper=row.upper))
        pending = after
    joints.append(JointSpec(name="tool_joint", kind="fixed", origin=pending))
    return chain_to_urdf(name, joints, link_radius=link_radius, comment=comment)


def _fmt(x: float) -> str:
    """Full precision for kinematics (FK must match the DH product to 1e-12 m)."""
    return repr(0.0 if abs(x) < 1e-15 else float(x))


def _short(x: float) -> str:
    """Six significant digits: enough for display-only sizes."""
    return f"{float(x):.6g}"


def _origin_xml(T: np.ndarray) -> str:
    xyz = " ".join(_fmt(v) for v in T[:3, 3])
    rpy = " ".join(_fmt(v) for v in lie.rpy(T[:3, :3])[0])  # URDF's R = Rz(yaw) Ry(pitch) Rx(roll)
    return f'<origin xyz="{xyz}" rpy="{rpy}"/>'


def _frame_along(z: np.ndarray, origin=(0.0, 0.0, 0.0)) -> np.ndarray:
    """A (4, 4) frame at ``origin`` (m) whose z axis is the unit vector ``z`` (visuals are built along z)."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    T[:3, 3] = origin
    return T


def _segment_visual(p: np.ndarray, radius: float, material: str) -> str:
    """A box from the link origin to point ``p`` (m), for rendering."""
    length = float(np.linalg.norm(p))
    if length < 1e-9:
        return ""
    T = _frame_along(p / length, p / 2)
    w = 1.4 * radius
    return (f"    <visual>{_origin_xml(T)}<geometry><box size=\"{_short(w)} {_short(w)} {_short(length)}\"/>"
            f"</geometry><material name=\"{material}\"/></visual>\n")


def _axis_visual(axis: np.ndarray, kind: str, radius: float) -> str:
    """A cylinder along a revolute axis (or a small box on a prismatic one) at the joint origin."""
    T = _frame_along(np.asarray(axis, float))
    geom = (f'<cylinder radius="{_short(1.6 * radius)}" length="{_short(5 * radius)}"/>' if kind == "revolute"
            else f'<box size="{_short(3 * radius)} {_short(3 * radius)} {_short(3 * radius)}"/>')
    return f'    <visual>{_origin_xml(T)}<geometry>{geom}</geometry><material name="joint"/></visual>\n'


def chain_to_urdf(name: str, joints: list[JointSpec], link_radius: float = 0.01, comment: str = "") -> str:
    """URDF text of a serial chain ``base_link -> link1 -> ... -> tool`` (a last fixed joint's child is ``tool``)."""
    if not joints:
        raise RobotLoadError("a chain needs at least one joint")
    lines = ['<?xml version="1.0"?>']
    if comment:
        lines.append("<!--\n" + escape(comment).replace("--", "- -") + "\n-->")
    lines += [f'<robot name="{escape(name)}">', '  <material name="link"><color rgba="0.55 0.6 0.7 1"/></material>',
              '  <material name="joint"><color rgba="0.9 0.5 0.1 1"/></material>']
    link_names = ["base_link"] + ["tool" if (j.kind == "fixed" and k == len(joints) - 1) else f"link{k + 1}"
                                  for k, j in enumerate(joints)]
    for k, link in enumerate(link_names):
        body = ""
        if k > 0 and joints[k - 1].kind != "fixed":
            body += _axis_visual(np.asarray(joints[k - 1].axis), joints[k - 1].kind, link_radius)
        if k < len(joints):
            body += _segment_visual(np.asarray(joints[k].origin)[:3, 3], link_radius, "link")
        if link == "tool":
            body += (f'    <visual><origin xyz="0 0 0" rpy="0 0 0"/><geometry><sphere radius="{_short(link_radius)}"/>'
                     '</geometry><material name="joint"/></visual>\n')
        lines.append(f'  <link name="{link}">\n{body}  </link>' if body else f'  <link name="{link}"/>')
    for k, j in enumerate(joints):
        parts = [f'  <joint name="{escape(j.name)}" type="{j.kind}">', f'    <parent link="{link_names[k]}"/>',
                 f'    <child link="{link_names[k + 1]}"/>', f"    {_origin_xml(np.asarray(j.origin, float))}"]
        if j.kind != "fixed":
            parts += [f'    <axis xyz="{" ".join(_fmt(v) for v in j.axis)}"/>',
                      f'    <limit lower="{_fmt(j.lower)}" upper="{_fmt(j.upper)}" effort="10.0" velocity="2.0"/>']
        parts.append("  </joint>")
        lines.append("\n".join(parts))
    lines.append("</robot>")
    return "\n".join(lines) + "\n"
