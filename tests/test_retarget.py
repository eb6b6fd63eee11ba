"""retarget: the bundled CMU walk onto G1 and Talos, checked by forward kinematics and the collision meshes (not by
the clip's own report): joint and velocity limits, planted feet, limb directions, no self-collision, the source's
world kept; Clip files; bad input; the CLI."""

import csv
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import evoik_pin as ek
from evoik_pin.cli import main
from evoik_pin.errors import EvoikError, MappingError, OptionError, OutputError
from evoik_pin.motion import Clip, detect_contacts, limb_pairs, load_clip, mapping_preset
from evoik_pin.motion.retarget import BASE_ANGULAR_SPEED, BASE_LINEAR_SPEED, velocity_limits_of

#: Limb-direction bounds (deg, mean over frames and over the group's limbs) set from measured runs (G1: legs 2.3,
#: trunk 1.2, arms 3.0; Talos: legs 4.4, trunk 7.0, arms 12.7) with room for solver noise. Talos's are wider for
#: reasons of its body, not of the method: its waist turns and pitches but has no roll (a sideways lean of the
#: person cannot be followed), and its hips are so wide that arms hanging as a person's do would pass through them:
#: the collision-free frames hold its arms off the hips.
ANGLE_BOUNDS = {"g1": {"legs": 5.0, "trunk": 4.0, "arms": 6.0}, "talos": {"legs": 7.0, "trunk": 10.0, "arms": 16.0}}
#: Slack of the limit checks (rad, m): float rounding of the box arithmetic.
EPS = 1e-9


@pytest.fixture(scope="module")
def walk():
    return load_clip("walk").slice(0, 30)


@pytest.fixture(scope="module", params=["g1", "talos"])
def retargeted(request, walk):
    robot = ek.load_robot(request.param, floating_base=True)
    return robot, ek.retarget(robot, walk)


def _frame_positions(robot, Q, frame):
    return np.array([robot.fk(q, frame).translation for q in Q])


def test_every_frame_within_the_joint_bounds(retargeted):
    robot, clip = retargeted
    assert clip.q.shape == (30, robot.n) and np.isfinite(clip.q).all()
    joints = clip.q[:, 6:]
    assert (joints >= robot.lower[6:] - EPS).all() and (joints <= robot.upper[6:] + EPS).all()
    assert clip.report["joint_limit_frames"] == []


def test_steps_within_the_velocity_limits(retargeted, walk):
    robot, clip = retargeted
    v_max = velocity_limits_of(robot, True)
    assert np.isfinite(v_max).all()  # every joint of these URDFs has a limit, the base has its defaults
    steps = np.abs(np.diff(clip.q, axis=0))
    assert (steps <= v_max / walk.fps + EPS).all()
    assert clip.report["velocity_limit_frames"] == []


def test_feet_in_contact_stay_planted(retargeted, walk):
    """A robot foot moves less than 2 mm between two frames in which the source foot is in contact."""
    robot, clip = retargeted
    frame_of = {keypoint: frame for frame, keypoint in mapping_preset("cmu", robot.name).items()}
    contacts = detect_contacts(walk)
    assert all(flags.sum() >= 5 for flags in contacts.values())  # the walk has stance phases to check
    for keypoint, flags in contacts.items():
        p = _frame_positions(robot, clip.q, frame_of[keypoint])
        both = flags[1:] & flags[:-1]
        moves = np.linalg.norm(np.diff(p, axis=0), axis=1)[both]
        assert moves.max() < 2e-3, f"{frame_of[keypoint]} slides {moves.max() * 1e3:.2f} mm in a frame"


def test_limb_directions_follow_the_source(retargeted, walk):
    """Angle between each robot limb (mapped frame to mapped frame) and the source's (keypoint to keypoint), mean
    over the frames and the group's limbs, below :data:`ANGLE_BOUNDS`."""
    robot, clip = retargeted
    frame_of = {keypoint: frame for frame, keypoint in mapping_preset("cmu", robot.name).items()}
    for group, limbs in limb_pairs("cmu").items():
        angles = []
        for a, b in limbs:
            u = _frame_positions(robot, clip.q, frame_of[b]) - _frame_positions(robot, clip.q, frame_of[a])
            v = walk.trajectory(b) - walk.trajectory(a)
            cos = np.einsum("ij,ij->i", u, v) / np.linalg.norm(u, axis=1) / np.linalg.norm(v, axis=1)
            angles.append(np.degrees(np.arccos(np.clip(cos, -1, 1))))
        mean = float(np.mean(angles))
        assert mean < ANGLE_BOUNDS[robot.name][group], f"{robot.name} {group}: {mean:.2f} deg"


