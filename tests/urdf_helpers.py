"""URDF builders and an independent FK reference (yourdfpy) for the robot-layer tests.

Not a test module: tests/test_robot_*.py import it (pytest puts tests/ on sys.path).
"""

from __future__ import annotations

import io
import re
import xml.etree.ElementTree as ET

import numpy as np
import yourdfpy

from evoik_pin.papers.dh import DHRow, dh_to_urdf

LIMIT = '<limit lower="{lo}" upper="{hi}" effort="1" velocity="1"/>'


def joint_xml(name, kind, parent, child, xyz="0 0 0", rpy="0 0 0", axis="0 0 1", lo=-2.0, hi=2.0, mimic=None):
    """One <joint> element as text; ``mimic`` = (joint, multiplier, offset)."""
    limit = LIMIT.format(lo=lo, hi=hi) if kind in ("revolute", "prismatic") else ""
    axis_xml = f'<axis xyz="{axis}"/>' if kind != "fixed" else ""
    mimic_xml = (f'<mimic joint="{mimic[0]}" multiplier="{mimic[1]}" offset="{mimic[2]}"/>' if mimic else "")
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz}" rpy="{rpy}"/>{axis_xml}{limit}{mimic_xml}</joint>')


def robot_xml(name, links, joints, declaration=True):
    head = '<?xml version="1.0"?>\n' if declaration else ""
    body = "".join(f'<link name="{x}"/>' for x in links) + "".join(joints)
    return head + f'<robot name="{name}">{body}</robot>'


def mimic_3r(multiplier=2.0, offset=0.1, lower3=-3.0, upper3=3.0):
    """A 3R chain whose joint j3 mimics j2: q3 = multiplier q2 + offset; tip ``tool``."""
    return robot_xml("mimic3r", ["base", "l1", "l2", "l3", "tool"], [
        joint_xml("j1", "revolute", "base", "l1", xyz="0 0 0.1", axis="0 0 1", lo=-3, hi=3),
        joint_xml("j2", "revolute", "l1", "l2", xyz="0.2 0 0", axis="0 1 0", lo=-2, hi=2),
        joint_xml("j3", "revolute", "l2", "l3", xyz="0.2 0 0", axis="0 1 0", lo=lower3, hi=upper3,
                  mimic=("j2", multiplier, offset)),
        joint_xml("jt", "fixed", "l3", "tool", xyz="0.1 0 0.02"),
    ])


def gripper(driver="finger_a", follower="finger_b"):
    """A wrist and a two-finger gripper whose ``follower`` finger mimics the ``driver`` one (q = -0.5 q_d +
    0.01): a tip on the follower's fingertip puts the driver, off that chain, into q."""
    return robot_xml("gripper", ["base", "palm", "fa", "fb", "fb_tip"], [
        joint_xml("wrist", "revolute", "base", "palm", xyz="0 0 0.1", axis="0 0 1", lo=-3, hi=3),
        joint_xml(follower, "prismatic", "palm", "fb", xyz="0 -0.02 0.05", axis="0 -1 0", lo=-0.03, hi=0.05,
                  mimic=(driver, -0.5, 0.01)),
        joint_xml(driver, "prismatic", "palm", "fa", xyz="0 0.02 0.05", axis="0 1 0", lo=0, hi=0.04),
        joint_xml("tip_joint", "fixed", "fb", "fb_tip", xyz="0 0 0.03", rpy="0.1 0 0"),
    ])


def yourdfpy_pose(robot, q, frame=None):
    """(4, 4) pose of ``frame`` (default: the tip) in the robot's base frame by yourdfpy, the joints set from
    ``robot.full_configuration(q)`` (yourdfpy applies the mimic couplings itself)."""
    text = re.sub(r"^\s*<\?xml[^>]*\?>", "", robot.urdf_xml)  # lxml wants bytes without a foreign declaration
    urdf = yourdfpy.URDF.load(io.BytesIO(text.encode("utf-8")), build_scene_graph=True, load_meshes=False,
                              build_collision_scene_graph=False, load_collision_meshes=False)
    full = robot.full_configuration(q)
    cfg = {}
    for name in urdf.actuated_joint_names:
        jm = robot.full_model.joints[robot.full_model.getJointId(name)]
        cfg[name] = float(np.arctan2(full[jm.idx_q + 1], full[jm.idx_q]) if jm.nq == 2 else full[jm.idx_q])
    urdf.update_cfg(cfg)
    return urdf.get_transform(frame or robot.tip, robot.base)


# ------------------------------------------------------------------------------------------- random DH chains
def dh_chain_urdf(rows, kinds, mimic, name="dh"):
    """URDF of a DH chain (standard convention) with extra joint kinds.

    ``rows``: DHRow list (kind revolute, prismatic or fixed, as dh.py writes them); ``kinds[i]`` may turn a
    revolute row into "continuous" (its <limit> dropped); ``mimic[i]`` = (row index of the driver, multiplier,
    offset) couples row i to an earlier or later movable row. Joint i is named ``joint<i>`` (fixed rows too).
    """
    named = [DHRow(r.a, r.alpha, r.d, r.theta, r.kind, r.lower, r.upper, name=f"joint{i}") for i, r in enumerate(rows)]
    # dh_to_urdf folds fixed rows into the next origin: keep them as real fixed joints by writing a zero-motion
    # revolute row and then fixing it, so every row has its own joint and link.
    movable = [DHRow(r.a, r.alpha, r.d, r.theta, "revolute" if r.kind == "fixed" else r.kind,
                     r.lower if r.kind != "fixed" else -1.0, r.upper if r.kind != "fixed" else 1.0, name=r.name)
               for r in named]
    root = ET.fromstring(dh_to_urdf(name, movable))
    for j in root.findall("joint"):
        jname = j.get("name")
        if not jname.startswith("joint"):
            continue
        i = int(jname[5:])
        if named[i].kind == "fixed":
            j.set("type", "fixed")
            for tag in ("axis", "limit"):
                el = j.find(tag)
                if el is not None:
                    j.remove(el)
        elif kinds[i] == "continuous":
            j.set("type", "continuous")
            j.remove(j.find("limit"))
        if mimic[i] is not None:
            d, m, c = mimic[i]
            ET.SubElement(j, "mimic", joint=f"joint{d}", multiplier=repr(float(m)), offset=repr(float(c)))
    return ET.tostring(root, encoding="unicode")


def dh_product(rows, values):
    """Tool pose (4, 4) of the standard-DH chain at per-row joint values (0 for fixed rows)."""
    from evoik_pin.papers.dh import dh_transform

    T = np.eye(4)
    for r, v in zip(rows, values, strict=True):
        T = T @ dh_transform(r, v if r.kind != "fixed" else 0.0)
    return T
