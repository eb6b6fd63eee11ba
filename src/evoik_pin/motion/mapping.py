"""Which robot frame follows which motion keypoint: presets for SMPL and CMU skeletons onto the example-robot-data
humanoids, their limb pairs, and the check of a mapping against a robot and a motion.

A mapping is ``{robot frame: motion keypoint}``. The presets pair the pelvis/base, hips, knees, ankles, torso,
head, shoulders, elbows and wrists; each robot frame is the link whose origin sits at that joint centre (checked
at the robot's neutral configuration by tests/test_motion_mapping.py: hips above knees above ankles, head above
torso, the left frames on one side and the right frames on the other).

Facing: with the floating base at the identity, G1, Talos and Romeo face +x with their left on +y, as the motions
of :func:`~evoik_pin.motion.load_bvh` do; iCub's root frame has x backward, so iCub faces -x with its left on -y and
a retargeter must turn its base by pi about z.
"""

from __future__ import annotations

from collections.abc import Mapping

from ..errors import MappingError
from ..robot.frames import closest_names, frame_names
from .motion import Motion

__all__ = ["LIMBS", "MAPPING_PRESETS", "ROBOT_JOINTS", "SKELETON_JOINTS", "limb_pairs", "mapping_preset",
           "resolve_mapping"]

#: The joints a preset pairs, in order, with their names in each source skeleton.
SKELETON_JOINTS: dict[str, dict[str, str]] = {
    "cmu": {
        "pelvis": "Hips", "left_hip": "LeftUpLeg", "left_knee": "LeftLeg", "left_ankle": "LeftFoot",
        "right_hip": "RightUpLeg", "right_knee": "RightLeg", "right_ankle": "RightFoot", "torso": "Spine1",
        "head": "Head", "left_shoulder": "LeftArm", "left_elbow": "LeftForeArm", "left_wrist": "LeftHand",
        "right_shoulder": "RightArm", "right_elbow": "RightForeArm", "right_wrist": "RightHand",
    },
    "smpl": {
        "pelvis": "pelvis", "left_hip": "left_hip", "left_knee": "left_knee", "left_ankle": "left_ankle",
        "right_hip": "right_hip", "right_knee": "right_knee", "right_ankle": "right_ankle", "torso": "spine3",
        "head": "head", "left_shoulder": "left_shoulder", "left_elbow": "left_elbow", "left_wrist": "left_wrist",
        "right_shoulder": "right_shoulder", "right_elbow": "right_elbow", "right_wrist": "right_wrist",
    },
}

#: The robot frame at each joint of :data:`SKELETON_JOINTS`, per example-robot-data humanoid (loaded with
#: ``floating_base=True``).
ROBOT_JOINTS: dict[str, dict[str, str]] = {
    "g1": {
        "pelvis": "pelvis", "left_hip": "left_hip_roll_link", "left_knee": "left_knee_link",
        "left_ankle": "left_ankle_roll_link", "right_hip": "right_hip_roll_link", "right_knee": "right_knee_link",
        "right_ankle": "right_ankle_roll_link", "torso": "torso_link", "head": "mid360_link",
        "left_shoulder": "left_shoulder_roll_link", "left_elbow": "left_elbow_link",
        "left_wrist": "left_wrist_roll_link", "right_shoulder": "right_shoulder_roll_link",
        "right_elbow": "right_elbow_link", "right_wrist": "right_wrist_roll_link",
    },
    "talos": {
        "pelvis": "base_link", "left_hip": "leg_left_2_link", "left_knee": "leg_left_4_link",
        "left_ankle": "leg_left_6_link", "right_hip": "leg_right_2_link", "right_knee": "leg_right_4_link",
        "right_ankle": "leg_right_6_link", "torso": "torso_2_link", "head": "head_2_link",
        "left_shoulder": "arm_left_2_link", "left_elbow": "arm_left_4_link", "left_wrist": "arm_left_7_link",
        "right_shoulder": "arm_right_2_link", "right_elbow": "arm_right_4_link", "right_wrist": "arm_right_7_link",
    },
    "romeo": {
        "pelvis": "base_link", "left_hip": "LHipPitchLink", "left_knee": "LKneePitchLink", "left_ankle": "l_ankle",
        "right_hip": "RHipPitchLink", "right_knee": "RKneePitchLink", "right_ankle": "r_ankle", "torso": "torso",
        "head": "HeadRollLink", "left_shoulder": "LShoulderPitchLink", "left_elbow": "LElbowRollLink",
        "left_wrist": "l_wrist", "right_shoulder": "RShoulderPitchLink", "right_elbow": "RElbowRollLink",
        "right_wrist": "r_wrist",
    },
    "icub": {
        "pelvis": "root_link", "left_hip": "l_hip_2", "left_knee": "l_lower_leg", "left_ankle": "l_ankle_2",
        "right_hip": "r_hip_2", "right_knee": "r_lower_leg", "right_ankle": "r_ankle_2", "torso": "chest",
        "head": "head", "left_shoulder": "l_shoulder_2", "left_elbow": "l_elbow_1", "left_wrist": "l_hand",
        "right_shoulder": "r_shoulder_2", "right_elbow": "r_elbow_1", "right_wrist": "r_hand",
    },
}

