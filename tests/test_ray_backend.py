"""solve_many(backend="ray") and reachability maps on Ray: one local 2-CPU Ray instance for the module (starting
Ray costs seconds: every Ray test of the suite is here), the same answers as the local backend (targets, goal lists),
a dying actor's chunk re-run, scenes rebuilt in the actors, clear errors for unreachable clusters."""

import numpy as np
import pytest
from test_batch import mixed, same
from test_goal_batch import talos_lists

import evoik_pin as ev
from evoik_pin.errors import BackendError, TargetError
from evoik_pin.problem import Target
from evoik_pin.solvers.batch import ray_actors

BUDGET = {"timeout": None, "max_restarts": 2}


@pytest.fixture(scope="module")
def ray():
    ray = pytest.importorskip("ray")
    started = not ray.is_initialized()
    if started:
        # Ray starts its workers at nice 15: beside busy processes (a loaded CI machine) they got about 3 % of a
        # core and this module took many minutes. The workers are the work under test: normal priority.
        with pytest.MonkeyPatch.context() as mp:
            mp.setenv("RAY_worker_niceness", "0")
            ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, configure_logging=False)
    yield ray
    ray_actors.shutdown_pool()
    if started:
        ray.shutdown()


@pytest.fixture(scope="module")
def panda():
    return ev.load_robot("panda")


@pytest.fixture(scope="module")
def targets(panda):
    return mixed(panda, 300, 11, every=4, far={3: [2.0, 0.0, 0.3]})


def test_pack_and_unpack_targets_round_trip():
    ts = [Target(np.array([0.1, 0.2, 0.3])), Target(np.array([0.3, 0.0, 0.1]), np.diag([1.0, -1.0, -1.0])),
          Target.planar_target(0.2, -0.1, 0.5), Target.planar_target(0.1, 0.1)]
    back = ray_actors.unpack_targets(ray_actors.pack_targets(ts))
    for a, b in zip(ts, back, strict=True):
        assert np.array_equal(a.position, b.position) and a.planar == b.planar and a.yaw == b.yaw
        assert (a.rotation is None and b.rotation is None) or np.array_equal(a.rotation, b.rotation)


def test_ray_gives_the_local_answers_in_target_order(ray, panda, targets, capsys):
    local = ev.solve_many(panda, targets, seed=3, workers=2, **BUDGET)
    remote = ev.solve_many(panda, targets, seed=3, backend="ray", workers=2, progress=True, **BUDGET)
    same(local, remote)
    assert "solve_many (ray)" in capsys.readouterr().err
    assert remote.stats["backend"] == "ray" and remote.stats["workers"] == 2
    assert not remote[3].success and "max_restarts (2)" in remote[3].message
    assert remote.stats["solved"] == local.stats["solved"] >= 295
    starts = np.array([r.q for r in local]) + 1e-3
    same(ev.solve_many(panda, targets, q0=starts, seed=3, **BUDGET),
          ev.solve_many(panda, targets, q0=starts, seed=3, backend="ray", **BUDGET))


def test_a_dying_actor_has_its_chunk_re_run(ray, panda, targets):
    work = Target.coerce_many(targets)
    local = ev.solve_many(panda, targets, seed=5, workers=1, **BUDGET)
    job = ray_actors.RayBatch(panda, ev.api.make_problem, ev.api._run, "memetic", 5, dict(BUDGET), workers=2,
                               chunk_size=64)
    replaced = job.pool.replaced
    job.crash_hook = {1, 3}  # the first attempts of chunks 1 and 3 kill their actor (os._exit) mid-run
    out = job.solve(work)
    assert job.pool.replaced == replaced + 2 and len(job.pool.actors) == 2
    same(local, out.results(job.template))


