#!/usr/bin/env python
"""Issue 23's goal sets, ``prefer=`` and preferences, measured (docs/BENCHMARKS.md, "Goal sets, prefer and
preferences").

    python scripts/bench_goal_kinds_prefer.py              # 200 targets per part, Panda and UR10, stdout
    python scripts/bench_goal_kinds_prefer.py --n 20       # quick
    python scripts/bench_goal_kinds_prefer.py --robots all --q0 both --parts prefer sets --n 100
                                                           # issue 32: every arm TRAC-IK loads, both q0 kinds

Parts (every target from forward kinematics of a configuration drawn uniformly in the limits, q0 drawn
independently the same way; seeds fixed):

1. ``prefer="nearest"`` on each arm of ``--robots`` (default Panda and UR10; ``all``: :data:`ARMS`) against
   pytracik's TRAC-IK ``solver_type="Distance"`` (5 ms, epsilon 1e-5; joint limits set from our model, targets in
   its base frame, as scripts/bench_ik.py drives it) from the same q0: success of each (ours: 1e-6 m and rad;
   TRAC-IK's answers judged by our forward kinematics by its own rule, every component of the position error and of
   the rotation vector within its epsilon 1e-5 (in parentheses: the norms within 1e-5, the rule of the runs before
   2026-11-28), continuous joints, which TRAC-IK leaves unbounded, wrapped into [-pi, pi] first), the share of the
   targets both solve on which our answer is no farther from q0 than its answer (Euclidean norm of q - q0, joints
   whose range spans a full turn at their turn nearest q0 inside the limits for both, a 1e-6 rad slack), TRAC-IK's
   answer taken to the exact solution (1e-12) nearest it (:func:`exact`: LM from the answer, a move of about its
   epsilon, so that two answers of one branch compare equal; near a singularity, where LM stalls there and a 1e-5
   pose band spans up to 1e-2 rad of joint space, the nearest of LM's solutions from starts around it, so that
   neither its band's width counts for it nor a nearer (more dexterous) exact solution it approximates against it;
   the answer as it is where none converges, counted), ours as they are (1e-6); median wall time
   per target (all targets) and the ratio. ``prefer="manipulability"`` against ``"Manip1"`` likewise: the share of
   the targets both solve on which our answer's sqrt(det(J J^T)) (6 x n, LOCAL_WORLD_ALIGNED; computed as the
   product of J's singular values, TRAC-IK's Manip1 measure, which is sqrt(det(J^T J)) on SO-ARM's 5 joints) is at
   least its own (1e-9 relative slack). ``--q0 random`` (the default): q0 drawn uniformly in the limits,
   independently of the target; ``--q0 near``: q0 near a known answer, the configuration the target was made from
   plus Gaussian noise (``--near-sigma``, 0.1 rad by default, per joint) clipped into the limits; ``--q0 both``:
   both, one row each. ``--trac-eps 1e-6`` makes TRAC-IK itself work to that accuracy. Beside each share, the
   share against TRAC-IK's answers as they are (near a singularity
   TRAC-IK's 1e-5 band lets its answer sit nearer q0 than every exact solution of the pose, on UR arms, whose closed
   form lists them all, a distance no answer exact to 1e-6 can match); on UR arms, the share of our answers with no
   exact solution nearer q0 (1e-6 rad slack): what "nearest" means, decided without TRAC-IK.
2. Goal sets on each arm of ``--robots``: 10 grasps of which 3 are reachable (forward kinematics of random
   configurations) and 7 are not (positions 1.2 to 1.6 m from the base for Panda, the original protocol; for the
   other arms 1.1 to 1.5 times the arm's reach, the largest tip distance from the base over 4000 random
   configurations, so beyond it; random orientations), shuffled: the share that finds a reachable one, and its
   median wall time against single-pose solves (``[Pose(tip, T)]``, the reachable grasp) of the same targets.
3. Preferences never cost success: the single-pose problems of each arm of ``--robots`` with ``Posture(mid-range)``
   or ``JointLimitMargin(0.1 rad)`` added: success with and without.

Prints one markdown section (``run(args)`` returns it) with the command, the date, the machine and its load.
"""

from __future__ import annotations

import argparse
import datetime
import functools
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

import evoik_pin as ev
from evoik_pin.goals import JointLimitMargin, Pose, Posture
from evoik_pin.solvers.lm import LevenbergMarquardt, wrapping_joints
from evoik_pin.solvers.search.prefer import BRANCHES_PREFER_TIMEOUT, DEFAULT_PREFER_TIMEOUT, nearest_turn

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_ik import ROBOTS, cpu_model, quiet_output, wrap_continuous  # noqa: E402
from bench_ik import load as load_bench  # noqa: E402

