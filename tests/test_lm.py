"""The LM engine (solvers/lm): the compiled chain kinematics against Pinocchio's, the kernel's runs against the
reference Python loop for every target kind, run_many, solve_pairs, and the engine option. (The Lie-group
formulas the kernel uses are tested in test_lie.py.)"""

import numpy as np
import pinocchio as pin
import pytest
from kernel_helpers import compiled_frames

import evoik_pin as ev
from evoik_pin import lie
from evoik_pin.errors import OptionError
from evoik_pin.goals.stack import TargetArrays
from evoik_pin.problem import IKProblem, Target
from evoik_pin.robot import list_robots, load_robot
from evoik_pin.solvers.lm import LevenbergMarquardt, solve_pairs
from evoik_pin.solvers.lm.layout import STATS_SIZE
from evoik_pin.solvers.lm.reference import ReferenceLM


@pytest.fixture(scope="module")
def robots():
    return {name: load_robot(name) for name in list_robots()}


@pytest.mark.parametrize("name", list_robots())
def test_chain_kinematics_equal_pinocchio(robots, name):
    # every bundled and example arm: revolute, prismatic (vehicle_arm) and continuous (kinova) joints
    robot = robots[name]
    for q in robot.random_configurations(5, np.random.default_rng(3)):
        ((R, p, J),) = compiled_frames(robot, q, [robot.tip])
        T = robot.fk(q)
        assert np.abs(R - T.rotation).max() < 1e-12 and np.abs(p - T.translation).max() < 1e-12
        # base-frame axes and tip point velocity: Pinocchio's LOCAL_WORLD_ALIGNED Jacobian, i.e. "world"
        assert np.abs(J - robot.jacobian(q, "world")).max() < 1e-12


def _target(kind, robot, q, yaw_offset=0.0):
    T = robot.fk(q)
    if kind == "pose":
        return T
    if kind == "position":
        return Target(T.translation)
    yaw = float(np.arctan2(T.rotation[1, 0], T.rotation[0, 0])) + yaw_offset
    return Target.planar_target(*T.translation[:2], yaw=yaw if kind == "planar_yaw" else None)


@pytest.mark.parametrize("name, kind", [("panda", "pose"), ("ur5", "pose"), ("kinova", "pose"),
                                        ("redundant7r", "pose"), ("ax18", "position"), ("vehicle_arm", "position"),
                                        ("planar2r", "planar"), ("vehicle_arm", "planar_yaw"),
                                        ("vehicle_arm", "planar")])
def test_compiled_runs_equal_the_python_loop(robots, name, kind):
    """The kernel is the Python loop's iteration compiled: from the same starts, the same steps.

    Both sides round differently (our FK against Pinocchio's, about 1e-16), which can flip a comparison at
    1e-12 (whether a finishing step improved) or, rarely, an accept test early on, so the check is that
    nearly every run is identical (steps, evaluations, end configuration to 1e-8) and that both engines
    converge on the same starts.
    """
    robot = robots[name]
    rng = np.random.default_rng(17)
    identical = converged = 0
    runs = 40
    for _ in range(runs):
        qt, q0 = robot.random_configurations(2, rng)
        target = Target.coerce(_target(kind, robot, qt))
        problem = IKProblem(robot, target)
        a = LevenbergMarquardt(problem).run(q0, 30)
        b = ReferenceLM(problem).run(q0, 30)
        assert a.converged == b.converged
        assert robot.within_bounds(a.q)
        identical += (a.iterations == b.iterations and a.evaluations == b.evaluations
                      and np.allclose(a.q, b.q, atol=1e-8))
        converged += a.converged
        assert (a.orientation_error is None) == (kind in ("position", "planar"))
        if a.converged:
            Tq = robot.fk(a.q)
            if kind in ("pose", "position"):
                assert np.linalg.norm(Tq.translation - target.position) <= 1e-6
            else:  # planar: x, y in the base plane, and the heading when given
                assert np.linalg.norm(Tq.translation[:2] - target.position) <= 1e-6
                if kind == "planar_yaw":
                    yaw = np.arctan2(Tq.rotation[1, 0], Tq.rotation[0, 0])
                    assert abs(lie.wrap_angle(yaw - target.yaw)) <= 1e-6
            if kind == "pose":
                assert a.orientation_error <= 1e-6
                assert np.linalg.norm(pin.log3(target.rotation.T @ Tq.rotation)) <= 1e-6
    assert identical >= runs - 2
    assert converged >= runs // 4  # the comparison covers converging runs, not only failures


