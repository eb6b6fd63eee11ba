"""solve_trajectory(dt=, velocity_limits=): every answer within v_max dt of the one before (no flip, no jump), the
reachable points solved, unreachable ones answered inside the box with success=False, scenes holding, bad options
refused."""

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from velocity_paths import pose_goals, smooth_path, steps_within

import evoik_pin as ek
from evoik_pin.errors import OptionError
from evoik_pin.goals import Position
from evoik_pin.robot.velocity_limits import (
    DEFAULT_BASE_ANGULAR_SPEED,
    DEFAULT_BASE_LINEAR_SPEED,
    urdf_velocity_limits,
    velocity_limits,
)
from evoik_pin.scene import Scene

DT = 0.01  # s


@pytest.fixture(scope="module")
def panda():
    return ek.load_robot("panda")


@pytest.fixture(scope="module")
def talos_floating():
    return ek.load_robot("talos", floating_base=True)


def _poses(robot, Q):
    return [robot.fk(q) for q in Q]


def _jumped(T, start: int, stop: int, by=(0.5, 0.0, 0.0)):
    """The targets with those of [start, stop) moved by ``by`` (m): out of reach of any box."""
    T = list(T)
    for i in range(start, stop):
        T[i] = pin.SE3(T[i].rotation, T[i].translation + np.asarray(by))
    return T


def test_panda_smooth_path_every_point_solved_within_the_box(panda):
    Q = smooth_path(panda, 150, DT, seed=0)
    results = ek.solve_trajectory(panda, _poses(panda, Q), dt=DT, velocity_limits=True, q0=Q[0], seed=0)
    assert all(r.success for r in results)
    answers = np.array([r.q for r in results])
    assert steps_within(answers, urdf_velocity_limits(panda) * DT, Q[0]).all()
    # no flip: the answers stay near the path they were made from (a branch flip moves joints by radians)
    assert np.abs(answers - Q).max() < 0.5


@settings(max_examples=12, deadline=None)
@given(seed=st.integers(0, 10_000), fraction=st.floats(0.2, 3.0), factor=st.floats(0.2, 2.0))
def test_every_answer_inside_the_box_whatever_the_path(panda, seed, fraction, factor):
    """Paths up to 3x faster than the limits (the targets run away): the answers never leave the box."""
    Q = smooth_path(panda, 40, DT, seed=seed, fraction=fraction)
    results = ek.solve_trajectory(panda, _poses(panda, Q), dt=DT, velocity_limits=factor, q0=Q[0], seed=seed)
    answers = np.array([r.q for r in results])
    assert steps_within(answers, factor * urdf_velocity_limits(panda) * DT, Q[0]).all()
    assert all(panda.within_bounds(q) for q in answers)
    for r, T in zip(results, _poses(panda, Q), strict=True):  # the reported errors are the answer's own
        assert r.position_error == pytest.approx(np.linalg.norm(panda.fk(r.q).translation - T.translation),
                                                 abs=1e-9)
        assert r.success == (r.position_error <= 1e-6 and r.orientation_error <= 1e-6)


def test_an_infeasible_stretch_gives_failures_inside_the_box_then_recovers(panda):
    Q = smooth_path(panda, 130, DT, seed=1)
    T = _jumped(_poses(panda, Q), 30, 45)
    results = ek.solve_trajectory(panda, T, dt=DT, velocity_limits=True, q0=Q[0], seed=0)
    answers = np.array([r.q for r in results])
    assert steps_within(answers, urdf_velocity_limits(panda) * DT, Q[0]).all()
    assert all(r.success for r in results[:30])
    for r in results[30:45]:  # 0.5 m away: out of every box, the closest answer inside it
        assert not r.success and r.position_error > 0.1 and "velocity box" in r.message
    assert all(r.success for r in results[-20:])  # back on the path


def test_a_full_turn_joint_moves_in_unwrapped_values(panda):
    """With joint 1 bounded to [-pi, pi] (a full turn: it wraps), a path crossing pi keeps going past it."""
    lower, upper = panda.lower.copy(), panda.upper.copy()
    lower[0], upper[0] = -np.pi, np.pi
    q = np.array([3.0, -0.3, 0.0, -2.0, 0.0, 1.6, 0.8])
    Q = np.array([q + [k * 0.01, 0, 0, 0, 0, 0, 0] for k in range(30)])  # 1 rad/s on joint 1, through pi
    locked = {f"panda_joint{j}": float(q[j - 1]) for j in range(2, 8)}  # joint 1 alone moves the tip
    results = ek.solve_trajectory(panda, _poses(panda, Q), dt=DT, velocity_limits=True, q0=Q[0], seed=0,
                                  bounds=(lower, upper), locked=locked)
    answers = np.array([r.q for r in results])
    assert all(r.success for r in results)
    assert steps_within(answers, urdf_velocity_limits(panda) * DT, Q[0]).all()
    assert answers[-1, 0] == pytest.approx(Q[-1, 0])  # unwrapped past pi, not a 2 pi jump back to -pi


def test_the_first_point_is_free_without_q0(panda):
    Q = smooth_path(panda, 20, DT, seed=2)
    T = _poses(panda, Q)
    results = ek.solve_trajectory(panda, T, dt=DT, velocity_limits=True, seed=3)
    assert results[0].success and results[0].method == "memetic"
    answers = np.array([r.q for r in results])
    assert steps_within(answers[1:], urdf_velocity_limits(panda) * DT, answers[0]).all()


