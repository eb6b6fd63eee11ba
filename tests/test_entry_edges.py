"""The loose edges of the Python entry points: every option checked the same way before any work, a single target
given to solve_many, targets out of any reach, scene file paths, and what a failure message quotes.

Entry points: ``solve``, ``solve_all``, ``solve_many``, ``solve_trajectory``, ``reachability_map``. Budgets are
deterministic (``timeout=None, max_restarts=k``) wherever answers are compared.
"""

import math
import re
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import evoik_pin as ek
from evoik_pin import api
from evoik_pin.errors import OptionError, SceneError, TargetError
from evoik_pin.problem import MAX_TARGET_NORM, Target
from evoik_pin.scene import Scene
from evoik_pin.scene.examples import SHELF_INTERIOR, free_configurations
from evoik_pin.solvers.batch import threads as batch_threads

ROOT = Path(__file__).resolve().parents[1]
SHELF = ROOT / "examples" / "panda_shelf.yaml"
BUDGET = {"timeout": None, "max_restarts": 1}


@pytest.fixture(scope="module")
def panda():
    return ek.load_robot("panda")


@pytest.fixture(scope="module")
def pose(panda):
    return panda.fk(np.array([0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8]))


@pytest.fixture
def no_work(monkeypatch):
    """Any solving (a per-target solve through api._run or through a kept IKSolver, as solve and solve_trajectory
    make them, a batched LM round) fails the test: the options must be refused before."""

    def work(*args, **kwargs):
        raise AssertionError("work started before every option was checked")

    monkeypatch.setattr(api, "_run", work)
    monkeypatch.setattr(ek.IKSolver, "solve", work)
    monkeypatch.setattr(batch_threads, "solve_pairs", work)


# ---------------------------------------------------------------------- options: one check, before any work
# (option values, the option's name in the message, the accepted range in the message)
BAD_OPTIONS = [
    ({"timeout": -1}, r"timeout \(s; or None\)", r"a finite number > 0"),
    ({"timeout": float("nan")}, r"timeout \(s; or None\)", r"a finite number > 0"),
    ({"max_restarts": -1}, r"max_restarts", r"an integer >= 0"),
    ({"population": 0}, r"population", r"an integer >= 4"),
    ({"generations": -1}, r"generations", r"an integer >= 0"),
    ({"polish_count": -1}, r"polish_count", r"an integer >= 1"),
    ({"iterations": 0}, r"iterations", r"an integer >= 1"),
    ({"batch": 0}, r"batch", r"an integer >= 1"),
    ({"table_size": -5}, r"table_size", r"an integer >= 0"),
    ({"table_seeds": -1}, r"table_seeds", r"an integer >= 0"),
    ({"engine": "gpu"}, r"engine", r"'compiled', 'python'"),
    ({"timeout": None, "max_restarts": None}, r"timeout \(s\) or max_restarts", r"finite budget"),
]


def _solve_many(robot, pose, options):
    return ek.solve_many(robot, [pose, pose.translation], seed=0, workers=1, **options)


def _solve_trajectory(robot, pose, options):
    return ek.solve_trajectory(robot, [pose, pose], seed=0, **options)


def _reach(robot, pose, options):
    return ek.reachability_map(robot, voxel=0.5, orientations=1, progress=False, **options)


ENTRY_POINTS = {"solve_many": _solve_many, "solve_trajectory": _solve_trajectory, "reachability_map": _reach}


@pytest.mark.parametrize("options, name, accepted", BAD_OPTIONS, ids=[str(o) for o, _, _ in BAD_OPTIONS])
@pytest.mark.parametrize("entry", list(ENTRY_POINTS))
def test_every_entry_point_refuses_a_bad_option_before_any_work(panda, pose, no_work, entry, options, name,
                                                                  accepted):
    with pytest.raises(OptionError, match=name) as info:
        ENTRY_POINTS[entry](panda, pose, options)
    assert re.search(accepted, str(info.value))


@pytest.mark.parametrize("options, name, accepted", BAD_OPTIONS, ids=[str(o) for o, _, _ in BAD_OPTIONS])
def test_the_entry_points_give_solves_message(panda, pose, options, name, accepted):
    with pytest.raises(OptionError) as single:
        ek.solve(panda, pose, **options)
    for entry in ENTRY_POINTS.values():
        with pytest.raises(OptionError) as many:
            entry(panda, pose, options)
        assert str(many.value) == str(single.value)


@pytest.mark.parametrize("options, name", [
    ({"count": 0}, r"count must be an integer >= 1"),
    ({"class_radius": -1.0}, r"class_radius must be a finite number > 0 rad"),
    ({"engine": "gpu"}, r"engine 'gpu' is not one of 'compiled', 'python'"),
])
def test_solve_all_checks_its_method_options_the_same_way(panda, pose, options, name):
    with pytest.raises(OptionError, match=name):
        ek.solve_all(panda, pose, **options)
    with pytest.raises(OptionError, match=name):  # the same check through solve_many's up-front path
        ek.solve_many(panda, [pose], method="memetic-all", workers=1, **options)


