#!/usr/bin/env python
"""Benchmark IK solvers on random reachable 6-D pose targets: memetic against TRAC-IK, ikpy and a paper solver.

For every robot, ``--targets`` targets are the FK of configurations drawn uniformly within the joint limits
(a fixed seed), each with a random start configuration (the "seed" TRAC-IK needs; ikpy starts there too, and
the ``memetic (q0)`` row gets it as ``q0``). The solvers run interleaved target by target in one process,
so machine load hits them alike. Every answer is judged by the same rule, with our own forward kinematics
(Pinocchio): position error norm <= 2e-5 m and rotation angle <= 2e-5 rad (TRAC-IK's epsilon bounds each
error component, so its answers reach norms near 1.5e-5), joint limits respected (continuous joints, which
TRAC-IK and ikpy leave unbounded, are wrapped into [-pi, pi] first); success at 1e-6 and 1e-10 is reported
too. Times are wall-clock per call (TRAC-IK: the C++ ``ik`` call alone, the quaternion conversion excluded).

Peers are optional (``pip install -e '.[bench]'``): a peer that is not installed is reported and skipped.

    python scripts/bench_ik.py                      # 500 targets per robot, all robots, writes docs/BENCHMARKS.md
    python scripts/bench_ik.py --quick              # 50 targets, a few robots, stdout only
    python scripts/bench_ik.py --robots panda ur5 --targets 200 --json out.json
    python scripts/bench_ik.py --throughput 10000   # solve_many on Panda vs TRAC-IK sequential
    python scripts/bench_ik.py --profile panda      # where memetic's time goes (cProfile)
"""

from __future__ import annotations

import argparse
import contextlib
import cProfile
import datetime
import io
import json
import os
import platform
import pstats
import sys
import tempfile
import time
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin

import evoik_pin as ev
import evoik_pin.solvers
from evoik_pin.robot import example_robot_data_dir

sys.path.insert(0, str(Path(__file__).resolve().parent))
from docs_block import write_block  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs" / "BENCHMARKS.md"
BEGIN, END = "<!-- bench_ik:begin -->", "<!-- bench_ik:end -->"

#: name -> (load_robot source, base, tip); None base/tip = the arm's defaults.
ROBOTS: dict[str, tuple[str, str | None, str | None]] = {
    "panda": ("panda", None, None),
    "ur5": ("ur5", None, None),
    "kinova": ("kinova", None, None),
    "z1": ("z1", None, None),
    "xarm": ("xarm", None, None),
    "redundant7r": ("redundant7r", None, None),
    "baxter_left": ("baxter_description/urdf/baxter.urdf", "torso", "left_gripper"),
    "tiago_dual_left": ("tiago_description/robots/tiago_dual.urdf", "torso_lift_link", "arm_left_tool_link"),
}
QUICK_ROBOTS = ["panda", "kinova", "baxter_left"]
THRESHOLD = 2e-5


def load(name: str) -> ev.Robot:
    source, base, tip = ROBOTS[name]
    if source.endswith(".urdf"):
        source = str(example_robot_data_dir() / source)
    return ev.load_robot(source, base=base, tip=tip)


