"""``solve_all`` and its default method ``memetic-all``: every IK solution of 6-D poses, checked against the
UR closed form (written here from the UR DH parameters and verified against our FK first) and against a
brute-force oracle (LM from thousands of random starts) on Kinova, a Puma560-type arm and a general 6R built
from DH tables; spread solutions on redundant arms; position and planar targets; bad input.

``scripts/bench_all_solutions.py`` imports the closed form and the oracle from this module.
"""

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import evoik_pin
from evoik_pin.errors import ConfigurationError, OptionError
from evoik_pin.papers.dh import DHRow, dh_to_urdf
from evoik_pin.problem import IKProblem, Target
from evoik_pin.solvers.lm import LevenbergMarquardt, solve_pairs, wrapping_joints
from evoik_pin.solvers.paper.analytic import planar2r_ik, puma_ik
from evoik_pin.solvers.paper.clustering import joint_differences, leader_clusters
from evoik_pin.solvers.search.all_solutions import DEFAULT_CLASS_RADIUS
from evoik_pin.solvers.search.solution_classes import SolutionClasses, class_representatives, farthest_point_selection

# ------------------------------------------------------------------------------------------ UR closed form
#: UR standard DH parameters (m): d1, a2, a3, d4, d5, d6 (Universal Robots' published tables).
UR_DH = {"ur3": (0.1519, -0.24365, -0.21325, 0.11235, 0.08535, 0.0819),
         "ur5": (0.089159, -0.425, -0.39225, 0.10915, 0.09465, 0.0823),
         "ur10": (0.1273, -0.612, -0.5723, 0.163941, 0.1157, 0.0922)}
UR_ALPHA = (np.pi / 2, 0.0, 0.0, np.pi / 2, -np.pi / 2, 0.0)
#: example-robot-data's UR ``base_link`` is the DH base frame turned by pi about z (checked below).
UR_BASE = pin.SE3(pin.utils.rotate("z", np.pi), np.zeros(3)).homogeneous


def _dh(a: float, alpha: float, d: float, theta: float) -> np.ndarray:
    ca, sa, ct, st_ = np.cos(alpha), np.sin(alpha), np.cos(theta), np.sin(theta)
    return np.array([[ct, -st_ * ca, st_ * sa, a * ct], [st_, ct * ca, -ct * sa, a * st_], [0.0, sa, ca, d],
                     [0.0, 0.0, 0.0, 1.0]])


def _ur_rows(p):
    d1, a2, a3, d4, d5, d6 = p
    return [(0.0, UR_ALPHA[0], d1), (a2, 0.0, 0.0), (a3, 0.0, 0.0), (0.0, UR_ALPHA[3], d4), (0.0, UR_ALPHA[4], d5),
            (0.0, 0.0, d6)]


def ur_dh_fk(name: str, q) -> np.ndarray:
    """Tip pose (4, 4) in the DH base frame of a UR arm at q (6,) rad: the product of the six DH transforms."""
    T = np.eye(4)
    for (a, alpha, d), theta in zip(_ur_rows(UR_DH[name]), q, strict=True):
        T = T @ _dh(a, alpha, d, theta)
    return T


def ur_closed_form(name: str, T: np.ndarray) -> list[np.ndarray]:
    """Every IK solution (rad, wrapped into [-pi, pi)) of a UR arm for the DH-frame pose T (4, 4), by the
    classical analytic solution (Hawkins 2013): shoulder (2) x wrist (2) x elbow (2) branches, up to 8;
    branches at an exact wrist singularity (sin t5 = 0, a continuum) are left out."""
    d1, a2, a3, d4, d5, d6 = UR_DH[name]
    rows = _ur_rows(UR_DH[name])
    p06 = T[:3, 3]
    p05 = p06 - d6 * T[:3, 2]
    r = np.hypot(p05[0], p05[1])
    out: list[np.ndarray] = []
    if r < abs(d4):
        return out
    for s1 in (1.0, -1.0):
        t1 = np.arctan2(p05[1], p05[0]) + s1 * np.arccos(d4 / r) + np.pi / 2
        c5 = (p06[0] * np.sin(t1) - p06[1] * np.cos(t1) - d4) / d6
        if abs(c5) > 1.0 + 1e-12:
            continue
        for s5 in (1.0, -1.0):
            t5 = s5 * np.arccos(np.clip(c5, -1.0, 1.0))
            if abs(np.sin(t5)) < 1e-12:
                continue
            t6 = np.arctan2((-T[0, 1] * np.sin(t1) + T[1, 1] * np.cos(t1)) / np.sin(t5),
                            (T[0, 0] * np.sin(t1) - T[1, 0] * np.cos(t1)) / np.sin(t5))
            T14 = np.linalg.inv(_dh(*rows[0], t1)) @ T @ np.linalg.inv(_dh(*rows[4], t5) @ _dh(*rows[5], t6))
            p13 = T14 @ np.array([0.0, -d4, 0.0, 1.0])
            L2 = p13[0] ** 2 + p13[1] ** 2
            c3 = (L2 - a2 * a2 - a3 * a3) / (2 * a2 * a3)
            if abs(c3) > 1.0 + 1e-12:
                continue
            for s3 in (1.0, -1.0):
                t3 = s3 * np.arccos(np.clip(c3, -1.0, 1.0))
                t2 = np.arctan2(-p13[1], -p13[0]) - np.arcsin(np.clip(-a3 * np.sin(t3) / np.sqrt(L2), -1.0, 1.0))
                T34 = np.linalg.inv(_dh(*rows[1], t2) @ _dh(*rows[2], t3)) @ T14
                t4 = np.arctan2(T34[1, 0], T34[0, 0])
                out.append((np.array([t1, t2, t3, t4, t5, t6]) + np.pi) % (2 * np.pi) - np.pi)
    return out


