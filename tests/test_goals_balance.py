"""CenterOfMass and RelativePose goals (evoik_pin.goals): their checks when made and bound; the compiled centre of
mass and its Jacobian against Pinocchio (centerOfMass, jacobianCenterOfMass, finite differences) on Talos and G1
with a floating base, a chain, and random trees with random inertias; the support polygon's one-sided rows; the
relative pose's rows against finite differences; populations' violations; and memetic solves judged by
Pinocchio."""

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from urdf_helpers import joint_xml

import evoik_pin as ek
from evoik_pin.errors import FrameError, OptionError, TargetError
from evoik_pin.goals import CenterOfMass, Pose, RelativePose, bind
from evoik_pin.goals.center_of_mass import com_batch, com_of, contact_points, polygon_distance
from evoik_pin.problem import IKProblem
from evoik_pin.solvers.lm import kernel as K


@pytest.fixture(scope="module")
def talos():
    return ek.load_robot("talos", floating_base=True)


def rows(robot, goals, q):
    """(e, E, goal errors (G, 2)) of the compiled kernel at q for a goal list."""
    _, stack, pt, Rt = bind(robot, goals)
    e, E, ge = np.empty(stack.rows), np.empty((stack.rows, robot.n)), np.empty((len(goals), 2))
    K.task_rows(np.asarray(q, dtype=float), *robot.tree_constants(), *stack.arrays, pt, Rt, e, E, ge)
    return e, E, ge


def numeric_jacobian(f, q, h=1e-6):
    """Central differences (rows, n) of f at q."""
    cols = []
    for k in range(q.size):
        d = np.zeros_like(q)
        d[k] = h
        cols.append((f(q + d) - f(q - d)) / (2 * h))
    return np.array(cols).T


def check_com(robot, q):
    """The kernel's CoM (a point goal at the origin: e = CoM) and its Jacobian against Pinocchio's centerOfMass of
    the whole URDF, its finite differences, and jacobianCenterOfMass where the reduced model holds every mass."""
    e, E, _ = rows(robot, [CenterOfMass(point=np.zeros(3))], q)
    assert np.allclose(e, com_of(robot, q), atol=1e-12, rtol=0)
    assert np.allclose(com_batch(robot, q[None])[0], e, atol=1e-12, rtol=0)
    assert np.allclose(E, numeric_jacobian(lambda x: com_of(robot, x), q), atol=1e-6)
    model = robot.model
    if model.inertias[0].mass == robot.full_model.inertias[0].mass and not robot.mimic_joints:
        data = model.createData()
        J = pin.jacobianCenterOfMass(model, data, robot.to_pinocchio(q))
        assert np.allclose(E, robot.tree.base_R @ J, atol=1e-10)


@pytest.mark.parametrize("name, kw", [("talos", {"floating_base": True}), ("g1", {"floating_base": True}),
                                      ("panda", {}), ("talos", {"tips": ["arm_left_7_link"]}),
                                      ("ur5", {"base": "base_link"})])
def test_compiled_center_of_mass_and_jacobian_equal_pinocchio(name, kw, rng):
    robot = ek.load_robot(name, **kw)
    for q in robot.random_configurations(2, rng):
        check_com(robot, q)