def test_solve_trajectory_checks_the_pro_box_half_width_before_the_first_point(panda, pose, no_work):
    with pytest.raises(OptionError, match=r"delta \(the Pro box half-width\) must be a finite number > 0 rad"):
        ek.solve_trajectory(panda, [pose, pose], pro=True, delta=-1.0)


def test_solve_trajectory_names_a_bad_target_before_the_first_point(panda, pose, no_work):
    with pytest.raises(TargetError, match=r"target 2: .*NaN"):
        ek.solve_trajectory(panda, [pose, pose, [0.3, np.nan, 0.2]])


def test_solve_many_refuses_a_bad_option_for_a_method_solved_one_by_one(panda, pose, no_work):
    with pytest.raises(OptionError, match=r"unknown option\(s\) population for method 'memetic-all'"):
        ek.solve_many(panda, [pose], method="memetic-all", population=10)


# ---------------------------------------------------------------------- solve_many: one target is one target
@pytest.mark.parametrize("form", ["se3", "4x4", "4x4 list", "target", "position"])
def test_solve_many_takes_one_target_as_one_target(panda, pose, form):
    one = {"se3": pose, "4x4": pose.homogeneous, "4x4 list": pose.homogeneous.tolist(), "target": Target.coerce(pose),
           "position": pose.translation}[form]
    many = ek.solve_many(panda, one, seed=0, workers=1, **BUDGET)
    assert len(many) == 1
    single = ek.solve(panda, one, seed=0, **BUDGET)
    assert many[0].success and single.success
    assert many[0].position_error <= 1e-6 and (many[0].orientation_error is None) == (form == "position")


# ---------------------------------------------------------------------- targets out of any reach
def _far_pose(pose, x: float) -> np.ndarray:
    H = pose.homogeneous.copy()
    H[0, 3] = x
    return H


FAR_ENTRY_POINTS = {
    "solve": lambda robot, H: ek.solve(robot, H),
    "solve position": lambda robot, H: ek.solve(robot, H[:3, 3]),
    "solve se3": lambda robot, H: ek.solve(robot, pin.SE3(H[:3, :3].copy(), H[:3, 3].copy())),
    "solve_all": lambda robot, H: ek.solve_all(robot, H),
    "solve_trajectory": lambda robot, H: ek.solve_trajectory(robot, [np.eye(4), H]),
    "solve_many list": lambda robot, H: ek.solve_many(robot, [H[:3, 3] * 0, H], workers=1),
    "solve_many (1, 4, 4)": lambda robot, H: ek.solve_many(robot, H[None], workers=1),
    "solve_many (2, 4, 4)": lambda robot, H: ek.solve_many(robot, np.stack([np.eye(4), H]), workers=1),
    "Target.from_poses": lambda robot, H: Target.from_poses(np.stack([np.eye(4), H])),
}


@pytest.mark.parametrize("x", [1e300, 1.5 * MAX_TARGET_NORM, -1e7])
@pytest.mark.parametrize("entry", list(FAR_ENTRY_POINTS))
def test_a_target_beyond_any_reach_is_refused_without_warnings(panda, pose, entry, x):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(TargetError, match=r"beyond any arm's reach \(accepted: at most MAX_TARGET_NORM = "
                                              r"1e\+06 m\)") as info:
            FAR_ENTRY_POINTS[entry](panda, _far_pose(pose, x))
    if entry in ("solve_trajectory", "solve_many list", "solve_many (2, 4, 4)", "Target.from_poses"):
        assert str(info.value).startswith("target 1: ")
    elif entry == "solve_many (1, 4, 4)":
        assert str(info.value).startswith("target 0: ")


def test_a_huge_rotation_entry_is_no_rotation_without_warnings():
    H = np.eye(4)
    H[0, 0] = 1e300
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(TargetError, match="not a rotation matrix"):
            Target.coerce(H)
        with pytest.raises(TargetError, match="target 0: rotation is not a rotation matrix"):
            Target.check_poses(H[None])


def test_a_target_at_the_bound_is_accepted(panda):
    assert Target.coerce([MAX_TARGET_NORM, 0.0, 0.0]).position[0] == MAX_TARGET_NORM
    H = np.eye(4)
    H[:3, 3] = MAX_TARGET_NORM / math.sqrt(3.0) * (1 - 1e-12)
    assert Target.check_poses(H[None]).shape == (1, 4, 4)


finite = st.floats(allow_nan=False, allow_infinity=False)