def test_talos_floating_base_four_goals(talos_floating):
    talos = talos_floating
    Q = smooth_path(talos, 60, DT, seed=4)
    results = ek.solve_trajectory(talos, pose_goals(talos, Q), dt=DT, velocity_limits=True, q0=Q[0], seed=0)
    assert all(r.success for r in results)
    assert all(len(r.goal_errors) == 4 for r in results)
    answers = np.array([r.q for r in results])
    assert steps_within(answers, urdf_velocity_limits(talos) * DT, Q[0]).all()


def test_floating_base_limits_linear_and_angular(talos_floating):
    limits = urdf_velocity_limits(talos_floating)
    assert np.array_equal(limits[:3], [DEFAULT_BASE_LINEAR_SPEED] * 3)
    assert np.array_equal(limits[3:6], [DEFAULT_BASE_ANGULAR_SPEED] * 3)
    assert np.array_equal(limits[6:], talos_floating.model.velocityLimit[6:])  # the URDF's for the joints
    # a base target far away: the base moves at most its linear limit per step
    q0 = np.zeros(talos_floating.n)
    goals = [[Position("base_link", [0.5, 0.0, 0.0])]] * 5
    results = ek.solve_trajectory(talos_floating, goals, dt=DT, velocity_limits=True, q0=q0, seed=0)
    assert not results[-1].success
    assert results[-1].q[0] == pytest.approx(5 * DEFAULT_BASE_LINEAR_SPEED * DT)


def test_talos_arm_never_passes_through_the_torso():
    """A right-hand target sweeping behind the body: with the self-collision scene the arm stops at the torso (every
    answer collision-free, the blocked points success=False); without it the answers go through."""
    talos = ek.load_robot("talos")
    scene = Scene(talos)
    hands = {"arm_left_7_link": [0.2363, 0.446, 0.2557], "arm_right_7_link": [0.6543, -0.1669, 0.1208]}
    q0 = ek.solve(talos, [Position(f, p) for f, p in hands.items()], seed=0, scene=scene).q
    assert not scene.in_collision(q0, 0.0)
    a, b = np.array(hands["arm_right_7_link"]), np.array([-0.2, 0.1, 0.1208])
    targets = [[Position("arm_right_7_link", a + (k / 59) * (b - a)),
                Position("arm_left_7_link", hands["arm_left_7_link"])] for k in range(60)]
    results = ek.solve_trajectory(talos, targets, dt=0.02, velocity_limits=True, q0=q0, scene=scene, seed=0)
    assert not any(scene.in_collision(r.q, 0.0) for r in results)
    assert all(r.collision_free for r in results)
    assert results[0].success and not results[-1].success
    answers = np.array([r.q for r in results])
    assert steps_within(answers, urdf_velocity_limits(talos) * 0.02, q0).all()
    unguarded = ek.solve_trajectory(talos, targets, dt=0.02, velocity_limits=True, q0=q0, seed=0)
    assert any(scene.in_collision(r.q, 0.0) for r in unguarded)  # the scene is what held the arm back


def test_same_seed_same_answers(panda):
    Q = smooth_path(panda, 60, DT, seed=5)
    T = _jumped(_poses(panda, Q), 20, 30)  # failing points draw extra starts from the generator
    one = ek.solve_trajectory(panda, T, dt=DT, velocity_limits=0.5, q0=Q[0], seed=7)
    two = ek.solve_trajectory(panda, T, dt=DT, velocity_limits=0.5, q0=Q[0], seed=7)
    assert all(np.array_equal(a.q, b.q) for a, b in zip(one, two, strict=True))


@pytest.mark.parametrize("kwargs, words", [
    ({"dt": 0.01}, "velocity_limits"),
    ({"velocity_limits": True}, "dt"),
    ({"dt": 0.0, "velocity_limits": True}, "dt must be"),
    ({"dt": -0.01, "velocity_limits": True}, "dt must be"),
    ({"dt": float("nan"), "velocity_limits": True}, "dt must be"),
    ({"dt": "fast", "velocity_limits": True}, "dt must be"),
    ({"dt": 0.01, "velocity_limits": False}, "velocity_limits must be"),
    ({"dt": 0.01, "velocity_limits": 0.0}, "factor"),
    ({"dt": 0.01, "velocity_limits": -2.0}, "factor"),
    ({"dt": 0.01, "velocity_limits": [1.0, 2.0]}, "shape"),
    ({"dt": 0.01, "velocity_limits": [1.0] * 6 + [0.0]}, "entries"),
    ({"dt": 0.01, "velocity_limits": [1.0] * 6 + [np.inf]}, "entries"),
    ({"dt": 0.01, "velocity_limits": True, "pro": True}, "pro"),
])
def test_bad_options(panda, kwargs, words):
    T = _poses(panda, smooth_path(panda, 3, DT, seed=0))
    with pytest.raises(OptionError, match=words):
        ek.solve_trajectory(panda, T, q0=np.zeros(7), **kwargs)


def test_velocity_limits_array_and_factor(panda):
    assert np.array_equal(velocity_limits(panda, 0.5), 0.5 * urdf_velocity_limits(panda))
    assert np.array_equal(velocity_limits(panda, np.ones(7)), np.ones(7))
    assert np.array_equal(urdf_velocity_limits(panda), panda.model.velocityLimit)


def test_preferences_refused_before_any_point(panda):
    from evoik_pin.goals import Pose
    from evoik_pin.goals.preferences import Posture

    Q = smooth_path(panda, 3, DT, seed=0)
    lists = [[Pose("panda_hand_tcp", T)] for T in _poses(panda, Q)]
    lists[2] = lists[2] + [Posture(Q[2])]
    with pytest.raises(OptionError, match="preferences"):
        ek.solve_trajectory(panda, lists, dt=DT, velocity_limits=True, q0=Q[0])