TOL = 1e-6
TRAC_EPS = 1e-5

#: Issue 32's arms: every example-robot-data arm TRAC-IK loads. name -> (load_robot source, base, tip), as
#: scripts/bench_ik.py's ROBOTS (whose chains are taken as they are); None base/tip = the arm's defaults.
ARMS: dict[str, tuple[str, str | None, str | None]] = {
    "panda": ROBOTS["panda"],
    "ur3": ("ur3", None, None),
    "ur5": ROBOTS["ur5"],
    "ur10": ("ur10", None, None),
    "kinova": ROBOTS["kinova"],
    "xarm": ROBOTS["xarm"],
    "z1": ROBOTS["z1"],
    "so_arm": ("so_arm", None, None),
    "baxter_left": ROBOTS["baxter_left"],
    "pr2_left": ("pr2_description/urdf/pr2.urdf", "torso_lift_link", "l_gripper_tool_frame"),
    "tiago_dual_left": ROBOTS["tiago_dual_left"],
}
DEFAULT_ROBOTS = ["panda", "ur10"]


def load_arm(name: str) -> ev.Robot:
    """One of :data:`ARMS`, loaded as scripts/bench_ik.py loads its robots (URDF paths inside example-robot-data)."""
    if name in ROBOTS and ROBOTS[name] == ARMS[name]:
        return load_bench(name)
    source, base, tip = ARMS[name]
    if source.endswith(".urdf"):
        from evoik_pin.robot import example_robot_data_dir

        source = str(example_robot_data_dir() / source)
    return ev.load_robot(source, base=base, tip=tip)


def resolve_robots(names: list[str] | None) -> list[str]:
    """``--robots``' names (``all``: every arm of :data:`ARMS`), checked."""
    if not names:
        return list(DEFAULT_ROBOTS)
    if names == ["all"]:
        return list(ARMS)
    unknown = [n for n in names if n not in ARMS]
    if unknown:
        raise SystemExit(f"unknown robots {unknown}; choose from {list(ARMS)} or 'all'")
    return names


class Trac:
    """pytracik's TRAC-IK in one solve type, driven as scripts/bench_ik.py drives it."""

    def __init__(self, robot, solver_type: str, timeout: float = 0.005) -> None:
        import pytracik
        from trac_ik import TracIK

        with quiet_output():
            solver = TracIK(robot.base, robot.tip, str(robot.urdf_path), timeout=timeout, epsilon=TRAC_EPS,
                            solver_type=solver_type)
        assert solver.dof == robot.n, (solver.dof, robot.n)
        solver.joint_limits = (robot.lower, robot.upper)
        self._ik, self._handle, self._robot = pytracik.ik, solver._ik_solver, robot
        q = (robot.lower + robot.upper) / 2
        p, R = solver.fk(q)
        T = robot.fk(q)
        assert np.abs(p - T.translation).max() < 1e-9 and np.abs(R - T.rotation).max() < 1e-9, "frames differ"

    def __call__(self, T: pin.SE3, q0: np.ndarray):
        quat = pin.Quaternion(T.rotation)
        x, y, z = T.translation
        r = self._ik(self._handle, q0, x, y, z, quat.x, quat.y, quat.z, quat.w)
        # continuous joints: TRAC-IK leaves them unbounded whatever limits it is given; wrapped into [-pi, pi]
        # (ours) as scripts/bench_ik.py judges them
        return wrap_continuous(self._robot, r[1:]) if r[0] >= 0 else None


def met(robot, T: pin.SE3, q, tol: float) -> bool:
    if q is None or not robot.within_bounds(q, 1e-9):
        return False
    Tq = robot.fk(q)
    return (np.linalg.norm(Tq.translation - T.translation) <= tol
            and np.linalg.norm(pin.log3(T.rotation.T @ Tq.rotation)) <= tol)


def met_own(robot, T: pin.SE3, q, eps: float | None = None) -> bool:
    """TRAC-IK's own test of its answer: every component of the position error and of the rotation vector (base
    frame, KDL's ``diff``) within ``eps`` (1e-9 slack): norms up to sqrt(3) eps, which the 1e-5 norm rule rejects."""
    eps = TRAC_EPS if eps is None else eps
    if q is None or not robot.within_bounds(q, 1e-9):
        return False
    Tq = robot.fk(q)
    rot = T.rotation @ pin.log3(T.rotation.T @ Tq.rotation)
    return bool(np.abs(Tq.translation - T.translation).max() <= eps + 1e-9 and np.abs(rot).max() <= eps + 1e-9)