def test_compiled_run_holds_joints_on_their_limits(robots):
    # targets whose solution has joint 5 on its upper limit, from starts 0.3 rad around it: the clip and
    # re-solve path of the step runs; the answers stay inside the box and equal the Python loop's
    robot = robots["panda"]
    rng = np.random.default_rng(8)
    on_limit = 0
    for _ in range(20):
        qt = robot.random_configurations(1, rng)[0]
        qt[5] = robot.upper[5]
        T = robot.fk(qt)
        q0 = np.clip(qt + 0.3 * rng.standard_normal(robot.n), robot.lower, robot.upper)
        a = LevenbergMarquardt(IKProblem(robot, T)).run(q0, 30)
        b = ReferenceLM(IKProblem(robot, T)).run(q0, 30)
        assert robot.within_bounds(a.q) and a.converged == b.converged and np.allclose(a.q, b.q, atol=1e-8)
        on_limit += a.converged and a.q[5] == robot.upper[5]
    assert on_limit >= 5


def test_wrapping_joints_wrap_in_the_kernel(robots):
    # kinova's continuous joints: a start just below -pi and a target just above +pi on that joint
    robot = robots["kinova"]
    k = int(np.nonzero(robot.continuous)[0][0])
    q0 = robot.random_configurations(1, np.random.default_rng(9))[0]
    q0[k] = -np.pi + 0.05
    qt = q0.copy()
    qt[k] = np.pi - 0.05
    a = LevenbergMarquardt(IKProblem(robot, robot.fk(qt))).run(q0, 30)
    assert a.converged and a.iterations <= 6
    assert abs(a.q[k] - qt[k]) < 1e-6 and robot.within_bounds(a.q)


def test_engine_option(robots, reachable_pose):
    robot = robots["panda"]
    T = reachable_pose(robot, 4)
    for engine in ("compiled", "python"):
        res = ev.solve(robot, T, seed=11, engine=engine, timeout=None, max_restarts=5)
        assert res.success and res.position_error <= 1e-6
    with pytest.raises(OptionError, match="compiled"):
        ev.solve(robot, T, engine="fortran")
    # planar targets run in the kernel too
    planar = robots["planar2r"]
    x, y = reachable_pose(planar, 5).translation[:2]
    for engine in ("compiled", "python"):
        res = ev.solve(planar, Target.planar_target(x, y), seed=1, engine=engine, timeout=None, max_restarts=5)
        assert res.success and res.position_error <= 1e-6


@pytest.mark.parametrize("name, kind", [("panda", "pose"), ("ax18", "position"), ("vehicle_arm", "planar_yaw"),
                                        ("planar2r", "planar")])
def test_solve_pairs_equal_one_run_per_pair(robots, name, kind):
    # solve_many's rounds: one kernel call over all pairs gives what one LM run per pair gives, and the
    # python engine's pairs what the reference loop gives
    robot = robots[name]
    rng = np.random.default_rng(21)
    Qt, Q0 = robot.random_configurations(30, rng), robot.random_configurations(30, rng)
    targets = [Target.coerce(_target(kind, robot, q, yaw_offset=0.2)) for q in Qt]
    out = solve_pairs(robot, Q0, targets, robot.lower, robot.upper, 1e-6, 1e-6)
    ref = solve_pairs(robot, Q0, targets, robot.lower, robot.upper, 1e-6, 1e-6, engine="python")
    assert 0 < out.converged.sum()
    assert (out.converged == ref.converged).mean() >= 0.9
    arrays = TargetArrays.of(targets)  # the batch solver's encoding gives the same pairs on both engines
    for engine, listed in (("compiled", out), ("python", ref)):
        enc = solve_pairs(robot, Q0, arrays, robot.lower, robot.upper, 1e-6, 1e-6, engine=engine)
        assert np.array_equal(enc.q, listed.q) and np.array_equal(enc.converged, listed.converged)
        assert np.array_equal(enc.position_error, listed.position_error)
    for i, t in enumerate(targets):
        one = LevenbergMarquardt(IKProblem(robot, t)).run(Q0[i], 30)
        assert np.array_equal(out.q[i], one.q) and out.converged[i] == one.converged
        assert out.position_error[i] == one.position_error and out.evaluations[i] == one.evaluations
        if kind in ("position", "planar"):
            assert out.orientation_error is None and ref.orientation_error is None
        else:
            assert out.orientation_error[i] == one.orientation_error