def test_no_frame_in_self_collision(retargeted):
    robot, clip = retargeted
    scene = ek.Scene(robot, self_collision=True)
    assert [i for i, q in enumerate(clip.q) if scene.in_collision(q)] == []


def test_the_clip_stays_in_the_source_world(retargeted, walk):
    """The robot walks where the person walks (scaled), facing the same way: no global turn."""
    robot, clip = retargeted
    src = walk.trajectory("Hips")[:, :2]
    root = clip.q[:, :2]
    d_src, d_robot = src[-1] - src[0], root[-1] - root[0]
    cos = d_src @ d_robot / np.linalg.norm(d_src) / np.linalg.norm(d_robot)
    assert cos > np.cos(np.radians(10))
    assert np.linalg.norm(d_robot) == pytest.approx(clip.report["scale"] * np.linalg.norm(d_src), rel=0.2)
    # facing: the robot's left (its base y axis, yaw) matches the source's hips, left minus right
    left = walk.trajectory("LeftUpLeg") - walk.trajectory("RightUpLeg")
    yaw_src = np.arctan2(left[:, 1], left[:, 0]) - np.pi / 2
    turn = np.angle(np.exp(1j * (clip.q[:, 3] - yaw_src)))
    assert np.abs(turn).max() < np.radians(15)


def test_configurations_are_pinocchio_free_flyer_rows(retargeted):
    robot, clip = retargeted
    assert clip.configurations.shape == (30, robot.full_model.nq)
    np.testing.assert_allclose(clip.configurations[7], robot.full_configuration(clip.q[7]))
    np.testing.assert_allclose(np.linalg.norm(clip.root_rot, axis=1), 1.0)
    assert len(clip.joint_names) == robot.full_model.nq - 7 and clip.fps == 30.0


def test_save_round_trips(retargeted, tmp_path):
    robot, clip = retargeted
    data = np.load(clip.save(tmp_path / "c.npz"))
    np.testing.assert_array_equal(data["q"], clip.q)
    np.testing.assert_array_equal(data["configurations"], clip.configurations)
    assert float(data["fps"]) == 30.0 and tuple(data["joint_names"]) == clip.joint_names
    with open(clip.save(tmp_path / "c.csv"), newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0][:7] == ["root_x", "root_y", "root_z", "root_qx", "root_qy", "root_qz", "root_qw"]
    assert tuple(rows[0][7:]) == clip.joint_names
    np.testing.assert_array_equal(np.array(rows[1:], dtype=float), clip.configurations)  # repr: exact floats
    with open(clip.save(tmp_path / "c.pkl"), "rb") as f:
        gmr = pickle.load(f)
    assert gmr["fps"] == 30.0
    np.testing.assert_array_equal(gmr["root_pos"], clip.configurations[:, :3])
    np.testing.assert_array_equal(gmr["root_rot"], clip.configurations[:, 3:7])
    np.testing.assert_array_equal(gmr["dof_pos"], clip.configurations[:, 7:])
    with pytest.raises(OutputError, match=r"\.npz, \.csv, \.pkl"):
        clip.save(tmp_path / "c.json")


@settings(max_examples=20, deadline=None)
@given(st.floats(0.01, 10.0))
def test_velocity_limit_factor_scales_the_urdf_limits(factor):
    robot = _talos()
    np.testing.assert_allclose(velocity_limits_of(robot, factor), factor * velocity_limits_of(robot, True))


def _talos():
    if not hasattr(_talos, "robot"):
        _talos.robot = ek.load_robot("talos", floating_base=True)
    return _talos.robot


def test_velocity_limits_read_the_urdf_and_the_base_defaults():
    robot = _talos()
    v = velocity_limits_of(robot, True)
    assert (v[:3] == BASE_LINEAR_SPEED).all() and (v[3:6] == BASE_ANGULAR_SPEED).all()
    k = robot.joint_names.index("leg_left_1_joint")
    model = robot.model
    assert v[k] == model.velocityLimit[model.joints[model.getJointId("leg_left_1_joint")].idx_v]
    assert np.isinf(velocity_limits_of(robot, False)).all()
    np.testing.assert_array_equal(velocity_limits_of(robot, np.full(robot.n, 3.0)), 3.0)