def distinct(robot, Q, radius: float = DEFAULT_CLASS_RADIUS) -> np.ndarray:
    """One row per class of ``Q`` (wrapped joint distance on the robot's full-turn joints, within ``radius``)."""
    Q = np.asarray(Q, dtype=float).reshape(-1, robot.n)
    if not len(Q):
        return Q
    leaders, _ = leader_clusters(Q, np.zeros(len(Q)), radius, wrapping_joints(robot, robot.lower, robot.upper))
    return Q[leaders]


def ur_solutions(robot, T: pin.SE3) -> np.ndarray:
    """The closed-form solution classes of a UR arm (robot.name ur3 / ur5 / ur10) for a base_link pose T."""
    return distinct(robot, ur_closed_form(robot.name, np.linalg.inv(UR_BASE) @ T.homogeneous))


# ------------------------------------------------------------------------------------------ oracle
def oracle_solutions(robot, T, starts: int = 3000, seed: int = 0) -> tuple[np.ndarray, float]:
    """Brute force: LM from ``starts`` uniform random configurations (100 steps each), the converged ones
    clustered, each cluster refined by a patient LM run to 1e-12, clustered again.

    Returns (solution classes (M, n), largest refined error (m + rad): above 1e-10 the pose is degenerate,
    its solutions not isolated)."""
    target = Target.coerce(T)
    lo, hi = robot.lower, robot.upper
    S = robot.random_configurations(starts, np.random.default_rng(seed))
    out = solve_pairs(robot, S, [target] * starts, lo, hi, 1e-6, 1e-6, max_iterations=100)
    lm = LevenbergMarquardt(IKProblem(robot, target, tolerance=1e-12, rotation_tolerance=1e-12), stall_window=20,
                            stall_ratio=0.9)
    refined = [lm.run(q, 300) for q in distinct(robot, out.q[out.converged])]
    worst = max((o.error for o in refined), default=0.0)
    return distinct(robot, [o.q for o in refined]), worst


def matched(robot, reference: np.ndarray, found: np.ndarray, radius: float = DEFAULT_CLASS_RADIUS) -> tuple[int, int]:
    """(classes of ``reference`` that some row of ``found`` reaches within ``radius``, rows of ``found`` that
    match no reference class), wrapped distances."""
    wrap = wrapping_joints(robot, robot.lower, robot.upper)
    reference, found = np.asarray(reference).reshape(-1, robot.n), np.asarray(found).reshape(-1, robot.n)
    if not len(reference) or not len(found):
        return 0, len(found)
    D = np.linalg.norm(joint_differences(reference[:, None], found[None], wrap), axis=2)
    return int((D.min(axis=1) <= radius).sum()), int((D.min(axis=0) > radius).sum())


# ------------------------------------------------------------------------------------------ arms
PUMA560 = [DHRow(0.0, np.pi / 2, 0.0), DHRow(0.4318, 0.0, 0.0), DHRow(0.0203, -np.pi / 2, 0.15005),
           DHRow(0.0, np.pi / 2, 0.4318), DHRow(0.0, -np.pi / 2, 0.0), DHRow(0.0, 0.0, 0.0)]