@pytest.mark.parametrize("engine", ["compiled", "python"])
def test_run_many_stops_at_the_first_converged_start(robots, engine):
    robot = robots["panda"]
    rng = np.random.default_rng(32)
    q = robot.random_configurations(1, rng)[0]
    problem = IKProblem(robot, robot.fk(q))
    lm = LevenbergMarquardt(problem, engine=engine)
    starts = robot.random_configurations(8, rng)
    starts[5] = np.clip(q + 0.05, robot.lower, robot.upper)  # one start in the basin of the solution
    singles = [lm.run(s, 50) for s in starts]
    first = next(k for k, o in enumerate(singles) if o.converged)
    out, k = lm.run_many(starts, 50)
    assert k == first and out.converged and np.array_equal(out.q, singles[k].q)
    assert out.iterations == sum(o.iterations for o in singles[:k + 1])
    assert out.evaluations == sum(o.evaluations for o in singles[:k + 1])
    pos = np.linalg.norm(robot.fk(out.q).translation - robot.fk(q).translation)
    assert pos <= 1e-6 and robot.within_bounds(out.q)
    # none converges (out of reach): every start runs and the one with the lowest error is returned
    far = LevenbergMarquardt(IKProblem(robot, pin.SE3(np.eye(3), np.array([3.0, 0, 0]))), engine=engine)
    out, k = far.run_many(starts, 20)
    errs = [far.run(s, 20).error for s in starts]
    assert not out.converged and k == int(np.argmin(errs)) and out.error == pytest.approx(min(errs), abs=0)


def test_solve_many_engines_agree_on_success(robots):
    robot = robots["kinova"]
    H = np.array([robot.fk(q).homogeneous for q in robot.random_configurations(200, np.random.default_rng(22))])
    for engine in ("compiled", "python"):
        res = ev.solve_many(robot, H, seed=3, engine=engine, timeout=None, max_restarts=10)
        assert res.stats["success_rate"] == 1.0
        for r, T in zip(res, H, strict=True):
            Tq = robot.fk(r.q)
            assert np.linalg.norm(Tq.translation - T[:3, 3]) <= 1e-6 and robot.within_bounds(r.q)
            assert np.linalg.norm(pin.log3(T[:3, :3].T @ Tq.rotation)) <= 1e-6


def _kernel_pairs(robot, kind, count, seed):
    """Inputs of the kernel's batch entry points: ``count`` (start, target) pairs of one target kind, some
    starts on or beyond the joint limits (clipping, holding, wrapping), the tip goal's stack and the params."""
    from evoik_pin.goals.stack import GoalStack, encode_targets, target_kind
    from evoik_pin.solvers.lm.layout import box_constants, kernel_params

    rng = np.random.default_rng(seed)
    Qt, Q0 = robot.random_configurations(count, rng), robot.random_configurations(count, rng)
    Q0[::5] = np.clip(Qt[::5] + 0.3 * rng.standard_normal(Q0[::5].shape), robot.lower, robot.upper)
    Q0[1::5] = np.where(rng.random(Q0[1::5].shape) < 0.3, robot.upper, Q0[1::5])
    Q0[2::5] += rng.uniform(-7.0, 7.0, Q0[2::5].shape)  # outside the box: clipped or wrapped first
    targets = [Target.coerce(_target(kind, robot, q, yaw_offset=0.2)) for q in Qt]
    P, Rts = encode_targets(targets)
    _, any_wrap, _, _, box = box_constants(robot, robot.lower, robot.upper)
    stack = GoalStack.single(robot, target_kind(targets[0]), 1e-6, 1e-6)
    params = kernel_params(30)
    return (np.ascontiguousarray(Q0), tuple(robot.tree_constants()), box, any_wrap, tuple(stack.arrays),
            P[:, None].copy(), Rts[:, None].copy(), params)