def test_unlimited_steps_are_larger(walk):
    """Without velocity limits the first frames' steps exceed the limited box somewhere: the limits bind."""
    robot = ek.load_robot("g1", floating_base=True)
    short = walk.slice(0, 4)
    free = ek.retarget(robot, short, velocity_limits=False, self_collision=False)
    tight = ek.retarget(robot, short, velocity_limits=0.05, self_collision=False)
    v = velocity_limits_of(robot, 0.05)
    assert (np.abs(np.diff(tight.q, axis=0)) <= v / short.fps + EPS).all()
    assert (np.abs(np.diff(free.q, axis=0)) > v / short.fps + EPS).any()


@pytest.mark.parametrize("option, value, match", [
    ("scale", "big", "scale"), ("scale", -1.0, "scale"), ("ground", "floor", "ground"),
    ("contacts", "yes", "contacts"), ("velocity_limits", "fast", "velocity_limits"),
    ("velocity_limits", [1.0, 2.0], "velocity_limits"), ("timeout", 0.0, "timeout"),
    ("self_collision", "yes", "self_collision"),
])
def test_unknown_option_values_are_refused(walk, option, value, match):
    robot = _talos()
    with pytest.raises(OptionError, match=match):
        ek.retarget(robot, walk.slice(0, 2), **{option: value})


def test_bad_mappings_and_robots_are_refused(walk):
    robot = _talos()
    with pytest.raises(MappingError, match="leg_left_9_link"):
        ek.retarget(robot, walk, mapping={"base_link": "Hips", "leg_left_9_link": "LeftFoot"})
    with pytest.raises(MappingError, match="closest"):
        ek.retarget(robot, walk, mapping={"base_link": "Hipps"})
    with pytest.raises(MappingError, match="pelvis keypoint"):
        ek.retarget(robot, walk, mapping={"arm_left_7_link": "LeftHand"})
    with pytest.raises(MappingError, match="floating_base=True"):
        ek.retarget(ek.load_robot("talos"), walk)
    with pytest.raises(OptionError, match="Motion"):
        ek.retarget(robot, walk.positions)
    with pytest.raises(OptionError, match="bool array"):
        ek.retarget(robot, walk, contacts={"leg_left_6_link": np.ones(3, dtype=bool)})


def test_cli_writes_the_clip(tmp_path, capsys):
    out = tmp_path / "walk.npz"
    assert main(["retarget", "walk", "--robot", "g1", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "self-collision frames 0" in text and f"wrote {out}" in text
    data = np.load(out)
    assert data["configurations"].shape == (load_clip("walk").frames, 36)
    assert main(["retarget", "walk", "--robot", "g1", "--out", str(tmp_path / "walk.txt")]) == 2
    assert "accepted file types" in capsys.readouterr().err


def test_cli_names_the_bundled_clips_for_a_name_that_is_neither(tmp_path, capsys):
    assert main(["retarget", "wlak", "--robot", "g1", "--out", str(tmp_path / "walk.npz")]) == 2
    err = capsys.readouterr().err
    assert "'wlak' is neither a BVH file nor a bundled clip" in err and "walk" in err and "jump" in err
    assert not (tmp_path / "walk.npz").exists()


def test_clip_is_exported_from_the_package():
    assert ek.retarget is ek.motion.retarget and Clip.__module__ == "evoik_pin.motion.clip"


def test_same_seed_same_clip(walk):
    robot = ek.load_robot("g1", floating_base=True)
    short = walk.slice(0, 6)
    np.testing.assert_array_equal(ek.retarget(robot, short, seed=3).q, ek.retarget(robot, short, seed=3).q)


def test_given_contacts_hold_a_foot_without_a_floor(walk):
    """contacts={frame: flags} and ground=None: the flagged foot (the source's stance foot) does not slide."""
    robot = ek.load_robot("g1", floating_base=True)
    short = walk.slice(0, 8)
    flags = detect_contacts(short)["RightFoot"]
    assert flags.sum() >= 6
    clip = ek.retarget(robot, short, contacts={"right_ankle_roll_link": flags}, ground=None, self_collision=False)
    p = _frame_positions(robot, clip.q, "right_ankle_roll_link")[flags]
    assert np.linalg.norm(p - p[0], axis=1).max() < 2e-3
    assert clip.report["ground_penetration_mm"] == 0.0  # no floor: nothing to measure against


def test_html_plays_the_robot_and_the_source_keypoints(walk, tmp_path):
    from evoik_pin.viz import html_commands, save_clip_html

    robot = ek.load_robot("g1", floating_base=True)
    clip = ek.retarget(robot, walk.slice(0, 3), self_collision=False)
    commands = html_commands(save_clip_html(robot, clip, tmp_path / "clip.html").read_text())
    spheres = {c["path"] for c in commands if c["type"] == "set_object" and "/keypoints/" in c["path"]}
    assert spheres == {f"/meshcat/keypoints/{name}" for name in walk.names}
    (animation,) = [c for c in commands if c["type"] == "set_animation"]
    keyed = {a["path"] for a in animation["animations"]}
    assert "/meshcat/keypoints/Hips" in keyed and any(p.startswith("/meshcat/robot") for p in keyed)


@pytest.fixture(scope="module")
def g1_checks():
    from evoik_pin.motion.retarget import self_collision_check, self_collision_scene

    robot = ek.load_robot("g1", floating_base=True)
    return robot, self_collision_scene(robot), self_collision_check(robot)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), spread=st.sampled_from([0.3, 1.0, 3.0]))
