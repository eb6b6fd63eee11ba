"""Whole-robot IK problems (scripts/goal_problems.py), their judge (scripts/judge_goals.py) and the pure helpers of
the pink/PlaCo side-runner (scripts/peers_runner.py; the peers themselves run in their own virtual environment,
exercised by the last test only where that environment exists)."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"
sys.path.insert(0, str(SCRIPTS))

import goal_problems as gp  # noqa: E402
import judge_goals as jg  # noqa: E402
import peers_runner as pr  # noqa: E402

PEERS_PYTHON = Path(os.environ.get("PEERS_VENV", "/work/peers-venv")) / "bin" / "python"


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Three problems of each robot that covers a case: go2 (free-flyer, clipped neutral), pr2 (continuous
    joints, a shared torso), allegro (positions only); written to JSON and read back as a solver would."""
    out = tmp_path_factory.mktemp("goals")
    loaded = {}
    for robot in ("go2", "pr2", "allegro"):
        path = out / f"{robot}.json"
        path.write_text(json.dumps(gp.make_problems(robot, 3, seed=7)), encoding="utf-8")
        loaded[robot] = gp.load_problems(path)
    return loaded


def _model(problems):
    return gp.model_of(problems)


def test_targets_are_the_forward_kinematics_of_the_stored_configuration(files):
    for problems in files.values():
        rows = jg.judge(problems, [p["q_generating"] for p in problems["problems"]])
        assert all(r["success"] and r["valid"] and r["within_limits"] for r in rows)
        assert max(r["max_position_m"] for r in rows) < 1e-12
        assert max(r["max_rotation_rad"] for r in rows) < 1e-12


def test_only_active_joints_are_drawn_and_they_stay_within_limits(files):
    for problems in files.values():
        model = _model(problems)
        lower, upper = gp.limits_of(problems)
        neutral = np.array(problems["neutral"])
        assert np.all(neutral >= lower) and np.all(neutral <= upper)
        for p in problems["problems"]:
            q = np.array(p["q_generating"])
            assert np.all(q >= lower) and np.all(q <= upper)
            for j in range(1, model.njoints):
                joint, name = model.joints[j], model.names[j]
                block = slice(joint.idx_q, joint.idx_q + joint.nq)
                if name not in problems["active_joints"]:
                    assert np.array_equal(q[block], neutral[block]), name
                elif joint.nq == 2:  # continuous: a unit (cos, sin) pair
                    assert abs(np.linalg.norm(q[block]) - 1.0) < 1e-12


def test_free_flyer_base_within_the_cube_and_thirty_degrees_of_upright(files):
    problems = files["go2"]
    assert problems["floating_base"] and problems["joint_names"][0] == "root_joint"
    neutral = np.array(problems["neutral"])
    for p in problems["problems"]:
        q = np.array(p["q_generating"])
        assert np.all(np.abs(q[:3] - neutral[:3]) <= gp.BASE_BOX_M / 2)
        tilt = np.linalg.norm(pin.log3(pin.Quaternion(q[3:7]).toRotationMatrix()))
        assert tilt <= np.radians(gp.BASE_TILT_DEG) + 1e-12


def test_file_says_the_goals_active_joints_and_clipped_neutral(files):
    go2, pr2, allegro = files["go2"], files["pr2"], files["allegro"]
    assert [g["kind"] for g in go2["goals"]] == ["pose"] + ["position"] * 4
    assert go2["neutral_clipped"] == ["FL_calf_joint", "FR_calf_joint", "RL_calf_joint", "RR_calf_joint"]
    assert len(go2["problems"][0]["goals"][1]["target"]) == 3
    assert np.array(go2["problems"][0]["goals"][0]["target"]).shape == (4, 4)
    assert pr2["active_joints"][0] == "torso_lift_joint" and len(pr2["active_joints"]) == 15
    assert not any("gripper" in n or "head" in n for n in pr2["active_joints"])
    assert len(allegro["active_joints"]) == 16 and not allegro["floating_base"]
    for problems in files.values():
        assert Path(problems["urdf"]).is_file() and problems["nq"] == len(problems["neutral"])