#: ``{preset: {robot: {robot frame: keypoint}}}``: every skeleton onto every robot.
MAPPING_PRESETS: dict[str, dict[str, dict[str, str]]] = {
    skeleton: {robot: {frame: names[joint] for joint, frame in frames.items()}
               for robot, frames in ROBOT_JOINTS.items()}
    for skeleton, names in SKELETON_JOINTS.items()
}

#: Limbs as (parent joint, child joint) per group, in :data:`SKELETON_JOINTS`' joint names: the segments whose
#: directions a retargeter copies onto the robot.
LIMBS: dict[str, tuple[tuple[str, str], ...]] = {
    "legs": (("left_hip", "left_knee"), ("left_knee", "left_ankle"),
             ("right_hip", "right_knee"), ("right_knee", "right_ankle")),
    "trunk": (("pelvis", "torso"), ("torso", "head")),
    "arms": (("left_shoulder", "left_elbow"), ("left_elbow", "left_wrist"),
             ("right_shoulder", "right_elbow"), ("right_elbow", "right_wrist")),
}


def _preset_name(name: str) -> str:
    if name not in SKELETON_JOINTS:
        close = closest_names(str(name), list(SKELETON_JOINTS))
        raise MappingError(f"unknown mapping preset {name!r}; accepted: {list(SKELETON_JOINTS)} or a dict "
                           f"{{robot frame: motion keypoint}}" + (f" (closest: {close})" if close else ""))
    return name


def limb_pairs(preset: str) -> dict[str, list[tuple[str, str]]]:
    """``{group: [(parent keypoint, child keypoint), ...]}`` for the groups ``"legs"``, ``"trunk"``, ``"arms"``
    in the keypoint names of skeleton ``preset`` (``"cmu"`` or ``"smpl"``)."""
    names = SKELETON_JOINTS[_preset_name(preset)]
    return {group: [(names[a], names[b]) for a, b in pairs] for group, pairs in LIMBS.items()}


def mapping_preset(preset: str, robot_name: str) -> dict[str, str]:
    """The preset ``{robot frame: keypoint}`` of skeleton ``preset`` onto the robot named ``robot_name``."""
    by_robot = MAPPING_PRESETS[_preset_name(preset)]
    if robot_name not in by_robot:
        raise MappingError(f"mapping preset {preset!r} has no entry for robot {robot_name!r}; presets exist for "
                           f"{list(by_robot)}: pass a dict {{robot frame: motion keypoint}} for another robot")
    return dict(by_robot[robot_name])


def resolve_mapping(robot, motion: Motion, mapping: str | Mapping[str, str]) -> list[tuple[str, str]]:
    """Checked ``[(robot frame, motion keypoint), ...]`` of ``mapping`` (a preset name, ``"cmu"`` or
    ``"smpl"``, looked up by ``robot.name``; or a dict ``{robot frame: keypoint}``) for ``robot`` (a
    :class:`~evoik_pin.Robot` loaded with ``floating_base=True``) and ``motion``.

    Raises :class:`~evoik_pin.errors.MappingError` for a robot without a floating base, an unknown preset, an empty
    mapping, or a frame absent from the robot or a keypoint absent from the motion (naming the closest names).
    """
    if not getattr(robot, "floating_base", False):
        raise MappingError(f"robot {getattr(robot, 'name', robot)!r} has a fixed base, but following a motion moves "
                           f"the whole body: load it with load_robot(..., floating_base=True)")
    if isinstance(mapping, str):
        pairs = mapping_preset(mapping, robot.name)
    elif isinstance(mapping, Mapping):
        pairs = dict(mapping)
    else:
        raise MappingError(f"mapping must be a preset name {list(SKELETON_JOINTS)} or a dict {{robot frame: motion "
                           f"keypoint}}; got {type(mapping).__name__}")
    if not pairs:
        raise MappingError("the mapping is empty: give at least one {robot frame: motion keypoint} pair")
    frames = frame_names(robot.model)
    known_frames = set(frames)
    for frame, keypoint in pairs.items():
        if frame not in known_frames:
            close = closest_names(str(frame), frames)
            raise MappingError(f"mapping entry {frame!r}: robot {robot.name!r} has no frame {frame!r}"
                               + (f"; closest: {close}" if close else ""))
        if keypoint not in motion.names:
            close = closest_names(str(keypoint), list(motion.names))
            raise MappingError(f"mapping entry {frame!r}: the motion has no keypoint {keypoint!r}"
                               + (f"; closest: {close}" if close else f"; keypoints: {list(motion.names)}"))
    return list(pairs.items())
