"""scripts/judge_retarget.py: the retargeting judge on tiny hand-made cases whose answers are known."""

import json
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"
sys.path.insert(0, str(SCRIPTS))

import goal_problems as gp  # noqa: E402
import judge_retarget as jr  # noqa: E402

# A free-flying box with one arm (revolute j1 about y, +-1 rad, 1 rad/s) ending in "tip" 1 m above the joint,
# and a foot sphere (radius 0.05 m) on the fixed frame "foot" 0.1 m below the base origin.
TINY_URDF = """<?xml version="1.0"?>
<robot name="tiny">
  <link name="base">
    <collision><origin xyz="0 0 0"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision>
  </link>
  <link name="arm"/>
  <link name="tip"/>
  <link name="foot">
    <collision><origin xyz="0 0 0"/><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="arm"/><origin xyz="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" velocity="1" effort="1"/>
  </joint>
  <joint name="tip_fix" type="fixed"><parent link="arm"/><child link="tip"/><origin xyz="0 0 1"/></joint>
  <joint name="foot_fix" type="fixed"><parent link="base"/><child link="foot"/><origin xyz="0 0 -0.1"/></joint>
</robot>
"""
G1_URDF = gp.example_robot_data_dir() / "g1_description" / "urdf" / "g1_29dof_rev_1_0.urdf"


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    path = tmp_path_factory.mktemp("judge") / "tiny.urdf"
    path.write_text(TINY_URDF, encoding="utf-8")
    return path


def configurations(xs, j1s, z=1.0):
    """(N, 8) free-flyer configurations of the tiny robot: base at (x, 0, z), upright, arm at j1."""
    q = np.zeros((len(xs), 8))
    q[:, 0] = xs
    q[:, 2] = z
    q[:, 6] = 1.0  # quaternion w
    q[:, 7] = j1s
    return q


def judge(urdf, q, fps=10.0, contacts=None, keypoints=None, limbs=None, ground=0.0, **kw):
    n = len(q)
    keys = np.zeros((n, 2, 3)) if keypoints is None else keypoints
    return jr.judge_clip(urdf, None, q, fps, keys, [], contacts or {}, ground, limbs or {}, **kw)


def test_a_frame_beyond_a_joint_limit_is_counted_and_one_inside_the_tolerance_is_not(tiny):
    q = configurations([0, 0, 0, 0], [0.0, 1.0 + 5e-7, 1.01, -0.2])
    verdict = judge(tiny, q, fps=1.0)  # slow frames: no velocity verdict in the way
    assert verdict["joint_limit_frames"] == 1
    assert verdict["joint_limit_worst"]["joint"] == "j1" and verdict["joint_limit_worst"]["frame"] == 2
    assert verdict["joint_limit_worst"]["beyond"] == pytest.approx(0.01)


def test_a_step_too_fast_for_the_urdf_velocity_is_counted_and_the_factor_scales_the_limit(tiny):
    # 1 rad/s at 10 fps allows 0.1 rad per frame: steps 0.05, 0.15, 0.05
    q = configurations([0, 0, 0, 0], [0.0, 0.05, 0.2, 0.25])
    verdict = judge(tiny, q)
    assert verdict["velocity_limit_frames"] == 1
    assert verdict["velocity_limit_worst"] == {"frame": 2, "joint": "j1", "ratio": pytest.approx(1.5)}
    assert judge(tiny, q, velocity_factor=2.0)["velocity_limit_frames"] == 0
    assert judge(tiny, q, velocity_factor=0.4)["velocity_limit_frames"] == 3


def test_the_base_steps_are_reported_and_judged_only_when_limits_are_given(tiny):
    q = configurations([0.0, 0.1, 0.2], [0, 0, 0])  # 0.1 m per frame at 10 fps: 1 m/s
    verdict = judge(tiny, q)
    assert verdict["velocity_limit_frames"] == 0
    assert verdict["base_steps"]["linear_step_m"]["mean"] == pytest.approx(0.1)
    assert judge(tiny, q, base_velocity_limits=(0.5, 1.0))["velocity_limit_frames"] == 2
    assert judge(tiny, q, base_velocity_limits=(2.0, 1.0))["velocity_limit_frames"] == 0


def test_a_foot_sliding_5_mm_per_frame_in_contact_measures_5_and_swing_frames_do_not_count(tiny):
    xs = [0.0, 0.005, 0.010, 0.015, 0.5, 0.9]  # three 5 mm steps in contact, then big swing steps
    contact = np.array([True, True, True, True, False, True])  # the last step lands: off -> on is no slide
    verdict = judge(tiny, configurations(xs, [0] * 6), fps=1.0, contacts={"foot": contact})
    assert verdict["foot_skating_mm_mean"] == pytest.approx(5.0)
    assert verdict["feet"]["foot"]["skating_mm"]["n"] == 3
    assert verdict["feet"]["foot"]["contact_frames"] == 5


