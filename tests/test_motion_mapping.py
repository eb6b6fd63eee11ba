"""Mapping presets (SMPL and CMU skeletons onto the example-robot-data humanoids) and resolve_mapping's checks."""

import numpy as np
import pinocchio as pin
import pytest

import evoik_pin
from evoik_pin.errors import MappingError, MotionError
from evoik_pin.motion import Motion, limb_pairs, load_clip, mapping_preset, resolve_mapping
from evoik_pin.motion.mapping import MAPPING_PRESETS, ROBOT_JOINTS, SKELETON_JOINTS

ROBOTS = ["g1", "talos", "romeo", "icub"]
SMPL_24 = ["pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2", "left_ankle",
           "right_ankle", "spine3", "left_foot", "right_foot", "neck", "left_collar", "right_collar", "head",
           "left_shoulder", "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist", "left_hand",
           "right_hand"]


@pytest.fixture(scope="module", params=ROBOTS)
def robot(request):
    return evoik_pin.load_robot(request.param, floating_base=True)


@pytest.fixture(scope="module")
def walk():
    return load_clip("walk")


@pytest.fixture(scope="module")
def smpl():
    return Motion(np.random.default_rng(0).normal(size=(3, 24, 3)), SMPL_24, 30)


def test_presets_cover_every_robot_and_skeleton():
    assert set(MAPPING_PRESETS) == {"cmu", "smpl"}
    for preset in MAPPING_PRESETS.values():
        assert set(preset) == set(ROBOTS)
    assert set(SKELETON_JOINTS["smpl"].values()) <= set(SMPL_24)


@pytest.mark.parametrize("preset", ["cmu", "smpl"])
def test_presets_resolve(robot, walk, smpl, preset):
    motion = walk if preset == "cmu" else smpl
    pairs = resolve_mapping(robot, motion, preset)
    assert len(pairs) == len(SKELETON_JOINTS[preset]) == 15
    assert len({f for f, _ in pairs}) == 15 and len({k for _, k in pairs}) == 15
    assert pairs == list(mapping_preset(preset, robot.name).items())


def test_preset_frames_sit_where_the_joints_are(robot):
    """At the neutral configuration: hips above knees above ankles, head above torso, shoulders above elbows or
    level with them, and every left frame on one side of the sagittal plane, every right frame on the other."""
    model = robot.model
    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    at = {j: data.oMf[model.getFrameId(f)].translation for j, f in ROBOT_JOINTS[robot.name].items()}
    for side in ("left", "right"):
        assert at[f"{side}_hip"][2] > at[f"{side}_knee"][2] + 0.15 > at[f"{side}_ankle"][2] + 0.3
        assert at[f"{side}_shoulder"][2] >= at[f"{side}_elbow"][2] - 1e-6
    assert at["head"][2] > at["torso"][2] + 0.1 and at["torso"][2] > at["left_hip"][2]
    base_y = np.sign(at["left_hip"][1])  # iCub's root frame has its left on -y: only the sides are compared
    for j in at:
        if j.startswith("left_"):
            assert np.sign(at[j][1]) == base_y, j
        elif j.startswith("right_"):
            assert np.sign(at[j][1]) == -base_y, j


def test_limb_pairs_name_motion_keypoints(walk):
    limbs = limb_pairs("cmu")
    assert set(limbs) == {"legs", "trunk", "arms"}
    for pairs in limbs.values():
        for parent, child in pairs:
            walk.index(parent), walk.index(child)
    assert ("LeftUpLeg", "LeftLeg") in limbs["legs"]
    assert ("left_elbow", "left_wrist") in limb_pairs("smpl")["arms"]


def test_dict_mapping(walk):
    g1 = evoik_pin.load_robot("g1", floating_base=True)
    assert resolve_mapping(g1, walk, {"pelvis": "Hips", "left_knee_link": "LeftLeg"}) == [
        ("pelvis", "Hips"), ("left_knee_link", "LeftLeg")]


def test_errors_name_the_closest(walk):
    g1 = evoik_pin.load_robot("g1", floating_base=True)
    with pytest.raises(MappingError, match="no frame 'left_knee_lnk'; closest: \\['left_knee_link'"):
        resolve_mapping(g1, walk, {"left_knee_lnk": "LeftLeg"})
    with pytest.raises(MappingError, match="no keypoint 'LeftLg'; closest: \\['LeftLeg'"):
        resolve_mapping(g1, walk, {"left_knee_link": "LeftLg"})
    with pytest.raises(MappingError, match="unknown mapping preset 'smlp'.*closest: \\['smpl'\\]"):
        resolve_mapping(g1, walk, "smlp")
    with pytest.raises(MappingError, match="empty"):
        resolve_mapping(g1, walk, {})
    with pytest.raises(MappingError, match="preset name"):
        resolve_mapping(g1, walk, [("pelvis", "Hips")])
    assert issubclass(MappingError, MotionError) and issubclass(MappingError, KeyError)
    assert "'" not in str(MappingError("plain"))[:1]  # printed as a message, not a quoted key


def test_fixed_base_robot_is_refused(walk):
    with pytest.raises(MappingError, match="floating_base=True"):
        resolve_mapping(evoik_pin.load_robot("g1"), walk, "cmu")


def test_robot_without_a_preset():
    panda = evoik_pin.load_robot("panda", floating_base=True)
    with pytest.raises(MappingError, match="no entry for robot 'panda'"):
        mapping_preset("cmu", panda.name)