def test_broad_phase_check_gives_the_scene_verdict(g1_checks, seed, spread):
    """The retargeter's self-collision check (bounding boxes, hulls, then meshes) says what the scene's exact check
    over every pair says, on configurations from the neutral pose to anywhere in the bounds (many colliding)."""
    robot, scene, check = g1_checks
    rng = np.random.default_rng(seed)
    lower, upper = np.maximum(robot.lower, -np.pi), np.minimum(robot.upper, np.pi)
    q = np.clip(rng.normal(0.0, spread, robot.n), lower, upper)
    assert check.in_collision(q) == scene.in_collision(q)


def test_broad_phase_check_sees_both_verdicts(g1_checks):
    """The drawn configurations hold colliding and free ones (the test above compares both kinds)."""
    robot, scene, check = g1_checks
    rng = np.random.default_rng(0)
    Q = np.clip(rng.normal(0.0, 1.0, (40, robot.n)), robot.lower, robot.upper)
    verdicts = [check.in_collision(q) for q in Q]
    assert verdicts == [scene.in_collision(q) for q in Q]
    assert any(verdicts) and not all(verdicts)


def test_report_gives_the_set_up_and_the_first_frame_apart(retargeted):
    """Set-up (s), first frame (s) and the warm-started rate are reported apart; fps (frames over the loop's time)
    agrees with them: N / fps = first frame + (N - 1) / steady fps."""
    _, clip = retargeted
    report = clip.report
    assert report["setup_s"] > 0 and report["first_frame_s"] > 0 and report["steady_fps"] > 0
    n = len(clip.q)
    assert n / report["fps"] == pytest.approx(report["first_frame_s"] + (n - 1) / report["steady_fps"], rel=1e-9)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_broad_phase_colliding_pairs_are_the_scene_ones(g1_checks, seed):
    robot, scene, check = g1_checks
    q = np.clip(np.random.default_rng(seed).normal(0.0, 1.0, robot.n), robot.lower, robot.upper)
    assert check.colliding_pairs(q) == scene.colliding_pairs(q)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), most=st.integers(1, 6))
def test_the_first_colliding_pairs_are_the_scene_ones(g1_checks, seed, most):
    """``most``: the narrow phase stops at the most-th pair found, the same pairs as the whole list's first ones."""
    robot, scene, check = g1_checks
    q = np.clip(np.random.default_rng(seed).normal(0.0, 1.0, robot.n), robot.lower, robot.upper)
    first = scene.colliding_pairs(q)[:most]
    assert check.colliding_pairs(q, most=most) == first == scene.colliding_pairs(q, most=most)


def test_broad_phase_finds_a_contact_the_hulls_alone_miss(g1_checks):
    """At this configuration the left knee's mesh is 70 um into the left shoulder roll link's while their Qhull hulls
    are apart: the hull filter's margin keeps the pair, and the verdict is the scene's."""
    robot, scene, check = g1_checks
    q = np.clip(np.random.default_rng(27).normal(0.0, 3.0, robot.n), np.maximum(robot.lower, -np.pi),
                np.minimum(robot.upper, np.pi))
    pairs = check.colliding_pairs(q)
    assert ("left_knee_link", "left_shoulder_roll_link") in pairs
    assert pairs == scene.colliding_pairs(q)