#: A general 6R (no three axes meeting or parallel; random DH rows, standard convention): up to 12 real
#: solutions on the poses below.
GENERAL6R = [DHRow(0.0879, 1.9685, 0.155), DHRow(0.4685, -1.1793, -0.0773), DHRow(0.1081, 2.326, 0.1556),
             DHRow(0.8607, -1.4935, 0.0678), DHRow(0.3369, -2.1241, 0.3527), DHRow(0.3162, 0.3729, -0.187)]


def dh_arm(name: str):
    return evoik_pin.load_robot(dh_to_urdf(name, {"puma560": PUMA560, "general6r": GENERAL6R}[name]))


def assert_valid(robot, solutions, T, tol: float = 1e-6, radius: float = DEFAULT_CLASS_RADIUS) -> None:
    """Every solution inside the bounds, within the tolerances by Pinocchio's FK, no two of one class."""
    Q = np.array([s.q for s in solutions]).reshape(-1, robot.n)
    assert np.all(Q >= robot.lower) and np.all(Q <= robot.upper)
    target = Target.coerce(T).se3()
    for q in Q:
        err = pin.log6(target.actInv(robot.fk(q))).vector
        assert np.linalg.norm(err[:3]) <= tol and np.linalg.norm(err[3:]) <= tol
    wrap = wrapping_joints(robot, robot.lower, robot.upper)
    for i in range(len(Q) - 1):
        assert np.linalg.norm(joint_differences(Q[i + 1:], Q[i], wrap), axis=1).min() > radius


# ------------------------------------------------------------------------------------------ tests
@pytest.mark.parametrize("name", ["ur5", "ur10"])
@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_ur_closed_form_agrees_with_our_fk(name, seed):
    robot = evoik_pin.load_robot(name)
    q = robot.random_configurations(1, np.random.default_rng(seed))[0]
    T = robot.fk(q).homogeneous
    assert np.abs(UR_BASE @ ur_dh_fk(name, q) - T).max() < 1e-9  # the DH table is our arm
    sols = ur_closed_form(name, np.linalg.inv(UR_BASE) @ T)
    wrap = np.ones(6, dtype=bool)
    # q is among them, to what a pose known to 1e-9 (the DH table's agreement above) fixes of the joints: 1e-9 over
    # the Jacobian's smallest singular value, which near a singularity (an elbow almost straight, sin t5 small) is
    # ~1e-3 (seed 955: joints 4.3e-7 apart for poses 1e-11 apart)
    sigma = np.linalg.svd(robot.jacobian(q, "world"), compute_uv=False).min()
    assert min(np.abs(joint_differences(s, q, wrap)).max() for s in sols) < max(1e-7, 1e-9 / sigma)
    for s in sols:  # and every one reaches the pose
        assert np.abs(robot.fk(s).homogeneous - T).max() < 1e-9


@pytest.mark.parametrize("name", ["ur5", "ur10"])
def test_ur_poses_give_the_closed_form_set(name):
    robot = evoik_pin.load_robot(name)
    rng = np.random.default_rng(5)
    sizes = []
    for _ in range(10):
        T = robot.fk(robot.random_configurations(1, rng)[0])
        reference = ur_solutions(robot, T)
        sols = evoik_pin.solve_all(robot, T, seed=0)
        assert_valid(robot, sols, T)
        found = [s.q for s in sols]
        assert matched(robot, reference, found) == (len(reference), 0), sols.message
        sizes.append(len(sols))
    assert max(sizes) == 8  # most UR poses have all eight


def test_a_near_singular_wrist_still_gives_one_answer_per_solution():
    """t5 = 3e-4: LM runs stop anywhere along a flat valley that meets 1e-6; each is one solution."""
    robot = evoik_pin.load_robot("ur5")
    T = robot.fk(np.array([0.976, 1.285, 2.905, -5.375, 3e-4, 3.067]))
    reference = ur_solutions(robot, T)
    sols = evoik_pin.solve_all(robot, T, seed=0)
    assert_valid(robot, sols, T)
    assert len(reference) == 6 and matched(robot, reference, [s.q for s in sols]) == (6, 0), sols.message