@settings(max_examples=20, deadline=None)
@given(slide_mm=st.floats(0.0, 50.0), direction=st.floats(0.0, 2 * np.pi))
def test_skating_is_the_horizontal_slide_in_any_direction_and_ignores_vertical_motion(tiny, slide_mm, direction):
    n = 4
    q = configurations([0] * n, [0] * n)
    steps = np.arange(n) * slide_mm * 1e-3
    q[:, 0], q[:, 1] = steps * np.cos(direction), steps * np.sin(direction)
    q[:, 2] = 1.0 + 0.01 * np.arange(n)  # rising does not count as skating
    verdict = judge(tiny, q, fps=1.0, contacts={"foot": np.ones(n, dtype=bool)})
    assert verdict["foot_skating_mm_mean"] == pytest.approx(slide_mm, abs=1e-6)


def test_ground_penetration_is_the_depth_of_the_foot_geometry_lowest_point(tiny):
    # base at z = 0.12: foot frame at 0.02, the sphere's bottom at -0.03 m: 30 mm below the floor at 0
    q = configurations([0, 0], [0, 0], z=0.12)
    verdict = judge(tiny, q, contacts={"foot": np.ones(2, dtype=bool)})
    assert verdict["ground_penetration_mm_max"] == pytest.approx(30.0)
    assert verdict["feet"]["foot"]["lowest_point"] == "collision geometry"
    assert judge(tiny, q, contacts={"foot": np.ones(2, dtype=bool)}, ground=-0.05)["ground_penetration_mm_max"] \
        == pytest.approx(0.0)
    # the tip has no geometry: its origin minus the given sole offset
    deep = judge(tiny, configurations([0], [0], z=0.0), contacts={"tip": np.ones(1, dtype=bool)},
                 sole_offsets={"tip": 1.2})
    assert deep["ground_penetration_mm_max"] == pytest.approx(200.0)


def test_a_limb_at_90_deg_measures_90_and_an_aligned_one_0_per_limb_and_per_group(tiny):
    n = 3
    keys = np.zeros((n, 3, 3))
    keys[:, 1] = [1.0, 0.0, 0.0]  # source limb 0 -> 1 along +x: the robot's arm (along +z) is 90 deg off
    keys[:, 2] = [0.0, 0.0, 2.0]  # source limb 0 -> 2 along +z: aligned
    limbs = {"arms": [("base", "tip", 0, 1)], "trunk": [("base", "tip", "a", "c")]}
    verdict = judge(tiny, configurations([0] * n, [0] * n), keypoints=keys, limbs=limbs, keypoint_names="abc")
    assert verdict["limbs"]["arms"]["mean_deg"] == pytest.approx(90.0)
    assert verdict["limbs"]["arms"]["limbs"]["base->tip"]["max"] == pytest.approx(90.0)
    assert verdict["limbs"]["trunk"]["mean_deg"] == pytest.approx(0.0, abs=1e-5)


def test_a_limb_left_behind_shows_in_its_groups_worst_limb(tiny):
    keys = np.zeros((2, 3, 3))
    keys[:, 1] = [0.0, 0.0, 1.0]
    keys[:, 2] = [0.0, 1.0, 0.0]
    limbs = {"legs": [("base", "tip", 0, 1)] * 3 + [("base", "tip", 0, 2)]}  # three aligned, one 90 deg off
    verdict = judge(tiny, configurations([0, 0], [0, 0]), keypoints=keys, limbs=limbs)
    assert verdict["limbs"]["legs"]["mean_deg"] == pytest.approx(22.5)
    assert verdict["limbs"]["legs"]["worst_limb_mean_deg"] == pytest.approx(90.0)


def test_tracking_is_the_distance_of_each_mapped_frame_to_its_keypoint(tiny):
    keys = np.zeros((1, 1, 3))
    keys[0, 0] = [0.0, 0.003, 2.0 + 0.004]  # the tip is at (0, 0, 2): 5 mm away
    verdict = jr.judge_clip(tiny, None, configurations([0], [0]), 30.0, keys, [("tip", 0)], {}, 0.0, {})
    assert verdict["tracking_mm"]["tip"]["mean"] == pytest.approx(5.0)


def test_bad_shapes_and_unknown_frames_are_refused(tiny):
    with pytest.raises(ValueError, match="nq=8"):
        judge(tiny, np.zeros((2, 7)))
    with pytest.raises(ValueError, match="no frame 'hand'"):
        judge(tiny, configurations([0], [0]), contacts={"hand": np.ones(1, dtype=bool)})
    with pytest.raises(ValueError, match="no keypoint_names"):
        judge(tiny, configurations([0], [0]), limbs={"arms": [("base", "tip", "a", "b")]})


@pytest.fixture(scope="module")
def g1_model():
    return jr.build_model(G1_URDF)


def test_g1_neutral_does_not_self_collide_and_an_arm_swung_into_the_torso_does(g1_model):
    q = np.tile(pin.neutral(g1_model), (3, 1))
    roll = g1_model.idx_qs[g1_model.getJointId("left_shoulder_roll_joint")]
    q[1, roll] = -1.0  # the left arm swung across the chest
    verdict = jr.judge_clip(G1_URDF, None, q, 1.0, np.zeros((3, 1, 3)), [], {}, 0.0, {})
    assert verdict["self_collision_frames"] == 1
    assert any("torso_link" in pair for pair in verdict["self_collision_pairs"])
    assert verdict["joint_limit_frames"] == 0