def test_continuous_and_free_flyer_coordinates_have_no_limits(files):
    pr2 = files["pr2"]
    model = _model(pr2)
    roll = model.joints[model.getJointId("l_forearm_roll_joint")]
    assert pr2["lower"][roll.idx_q] is None and pr2["upper"][roll.idx_q + 1] is None
    assert all(v is None for v in files["go2"]["lower"][:7])


def test_talos_goals_move_legs_torso_and_arms_but_not_head_or_grippers():
    model = gp.build_model(gp.example_robot_data_dir() / gp.ROBOT_SETS["talos"].urdf, True)
    names = [model.names[j] for j in gp.active_joint_ids(model, [f for f, _ in gp.ROBOT_SETS["talos"].goals])]
    assert names[0] == "root_joint" and len(names) == 29
    assert {"torso_1_joint", "torso_2_joint", "leg_left_6_joint", "arm_right_7_joint"} <= set(names)
    assert not any(n.startswith(("head", "gripper")) for n in names)


def test_unknown_robot_and_bad_count_are_named():
    with pytest.raises(KeyError, match="accepted: talos, baxter, go2, allegro, pr2"):
        gp.make_problems("atlas", 2, 0)
    with pytest.raises(ValueError, match="accepted: 1 or more"):
        gp.make_problems("allegro", 0, 0)


def test_bad_goals_are_named_by_index_and_frame():
    with pytest.raises(ValueError, match=r"goal 0 \('tip'\): kind 'axis'"):
        gp.parse_goals([{"frame": "tip", "kind": "axis", "target": [0, 0, 1]}])
    with pytest.raises(ValueError, match=r"goal 1 \('b', pose\): target of shape \(3,\)"):
        gp.parse_goals([{"frame": "a", "kind": "position", "target": [0, 0, 1]},
                        {"frame": "b", "kind": "pose", "target": [0, 0, 1]}])


# ------------------------------------------------------------------------------------------------ judge


def test_judge_measures_position_and_rotation_error_by_forward_kinematics(files):
    go2 = files["go2"]
    q = np.array(go2["problems"][0]["q_generating"])
    moved = q.copy()
    rotation = pin.Quaternion(q[3:7]).toRotationMatrix() @ pin.exp3(np.array([0.0, 0.0, 2e-6]))
    moved[3:7] = pin.Quaternion(rotation).coeffs()
    moved[0] += 3e-6
    row = jg.judge({**go2, "problems": go2["problems"][:1]}, [moved])[0]
    assert row["rotation_rad"][0] == pytest.approx(2e-6, rel=1e-6)  # the base frame is the root joint's
    assert row["position_m"][0] == pytest.approx(3e-6, rel=1e-6)
    assert row["rotation_rad"][1:] == [0.0] * 4  # position goals have no rotation error
    assert not row["success"] and row["within_limits"] and row["valid"]
    assert jg.solved_at([row], 1e-5).tolist() == [True]


def test_judge_fails_answers_out_of_limits_invalid_or_missing(files):
    pr2 = files["pr2"]
    model = _model(pr2)
    q = np.array(pr2["problems"][0]["q_generating"])
    lift = model.joints[model.getJointId("torso_lift_joint")].idx_q
    roll = model.joints[model.getJointId("l_wrist_roll_joint")].idx_q
    beyond = q.copy()
    beyond[lift] = pr2["upper"][lift] + 1e-6
    unnormalized = q.copy()
    unnormalized[roll:roll + 2] *= 1.001
    rows = jg.judge(pr2, [beyond, unnormalized, None])
    assert not rows[0]["within_limits"] and rows[0]["limit_violation"] == pytest.approx(1e-6, rel=1e-6)
    assert not rows[0]["success"]
    assert not rows[1]["valid"] and not rows[1]["success"]
    assert not rows[2]["answered"] and rows[2]["max_position_m"] == np.inf and not rows[2]["success"]
    wrong_length = jg.judge({**pr2, "problems": pr2["problems"][:1]}, [q[:-1]])[0]
    assert wrong_length["answered"] and not wrong_length["success"]