def test_a_scene_is_rebuilt_in_the_actors(ray, panda):
    from evoik_pin.scene import Scene
    from evoik_pin.scene.examples import SHELF_INTERIOR, add_table_and_shelf, free_configurations

    scene = add_table_and_shelf(Scene(panda))
    Q = free_configurations(scene, 12, np.random.default_rng(2), SHELF_INTERIOR)
    H = np.array([panda.fk(q).homogeneous for q in Q])
    H[5, :3, 3] = [0.6, 0.0, 0.4]  # inside the shelf's open interior, an orientation it cannot reach
    local = ev.solve_many(panda, H, scene=scene, seed=0, **BUDGET)
    remote = ev.solve_many(panda, H, scene=scene, seed=0, backend="ray", **BUDGET)
    same(local, remote)
    for r in remote:
        assert r.collision_free == (not scene.in_collision(r.q))
        assert r.min_distance == pytest.approx(scene.distance(r.q))


def test_reachability_map_on_ray(ray):
    from evoik_pin.reach import reachability_map

    local = reachability_map("planar2r", voxel=0.05, progress=False)
    remote = reachability_map("planar2r", voxel=0.05, backend="ray", workers=2, progress=False)
    assert np.array_equal(local.index, remote.index) and np.array_equal(local.manipulability, remote.manipulability)
    assert remote.settings["backend"] == "ray"


def test_goal_lists_on_ray_give_the_local_answers(ray):
    """Goal lists (four poses on the floating Talos) reach the actors: the local backend's answers and goal errors."""
    talos = ev.load_robot("talos", floating_base=True)
    lists = talos_lists(talos, 40, 3)[:12]
    local = ev.solve_many(talos, lists, seed=2, workers=2, **BUDGET)
    remote = ev.solve_many(talos, lists, seed=2, backend="ray", workers=2, **BUDGET)
    same(local, remote)
    assert [r.goal_errors for r in local] == [r.goal_errors for r in remote]


def test_unreachable_cluster_address_is_a_clear_error(panda, monkeypatch):
    pytest.importorskip("ray")
    with pytest.raises(BackendError, match=r"cannot reach the Ray cluster at '127\.0\.0\.1:1'"):
        ev.solve_many(panda, [np.array([0.3, 0.0, 0.5])], backend="ray", address="127.0.0.1:1")
    monkeypatch.setenv("RAY_ADDRESS", "127.0.0.1:1")
    with pytest.raises(BackendError, match="cannot reach"):
        ray_actors.connect()
    with pytest.raises(BackendError, match="not host:port"):
        ray_actors.connect(address="nowhere")


def test_pose_arrays_go_to_the_actors_as_arrays_and_a_bad_pose_is_named_by_its_index(ray, panda):
    """An (N, 4, 4) array is solved by the actors as an array (the local answers), and a bad pose in a later chunk
    is a TargetError naming its index in the whole call."""
    H = np.array([panda.fk(q).homogeneous for q in panda.random_configurations(1500, np.random.default_rng(2))])
    local = ev.solve_many(panda, H, seed=4, workers=1, **BUDGET)
    same(local, ev.solve_many(panda, H, seed=4, backend="ray", workers=2, **BUDGET))
    H[1234, :3, :3] *= 2.0  # not a rotation
    with pytest.raises(TargetError, match="target 1234"):
        ev.solve_many(panda, H, seed=4, backend="ray", workers=2, **BUDGET)


def test_prefer_locked_and_preferences_on_ray_give_the_local_answers(ray, panda):
    """prefer=, locked= and goal lists holding preferences reach the actors: the local backend's answers."""
    from evoik_pin.goals import Pose, Posture

    Q = panda.random_configurations(6, np.random.default_rng(31))
    Q[:, 2] = 0.25
    poses = [panda.fk(q) for q in Q]
    lists = [[Pose(panda.tip, T), Posture({"panda_joint1": 0.3}, 0.5)] for T in poses]
    for targets, options in ((poses, {"prefer": "nearest", "q0": np.full(7, 0.1)}),
                             (lists, {"locked": {"panda_joint3": 0.25}, "prefer": "manipulability"})):
        local = ev.solve_many(panda, targets, seed=9, workers=1, **options, **BUDGET)
        remote = ev.solve_many(panda, targets, seed=9, backend="ray", workers=2, **options, **BUDGET)
        np.testing.assert_array_equal(local.q, remote.q)
        assert remote.success.all() and [r.message for r in local] == [r.message for r in remote]