@pytest.fixture(scope="module")
def walk_stacks(walk):
    """G1, the walk's plan and its FrameStacks (the per-frame targets written into goal stacks bound once)."""
    from evoik_pin.motion.frame_stacks import FrameStacks
    from evoik_pin.motion.retarget import FLOOR_BAND, _frame_goals, _Plan

    robot = ek.load_robot("g1", floating_base=True)
    plan = _Plan(robot, walk, "cmu", "auto", "auto", "auto")
    return robot, plan, FrameStacks(robot, plan, lambda *a, **k: _frame_goals(plan, *a, **k), FLOOR_BAND)


def _feet_cases(robot, plan, i, rng):
    """(holds, clearance, level) of frame i: each foot held at a random point where the source is in contact."""
    holds = {f: rng.normal(0.0, 0.5, 3) for f, flags in plan.contacts.items() if flags[i]}
    clearance = {f: plan.sole[f] + rng.uniform(0.0, 0.02) for f in plan.contacts}
    rotations = [robot.fk(rng.uniform(robot.lower, robot.upper) * 0.3, f).rotation for f in plan.contacts]
    return holds, clearance, dict(zip(plan.contacts, rotations, strict=True))


def test_frame_stack_targets_are_those_of_the_goal_list(walk_stacks):
    """The targets FrameStacks writes per frame (computed for every frame at once, the feet's per frame) are the
    goal list's own (_frame_goals, bound), in its order, for every frame and contact state."""
    from evoik_pin.goals.stack import bind
    from evoik_pin.motion.retarget import _frame_goals

    robot, plan, stacks = walk_stacks
    rng = np.random.default_rng(0)
    structures = set()
    for i in range(plan.points.shape[0]):
        holds, clearance, level = _feet_cases(robot, plan, i, rng)
        _, stack, pt, Rt = bind(robot, _frame_goals(plan, i, holds, clearance=clearance, level=level))
        mine, mine_R = np.full_like(pt, np.nan), np.broadcast_to(np.eye(3), Rt.shape).copy()
        stacks.targets(i, holds, clearance, level, mine, mine_R)
        assert np.allclose(mine, pt, rtol=0, atol=1e-12) and np.allclose(mine_R, Rt, rtol=0, atol=1e-12), i
        structures.add(tuple(stack.kinds) + (len(holds),))
    assert len(structures) >= 2  # frames with one and with two feet held were compared


def test_frame_stack_solve_is_the_solvers_run(walk_stacks):
    """A frame's run on its bound stack gives the answer evoik_pin.solve gives for the same goal list, start and box
    with the retargeter's per-frame options (one LM run from q0), and the same verdict."""
    from evoik_pin.motion.retarget import FRAME_OPTIONS, TOLERANCES, WEIGHTS, _frame_goals, _initial_q

    robot, plan, stacks = walk_stacks
    rng = np.random.default_rng(1)
    q_prev = _initial_q(robot, plan)
    for i in (3, 12, 21):
        holds, clearance, level = _feet_cases(robot, plan, i, rng)
        for f in holds:  # reachable holds: where the foot is at a nearby configuration
            holds[f] = np.array(robot.fk(q_prev, f).translation)
        lower, upper = np.maximum(q_prev - 0.1, robot.lower), np.minimum(q_prev + 0.1, robot.upper)
        lower[:6], upper[:6] = q_prev[:6] - 0.05, q_prev[:6] + 0.05
        assert stacks.usable(lower, upper)
        out = stacks.solve(i, holds, clearance, level, TOLERANCES, WEIGHTS["contact"], q_prev, lower, upper)
        goals = _frame_goals(plan, i, holds, clearance=clearance, level=level)
        ref = ek.solve(robot, goals, seed=0, q0=q_prev, bounds=(lower, upper), timeout=None, **FRAME_OPTIONS)
        assert np.allclose(out.q, ref.q, rtol=0, atol=1e-9), i
        assert out.success == ref.success
        for (p, r), (p_ref, r_ref) in zip(out.goal_errors, ref.goal_errors, strict=True):
            assert (p is None) == (p_ref is None) and (r is None) == (r_ref is None)
            assert abs((p or 0.0) - (p_ref or 0.0)) < 1e-9 and abs((r or 0.0) - (r_ref or 0.0)) < 1e-9
        q_prev = out.q


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_touching_pair_is_one_of_the_scene_pairs(g1_checks, seed):
    """touching_pair is one of the scene's colliding pairs (None when free), before and after in_collision."""
    robot, scene, check = g1_checks
    q = np.clip(np.random.default_rng(seed).normal(0.0, 1.0, robot.n), robot.lower, robot.upper)
    pairs = scene.colliding_pairs(q)
    found = check.touching_pair(q)
    assert (found in pairs) if pairs else found is None
    assert check.in_collision(q) == bool(pairs) and check.touching_pair(q) == found