def lm_for(robot, T):
    """LM on the pose T to 1e-12 (m and rad): :func:`exact`'s."""
    return LevenbergMarquardt(ev.make_problem(robot, T, tolerance=1e-12)[0])


#: Starts around an answer LM cannot take to an exact solution from the answer itself (near a singularity, where a
#: 1e-5 pose band spans up to 1e-2 rad of joint space): this many per scale (rad per joint, Gaussian), from which
#: :func:`exact` takes the converged solution nearest the answer.
NEAREST_EXACT_SCALES, NEAREST_EXACT_STARTS = (1e-3, 3e-3, 1e-2, 3e-2), 8


def exact(lm, q, flag: bool = False, seed: int = 0):
    """The exact solution (``lm``: :func:`lm_for`, 1e-12) nearest TRAC-IK's answer ``q`` (within its epsilon,
    1e-5), so that two answers of one branch compare equal and its tolerance band's width is no gain: LM from ``q``
    itself (a few steps, ~1e-5 rad), else (near a singularity LM stalls at ~1e-5, and the nearest exact solution may
    lie 1e-2 rad away) the nearest of LM's solutions from :data:`NEAREST_EXACT_STARTS` starts per scale of
    :data:`NEAREST_EXACT_SCALES` around it (``seed``: their draws); ``q`` itself where none converges. ``flag``: with
    0 (LM from ``q`` converged), 1 (a solution found around ``q``) or 2 (none: ``q`` as it is)."""
    lower, upper = lm.problem.lower, lm.problem.upper
    out = lm.run(np.clip(q, lower, upper), 30)
    if out.converged:
        return (out.q, 0) if flag else out.q
    rng = np.random.default_rng([seed, 3])
    best, how = q, 2
    for scale in NEAREST_EXACT_SCALES:
        for _ in range(NEAREST_EXACT_STARTS):
            o = lm.run(np.clip(q + rng.normal(0.0, scale, q.shape), lower, upper), 30)
            if o.converged and (how == 2 or np.linalg.norm(o.q - q) < np.linalg.norm(best - q)):
                best, how = o.q, 1
    return (best, how) if flag else best


#: Arms whose every IK solution the UR closed form of tests/test_all_solutions.py lists (robot.name).
UR_ARMS = ("ur3", "ur5", "ur10")