def test_judge_wants_one_answer_per_problem(files):
    with pytest.raises(ValueError, match="2 answers for 3 problems"):
        jg.judge(files["allegro"], [None, None])


def test_judge_table_of_a_results_file(files):
    allegro = files["allegro"]
    answers = [{"q": p["q_generating"], "wall_s": 0.001} for p in allegro["problems"][:2]]
    table = jg.judge_results(allegro, {"n_problems": 2, "peers": {"oracle": {"answers": answers}}})
    assert "allegro (2 problems)" in table
    assert table.splitlines()[-1].split()[:4] == ["oracle", "100.0%", "100.0%", "100.0%"]


# ---------------------------------------------------------------------------------------- runner helpers


def test_placo_gets_a_kinematic_urdf_with_continuous_joints_made_unlimited_revolute(files):
    text = pr._kinematic_urdf(files["pr2"]["urdf"], continuous_as_revolute=True)
    assert "<visual" not in text and "<collision" not in text and 'type="continuous"' not in text
    model = pin.buildModelFromXML(text)
    roll = model.getJointId("l_forearm_roll_joint")
    assert model.joints[roll].nq == 1
    assert model.lowerPositionLimit[model.joints[roll].idx_q] == model.upperPositionLimit[model.joints[roll].idx_q] == 0
    kept = pin.buildModelFromXML(pr._kinematic_urdf(files["pr2"]["urdf"], continuous_as_revolute=False))
    assert kept.nq == files["pr2"]["nq"]


def test_configurations_map_to_a_model_with_angles_for_continuous_joints_and_back(files):
    pr2 = files["pr2"]
    full = _model(pr2)
    other = pin.buildModelFromXML(pr._kinematic_urdf(pr2["urdf"], continuous_as_revolute=True),
                                  pin.JointModelFreeFlyer())
    maps = pr._joint_maps(full, other, pr2["joint_names"])
    q = np.array(pr2["problems"][1]["q_generating"])
    q_other = pr._from_full(pin.neutral(other), q, maps)
    assert q_other.shape == (other.nq,) and np.array_equal(q_other[:7], pin.neutral(other)[:7])
    assert np.allclose(pr._to_full(np.array(pr2["neutral"]), q_other, maps), q, atol=1e-15)


def test_runner_settings_are_checked_by_name():
    settings = pr._override(pr.PinkSettings(), ["damping=1e-6", "velocity_limit=1"])
    assert settings.damping == 1e-6 and settings.velocity_limit == 1
    with pytest.raises(ValueError, match="KEY one of position_weight"):
        pr._override(pr.PlacoSettings(), ["weight=2"])


@pytest.mark.skipif(not PEERS_PYTHON.is_file(), reason="no peers venv (scripts/peers_venv.sh)")
def test_peers_answer_every_problem_in_their_own_environment(files, tmp_path):
    problems_path = tmp_path / "allegro.json"
    problems_path.write_text(json.dumps(files["allegro"]), encoding="utf-8")
    out = tmp_path / "results.json"
    subprocess.run([str(PEERS_PYTHON), str(SCRIPTS / "peers_runner.py"), str(problems_path), "-o", str(out),
                    "--limit", "2", "--budget", "0.05"], check=True, capture_output=True, cwd=tmp_path)
    results = json.loads(out.read_text())
    assert set(results["peers"]) == {"pink", "placo"} and results["n_problems"] == 2
    for entry in results["peers"].values():
        assert len(entry["answers"]) == 2
        for answer in entry["answers"]:
            assert len(answer["q"]) == files["allegro"]["nq"] and answer["wall_s"] > 0
        rows = jg.judge({**files["allegro"], "problems": files["allegro"]["problems"][:2]},
                        [a["q"] for a in entry["answers"]])
        assert all(r["valid"] and r["within_limits"] for r in rows)