@pytest.mark.parametrize("name, kind", [("panda", "pose"), ("ur5", "pose"), ("ax18", "position"),
                                        ("vehicle_arm", "planar_yaw")])
def test_kernel_runs_do_not_depend_on_earlier_runs(robots, name, kind):
    # the batch entry points reuse one workspace for all their runs: each run must write every buffer before
    # reading it, so a pair's result (bit for bit) does not depend on which runs came before it
    from evoik_pin.solvers.lm.kernel import lm_run, lm_runs

    robot = robots[name]
    Q0, *args, P, Rts, params = _kernel_pairs(robot, kind, 60, 41)
    N, n = Q0.shape
    out, stats, g = np.empty((N, n)), np.empty((N, STATS_SIZE)), np.empty((N, 1, 2))
    lm_runs(Q0, *args, P, Rts, params, out, stats, g)
    back, back_stats, back_g = np.empty((N, n)), np.empty((N, STATS_SIZE)), np.empty((N, 1, 2))
    lm_runs(Q0[::-1].copy(), *args, P[::-1].copy(), Rts[::-1].copy(), params, back, back_stats, back_g)
    assert np.array_equal(out, back[::-1]) and np.array_equal(stats, back_stats[::-1], equal_nan=True)
    assert np.array_equal(g, back_g[::-1], equal_nan=True)
    assert stats[:, 2].any() and (stats[:, 4] > 2).any()  # converged runs, runs of several steps
    for i in range(0, N, 7):  # a fresh workspace per run
        one = np.empty(n)
        assert lm_run(Q0[i], *args, P[i], Rts[i], params, one, np.empty((1, 2)))[3] == stats[i, 3]
        assert np.array_equal(one, out[i])
    # several starts for one target, after runs for other targets: the same runs again
    starts, starts_stats = np.empty((N, n)), np.full((N, STATS_SIZE), -1.0)
    k = lm_runs(Q0, *args, P[:1], Rts[:1], params, starts, starts_stats, np.empty((N, 1, 2)), first=True)
    runs = k + 1 if k >= 0 else -(k + 1)
    for i in range(runs):
        one = np.empty(n)
        lm_run(Q0[i], *args, P[0], Rts[0], params, one, np.empty((1, 2)))
        assert np.array_equal(one, starts[i])
    assert (starts_stats[runs:] == -1.0).all()


def test_kernel_batches_from_threads_equal_one_call(robots):
    # the batch solver calls the kernel from several threads at once (it releases the GIL): each call has its
    # own workspace, so chunks solved concurrently give what one call gives
    from concurrent.futures import ThreadPoolExecutor

    from evoik_pin.solvers.lm.kernel import lm_runs

    robot = robots["panda"]
    Q0, *args, P, Rts, params = _kernel_pairs(robot, "pose", 400, 43)
    N, n = Q0.shape
    out, stats, g = np.empty((N, n)), np.empty((N, STATS_SIZE)), np.empty((N, 1, 2))
    lm_runs(Q0, *args, P, Rts, params, out, stats, g)
    out_t, stats_t, g_t = np.empty((N, n)), np.empty((N, STATS_SIZE)), np.empty((N, 1, 2))

    def chunk(s):
        lm_runs(Q0[s], *args, P[s], Rts[s], params, out_t[s], stats_t[s], g_t[s])

    with ThreadPoolExecutor(4) as pool:
        list(pool.map(chunk, [slice(i, i + 50) for i in range(0, N, 50)]))
    assert np.array_equal(out, out_t) and np.array_equal(stats, stats_t) and np.array_equal(g, g_t)


