"""viz/ with whole robots: every link of a tree drawn, its floating base placed by q, and a marker per goal of a goal
list (checked in the static HTML export)."""

import numpy as np
import pinocchio as pin
import pytest

from evoik_pin.errors import FrameError, TargetError
from evoik_pin.goals import Pose, Position
from evoik_pin.robot import load_robot
from evoik_pin.viz import Viewer, html_commands, save_solution_html, skeleton_model


@pytest.fixture(scope="module")
def talos():
    return load_robot("talos", floating_base=True)


def _q(robot) -> np.ndarray:
    """A configuration with the base moved and turned, the arms and a leg bent."""
    q = np.zeros(robot.n)
    q[:6] = [0.1, 0.05, 1.02, 0.3, 0.05, -0.04]
    bent = {"arm_left_2_joint": 0.6, "arm_left_4_joint": -1.2, "arm_right_4_joint": -1.5, "leg_left_4_joint": 1.0}
    for name, value in bent.items():
        q[robot.joint_names.index(name)] = value
    return q


def _goals(robot, q) -> list:
    return [Pose("left_sole_link", robot.fk(q, frame="left_sole_link")),
            Pose("right_sole_link", robot.fk(q, frame="right_sole_link")),
            Pose("arm_left_7_link", robot.fk(q, frame="arm_left_7_link")),
            Position("arm_right_7_link", robot.fk(q, frame="arm_right_7_link").translation)]


def _transform(cmds, path: str) -> np.ndarray:
    matrix = [c["matrix"] for c in cmds if c["type"] == "set_transform" and c["path"] == path][-1]
    return np.array(matrix).reshape(4, 4).T  # meshcat sends column-major


def test_html_of_a_goal_list_answer_has_every_link_and_a_marker_per_goal(talos, tmp_path):
    q = _q(talos)
    goals = _goals(talos, q)
    cmds = html_commands(save_solution_html(talos, q, goals, tmp_path / "talos.html").read_text())
    objects = {c["path"] for c in cmds if c["type"] == "set_object"}

    # the whole robot: every visual object of the model (legs, arms, torso, head), each where Pinocchio puts it
    visuals = talos.visual_model.geometryObjects
    drawn = {p.rsplit("/", 1)[1] for p in objects if p.startswith("/meshcat/robot/visuals/")}
    assert drawn == {g.name for g in visuals}
    links = {talos.model.frames[g.parentFrame].name for g in visuals}
    assert {"base_link", "torso_2_link", "head_2_link", "leg_left_6_link", "leg_right_6_link", "arm_left_7_link",
            "arm_right_7_link"} <= links
    placements = talos.geometry_placements(talos.visual_model, q)
    for g, M in zip(visuals, placements, strict=True):  # meshes drawn at their scale (the right arm's mirrored)
        if talos.model.frames[g.parentFrame].name in ("base_link", "leg_left_6_link", "arm_right_7_link"):
            scaled = M.homogeneous @ np.diag([*g.meshScale, 1.0])
            assert np.allclose(_transform(cmds, f"/meshcat/robot/visuals/{g.name}"), scaled, atol=1e-6)
    # the floating base placed by q's six entries: as Pinocchio's free-flyer model of the URDF puts the root link
    full = talos.full_model
    data = full.createData()
    pin.framesForwardKinematics(full, data, talos.full_configuration(q))
    (g,) = [g for g in visuals if talos.model.frames[g.parentFrame].name == "base_link"]
    oMg = (data.oMf[full.getFrameId("base_link")] * g.placement).homogeneous @ np.diag([*g.meshScale, 1.0])
    assert np.allclose(_transform(cmds, f"/meshcat/robot/visuals/{g.name}"), oMg, atol=1e-6)

    # one marker per goal: a triad for a pose, a sphere for a position, each with its label, at its target
    for goal in goals:
        node = f"/meshcat/goals/{goal.frame}"
        parts = {p.rsplit("/", 1)[1] for p in objects if p.startswith(node + "/")}
        assert parts == ({"origin", "x", "y", "z", "label"} if goal.has_orientation else {"point", "label"})
        (label,) = [c for c in cmds if c["type"] == "set_object" and c["path"] == f"{node}/label"]
        assert label["object"]["object"]["type"] == "Sprite"
        assert [t["text"] for t in label["object"]["textures"]] == [goal.frame]
        p, R = goal.encode()
        T = _transform(cmds, node)
        assert np.allclose(T[:3, 3], p, atol=1e-9)
        if goal.has_orientation:
            assert np.allclose(T[:3, :3], R, atol=1e-9)
    assert len({p.split("/")[3] for p in objects if p.startswith("/meshcat/goals/")}) == len(goals)


def test_show_goals_names_its_nodes_and_checks_the_goals(talos, tmp_path):
    q = _q(talos)
    goals = _goals(talos, q)
    with Viewer(talos) as v:
        nodes = v.show_goals(goals, labels=False)
        assert nodes == [f"goals/{g.frame}" for g in goals]
        assert v.scene["goals/arm_right_7_link"] == "goal point: arm_right_7_link"
        assert v.scene["goals/left_sole_link"] == "goal triad: left_sole_link"
        cmds = html_commands(v.save_html(tmp_path / "goals.html").read_text())
        assert not any(c["path"].endswith("/label") for c in cmds if c["type"] == "set_object")
        with pytest.raises(TargetError, match="goal list is empty"):
            v.show_goals([])
        with pytest.raises(FrameError, match="no frame 'arm_left_77_link'"):
            v.show_goals([Position("arm_left_77_link", [0.0, 0.0, 0.0])])
        v.show_goals(goals[:1])  # drawing the group again replaces it
        assert [k for k in v.scene if k.startswith("goals/")] == ["goals/left_sole_link"]


def test_skeleton_of_a_tree_marks_every_joint_and_no_base_joint(talos):
    geom = skeleton_model(talos)
    names = {g.name for g in geom.geometryObjects}
    joints = list(talos.model.names)[7:]  # after the universe and the floating base's six
    assert {f"skeleton_{j}" for j in joints} <= names
    assert not any(n.startswith("skeleton_floating_base") or "rail_floating" in n for n in names)
    data = talos.model.createData()
    pin.forwardKinematics(talos.model, data, talos.to_pinocchio(_q(talos)))
    gdata = pin.GeometryData(geom)
    pin.updateGeometryPlacements(talos.model, data, geom, gdata)
    sphere = gdata.oMg[geom.getGeometryId("skeleton_leg_left_4_joint")]
    assert np.allclose(sphere.translation, talos.fk(_q(talos), frame="leg_left_4_joint").translation, atol=1e-9)