def test_representatives_are_the_copies_nearest_q0_and_come_nearest_first():
    robot = evoik_pin.load_robot("ur5")
    q = np.array([-4.0, 1.0, -2.0, 5.0, -1.0, 3.5])  # beyond +-pi on several +-2 pi joints
    T = robot.fk(q)
    sols = evoik_pin.solve_all(robot, T, q0=q, seed=0)
    assert np.abs(sols[0].q - q).max() < 1e-7  # q0's own class, as q0 itself
    distances = [np.linalg.norm(s.q - q) for s in sols]
    assert distances == sorted(distances)
    wrap = wrapping_joints(robot, robot.lower, robot.upper)
    for s in sols:
        for j in np.flatnonzero(wrap):
            for shift in (-2 * np.pi, 2 * np.pi):  # no other copy inside the box is nearer to q0
                other = s.q[j] + shift
                assert not (robot.lower[j] <= other <= robot.upper[j]) or abs(other - q[j]) >= abs(s.q[j] - q[j])
    plain = evoik_pin.solve_all(robot, T, seed=0)  # no q0: the copies nearest zero, nearest zero first
    assert all(np.abs(s.q[wrap]).max() <= np.pi for s in plain)
    assert [np.linalg.norm(s.q) for s in plain] == sorted(np.linalg.norm(s.q) for s in plain)


@pytest.mark.parametrize("arm, seed", [("kinova", 1), ("kinova", 2), ("puma560", 3), ("puma560", 4), ("general6r", 46)])
def test_six_joint_arms_match_the_brute_force_oracle(arm, seed):
    robot = evoik_pin.load_robot(arm) if arm == "kinova" else dh_arm(arm)
    T = robot.fk(robot.random_configurations(2, np.random.default_rng(seed))[-1])
    reference, worst = oracle_solutions(robot, T)
    assert worst < 1e-10  # isolated solutions: a fair reference
    sols = evoik_pin.solve_all(robot, T, seed=0)
    assert_valid(robot, sols, T)
    assert matched(robot, reference, [s.q for s in sols]) == (len(reference), 0), sols.message
    if arm == "general6r":
        assert len(reference) > 8  # more than any 6R with a spherical wrist or UR geometry can have


def test_redundant_arms_get_count_spread_solutions():
    robot = evoik_pin.load_robot("panda")
    T = robot.fk(robot.random_configurations(1, np.random.default_rng(0))[0])
    sols = evoik_pin.solve_all(robot, T, seed=0)
    assert len(sols) == 8  # default count
    assert_valid(robot, sols, T)
    five = evoik_pin.solve_all(robot, T, seed=0, count=5)
    assert len(five) == 5
    assert_valid(robot, five, T)
    Q = np.array([s.q for s in five])
    wrap = wrapping_joints(robot, robot.lower, robot.upper)
    smallest = min(np.linalg.norm(joint_differences(Q[i + 1:], Q[i], wrap), axis=1).min() for i in range(4))
    reported = five.result.history["min_pairwise_distance"][0]
    assert reported == pytest.approx(smallest) and f"{smallest:.3g} rad" in five.message
    assert smallest > 0.5  # spread over the self-motion manifold, not one family


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), count=st.integers(1, 12))
def test_farthest_point_selection_picks_the_farthest_each_time(seed, count):
    rng = np.random.default_rng(seed)
    Q = rng.uniform(-np.pi, np.pi, size=(20, 3))
    wrap = np.array([True, False, True])
    chosen = farthest_point_selection(Q, count, 4, wrap)
    assert chosen[0] == 4 and len(set(chosen.tolist())) == len(chosen) == min(count, 20)
    for k in range(1, len(chosen)):
        nearest = np.min([np.linalg.norm(joint_differences(Q, Q[c], wrap), axis=1) for c in chosen[:k]], axis=0)
        assert nearest[chosen[k]] == pytest.approx(nearest.max())


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_class_representatives_stay_in_the_box_and_nearest_the_reference(seed):
    rng = np.random.default_rng(seed)
    lower, upper = np.array([-2 * np.pi, -np.pi, -1.0, -3 * np.pi]), np.array([2 * np.pi, np.pi, 2.0, np.pi])
    wrap = upper - lower >= 2 * np.pi
    Q = rng.uniform(lower, upper, size=(10, 4))
    reference = rng.uniform(-7, 7, size=4)
    R = class_representatives(Q, reference, lower, upper, wrap)
    assert np.all(R >= lower) and np.all(R <= upper)
    assert np.array_equal(R[:, ~wrap], Q[:, ~wrap])
    turns = (R - Q)[:, wrap] / (2 * np.pi)
    assert np.allclose(turns, np.round(turns), atol=1e-9)  # the same angles
    for shift in (-2 * np.pi, 2 * np.pi):
        other = R + shift
        inside = (other >= lower) & (other <= upper)
        assert np.all(~inside[:, wrap] | (np.abs(other - reference) >= np.abs(R - reference) - 1e-12)[:, wrap])


