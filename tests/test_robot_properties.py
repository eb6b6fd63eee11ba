"""Properties of the robot layer, with hypothesis (run ``pytest --hypothesis-show-statistics`` for the counts).

(a) random DH chains (revolute, prismatic, continuous and mimic joints, fixed joints between them, random
    limits) written to URDF load with one entry of q per independent joint and match the DH product and
    yourdfpy's FK, one configuration or a batch, Jacobians included;
(b) IK round trips from random reachable poses on every bundled and example-robot-data arm (and two mimic
    arms) succeed within 1e-6 and the joint limits;
(c) URDF XML mutated at random (deleted attributes and elements, bad numbers, unknown joint types, cycles,
    duplicate names, truncation, stray bytes, very large files) loads, or raises an EvoikError naming the
    file (or "URDF string"); never another exception, never a hang, nothing on stderr.
"""

import copy
import functools
import time
import warnings
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from urdf_helpers import dh_chain_urdf, dh_product, gripper, mimic_3r, yourdfpy_pose

import evoik_pin as ev
from evoik_pin.errors import EvoikError
from evoik_pin.papers.dh import DHRow
from evoik_pin.robot import list_robots, load_robot

# ---------------------------------------------------------------------------------------------- (a) DH chains
small = st.floats(-0.4, 0.4, allow_nan=False)
angle = st.floats(-np.pi, np.pi, allow_nan=False)


@st.composite
def dh_chains(draw):
    """(rows, kinds, mimic) for :func:`urdf_helpers.dh_chain_urdf`: 1-6 rows, at least one independent joint."""
    count = draw(st.integers(1, 6))
    rows, kinds = [], []
    for _ in range(count):
        kind = draw(st.sampled_from(["revolute", "prismatic", "continuous", "fixed"]))
        lower = draw(st.floats(-3.0, -0.1)) if kind != "prismatic" else draw(st.floats(-0.5, 0.0))
        upper = draw(st.floats(0.1, 3.0)) if kind != "prismatic" else draw(st.floats(0.05, 0.5))
        rows.append(DHRow(draw(small), draw(angle), draw(small), draw(angle),
                          "prismatic" if kind == "prismatic" else "fixed" if kind == "fixed" else "revolute",
                          lower, upper))
        kinds.append(kind)
    movable = [i for i, k in enumerate(kinds) if k != "fixed"]
    if not movable:  # make one row movable
        rows[0] = DHRow(rows[0].a, rows[0].alpha, rows[0].d, rows[0].theta, "revolute", -2.0, 2.0)
        kinds[0] = "revolute"
        movable = [0]
    mimic: list = [None] * count
    drivers = [movable[0]] + [i for i in movable[1:] if not draw(st.booleans())]  # rows that stay independent
    for i in movable:
        if i not in drivers:
            mimic[i] = (draw(st.sampled_from(drivers)), draw(st.floats(-2.0, 2.0)), draw(st.floats(-0.5, 0.5)))
            if kinds[i] != "continuous":  # wide limits: the coupling, not the mimic joint's limits, is tested
                wide = 50.0 if rows[i].kind == "revolute" else 5.0
                r = rows[i]
                rows[i] = DHRow(r.a, r.alpha, r.d, r.theta, r.kind, -wide, wide)
    return rows, kinds, mimic


@settings(max_examples=100, deadline=None, database=None)
@given(chain=dh_chains(), data=st.data())
def test_random_dh_chains_match_the_dh_product_and_yourdfpy(chain, data):
    rows, kinds, mimic = chain
    robot = load_robot(dh_chain_urdf(rows, kinds, mimic))
    independent = [i for i, k in enumerate(kinds) if k != "fixed" and mimic[i] is None]
    order = []  # base to tip, each independent joint where it first moves the chain (itself or a mimic of it)
    for i, k in enumerate(kinds):
        d = i if mimic[i] is None else mimic[i][0] if mimic[i][1] != 0.0 else None
        if k != "fixed" and d is not None and d not in order:
            order.append(d)
    assert robot.joint_names == [f"joint{i}" for i in order] and sorted(order) == independent
    assert robot.tip == "tool" and robot.n == len(independent)
    assert robot.continuous.tolist() == [kinds[int(name[5:])] == "continuous" for name in robot.joint_names]
    for i in independent:  # URDF limits (continuous: [-pi, pi]), narrowed by mimic joints only when they bind
        k = robot.joint_names.index(f"joint{i}")
        lo, hi = (-np.pi, np.pi) if kinds[i] == "continuous" else (rows[i].lower, rows[i].upper)
        assert lo - 1e-12 <= robot.lower[k] <= robot.upper[k] <= hi + 1e-12
    Q = np.array([data.draw(st.lists(st.floats(-3.0, 3.0), min_size=robot.n, max_size=robot.n)) for _ in range(3)])
    P, R, J = robot.fk_jacobian_batch(Q)
    for qi, q in enumerate(Q):
        value = dict(zip(robot.joint_names, q, strict=True))
        values = [0.0 if k == "fixed" else value[f"joint{i}"] if mimic[i] is None
                  else mimic[i][1] * value[f"joint{mimic[i][0]}"] + mimic[i][2] for i, k in enumerate(kinds)]
        T = robot.fk(q).homogeneous
        assert np.abs(T - dh_product(rows, values)).max() < 1e-9
        # yourdfpy (trimesh) drops angles and offsets below about 1e-8: 1e-7 still catches any wrong coupling
        assert np.abs(T - yourdfpy_pose(robot, q)).max() < 1e-7
        assert np.abs(P[qi] - T[:3, 3]).max() < 1e-12 and np.abs(R[qi] - T[:3, :3]).max() < 1e-12
        assert np.abs(J[qi] - robot.jacobian(q)).max() < 1e-12