@contextlib.contextmanager
def quiet_output():
    """Silence C++ libraries' chatter on stdout and stderr (KDL's URDF parser) during setup."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [(fd, os.dup(fd)) for fd in (1, 2)]
    with open(os.devnull, "w") as null:
        for fd, _ in saved:
            os.dup2(null.fileno(), fd)
        try:
            yield
        finally:
            for fd, copy in saved:
                os.dup2(copy, fd)
                os.close(copy)


# ---------------------------------------------------------------------- judging
def wrap_continuous(robot: ev.Robot, q: np.ndarray) -> np.ndarray:
    q = np.array(q, dtype=float)
    c = robot.continuous
    q[c] = (q[c] + np.pi) % (2 * np.pi) - np.pi
    return q


def judge(robot: ev.Robot, T: pin.SE3, q) -> tuple[float, float, bool]:
    """(position error m, rotation angle rad, within limits) of an answer, by our own FK; inf for no answer."""
    if q is None:
        return np.inf, np.inf, False
    q = wrap_continuous(robot, q)
    Tq = robot.fk(q)
    pos = float(np.linalg.norm(Tq.translation - T.translation))
    rot = float(np.linalg.norm(pin.log3(T.rotation.T @ Tq.rotation)))
    return pos, rot, robot.within_bounds(q, 1e-9)


# ---------------------------------------------------------------------- solvers
class Solver:
    name = ""
    available = True
    why = ""

    def __call__(self, T: pin.SE3, q_seed: np.ndarray, i: int):  # -> joint vector or None
        raise NotImplementedError


class Memetic(Solver):
    def __init__(self, robot, use_q0: bool = False, **options):
        self.robot, self.use_q0, self.options = robot, use_q0, options
        self.name = "memetic (q0)" if use_q0 else "memetic"
        if options:
            self.name += " " + " ".join(f"{k}={v}" for k, v in options.items())
        ev.solve(robot, robot.fk((robot.lower + robot.upper) / 2), seed=0, **options)  # warm the seed table

    def __call__(self, T, q_seed, i):
        r = ev.solve(self.robot, T, seed=10_000 + i, q0=q_seed if self.use_q0 else None, **self.options)
        return r.q


class PaperPolish(Solver):
    """A paper solver, one run (not the papers' best of 10), then the LM polish (``polish=True``)."""

    def __init__(self, robot, method: str):
        self.robot, self.method = robot, method
        self.options = {"runs": 1} if "runs" in ev.solvers.get_solver(method).options else {}
        self.name = f"{method} + polish"

    def __call__(self, T, q_seed, i):
        return ev.solve(self.robot, T, method=self.method, seed=20_000 + i, polish=True, **self.options).q


class TracIK(Solver):
    name = "TRAC-IK"

    def __init__(self, robot, timeout: float = 0.005, epsilon: float = 1e-5):
        try:
            import pytracik
            from trac_ik import TracIK as _TracIK
        except ImportError:
            self.available, self.why = False, "not installed (pip install pytracik)"
            return
        self._ik = pytracik.ik
        with quiet_output():
            solver = _TracIK(robot.base, robot.tip, str(robot.urdf_path), timeout=timeout, epsilon=epsilon)
        if solver.dof != robot.n:
            self.available, self.why = False, f"chain has {solver.dof} joints, ours {robot.n}"
            return
        # TRAC-IK's own reading of the limits is unreliable (e.g. zeros for Panda): set ours.
        solver.joint_limits = (robot.lower, robot.upper)
        self._handle = solver._ik_solver
        # same frames: its FK must equal ours
        q = (robot.lower + robot.upper) / 2
        p, R = solver.fk(q)
        T = robot.fk(q)
        if np.abs(p - T.translation).max() > 1e-9 or np.abs(R - T.rotation).max() > 1e-9:
            self.available, self.why = False, "its FK differs from ours (frames do not match)"

    def __call__(self, T, q_seed, i):
        quat = pin.Quaternion(T.rotation)
        x, y, z = T.translation
        t0 = time.perf_counter()
        r = self._ik(self._handle, q_seed, x, y, z, quat.x, quat.y, quat.z, quat.w)
        self.elapsed = time.perf_counter() - t0
        return np.array(r[1:]) if r[0] >= 0 else None


def _chain_urdf(robot) -> str:
    """A URDF holding only the base -> tip chain (ikpy follows the first child otherwise)."""
    root = ET.fromstring(robot.urdf_xml)
    by_child = {j.find("child").get("link"): j for j in root.findall("joint")}
    joints, link = [], robot.tip
    while link != robot.base:
        j = by_child[link]
        joints.append(j)
        link = j.find("parent").get("link")
    out = ET.Element("robot", name="chain")
    ET.SubElement(out, "link", name=robot.base)
    for j in reversed(joints):
        out.append(j)
        ET.SubElement(out, "link", name=j.find("child").get("link"))
    return ET.tostring(out, encoding="unicode")


class IKPy(Solver):
    name = "ikpy (1 attempt)"

    def __init__(self, robot):
        try:
            import ikpy.chain
        except ImportError:
            self.available, self.why = False, "not installed (pip install ikpy)"
            return
        with tempfile.NamedTemporaryFile("w", suffix=".urdf", delete=False) as f:
            f.write(_chain_urdf(robot))
            path = f.name
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                self.chain = ikpy.chain.Chain.from_urdf_file(path, base_elements=[robot.base], symbolic=False)
        finally:
            os.unlink(path)
        self.mask = np.array([link.joint_type != "fixed" for link in self.chain.links])
        self.chain.active_links_mask = self.mask
        if self.mask.sum() != robot.n:
            self.available, self.why = False, f"chain has {self.mask.sum()} joints, ours {robot.n}"

    def __call__(self, T, q_seed, i):
        full = np.zeros(len(self.chain.links))
        full[self.mask] = q_seed
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            sol = self.chain.inverse_kinematics(T.translation, T.rotation, orientation_mode="all",
                                                initial_position=full)
        return sol[self.mask]


def cpu_model() -> str:
    """The CPU's model name from /proc/cpuinfo (``platform.processor()`` is empty on many Linux VMs)."""
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    return platform.processor() or "unknown CPU"


# ---------------------------------------------------------------------- the run
def bench_robot(name: str, n_targets: int, n_slow: int, seed: int, paper: str | None, log) -> dict:
    robot = load(name)
    rng = np.random.default_rng([seed, sum(map(ord, name))])
    Qt = robot.random_configurations(n_targets, rng)
    Qs = robot.random_configurations(n_targets, rng)
    targets = [robot.fk(q) for q in Qt]
    solvers: list[tuple[Solver, int]] = [
        (Memetic(robot), n_targets), (Memetic(robot, use_q0=True), n_targets),
        # the same search with a deterministic budget instead of the 5 ms clock: what load costs it
        (Memetic(robot, timeout=None, max_restarts=20), n_targets),
        # the same solver with the LM iteration as a Python loop over Pinocchio instead of the numba kernel
        (Memetic(robot, engine="python"), n_targets),
        (TracIK(robot), n_targets), (IKPy(robot), n_slow)]
    methods = ev.methods()
    if paper:
        if paper in methods:
            solvers.append((PaperPolish(robot, paper), n_slow))
        else:
            log(f"  {paper}: not registered, skipped")
    for s, _ in solvers:
        if not s.available:
            log(f"  {name}: {s.name} skipped: {s.why}")
    solvers = [(s, k) for s, k in solvers if s.available]
    rows = {s.name: {"t": [], "pos": [], "rot": [], "ok": []} for s, _ in solvers}
    # Each target's solvers run in a fresh random order: whoever runs right after another solver on the same
    # target finds the caches (CPU, allocator) in the state that one left, so a fixed order would favour some.
    order_rng = np.random.default_rng([seed, 99])
    for i, T in enumerate(targets):
        for j in order_rng.permutation(len(solvers)):
            s, limit = solvers[j]
            if i >= limit:
                continue
            t0 = time.perf_counter()
            q = s(T, Qs[i], i)
            dt = getattr(s, "elapsed", None) or (time.perf_counter() - t0)
            pos, rot, inside = judge(robot, T, q)
            row = rows[s.name]
            row["t"].append(dt)
            row["pos"].append(pos)
            row["rot"].append(rot)
            row["ok"].append(inside)
    out = {}
    for s, _ in solvers:
        row = rows[s.name]
        if not row["t"]:  # --slow-targets 0: the slow solvers did not run
            continue
        t = np.array(row["t"]) * 1e3
        pos, rot, inside = np.array(row["pos"]), np.array(row["rot"]), np.array(row["ok"])

        def rate(th, pos=pos, rot=rot, inside=inside):
            return float(np.mean((pos <= th) & (rot <= th) & inside))

        good = (pos <= THRESHOLD) & (rot <= THRESHOLD) & inside
        out[s.name] = {
            "success_rate": rate(THRESHOLD), "success_1e-6": rate(1e-6), "success_1e-10": rate(1e-10),
            "median_ms": float(np.median(t)), "p95_ms": float(np.percentile(t, 95)),
            "max_pos_err": float(pos[good].max()) if good.any() else None,
            "max_rot_err": float(rot[good].max()) if good.any() else None,
            "n": int(t.size),
        }
    return out


def throughput(n: int, seed: int) -> dict:
    """solve_many on n Panda targets against TRAC-IK called sequentially on the same targets."""
    robot = load("panda")
    rng = np.random.default_rng([seed, 7])
    Qt = robot.random_configurations(n, rng)
    Qs = robot.random_configurations(n, rng)
    P, R = robot.fk_batch(Qt)
    H = np.zeros((n, 4, 4))
    H[:, :3, :3], H[:, :3, 3], H[:, 3, 3] = R, P, 1.0
    out = {}
    trac = TracIK(robot)
    if trac.available:
        dt = 0.0  # the IK calls alone (with their Python wrapper), not the judging
        ok = 0
        for i in range(n):
            T = pin.SE3(R[i], P[i])
            t0 = time.perf_counter()
            q = trac(T, Qs[i], i)
            dt += time.perf_counter() - t0
            pos, rot, inside = judge(robot, T, q)
            ok += pos <= THRESHOLD and rot <= THRESHOLD and inside
        out["TRAC-IK (sequential)"] = {"time_s": dt, "throughput": n / dt, "success_rate": ok / n}
    ev.solve(robot, pin.SE3(R[0], P[0]), seed=0)  # warm the seed table and load the compiled LM
    res = ev.solve_many(robot, H, seed=seed, workers=1)  # one core, like the sequential TRAC-IK calls
    ok = 0
    for i, r in enumerate(res):
        pos, rot, inside = judge(robot, pin.SE3(R[i], P[i]), r.q)
        ok += pos <= THRESHOLD and rot <= THRESHOLD and inside
    s = res.stats
    out["memetic solve_many"] = {"time_s": s["time_s"], "throughput": s["throughput"], "success_rate": ok / n,
                                 "batched": s["batched"], "fallback": s["fallback"]}
    return out


def profile(name: str, n: int, seed: int) -> str:
    robot = load(name)
    rng = np.random.default_rng([seed, 99])
    targets = [robot.fk(q) for q in robot.random_configurations(n, rng)]
    ev.solve(robot, targets[0], seed=0)
    prof = cProfile.Profile()
    prof.enable()
    for i, T in enumerate(targets):
        ev.solve(robot, T, seed=i)
    prof.disable()
    buf = io.StringIO()
    pstats.Stats(prof, stream=buf).sort_stats("tottime").print_stats(20)
    return buf.getvalue()


# ---------------------------------------------------------------------- output
def fmt(x, spec):
    return "-" if x is None else format(x, spec)


def markdown(results: dict, tp: dict | None, command: str) -> str:
    lines = [
        f"Date: {datetime.date.today().isoformat()}. Command: `{command}`.",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores ({cpu_model()}), "
        f"Python {platform.python_version()}, numpy {np.__version__}, pin {pin.__version__}; shared with other "
        "work, so compare solvers within one table (they ran interleaved), not across runs.",
        "",
        f"Success = position error <= {THRESHOLD:g} m and rotation angle <= {THRESHOLD:g} rad by our FK, within "
        "the joint limits; `ok 1e-6` / `ok 1e-10` use those thresholds instead. Max errors are over the "
        "successes.",
        "",
    ]
    for name, per in results.items():
        lines += [f"### {name}", "",
                  "| solver | n | success | ok 1e-6 | ok 1e-10 | median ms | p95 ms | max pos err (m) "
                  "| max rot err (rad) |", "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
        for solver, r in per.items():
            lines.append(
                f"| {solver} | {r['n']} | {r['success_rate']:.1%} | {r['success_1e-6']:.1%} | {r['success_1e-10']:.1%} "
                f"| {r['median_ms']:.3f} | {r['p95_ms']:.3f} | {fmt(r['max_pos_err'], '.1e')} "
                f"| {fmt(r['max_rot_err'], '.1e')} |")
        lines.append("")
    if tp:
        lines += ["### Throughput (Panda)", "", "| solver | targets/s | time s | success |",
                  "| --- | ---: | ---: | ---: |"]
        for solver, r in tp.items():
            lines.append(f"| {solver} | {r['throughput']:.0f} | {r['time_s']:.2f} | {r['success_rate']:.1%} |")
        lines.append("")
    return "\n".join(lines)


def write_docs(text: str) -> None:
    """Replace this script's own section of docs/BENCHMARKS.md (between its markers), or append it."""
    write_block(DOCS, BEGIN, END, text, "## IK solvers against TRAC-IK (scripts/bench_ik.py)")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--targets", type=int, default=500, help="targets per robot (default 500)")
    ap.add_argument("--slow-targets", type=int, default=100,
                    help="targets (the first ones) for the slow peers: ikpy and the paper solver (default 100)")
    ap.add_argument("--robots", nargs="+", choices=list(ROBOTS), help="robots (default: all)")
    ap.add_argument("--paper", default="isade", help="paper solver run with polish=True (default isade)")
    ap.add_argument("--quick", action="store_true", help="50 targets, 20 slow ones, three robots; no docs")
    ap.add_argument("--json", type=Path, help="write {robot: {solver: {success_rate, median_ms, ...}}} here")
    ap.add_argument("--throughput", type=int, default=None,
                    help="solve_many on this many Panda targets vs TRAC-IK sequential (default 10000; 0: skip)")
    ap.add_argument("--profile", metavar="ROBOT", help="only profile memetic on this robot and print the top")
    ap.add_argument("--no-docs", action="store_true", help="do not write docs/BENCHMARKS.md")
    ap.add_argument("--seed", type=int, default=2026)
    args = ap.parse_args(argv)
    if args.profile:
        print(profile(args.profile, 300, args.seed))
        return 0
    if args.quick:
        args.targets, args.slow_targets = min(args.targets, 50), min(args.slow_targets, 20)
        args.robots = args.robots or QUICK_ROBOTS
        args.throughput = 1000 if args.throughput is None else args.throughput
    robots = args.robots or list(ROBOTS)
    n_tp = 10_000 if args.throughput is None else args.throughput
    command = "python scripts/bench_ik.py " + " ".join(argv if argv is not None else sys.argv[1:])

    def log(msg):
        print(msg, file=sys.stderr, flush=True)

    results = {}
    for name in robots:
        log(f"{name} ...")
        t0 = time.perf_counter()
        results[name] = bench_robot(name, args.targets, min(args.slow_targets, args.targets), args.seed, args.paper,
                                    log)
        log(f"{name}: {time.perf_counter() - t0:.1f} s")
    tp = throughput(n_tp, args.seed) if n_tp > 0 else None
    text = markdown(results, tp, command.strip())
    print(text)
    if args.json:
        args.json.write_text(json.dumps(results, indent=2))
    if not (args.quick or args.no_docs):
        write_docs(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