# ---------------------------------------------------------------------------------------------- goal stacks
def _goal_problem(case, rng):
    """(robot, goals factory q -> goal list) of a goal-stack case."""
    from urdf_helpers import mimic_3r

    from evoik_pin.goals import Pose, Position

    if case == "baxter":  # two arms, two poses
        robot = load_robot("baxter", tips=["left_gripper", "right_gripper"])
        return robot, lambda q: [Pose(f, robot.fk(q, f)) for f in robot.tips]
    if case == "talos":  # a floating base, three poses and a position, weights
        robot = load_robot("talos", floating_base=True)
        frames = ["left_sole_link", "right_sole_link", "arm_left_7_link", "arm_right_7_link"]
        weights = (4.0, 4.0, 1.0)
        return robot, lambda q: ([Pose(f, robot.fk(q, f), weight=w) for f, w in zip(frames[:3], weights, strict=True)]
                                 + [Position(frames[3], robot.fk(q, frames[3]).translation, weight=0.5)])
    if case == "allegro":  # four fingertips, positions
        robot = load_robot("allegro_right")
        tips = ["link_3.0_tip", "link_7.0_tip", "link_11.0_tip", "link_15.0_tip"]
        return robot, lambda q: [Position(f, robot.fk(q, f).translation) for f in tips]
    if case == "ur5_rows_over_joints":  # 9 rows on 6 joints: the damped step in joint space
        robot = load_robot("ur5")
        return robot, lambda q: [Pose("tool0", robot.fk(q)), Position("forearm_link", robot.fk(q, "forearm_link")
                                                                      .translation, weight=2.0)]
    if case == "mimic":  # a mimic joint on the chain, two goals
        robot = load_robot(mimic_3r(), tip="tool")
        return robot, lambda q: [Position("tool", robot.fk(q).translation),
                                 Position("l2", robot.fk(q, "l2").translation)]
    raise AssertionError(case)


@pytest.mark.parametrize("case", ["baxter", "talos", "allegro", "ur5_rows_over_joints", "mimic"])
def test_goal_stacks_compiled_equal_the_python_loop(case):
    """The kernel on goal stacks (trees, floating base, weights, positions and poses, more rows than joints, mimic
    joints) takes the reference loop's steps from the same starts; converged answers meet every goal by Pinocchio."""
    rng = np.random.default_rng(23)
    robot, make = _goal_problem(case, rng)
    identical = converged = 0
    runs = 16
    for _ in range(runs):
        qt, q0 = robot.random_configurations(2, rng)
        q0 = np.clip(qt + 0.3 * rng.standard_normal(robot.n), robot.lower, robot.upper)  # near enough to converge
        problem = IKProblem(robot, make(qt))
        a = LevenbergMarquardt(problem).run(q0, 40)
        b = ReferenceLM(problem).run(q0, 40)
        assert a.converged == b.converged and robot.within_bounds(a.q)
        identical += (a.iterations == b.iterations and a.evaluations == b.evaluations
                      and np.allclose(a.q, b.q, atol=1e-8))
        assert (a.goal_errors is None) == (len(problem.goals) == 1)
        if a.converged:
            converged += 1
            errors = problem.goal_errors(a.q)
            assert problem.goals_met(errors)
            assert np.allclose(a.goal_errors[:, 0], [e[0] for e in errors], atol=1e-12)
            assert a.position_error == pytest.approx(max(e[0] for e in errors), abs=1e-12)
    assert identical >= runs - 2
    assert converged >= runs // 2


def test_a_goal_list_of_one_tip_goal_is_the_single_target(robots):
    # [Pose(tip, T)] packs to the very goal stack of the target T: the same runs, bit for bit
    from evoik_pin.goals import Pose, Position

    robot = robots["panda"]
    rng = np.random.default_rng(24)
    for qt, q0 in zip(robot.random_configurations(10, rng), robot.random_configurations(10, rng), strict=True):
        T = robot.fk(qt)
        for single, listed in ((T, [Pose(robot.tip, T)]), (T.translation, [Position(robot.tip, T.translation)])):
            a = LevenbergMarquardt(IKProblem(robot, single)).run(q0, 30)
            b = LevenbergMarquardt(IKProblem(robot, listed)).run(q0, 30)
            assert np.array_equal(a.q, b.q) and a.iterations == b.iterations and a.converged == b.converged
            assert a.position_error == b.position_error and a.orientation_error == b.orientation_error