# ---------------------------------------------------------------------------------------------- (b) IK round trips
ARMS = [*list_robots(), "mimic3r", "gripper"]


@functools.cache
def _arm(name):
    if name == "mimic3r":
        return load_robot(mimic_3r(), tip="tool")
    if name == "gripper":
        return load_robot(gripper(), tip="fb_tip")
    return load_robot(name)


@settings(max_examples=300, deadline=None, database=None)
@given(name=st.sampled_from(ARMS), u=st.lists(st.floats(0.1, 0.9), min_size=8, max_size=8), seed=st.integers(0, 99))
def test_ik_round_trips_from_reachable_poses(name, u, seed):
    """Configurations at least 10 % of each joint's range away from its limits (see the next test)."""
    robot = _arm(name)
    q = robot.lower + np.asarray(u[: robot.n]) * (robot.upper - robot.lower)
    T = robot.fk(q)
    r = ev.solve(robot, T, timeout=None, max_restarts=20, seed=seed)
    assert r.success, (name, q, r.message)
    assert r.position_error <= 1e-6 and r.orientation_error <= 1e-6
    assert robot.within_bounds(r.q)
    reached = robot.fk(r.q)
    assert np.linalg.norm(reached.translation - T.translation) <= 1e-6


@pytest.mark.parametrize("name", ["ax18", "panda", "z1"])
def test_ik_round_trips_near_joint_limit_corners(name):
    """Configurations with every joint within 3 % of a limit (the corners of the box that uniform draws and the
    seed table rarely visit): memetic's DE populations put a share of their coordinates on the bounds."""
    robot = _arm(name)
    rng = np.random.default_rng(11)
    solved = 0
    for i in range(20):
        frac = rng.uniform(0.0, 0.03, robot.n)
        q = np.where(rng.random(robot.n) < 0.5, robot.lower + frac * (robot.upper - robot.lower),
                     robot.upper - frac * (robot.upper - robot.lower))
        r = ev.solve(robot, robot.fk(q), timeout=None, max_restarts=20, seed=i)
        solved += r.success and robot.within_bounds(r.q)
    assert solved >= 19
    T = _arm("ax18").fk(_arm("ax18").lower)  # every joint exactly on its lower limit
    assert ev.solve(_arm("ax18"), T, timeout=None, max_restarts=20, seed=0).success


# ---------------------------------------------------------------------------------------------- (c) mutated URDFs
BASES = {
    "mimic3r": mimic_3r(),
    "gripper": gripper(),
    "planar2r": load_robot("planar2r").urdf_xml,  # visuals, materials, a comment
}
BAD_VALUES = ["", " ", "abc", "nan", "inf", "-inf", "1e999", "1e-400", "1 2", "0 0 0", "1,5", "--1", "0x10", "∞",
              "1 2 3 4", "-1e308", "\x7f", "&amp;", "0 0 0 0 0 0", "3.0.1"]


def _elements(root):
    return [el for el in root.iter() if el is not root]


