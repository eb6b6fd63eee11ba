"""The LM engines' finishing step (solvers/lm/kernel.py's _run, and reference.py's Python twin): one (almost)
undamped step after the goals are met, kept only when it lowers |e|^2 and every goal stays within its tolerances. Two
goals that cannot both be met exactly (a heavy loose one on Panda's tool, a light tight one on its wrist pulled 1 mm
along the rigid link between them): the least-squares point the undamped step heads for leaves the light goal past
its tolerance, so a run that reports convergence must not have taken it."""

import numpy as np
import pytest

import evoik_pin as ek
from evoik_pin.goals import Position
from evoik_pin.problem import IKProblem
from evoik_pin.solvers.lm import LevenbergMarquardt

#: m: how far apart the two targets pull (along the link, whose length is fixed).
PULL = 1e-3


@pytest.mark.parametrize("engine", ["compiled", "python"])
def test_a_converged_run_keeps_every_goal_within_its_tolerance(engine):
    panda = ek.load_robot("panda")
    rng = np.random.default_rng(0)
    converged = 0
    for _ in range(20):
        q = panda.random_configurations(1, rng)[0]
        tool, wrist = panda.fk(q).translation, panda.fk(q, "panda_link7").translation
        along = (tool - wrist) / np.linalg.norm(tool - wrist)
        goals = [Position(panda.tip, tool, weight=100.0, tolerance=2 * PULL),
                 Position("panda_link7", wrist - PULL * along, tolerance=0.6 * PULL)]
        tolerance = np.array([2 * PULL, 0.6 * PULL])
        lm = LevenbergMarquardt(IKProblem(panda, goals), engine=engine)
        for q0 in np.clip(q + 0.05 * rng.standard_normal((5, panda.n)), panda.lower, panda.upper):
            out = lm.run(q0, 100)
            if out.converged:
                converged += 1
                assert (out.goal_errors[:, 0] <= tolerance).all(), out.goal_errors
                # at q itself too (the kernel's errors are what Pinocchio's forward kinematics give)
                assert np.linalg.norm(panda.fk(out.q).translation - tool) <= tolerance[0]
                assert np.linalg.norm(panda.fk(out.q, "panda_link7").translation - goals[1].target) <= tolerance[1]
    assert converged >= 2  # the case is met (before the check, every such run ended past the wrist's tolerance)
