"""Tracker: one warm-started solve per control step inside the velocity limits (Panda at 1 kHz, Talos with a floating
base and four pose goals at 500 Hz), infeasible jumps answered inside the box and recovered from, bad options."""

import numpy as np
import pinocchio as pin
import pytest
from velocity_paths import pose_goals, smooth_path, steps_within

import evoik_pin as ek
from evoik_pin.errors import ConfigurationError, OptionError
from evoik_pin.robot.velocity_limits import urdf_velocity_limits


@pytest.fixture(scope="module")
def panda():
    return ek.load_robot("panda")


def _track(tracker, targets) -> tuple[list, np.ndarray]:
    results = [tracker.step(t) for t in targets]
    return results, np.array([r.q for r in results])


def test_panda_at_1khz_every_step_within_the_box_and_solved(panda):
    dt = 0.001
    Q = smooth_path(panda, 300, dt, seed=0)
    tracker = ek.Tracker(panda, dt=dt, q0=Q[0])
    results, answers = _track(tracker, [panda.fk(q) for q in Q])
    assert all(r.success for r in results)
    assert steps_within(answers, urdf_velocity_limits(panda) * dt, Q[0]).all()
    assert np.array_equal(tracker.q, answers[-1])
    assert np.array_equal(tracker.max_step, urdf_velocity_limits(panda) * dt)


def test_talos_floating_four_goals_at_500hz():
    talos = ek.load_robot("talos", floating_base=True)
    dt = 0.002
    Q = smooth_path(talos, 150, dt, seed=1)
    tracker = ek.Tracker(talos, dt=dt, q0=Q[0])
    results, answers = _track(tracker, pose_goals(talos, Q))
    assert all(r.success and len(r.goal_errors) == 4 for r in results)
    assert steps_within(answers, urdf_velocity_limits(talos) * dt, Q[0]).all()


def test_a_target_jumping_half_a_metre_then_back(panda):
    dt = 0.001
    Q = smooth_path(panda, 400, dt, seed=2)
    T = [panda.fk(q) for q in Q]
    for i in range(100, 150):
        T[i] = pin.SE3(T[i].rotation, T[i].translation + np.array([0.0, 0.5, 0.0]))
    tracker = ek.Tracker(panda, dt=dt, q0=Q[0], velocity_limits=2.0)
    results, answers = _track(tracker, T)
    assert steps_within(answers, 2.0 * urdf_velocity_limits(panda) * dt, Q[0]).all()
    assert all(r.success for r in results[:100])
    assert not any(r.success for r in results[100:150])
    assert results[149].position_error < results[100].position_error  # moving towards the jumped target
    assert all(r.success for r in results[-100:])  # caught up with the path


def test_reset_and_q_copies(panda):
    q0 = smooth_path(panda, 1, 0.001, seed=3)[0]
    tracker = ek.Tracker(panda, dt=0.001, q0=q0)
    q = tracker.q
    q[0] += 1.0  # a copy: the tracker's state is not written through
    assert np.array_equal(tracker.q, q0)
    far = panda.clip(q0 + 0.3)
    tracker.reset(far)
    r = tracker.step(panda.fk(far))
    assert r.success and np.abs(r.q - far).max() <= 1e-3 * 2.61 + 1e-12


def test_same_seed_same_steps(panda):
    dt = 0.001
    Q = smooth_path(panda, 60, dt, seed=4, fraction=4.0)  # faster than the limits: failing steps draw starts
    T = [panda.fk(q) for q in Q]
    a = _track(ek.Tracker(panda, dt=dt, q0=Q[0], seed=5), T)[1]
    b = _track(ek.Tracker(panda, dt=dt, q0=Q[0], seed=5), T)[1]
    assert np.array_equal(a, b)


def test_bad_options(panda):
    q0 = np.zeros(7)
    with pytest.raises(OptionError, match="dt must be"):
        ek.Tracker(panda, dt=0.0, q0=q0)
    with pytest.raises(OptionError, match="velocity_limits must be"):
        ek.Tracker(panda, dt=0.001, q0=q0, velocity_limits=[1.0, 2.0])
    with pytest.raises(OptionError, match="velocity_limits must be"):
        ek.Tracker(panda, dt=0.001, q0=q0, velocity_limits=None)
    with pytest.raises(ConfigurationError):
        ek.Tracker(panda, dt=0.001, q0=np.zeros(3))
    with pytest.raises(OptionError):
        ek.Tracker(panda, dt=0.001, q0=q0, population=-1)