@st.composite
def mutated_urdfs(draw):
    """(bytes of a mutated URDF, what was done)."""
    root = ET.fromstring(BASES[draw(st.sampled_from(sorted(BASES)))])
    done = []
    for _ in range(draw(st.integers(1, 3))):
        els = _elements(root)
        joints = root.findall("joint")
        links = root.findall("link")
        kind = draw(st.sampled_from(["drop_attr", "bad_number", "joint_type", "cycle", "duplicate", "drop_element",
                                     "swap", "dangling", "random_text", "copy_element", "root_tag", "large"]))
        done.append(kind)
        if kind in ("drop_attr", "bad_number", "random_text"):
            withattr = [el for el in els if el.attrib]
            el = draw(st.sampled_from(withattr))
            attr = draw(st.sampled_from(sorted(el.attrib)))
            if kind == "drop_attr":
                del el.attrib[attr]
            else:
                el.set(attr, draw(st.sampled_from(BAD_VALUES)) if kind == "bad_number" else
                       draw(st.text(st.characters(codec="utf-8", exclude_categories=["Cs", "Cc"]), max_size=12)))
        elif kind == "joint_type" and joints:
            draw(st.sampled_from(joints)).set("type", draw(st.sampled_from(
                ["hinge", "", "REVOLUTE", "floating", "planar", "fixed", "continuous", "prismatic", "spherical"])))
        elif kind == "cycle" and joints:  # a joint's parent becomes a link downstream of it (or itself)
            j = draw(st.sampled_from(joints))
            names = [x.get("name") for x in links if x.get("name")]
            if j.find("parent") is not None and names:
                j.find("parent").set("link", draw(st.sampled_from(names)))
        elif kind == "duplicate":
            group = draw(st.sampled_from([g for g in (links, joints) if len(g) > 1]))
            a, b = draw(st.sampled_from(group)), draw(st.sampled_from(group))
            a.set("name", b.get("name") or "")
        elif kind == "drop_element":
            el = draw(st.sampled_from(els))
            for parent in root.iter():
                if el in list(parent):
                    parent.remove(el)
                    break
        elif kind == "swap" and joints:
            j = draw(st.sampled_from(joints))
            p, c = j.find("parent"), j.find("child")
            if p is not None and c is not None:
                pl, cl = p.get("link"), c.get("link")
                p.set("link", cl or "")
                c.set("link", pl or "")
        elif kind == "dangling" and links:
            draw(st.sampled_from(links)).set("name", "renamed_" + str(draw(st.integers(0, 9))))
        elif kind == "copy_element":
            root.append(copy.deepcopy(draw(st.sampled_from(els))))
        elif kind == "root_tag":
            root.tag = draw(st.sampled_from(["sdf", "Robot", "robot", "urdf"]))
        elif kind == "large":  # a long chain appended below one link, or a huge comment
            named = [x.get("name") for x in links if x.get("name")]
            if draw(st.booleans()) and named:
                parent = draw(st.sampled_from(named))
                for k in range(draw(st.integers(50, 600))):
                    ET.SubElement(root, "link", name=f"big{k}")
                    j = ET.SubElement(root, "joint", name=f"bigj{k}", type="revolute")
                    ET.SubElement(j, "parent", link=parent if k == 0 else f"big{k - 1}")
                    ET.SubElement(j, "child", link=f"big{k}")
                    ET.SubElement(j, "origin", xyz="0.001 0 0")
                    ET.SubElement(j, "axis", xyz="0 0 1")
                    ET.SubElement(j, "limit", lower="-1", upper="1", effort="1", velocity="1")
            else:
                root.append(ET.Comment("x" * 2_000_000))
    data = ET.tostring(root, encoding="utf-8", xml_declaration=True)
    tail = draw(st.sampled_from(["none", "truncate", "insert"]))
    if tail == "truncate":
        data = data[: draw(st.integers(0, len(data)))]
    elif tail == "insert":
        at = draw(st.integers(0, len(data)))
        data = data[:at] + draw(st.binary(min_size=1, max_size=8)) + data[at:]
    done.append(tail)
    return data, done


@settings(max_examples=400, deadline=None, database=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                   HealthCheck.too_slow, HealthCheck.data_too_large])
@given(case=mutated_urdfs(), as_file=st.booleans())
def test_mutated_urdfs_load_or_raise_evoik_errors_naming_the_file(case, as_file, tmp_path, capfd):
    data, done = case
    path = tmp_path / "mutated.urdf"
    path.write_bytes(data)
    if not as_file:
        try:
            source = data.decode("utf-8")
        except UnicodeDecodeError:
            source = data  # bytes: decoded as their declaration says
    start = time.thread_time()  # the work of this thread: a loaded machine's waits do not count
    try:
        with warnings.catch_warnings():  # a RobotLoadWarning (a mimic of a removed joint) is fine too
            warnings.simplefilter("ignore")
            robot = load_robot(path if as_file else source)
    except EvoikError as exc:
        if as_file or "<" in str(source):  # (a string without "<" is a path or a name, and named as such)
            where = str(path.resolve()) if as_file else "URDF string"
            assert where in str(exc), (done, str(exc))
    else:
        q = np.clip(np.zeros(robot.n), robot.lower, robot.upper)
        assert np.all(np.isfinite(robot.fk(q).homogeneous)), done
    assert time.thread_time() - start < 20.0, done  # never a hang (a 600-joint chain loads in well under 1 s)
    assert capfd.readouterr().err == "", done

