"""scripts/bench_goal_kinds_prefer.py's helpers for issue 32: the arms, near q0s, the unreachable band, Manip1's
measure."""

import sys
from pathlib import Path

import numpy as np
import pytest

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"
sys.path.insert(0, str(SCRIPTS))

import bench_goal_kinds_prefer as bp  # noqa: E402


def test_resolve_robots():
    assert bp.resolve_robots(None) == ["panda", "ur10"]
    assert bp.resolve_robots(["all"]) == list(bp.ARMS)
    assert bp.resolve_robots(["so_arm", "pr2_left"]) == ["so_arm", "pr2_left"]
    with pytest.raises(SystemExit):
        bp.resolve_robots(["nope"])


@pytest.fixture(scope="module")
def panda():
    return bp.load_arm("panda")


def test_near_q0_is_near_the_targets_configuration_and_random_is_unchanged(panda):
    targets, Q0 = bp.problems(panda, 5, 3)
    targets_n, Q0n = bp.problems(panda, 5, 3, "near", 0.1)
    Q = panda.random_configurations(5, np.random.default_rng(3))
    assert all(np.allclose(a.homogeneous, b.homogeneous) for a, b in zip(targets, targets_n, strict=True))
    assert np.all(Q0n >= panda.lower) and np.all(Q0n <= panda.upper)
    assert np.abs(Q0n - Q).max() < 0.6 < np.abs(Q0 - Q).max()
    with pytest.raises(ValueError):
        bp.problems(panda, 2, 0, "far")


def test_manip_is_yoshikawas_for_6_joints_or_more_and_nonzero_for_so_arm(panda):
    q = (panda.lower + panda.upper) / 2 + 0.1
    J = panda.jacobian(q, "world")
    assert bp.manip(panda, q) == pytest.approx(np.sqrt(np.linalg.det(J @ J.T)), rel=1e-9)
    so = bp.load_arm("so_arm")
    q = (so.lower + so.upper) / 2 + 0.1
    J = so.jacobian(q, "world")
    assert bp.manip(so, q) == pytest.approx(np.sqrt(np.linalg.det(J.T @ J)), rel=1e-9) and bp.manip(so, q) > 1e-3


def test_far_band_is_beyond_reach(panda):
    assert bp.far_band("panda", panda) == (1.2, 1.6)
    ur5 = bp.load_arm("ur5")
    lo, hi = bp.far_band("ur5", ur5)
    assert lo > bp.reach(ur5) and hi > lo
    sets, singles = bp.goal_set_problems(ur5, 2, 0, (lo, hi))
    positions, _ = sets[0][0].member_targets
    assert len(singles) == 2 and len(positions) == 10
    assert (np.linalg.norm(positions, axis=1) >= lo).sum() == 7


class _StallingLM:
    """An LM stand-in over two solutions: from the answer itself it stalls (a singularity's band), from any other
    start it converges to the solution nearer that start (``converges`` False: never)."""

    def __init__(self, answer, solutions, converges=True):
        from types import SimpleNamespace

        self.answer, self.solutions, self.converges = answer, solutions, converges
        self.problem = SimpleNamespace(lower=np.full(3, -3.0), upper=np.full(3, 3.0))
        self._out = SimpleNamespace

    def run(self, q, iterations):
        if not self.converges or np.array_equal(q, self.answer):
            return self._out(q=q, converged=False)
        s = min(self.solutions, key=lambda s: np.linalg.norm(s - q))
        return self._out(q=s, converged=True)


def test_exact_takes_an_answer_to_the_exact_solution_nearest_it():
    """An answer LM takes to an exact solution from itself: LM's solution (flag 0); one it stalls at: the nearest of
    LM's solutions from starts around it (flag 1), not a farther one; none converging: the answer as it is (flag 2)."""
    answer = np.array([0.1, 0.2, 0.3])
    near, far = answer + np.array([4e-3, 0.0, 0.0]), answer + np.array([0.0, 0.05, 0.0])
    q, how = bp.exact(_StallingLM(answer, [near, far]), answer, flag=True, seed=1)
    assert how == 1 and np.array_equal(q, near)
    q, how = bp.exact(_StallingLM(answer, [near, far], converges=False), answer, flag=True)
    assert how == 2 and np.array_equal(q, answer)
    q, how = bp.exact(_StallingLM(answer + 1.0, [far]), answer, flag=True)
    assert how == 0 and np.array_equal(q, far)
    assert np.array_equal(bp.exact(_StallingLM(answer, [near, far]), answer), near)