def test_weights_set_the_compromise_between_goals_that_cannot_all_be_met():
    # the planar 2R arm's tool stretched out along x (joint 1 at 0) and its elbow on the y axis (joint 1 at pi/2)
    # cannot both hold: the heavier goal ends nearer its target, on both engines
    from evoik_pin.goals import Position

    robot = load_robot("planar2r")
    results = {}
    for w in (1.0, 9.0):
        goals = [Position("tool", [0.41, 0.0, 0.0], weight=w), Position("link2", [0.0, 0.25, 0.0])]
        problem = IKProblem(robot, goals)
        a = LevenbergMarquardt(problem).run(np.array([0.3, 0.2]), 60)
        b = ReferenceLM(problem).run(np.array([0.3, 0.2]), 60)
        assert not a.converged and not b.converged
        assert np.allclose(a.q, b.q, atol=1e-6)
        results[w] = a.goal_errors[:, 0]
    assert results[9.0][0] < results[1.0][0] and results[9.0][1] > results[1.0][1]


def test_read_only_arrays_do_not_make_the_kernel_compile_again(robots):
    """Every array reaching the kernel's compiled entries is a writable C array (layout.owned): a read-only one (a
    q0 the caller froze, a broadcast target, an array from Ray's object store) is another numba type, for which the
    whole LM run would compile again (about a minute, inside the caller's budget). So after solves fed read-only
    arrays through every path (a single run, runs from several starts, pairs, prefer's collection), no entry holds a
    read-only signature."""
    from numba import types

    from evoik_pin.solvers.lm import kernel
    from evoik_pin.solvers.search import guaranteed_runs

    panda = robots["panda"]
    rng = np.random.default_rng(3)
    Q = panda.random_configurations(4, rng)
    frozen = [q.copy() for q in Q]
    for q in frozen:
        q.setflags(write=False)
    H = np.stack([panda.fk(q).homogeneous for q in Q])
    H.setflags(write=False)
    ev.solve(panda, H[0], q0=frozen[1], seed=0)
    ev.IKSolver(panda).solve(H[1], q0=frozen[2], seed=0)
    ev.solve(panda, H[2], q0=frozen[0], prefer="nearest", seed=0)
    ev.solve_many(panda, H, q0=np.broadcast_to(frozen[3], (4, panda.n)), seed=0, workers=1)
    problem = IKProblem(panda, Target(H[3][:3, 3], H[3][:3, :3]), q0=frozen[0])
    lm = LevenbergMarquardt(problem)
    lm.run(frozen[1], 30)
    lm.run_many(np.broadcast_to(frozen[2], (2, panda.n)), 30)
    solve_pairs(panda, np.broadcast_to(frozen[3], (1, panda.n)), [Target(H[0][:3, 3], H[0][:3, :3])],
                panda.lower, panda.upper, 1e-6, 1e-6)
    entries = [*kernel.BASIC, *kernel.ALL, kernel.lm_run_basic, kernel.lm_run_all, guaranteed_runs.guaranteed_runs,
               guaranteed_runs.guaranteed_runs_basic]
    for entry in entries:
        for sig in entry.signatures:
            assert not any(isinstance(t, types.Array) and not t.mutable for t in sig), (entry.__name__, sig)


def test_goal_errors_use_the_compiled_signature_loaded_before_any_clock(robots):
    """``Goal.errors`` of the kinds with bands, free axes or an axis to point calls the kernel's compiled
    ``axes_error`` from Python; ``compiled_kernel(True)`` (the kernel of such goals, which their LM engine loads
    when made, before any solve's clock) loads the one signature those calls use, so memetic's later stages, which
    judge goal errors this way, never compile or load it mid-search (its loading had made a first band solve run out
    of its 5 ms)."""
    from evoik_pin.goals import Direction, Pose
    from evoik_pin.solvers.lm.axes import axes_error
    from evoik_pin.solvers.lm.engine import compiled_kernel

    compiled_kernel(True)
    loaded = list(axes_error.signatures)
    panda = robots["panda"]
    rng = np.random.default_rng(4)
    for q in panda.random_configurations(3, rng):
        T = panda.fk(q)  # Pinocchio's rotation: Fortran-ordered, as a user's target usually is
        goals = [Pose(panda.tip, T, tolerance=[0.002] * 3 + [0.05] * 3), Pose(panda.tip, T, free="rz"),
                 Direction(panda.tip, [0, 0, 1], T.rotation[:, 2])]
        for goal in goals:
            pos, rot = IKProblem(panda, [goal]).goal_errors(q)[0]
            assert (pos is None or pos <= 1e-9) and rot <= 1e-9
    assert list(axes_error.signatures) == loaded