def test_surely_free_is_never_wrong(g1_checks):
    """surely_free (the hulls of the pairs the given joints move, the exact verdict for the others) says True only
    where the scene finds no contact, and it does say True (as well as False) on these configurations."""
    robot, scene, check = g1_checks
    rng = np.random.default_rng(3)
    arm = np.array(["right_shoulder" in n or "right_elbow" in n or "right_wrist" in n for n in robot.joint_names])
    said = []
    for spread in (0.2, 0.5, 1.0):
        for q in np.clip(rng.normal(0.0, spread, (20, robot.n)), robot.lower, robot.upper):
            for moving in (None, arm):
                said.append(check.surely_free(q, moving))
                if said[-1]:
                    assert not scene.in_collision(q)
    assert any(said) and not all(said)


def test_kept_pair_verdicts_follow_a_bisection(g1_checks):
    """Along segments where only one arm's joints move (a collision step's bisection: the other links' pair verdicts
    are reused by placement, the last contacts tried first) every verdict is still the scene's."""
    robot, scene, check = g1_checks
    rng = np.random.default_rng(5)
    arm = np.array(["right_shoulder" in n or "right_elbow" in n or "right_wrist" in n for n in robot.joint_names])
    assert arm.any()
    verdicts = []
    for _ in range(6):
        q_to = np.clip(rng.normal(0.0, 0.8, robot.n), robot.lower, robot.upper)
        q_from = np.clip(q_to + np.where(arm, rng.normal(0.0, 1.0, robot.n), 0.0), robot.lower, robot.upper)
        for t in np.linspace(0.0, 1.0, 9):
            q = np.where(arm, q_from + t * (q_to - q_from), q_to)
            verdicts.append(check.in_collision(q))
            assert verdicts[-1] == scene.in_collision(q)
    assert any(verdicts) and not all(verdicts)


def test_a_configuration_surely_free_is_then_a_look_up(g1_checks, monkeypatch):
    """A configuration surely_free calls free is remembered free (True is exact): in_collision then tells it without a
    narrow phase, and says what the scene says."""
    robot, scene, check = g1_checks
    rng = np.random.default_rng(11)
    free = [q for q in np.clip(rng.normal(0.0, 0.3, (40, robot.n)), robot.lower, robot.upper)
            if check.surely_free(q)]
    assert free
    assert not any(scene.in_collision(q) for q in free)

    def no_narrow_phase(k):
        raise AssertionError("narrow phase of a configuration known free")

    monkeypatch.setattr(check, "_touching", no_narrow_phase)
    assert not any(check.in_collision(q) for q in free)


def test_candidate_pairs_of_the_same_configuration_again(g1_checks):
    """candidate_pairs of the configuration last placed gives its pairs again (not placed twice); another
    configuration gets its own; a configuration refused is refused every time."""
    robot, _, check = g1_checks
    rng = np.random.default_rng(12)
    q1, q2 = np.clip(rng.normal(0.0, 0.8, (2, robot.n)), robot.lower, robot.upper)
    first = check.candidate_pairs(q1).copy()
    assert np.array_equal(check.candidate_pairs(q1.copy()), first)
    second = check.candidate_pairs(q2).copy()
    assert not np.array_equal(second, first)
    assert np.array_equal(check.candidate_pairs(q1), first)
    bad = q1.copy()
    bad[0] = np.inf  # equal to itself: a refused configuration taken for placed would be answered the second time
    for _ in range(2):
        with pytest.raises(EvoikError):
            check.candidate_pairs(bad)