@functools.cache
def ur_closed_form_module():
    """tests/test_all_solutions.py, where the UR closed form lives with the tests that verify it (loaded once)."""
    import importlib.util

    path = Path(__file__).resolve().parents[1] / "tests" / "test_all_solutions.py"
    spec = importlib.util.spec_from_file_location("test_all_solutions", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def manip(robot, q) -> float:
    """The product of the singular values of the 6 x n Jacobian (LOCAL_WORLD_ALIGNED): TRAC-IK's Manip1 measure;
    ``sqrt(det(J J^T))`` for n >= 6, ``sqrt(det(J^T J))`` for fewer joints (SO-ARM's 5), where det(J J^T) is 0."""
    J = robot.jacobian(q, "world")
    return float(np.prod(np.linalg.svd(J, compute_uv=False)))


def problems(robot, n: int, seed: int, q0: str = "random", sigma: float = 0.1):
    """(targets, q0s): targets the forward kinematics of uniform configurations; q0s drawn uniformly (``random``)
    or near the target's own configuration (``near``: Gaussian noise of ``sigma`` rad per joint, clipped into the
    limits). The targets and the random q0s do not depend on ``q0``."""
    rng = np.random.default_rng(seed)
    Q = robot.random_configurations(n, rng)
    Q0 = robot.random_configurations(n, rng)
    if q0 == "near":
        noise = np.random.default_rng([seed, 1]).normal(0.0, sigma, size=Q.shape)
        Q0 = np.clip(Q + noise, robot.lower, robot.upper)
    elif q0 != "random":
        raise ValueError(f"q0 must be 'random' or 'near', not {q0!r}")
    return [robot.fk(q) for q in Q], Q0


def bench_prefer(name: str, n: int, seed: int, log, timeout: float | None = None, q0_kind: str = "random",
                 sigma: float = 0.1) -> list[str]:
    robot = load_arm(name)
    ev.prepare(robot)
    targets, Q0 = problems(robot, n, seed, q0_kind, sigma)
    wrap = wrapping_joints(robot, robot.lower, robot.upper)
    extra = {} if timeout is None else {"timeout": timeout}
    rows = []
    for prefer, stype in (("nearest", "Distance"), ("manipulability", "Manip1")):
        trac = Trac(robot, stype)
        ev.solve(robot, targets[0], q0=Q0[0], prefer=prefer, seed=0, **extra)  # warm
        ours, theirs, t_ours, t_theirs, by_norm = [], [], [], [], 0
        raw_theirs, how_theirs = [], []  # TRAC-IK's answers as it gives them; how exact() took them
        for i, (T, q0) in enumerate(zip(targets, Q0, strict=True)):
            t = time.perf_counter()
            r = ev.solve(robot, T, q0=q0, prefer=prefer, seed=i, **extra)
            t_ours.append(time.perf_counter() - t)
            ours.append(r.q if r.success else None)
            t = time.perf_counter()
            q = trac(T, q0)
            t_theirs.append(time.perf_counter() - t)
            raw_theirs.append(q if met_own(robot, T, q) else None)
            by_norm += met(robot, T, q, TRAC_EPS)
        for i, T in enumerate(targets):  # TRAC-IK's answers at the exact solution nearest each (exact())
            q, k = (None, 0) if raw_theirs[i] is None else exact(lm_for(robot, T), raw_theirs[i], True, i)
            theirs.append(q)
            how_theirs.append(k)
        both = [i for i in range(n) if ours[i] is not None and theirs[i] is not None]

        def dist(q, q0):
            return float(np.linalg.norm(nearest_turn(q, q0, robot.lower, robot.upper, wrap) - q0))

        def no_worse(a, b, i, nearest=prefer == "nearest"):
            """Whether answer a is no farther from q0 (no less dexterous) than answer b, on target i."""
            if nearest:
                return dist(a, Q0[i]) <= dist(b, Q0[i]) + 1e-6
            return manip(robot, a) >= manip(robot, b) * (1 - 1e-9)

        better = [no_worse(ours[i], theirs[i], i) for i in both]
        raw_better = [no_worse(ours[i], raw_theirs[i], i) for i in both]
        if prefer == "nearest":
            med = (np.median([dist(ours[i], Q0[i]) for i in both]), np.median([dist(theirs[i], Q0[i]) for i in both]))
            what = "no farther from q0"
        else:
            med = (np.median([manip(robot, ours[i]) for i in both]), np.median([manip(robot, theirs[i]) for i in both]))
            what = "at least as dexterous"
        missed = [i for i, ok in zip(both, better, strict=True) if not ok]
        s_ours = sum(q is not None for q in ours) / n
        s_theirs = sum(q is not None for q in theirs) / n
        mo, mt = np.median(t_ours) * 1e3, np.median(t_theirs) * 1e3
        share = float(np.mean(better)) if better else float("nan")
        oracle = ""
        if prefer == "nearest" and robot.name in UR_ARMS:  # every exact solution known: the nearest is decidable
            ur_solutions = ur_closed_form_module().ur_solutions
            solved = [i for i in range(n) if ours[i] is not None]
            nearest = [dist(ours[i], Q0[i]) <= min(dist(s, Q0[i]) for s in ur_solutions(robot, targets[i])) + 1e-6
                       for i in solved]
            oracle = f"; the closed form: no exact solution nearer on {100 * np.mean(nearest):.1f} %"
        misses = [m for m, bad in (("success", s_ours < s_theirs), ("share", not share >= 0.95),
                                   ("time", mo / mt > 0.2)) if bad]
        # TRAC-IK's answers LM took to an exact solution only from starts around them, and those it did not
        near_t, off_t = (sum(how_theirs[i] == k for i in both) for k in (1, 2))
        raw_share = float(np.mean(raw_better)) if raw_better else float("nan")
        row = (f"| {name} | {q0_kind} | {prefer} vs {stype} | {100 * s_ours:.1f} % | {100 * s_theirs:.1f} % "
               f"({100 * by_norm / n:.1f} %) | "
               f"{100 * share:.1f} % {what} ({len(both)} both solve; {len(missed)} missed; TRAC-IK's answers at the "
               f"exact solution nearest each, found from starts around it for {near_t}, none for {off_t}; "
               f"TRAC-IK's answers as they are: {100 * raw_share:.1f} %{oracle}) | "
               f"{med[0]:.4g} / {med[1]:.4g} | {mo:.3f} / {mt:.3f} ms | {mo / mt:.2f}x ({mo / 5:.2f}x of 5 ms) | "
               f"{'yes' if not misses else 'no: ' + ', '.join(misses)} |")
        log(row)
        rows.append(row)
    return rows


def reach(robot, seed: int = 0, count: int = 4000) -> float:
    """The arm's reach: the largest tip distance from the base over ``count`` random configurations (m)."""
    Q = robot.random_configurations(count, np.random.default_rng([seed, 2]))
    return max(float(np.linalg.norm(robot.fk(q).translation)) for q in Q)


def far_band(name: str, robot) -> tuple[float, float]:
    """Where part 2's unreachable grasps lie (m from the base): Panda's original 1.2 to 1.6 m; 1.1 to 1.5 times
    the reach for the other arms."""
    if name == "panda":
        return 1.2, 1.6
    r = reach(robot)
    return 1.1 * r, 1.5 * r


def goal_set_problems(robot, n: int, seed: int, band: tuple[float, float] = (1.2, 1.6)) -> tuple[list, list]:
    """Part 2's problems: (``n`` goal lists ``[Pose(tip, [10 grasps])]``, 3 reachable and 7 not (``band`` m from the
    base), shuffled; the single-pose lists ``[Pose(tip, T)]`` of each set's first reachable grasp)."""
    rng = np.random.default_rng(seed)
    sets, singles = [], []
    for _ in range(n):
        reach = [robot.fk(q) for q in robot.random_configurations(3, rng)]
        far = []
        for _ in range(7):
            d = rng.normal(size=3)
            d[2] = abs(d[2])
            p = d / np.linalg.norm(d) * rng.uniform(*band)
            far.append(pin.SE3(pin.exp3(rng.normal(size=3)), p))
        members = reach + far
        order = rng.permutation(10)
        sets.append([Pose(robot.tip, [members[k] for k in order])])
        singles.append([Pose(robot.tip, reach[0])])
    return sets, singles


def bench_sets(n: int, seed: int, log, name: str = "panda") -> list[str]:
    robot = load_arm(name)
    ev.prepare(robot)
    band = far_band(name, robot)
    sets, singles = goal_set_problems(robot, n, seed, band)
    ev.solve(robot, sets[0], seed=0)
    ok, t_set, t_one, ok_one = 0, [], [], 0
    for i, (gs, g1) in enumerate(zip(sets, singles, strict=True)):
        t = time.perf_counter()
        r = ev.solve(robot, gs, seed=i)
        t_set.append(time.perf_counter() - t)
        ok += r.success and r.chosen[0] is not None
        t = time.perf_counter()
        r1 = ev.solve(robot, g1, seed=i)
        t_one.append(time.perf_counter() - t)
        ok_one += r1.success
    ms, m1 = np.median(t_set) * 1e3, np.median(t_one) * 1e3
    row = (f"| {name} | 10 grasps, 7 unreachable ({band[0]:.2f}-{band[1]:.2f} m) | {100 * ok / n:.1f} % | "
           f"{ms:.3f} ms | single pose: {100 * ok_one / n:.1f} %, {m1:.3f} ms | {ms / m1:.2f}x | "
           f"{'yes' if ms / m1 < 3 else 'no'} |")
    log(row)
    return [row]


def bench_preferences(name: str, n: int, seed: int, log) -> list[str]:
    robot = load_arm(name)
    ev.prepare(robot)
    targets, _ = problems(robot, n, seed)
    mid = (robot.lower + robot.upper) / 2
    cases = {"goals alone": [], "+ Posture(mid-range, 0.1)": [Posture(mid, 0.1)],
             "+ JointLimitMargin(0.1 rad)": [JointLimitMargin(0.1)]}
    out = []
    for label, prefs in cases.items():
        ok, times = 0, []
        for i, T in enumerate(targets):
            t = time.perf_counter()
            r = ev.solve(robot, [Pose(robot.tip, T), *prefs], seed=i)
            times.append(time.perf_counter() - t)
            ok += r.success
        row = f"| {name} | {label} | {100 * ok / n:.1f} % | {np.median(times) * 1e3:.3f} ms |"
        log(row)
        out.append(row)
    return out


def run(args) -> str:
    def log(msg: str) -> None:
        if args.verbose:
            print(msg, file=sys.stderr, flush=True)

    robots = resolve_robots(getattr(args, "robots", None))
    q0s = {"random": ["random"], "near": ["near"], "both": ["random", "near"]}[getattr(args, "q0", "random")]
    parts = getattr(args, "parts", None) or ["prefer", "sets", "preferences"]
    sigma = getattr(args, "near_sigma", 0.1)
    command = f"python scripts/bench_goal_kinds_prefer.py --n {args.n}"
    if robots != DEFAULT_ROBOTS:
        command += " --robots " + (" ".join(robots) if robots != list(ARMS) else "all")
    if q0s != ["random"]:
        command += f" --q0 {args.q0}" + (f" --near-sigma {sigma:g}" if sigma != 0.1 else "")
    if parts != ["prefer", "sets", "preferences"]:
        command += " --parts " + " ".join(parts)
    if args.prefer_timeout:
        command += f" --prefer-timeout {args.prefer_timeout:g}"
    if args.seed:
        command += f" --seed {args.seed}"
    if TRAC_EPS != 1e-5:
        command += f" --trac-eps {TRAC_EPS:g}"
    near_text = f"; near q0: the target configuration + N(0, {sigma:g} rad) per joint, clipped"
    budget = (f"{args.prefer_timeout * 1e3:g} ms" if args.prefer_timeout else
              f"{DEFAULT_PREFER_TIMEOUT * 1e3:g} ms with a null space, without "
              + ", ".join(f"{t * 1e3:g} ms ({p})" for p, t in BRANCHES_PREFER_TIMEOUT.items()) + " (the defaults)")
    load = os.getloadavg()
    lines = ["### Goal sets, prefer and preferences (issues 23 and 32)", "",
             f"{datetime.date.today().isoformat()}, `{command}`, "
             f"{cpu_model()}, {os.cpu_count()} cores, Python {platform.python_version()}; load average "
             f"{load[0]:.2f} at the start (a shared, loaded machine: times are indicative, ratios were taken in the "
             f"same run, target by target interleaved). prefer's budget: `timeout` "
             f"{budget}{near_text if 'near' in q0s else ''}"
             ". Bar (issue 32): success >= TRAC-IK's, share >= 95 %, time ratio <= 0.2x; goal set < 3x.", ""]
    if "prefer" in parts:
        lines += ["| robot | q0 | prefer vs TRAC-IK | our success | "
                  f"TRAC-IK success ({TRAC_EPS:g} norms) | our answer | "
                  "median (ours / TRAC-IK) | median time (ours / TRAC-IK) | time ratio | meets the bar |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        for name in robots:
            for q0 in q0s:
                lines += bench_prefer(name, args.n, args.seed, log, args.prefer_timeout, q0, sigma)
                lines.append(f"<!-- load {os.getloadavg()[0]:.2f} after {name} {q0} -->")
        lines.append("")
    if "sets" in parts:
        lines += ["| robot | goal set | finds a reachable one | median time | single pose | ratio | under 3x |",
                  "|---|---|---|---|---|---|---|"]
        for name in robots:
            lines += bench_sets(args.n, args.seed + 1, log, name)
        lines.append("")
    if "preferences" in parts:
        lines += ["| robot | problems | success | median time |", "|---|---|---|---|"]
        for name in robots:
            lines += bench_preferences(name, args.n, args.seed + 2, log)
        lines.append("")
    load = os.getloadavg()
    lines += [f"Load average at the end: {load[0]:.2f}."]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=200, help="targets per part (default 200)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--verbose", action="store_true", help="rows on stderr as they come")
    parser.add_argument("--prefer-timeout", type=float, help="prefer's budget in s (default: the library's)")
    parser.add_argument("--robots", nargs="+", metavar="NAME",
                        help=f"arms (default {' '.join(DEFAULT_ROBOTS)}; 'all': {' '.join(ARMS)})")
    parser.add_argument("--q0", choices=("random", "near", "both"), default="random",
                        help="part 1's q0: uniform in the limits (default), near the target's configuration, or both")
    parser.add_argument("--near-sigma", type=float, default=0.1, help="--q0 near's noise per joint, rad (0.1)")
    parser.add_argument("--parts", nargs="+", choices=("prefer", "sets", "preferences"),
                        help="parts to run (default all three)")
    parser.add_argument("--trac-eps", type=float, default=TRAC_EPS,
                        help="TRAC-IK's epsilon (m and rad per component; default 1e-5, its own; 1e-6: the accuracy "
                             "our answers are held to)")
    args = parser.parse_args(argv)
    globals()["TRAC_EPS"] = args.trac_eps
    print(run(args))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
