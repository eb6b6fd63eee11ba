"""Collision scenes on whole robots (Talos, Baxter): the SRDF's disabled pairs and adjacent links skipped, and
memetic's goal-list answers kept out of collision, re-checked with Pinocchio's computeCollisions on the full
model of the URDF (independent of Scene's reduced model and bookkeeping)."""

import numpy as np
import pinocchio as pin
import pytest

import evoik_pin as ev
from evoik_pin.goals import Pose, Position
from evoik_pin.scene import Scene

#: Both wrists of Talos at the wrist positions of a collision-free configuration (m, base frame); answers without a
#: scene can collide (memetic before its composed starts pushed the right upper arm through the torso).
HANDS = {"arm_left_7_link": [0.2363, 0.446, 0.2557], "arm_right_7_link": [0.6543, -0.1669, 0.1208]}


def _reference(robot):
    """(geometry model, data) of the robot's collision meshes on its full model (``full_model``: the whole URDF,
    behind a free-flyer with a floating base) with every pair less the SRDF's disabled ones and parent-child
    links, built by Pinocchio from the URDF file."""
    full = robot.full_model
    geom = pin.buildGeomFromUrdf(full, str(robot.urdf_path), pin.GeometryType.COLLISION,
                                 package_dirs=robot.package_dirs)
    geom.addAllCollisionPairs()  # every pair of objects on different joints
    pin.removeCollisionPairs(full, geom, robot.srdf)
    joints = [g.parentJoint for g in geom.geometryObjects]
    pairs = [(int(p.first), int(p.second)) for p in geom.collisionPairs]  # ints: the vector changes below
    geom.removeAllCollisionPairs()
    for a, b in pairs:
        ja, jb = joints[a], joints[b]
        if full.parents[ja] != jb and full.parents[jb] != ja:
            geom.addCollisionPair(pin.CollisionPair(a, b))
    return geom, pin.GeometryData(geom)


def _collides(robot, reference, q) -> bool:
    geom, gdata = reference
    full = robot.full_model
    return bool(pin.computeCollisions(full, full.createData(), geom, gdata, robot.full_configuration(q), False))


@pytest.fixture(scope="module")
def talos():
    return ev.load_robot("talos")


@pytest.mark.parametrize("name", ["talos", "baxter"])
def test_whole_robot_scene_checks_the_pairs_the_srdf_leaves(name):
    robot = ev.load_robot(name)
    assert robot.srdf is not None and robot.srdf.endswith(".srdf")  # example-robot-data ships one
    scene = Scene(robot)
    geom, _ = _reference(robot)
    assert scene.pair_count == len(geom.collisionPairs)
    without = Scene(robot, srdf=None)
    assert without.srdf == robot.srdf  # srdf=None is the robot's own SRDF
    rest = np.zeros(robot.n)
    assert scene.in_collision(rest) == _collides(robot, _reference(robot), rest)


def test_talos_arms_do_not_pass_through_the_torso(talos):
    goals = [Position(frame, p) for frame, p in HANDS.items()]
    reference = _reference(talos)
    scene = Scene(talos)
    # LM from a random start alone (no table entries, no restarts) reaches both hands with the robot in collision:
    # the problem has colliding answers, deterministically. (memetic's own starts no longer find one here.)
    q0 = talos.random_configurations(1, np.random.default_rng(0))[0]
    free = ev.solve(talos, goals, seed=0, q0=q0, timeout=None, max_restarts=0, table_seeds=0)
    assert free.success and _collides(talos, reference, free.q)
    assert scene.colliding_pairs(free.q)

    r = ev.solve(talos, goals, seed=0, q0=q0, scene=scene)
    assert r.success and r.collision_free and r.min_distance > 0
    assert not _collides(talos, reference, r.q)
    assert all(p <= 1e-6 for p, _ in r.goal_errors)
    for frame, p in HANDS.items():
        assert np.linalg.norm(talos.fk(r.q, frame=frame).translation - p) <= 1e-6


def test_floating_talos_with_feet_and_hands_in_a_scene():
    talos = ev.load_robot("talos", floating_base=True)
    rest = np.zeros(talos.n)
    goals = [Pose("left_sole_link", talos.fk(rest, frame="left_sole_link")),
             Pose("right_sole_link", talos.fk(rest, frame="right_sole_link")),
             *(Position(frame, p) for frame, p in HANDS.items())]
    r = ev.solve(talos, goals, seed=0, scene=Scene(talos))
    assert r.success and r.collision_free
    assert not _collides(talos, _reference(talos), r.q)
    assert all(p <= 1e-6 and (a is None or a <= 1e-6) for p, a in r.goal_errors)