def test_srdf_disabled_pairs_are_not_checked(tmp_path):
    model = jr.build_model(G1_URDF)
    srdf = tmp_path / "g1.srdf"
    srdf.write_text('<robot name="g1"><disable_collisions link1="torso_link" link2="left_shoulder_roll_link" '
                    'reason="test"/></robot>', encoding="utf-8")
    full = len(jr.collision_model(model, G1_URDF).collisionPairs)
    assert len(jr.collision_model(model, G1_URDF, srdf).collisionPairs) == full - 1


def test_the_cli_reads_a_saved_case_and_prints_the_same_verdict(tiny, tmp_path, capsys):
    q = configurations([0, 0, 0, 0], [0.0, 0.05, 0.2, 1.5])
    case = dict(urdf_path=tiny, srdf_path=None, configurations=q, fps=10.0, keypoints=np.zeros((4, 2, 3)),
                mapping=[("tip", "b")], contacts={"foot": [True] * 4}, ground=0.0,
                limbs={"arms": [("base", "tip", "a", "b")]}, keypoint_names=["a", "b"])
    jr.save_case(tmp_path / "case.npz", **case)
    assert jr.main([str(tmp_path / "case.npz")]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed == json.loads(json.dumps(judge_clip_of(case)))
    assert printed["joint_limit_frames"] == 1 and printed["velocity_limit_frames"] == 2


def judge_clip_of(case):
    return jr.judge_clip(**{**case, "contacts": {k: np.array(v) for k, v in case["contacts"].items()}})


def test_the_bench_pelvis_orientation_is_the_identity_for_a_person_facing_x_and_turns_with_the_hips():
    import bench_retarget as br

    names = ["Hips", "LeftUpLeg", "RightUpLeg", "Spine1"]
    keys = np.array([[[0, 0, 1], [0, 0.1, 1], [0, -0.1, 1], [0.02, 0, 1.3]]], dtype=float)  # a slight lean
    R = br.pelvis_rotations(keys.copy(), names)[0]
    assert np.allclose(R.T @ R, np.eye(3)) and np.linalg.det(R) == pytest.approx(1.0)
    assert np.allclose(R[:, 1], [0, 1, 0]) and R[0, 0] > 0.99  # left along +y, facing +x
    turned = keys @ pin.utils.rpyToMatrix(0, 0, np.pi / 2).T  # the person turned to face +y
    assert np.allclose(br.pelvis_rotations(turned, names)[0], pin.utils.rpyToMatrix(0, 0, np.pi / 2) @ R)


def test_the_bench_scales_the_walk_so_its_stance_ankles_stand_at_the_robots_ankle_height():
    import bench_retarget as br

    case = br.prepare("walk", "g1")
    robot = br.robot_geometry("g1")
    assert 0.5 < case["scale"] < 1.0  # G1 (1.3 m) is shorter than the CMU subject
    ankles = [case["frames"].index(f) for f in ("left_ankle_roll_link", "right_ankle_roll_link")]
    stance = np.concatenate([case["targets"][case["contacts"][case["frames"][a]], a, 2] for a in ankles])
    assert np.median(stance) == pytest.approx(robot["ankle_height"], abs=0.015)


@pytest.mark.skipif(not Path("/work/peers-venv/bin/python").exists(), reason="needs the peers' venv (pink)")
def test_the_pink_baseline_follows_a_moving_target_within_its_velocity_limits_and_the_judge_agrees():
    import bench_retarget as br

    case = br.prepare("walk", "g1")
    n = 6
    model = jr.build_model(G1_URDF)
    data = model.createData()
    q0 = pin.neutral(model)
    q0[2] = 0.8
    pin.framesForwardKinematics(model, data, q0)
    still = np.array([data.oMf[model.getFrameId(f)].translation for f in case["frames"]])
    shift = np.zeros((n, 1, 3))
    shift[:, 0, 0] = 0.01 * np.arange(n)  # the whole body 10 mm further forward each frame, along x
    small = {**case, "targets": still[None] + shift, "q_init": q0, "motion": case["motion"].slice(0, n),
             "rotations": np.tile(np.eye(3), (n, 1, 1, 1))}
    run = br.run_pink("g1", small, steps=5)
    assert run["configurations"].shape == (n, model.nq) and run["failures"] == 0
    assert np.allclose(np.diff(run["configurations"][:, 0]), 0.01, atol=1e-3)  # the base follows
    keys = still[None] + shift  # the targets, keypoint k = mapped frame k
    verdict = jr.judge_clip(G1_URDF, None, run["configurations"], 30.0, keys,
                            [(f, k) for k, f in enumerate(case["frames"])], {}, 0.0, {})
    assert verdict["velocity_limit_frames"] == 0 and verdict["joint_limit_frames"] == 0
    assert verdict["tracking_mm_mean"] < 2.0