@pytest.mark.parametrize("refined", [False, True])
def test_solution_classes_count_hits_and_open_each_class_once(refined):
    robot = evoik_pin.load_robot("ur5")
    q = np.array([0.3, -1.0, 1.2, -0.5, 0.8, 0.2])
    problem = IKProblem(robot, Target.coerce(robot.fk(q)))
    refine = LevenbergMarquardt(problem) if refined else None
    classes = SolutionClasses(problem, wrapping_joints(robot, robot.lower, robot.upper), 1e-3, refine)
    Q = np.array([q, q + 2e-4, q + [2 * np.pi, 0, 0, 0, 0, 0]])  # one class: the same pose 2 pi apart, and a twin
    assert classes.add(Q[:1], np.zeros(1)) == [0]
    assert classes.add(Q, np.zeros(3)) == []  # a batch bringing nothing new
    assert classes.add(np.empty((0, 6)), np.zeros(0)) == []
    assert classes.add(Q[1:], np.zeros(2)) == []
    assert len(classes) == 1 and classes.hits == [6]
    assert classes.add((q + 0.5)[None], np.zeros(1)) == [1] and classes.hits == [6, 1]


@pytest.mark.parametrize("count", [0, -2, 1.5, True])
def test_count_below_one_is_an_option_error(count):
    with pytest.raises(OptionError, match="count must be an integer >= 1"):
        evoik_pin.solve_all("planar2r", Target.planar_target(0.2, 0.2), count=count)


def test_position_and_planar_targets_keep_working():
    planar = evoik_pin.solve_all("planar2r", Target.planar_target(0.2, 0.2), seed=0)
    assert matched(evoik_pin.load_robot("planar2r"), planar2r_ik(0.2, 0.2), [s.q for s in planar]) == (2, 0)
    point = np.array([-0.525, 0.393, -0.465])
    puma = evoik_pin.solve_all("puma3r", point, seed=0)
    assert len(puma_ik(point)) == 4 and matched(evoik_pin.load_robot("puma3r"), puma_ik(point),
                                                 [s.q for s in puma]) == (4, 0)
    assert all(s.orientation_error is None and s.position_error <= 1e-6 for s in puma)
    spread = evoik_pin.solve_all("ur5", np.array([0.3, 0.2, 0.4]), seed=0, count=3)  # 6 joints, 3 rows
    assert len(spread) == 3 and "self-motion" in spread.message


def test_an_unreachable_pose_gives_an_empty_list_that_says_why():
    sols = evoik_pin.solve_all("puma3r", [2.0, 0.0, 0.0], seed=0, timeout=0.005)
    assert sols == [] and isinstance(sols, list) and not sols
    assert sols.result is not None and not sols.result.success
    assert "no solution" in sols.message and "out of reach" in sols.message and "1.12 m" in sols.message


def test_the_default_is_memetic_all_and_hga_stays_the_papers_method():
    default = evoik_pin.solve_all("planar2r", [0.2, 0.2, 0.0], seed=0)
    assert default.result.method == "memetic-all" and all(s.method == "memetic-all" for s in default)
    hga = evoik_pin.solve_all("planar2r", [0.2, 0.2, 0.0], method="hga", seed=3, population=200)
    assert hga.result.method == "hga" and all(s.method == "hga" for s in hga)
    direct = evoik_pin.solve("planar2r", [0.2, 0.2, 0.0], method="hga", seed=3, population=200)
    assert [s.q.tolist() for s in hga] == [s.q.tolist() for s in direct.solutions]  # the same search


def test_same_seed_same_solutions():
    robot = evoik_pin.load_robot("kinova")
    T = robot.fk(robot.random_configurations(1, np.random.default_rng(9))[0])
    a = evoik_pin.solve_all(robot, T, seed=1, timeout=None)
    b = evoik_pin.solve_all(robot, T, seed=1, timeout=None)
    assert [s.q.tolist() for s in a] == [s.q.tolist() for s in b] and len(a) > 0


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_the_readme_viewer_example_draws_every_solution(name):
    from evoik_pin.viz import Viewer

    robot = evoik_pin.load_robot(name)
    T = robot.fk(robot.random_configurations(1, np.random.default_rng(0))[0])
    with Viewer(robot) as v:
        nodes = v.show_solutions(evoik_pin.solve_all(robot, T, seed=0))  # the README's line
        assert nodes == [f"solutions/{k}" for k in range(8)]
        far = evoik_pin.solve_all(robot, [5.0, 0.0, 0.0], seed=0, timeout=0.002)
        with pytest.raises(ConfigurationError, match=r"no configurations given .*no solution.*out of reach"):
            v.show_solutions(far)  # an empty list: a clear error quoting why it is empty