@settings(max_examples=200, deadline=None)
@given(p=st.tuples(finite, finite, finite), as_pose=st.booleans())
def test_any_finite_target_beyond_the_bound_is_out_of_reach_and_any_within_is_accepted(p, as_pose):
    p = np.array(p)
    H = np.eye(4)
    H[:3, 3] = p
    beyond = math.hypot(*p) > MAX_TARGET_NORM
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for check in (lambda: Target.coerce(H if as_pose else p), lambda: Target.check_poses(H[None])):
            if beyond:
                with pytest.raises(TargetError, match="beyond any arm's reach"):
                    check()
            else:
                check()


@settings(max_examples=100, deadline=None)
@given(p=st.tuples(finite, finite, finite), k=st.integers(0, 2), bad=st.sampled_from([np.nan, np.inf, -np.inf]))
def test_any_nan_or_inf_target_is_the_nan_error(p, k, bad):
    p = np.array(p)
    p[k] = bad
    H = np.eye(4)
    H[:3, 3] = p
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for check in (lambda: Target.coerce(p), lambda: Target.coerce(H), lambda: Target.check_poses(H[None])):
            with pytest.raises(TargetError, match="NaN or inf"):
                check()


# ---------------------------------------------------------------------- scene file paths
@pytest.mark.parametrize("as_path", [str, Path])
def test_every_entry_point_takes_a_scene_file_path(panda, as_path):
    scene = Scene.from_file(panda, SHELF)
    target = panda.fk(free_configurations(scene, 1, np.random.default_rng(3), SHELF_INTERIOR)[0])
    for given_scene in (scene, as_path(SHELF)):
        r = ek.solve(panda, target, seed=0, scene=given_scene, **BUDGET)
        assert r.success and r.collision_free
        if given_scene is scene:
            expected = r.q
        else:
            assert np.array_equal(r.q, expected)
    assert ek.solve_many(panda, [target], seed=0, workers=1, scene=as_path(SHELF), **BUDGET)[0].collision_free
    assert ek.solve_trajectory(panda, [target], seed=0, scene=as_path(SHELF), **BUDGET)[0].collision_free
    assert all(s.collision_free for s in ek.solve_all(panda, target, seed=0, scene=as_path(SHELF), count=2))


@pytest.mark.parametrize("entry", ["solve", "solve_all", "solve_many", "solve_trajectory", "reachability_map"])
def test_a_bad_scene_path_is_a_scene_error_naming_the_file(panda, pose, tmp_path, entry, no_work):
    call = {"solve": lambda s: ek.solve(panda, pose, scene=s),
            "solve_all": lambda s: ek.solve_all(panda, pose, scene=s),
            "solve_many": lambda s: ek.solve_many(panda, [pose], scene=s),
            "solve_trajectory": lambda s: ek.solve_trajectory(panda, [pose], scene=s),
            "reachability_map": lambda s: ek.reachability_map(panda, voxel=0.5, progress=False, scene=s)}[entry]
    missing = tmp_path / "missing.yaml"
    with pytest.raises(SceneError, match=r"scene file '.*missing\.yaml': not found"):
        call(missing)
    with pytest.raises(SceneError, match=r"unknown extension '\.txt'"):
        call(str(tmp_path / "scene.txt"))
    with pytest.raises(OptionError, match=r"scene must be an evoik_pin.Scene or the path of a scene file .*got int"):
        call(3)


# ---------------------------------------------------------------------- failure messages
def test_a_position_target_message_quotes_the_position_tolerance_only(panda):
    far = [2.0, 0.0, 0.5]  # 2 m: beyond the Panda's 0.85 m reach
    messages = {
        "memetic": ek.solve(panda, far, seed=0, **BUDGET).message,
        "isade": ek.solve(panda, far, method="isade", seed=0, max_generations=5, runs=1).message,
        "solve_all": ek.solve_all(panda, far, seed=0, timeout=None, max_starts=64).message,
        "solve_many": ek.solve_many(panda, [far], seed=0, workers=1, **BUDGET)[0].message,
    }
    for where, message in messages.items():
        assert "exceeds the tolerance (position error <= 1e-06 m)" in message, where
        assert "rad" not in message, where


def test_a_pose_target_message_quotes_both_tolerances_with_units(panda, pose):
    far = _far_pose(pose, 2.0)
    memetic = ek.solve(panda, far, seed=0, rotation_tolerance=1e-4, **BUDGET).message
    assert "exceeds the tolerance (position error <= 1e-06 m, orientation error <= 0.0001 rad)" in memetic
    isade = ek.solve(panda, far, method="isade", seed=0, max_generations=5, runs=1).message
    assert "exceeds the tolerance (position error <= 1e-06 m, orientation error <= 1e-06 rad)" in isade
