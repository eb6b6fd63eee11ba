#!/usr/bin/env python
"""Solve whole-robot IK problems with pink and PlaCo, inside the peers' own virtual environment.

    bash scripts/peers_venv.sh                       # creates /work/peers-venv if it is missing
    /work/peers-venv/bin/python scripts/peers_runner.py /tmp/goals/talos.json -o /tmp/peers/talos.json
    /work/peers-venv/bin/python scripts/peers_runner.py /tmp/goals/pr2.json -o out.json --peers placo \\
        --placo orientation_weight=0.5 --budget 0.2 --limit 5

PlaCo pins its own Pinocchio (3.8 when written), so this script runs apart from evoik_pin's environment and
imports none of evoik_pin: it reads a problems file (``goal_problems.py``) and writes, for each peer and problem,
the final configuration (Pinocchio's ``q`` of the problems file's model, ``nq`` numbers), the wall and CPU time
spent (s), the iterations, why it stopped and the peer's own final task errors. ``judge_goals.py`` judges the
answers by Pinocchio forward kinematics in evoik_pin's environment.

Each peer starts every problem from the file's neutral configuration and iterates its differential IK with joint
limits on, until every goal's error (position m, rotation rad, computed from the peer's own Pinocchio data) is
below ``stop_tol``, or the best error has not improved by ``stall_ratio`` over ``stall_iters`` iterations, or its
``budget`` (s, wall clock, per problem, from the creation of the solver state to the answer) is spent.
Building the models and tasks is done once per robot, outside the budget.

- pink (``pin-pink``, QP solver daqp): a model reduced to the active joints (``pin.buildReducedModel``, the other
  joints locked at neutral), a ``FrameTask`` per goal (orientation cost 0 for position goals), ``solve_ik`` with
  a ``ConfigurationLimit`` (and a ``VelocityLimit`` when ``velocity_limit=1``), integration of the velocity
  over ``dt``. Fixed-base robots are loaded without a root joint.
- PlaCo: ``RobotWrapper`` on the URDF text with its visual and collision elements removed (geometry plays no
  part in IK) and ``Flags.ignore_collisions``; a ``KinematicsSolver`` with soft frame tasks (poses) and soft
  position tasks (positions), ``mask_fbase(True)`` for fixed-base robots, ``mask_dof`` for every inactive joint,
  joint limits on, velocity limits off, ``solver.solve(True)`` then ``robot.update_kinematics()`` per
  iteration. PlaCo always adds a free-flyer root (masked for fixed bases); its joint-limit rows index ``q`` as
  if ``nq == nv``, which misaligns them on a model with continuous joints (PR2's forearm and wrist rolls), so
  continuous joints are given to PlaCo as revolute joints with both limits 0, which PlaCo reads as "no limit"
  (``continuous_as_revolute=1``; answers are mapped back to (cos, sin)).

The defaults of :class:`PinkSettings` and :class:`PlacoSettings` are each peer's best settings found by a small
sweep on 20 problems per robot of another seed (1) than the benchmark's, ranked by problems solved to 1e-7 over
the five robots, then time:

- pink: ``damping=1e-6`` (solve_ik's default 1e-12 lets daqp fail on rank-deficient steps), ``orientation_cost=0.1``
  per rad against ``position_cost=1`` per m (with the rest as chosen, 1.0 solved 63 of 100, 0.1 solved 73,
  0.03 also 73), ``config_limit_gain=0.2`` (0.5 and 0.9 take joints onto their limits, where steps stall), full
  steps (``gain=1``; 0.5 solved fewer), no ``lm_damping``, no velocity limit (so ``dt`` cancels out; URDF
  velocity limits with dt 0.02 or 0.05 solved 58).
- PlaCo: soft weights ``position_weight=1``, ``orientation_weight=0.1``, its default regularization 1e-8, the URDF
  velocity limits with ``dt=0.02`` as a per-step bound (defaults solved 49 of 100, velocity limits 56-57,
  with the lower orientation weight 58; a uniform per-joint step bound ``max_step`` 0.1-1 solved 51-58).
"""

from __future__ import annotations

import os

# One thread per process: the machine is shared, and a BLAS thread pool would make CPU time exceed wall time.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import json  # noqa: E402
import logging  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import xml.etree.ElementTree as ET  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from goal_problems import goal_errors, load_problems, model_of, parse_goals, placement_errors  # noqa: E402


@dataclasses.dataclass
class Common:
    """Stopping rules shared by both peers."""

    budget: float = 0.2  # s of wall time per problem
    stop_tol: float = 1e-7  # m and rad: every goal below this stops the iteration
    stall_iters: int = 100  # iterations without enough progress that stop the iteration
    stall_ratio: float = 0.999  # "enough progress": the best error shrinks below this fraction of its old value


@dataclasses.dataclass
class PinkSettings:
    """pink's knobs (see ``pink.solve_ik`` and ``pink.tasks.FrameTask``)."""

    dt: float = 1.0  # s; cancels out (dq = v dt) unless velocity_limit is on
    damping: float = 1e-6  # Tikhonov weight on the whole tangent step (solve_ik's default: 1e-12)
    lm_damping: float = 0.0  # FrameTask's Levenberg-Marquardt damping, scaled by the squared task error
    gain: float = 1.0  # FrameTask gain: 1 is a full Gauss-Newton step
    position_cost: float = 1.0  # cost / m
    orientation_cost: float = 0.1  # cost / rad (pose goals; position goals have 0)
    config_limit_gain: float = 0.2  # ConfigurationLimit: fraction of the distance to a limit one step may take
    velocity_limit: int = 0  # 1: also pink's VelocityLimit (URDF velocities times dt)
    max_step: float = 0.0  # > 0: a VelocityLimit of max_step / dt on every joint but the base (rad or m per step)


@dataclasses.dataclass
class PlacoSettings:
    """PlaCo's knobs (see ``placo.KinematicsSolver``)."""

    position_weight: float = 1.0  # soft weight of position (and the position part of frame) tasks
    orientation_weight: float = 0.1  # soft weight of the orientation part of frame tasks
    regularization: float = 1e-8  # solver.problem.regularization, the L2 weight on the step (PlaCo's default)
    velocity_limit: int = 1  # 1: PlaCo's velocity limits (URDF velocities times dt bound each step)
    dt: float = 0.02  # s, solver.dt; only used with velocity limits
    max_step: float = 0.0  # > 0: velocity limits of max_step / dt on every joint (rad or m per step)
    continuous_as_revolute: int = 1  # see the module docstring


def _override(settings, pairs: list[str]):
    """``settings`` with ``KEY=VALUE`` pairs applied (values converted to the field's type)."""
    fields = {f.name: f for f in dataclasses.fields(settings)}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or key not in fields:
            raise ValueError(f"setting {pair!r}; accepted: KEY=VALUE with KEY one of {', '.join(fields)}")
        setattr(settings, key, type(getattr(settings, key))(float(value)))
    return settings


class _Stopper:
    """Decides when an iteration stops: converged, stalled or out of budget."""

    def __init__(self, common: Common):
        self.common = common
        self.start = time.perf_counter()
        self.best = np.inf
        self.history: list[float] = []

    def check(self, err: np.ndarray) -> str | None:
        """A reason to stop given the current goal errors (n_goals, 2), or None to go on."""
        worst = float(err.max())
        if worst < self.common.stop_tol:
            return "converged"
        self.best = min(self.best, worst)
        self.history.append(self.best)
        n = self.common.stall_iters
        if len(self.history) > n and self.history[-1] > self.common.stall_ratio * self.history[-1 - n]:
            return "stalled"
        if time.perf_counter() - self.start >= self.common.budget:
            return "budget"
        return None


def _se3(goal: dict) -> pin.SE3:
    if goal["kind"] == "pose":
        return pin.SE3(goal["target"][:3, :3].copy(), goal["target"][:3, 3].copy())
    return pin.SE3(np.eye(3), goal["target"].copy())


def _joint_maps(full: pin.Model, other: pin.Model, names: list[str]) -> list[tuple[int, int, int, int]]:
    """(full idx_q, full nq, other idx_q, other nq) for each named joint present in both models."""
    out = []
    for name in names:
        jf, jo = full.joints[full.getJointId(name)], other.joints[other.getJointId(name)]
        out.append((jf.idx_q, jf.nq, jo.idx_q, jo.nq))
    return out


def _to_full(q_full0: np.ndarray, q_other: np.ndarray, maps) -> np.ndarray:
    """A configuration of the problems file's model: ``q_full0`` with each mapped joint taken from ``q_other``;
    a joint that is revolute (one angle) in the other model and continuous (cos, sin) here is converted."""
    q = q_full0.copy()
    for iq, nq, jq, jn in maps:
        if nq == jn:
            q[iq:iq + nq] = q_other[jq:jq + jn]
        else:  # nq 2 here, an angle there
            q[iq:iq + 2] = np.cos(q_other[jq]), np.sin(q_other[jq])
    return q


def _from_full(q_other0: np.ndarray, q_full: np.ndarray, maps) -> np.ndarray:
    """The inverse of :func:`_to_full`: the other model's configuration with the mapped joints from ``q_full``."""
    q = q_other0.copy()
    for iq, nq, jq, jn in maps:
        if nq == jn:
            q[jq:jq + jn] = q_full[iq:iq + nq]
        else:
            q[jq] = np.arctan2(q_full[iq + 1], q_full[iq])
    return q


class PinkPeer:
    """pink on a model reduced to the active joints."""

    name = "pink"

    def __init__(self, problems: dict, settings: PinkSettings, common: Common):
        import pink
        from pink.limits import ConfigurationLimit, VelocityLimit

        self.pink, self.settings, self.common = pink, settings, common
        full = model_of(problems)
        self.q_full0 = np.array(problems["neutral"])
        locked = [full.getJointId(n) for n in problems["joint_names"] if n not in problems["active_joints"]]
        self.model = pin.buildReducedModel(full, locked, self.q_full0) if locked else full
        self.data = self.model.createData()
        self.maps = _joint_maps(full, self.model, problems["active_joints"])
        self.q0 = _from_full(pin.neutral(self.model), self.q_full0, self.maps)
        self.limits = [ConfigurationLimit(self.model, settings.config_limit_gain)]
        if settings.max_step > 0:  # the same bound on every joint's step (a box trust region), not on the base
            bound = np.full(self.model.nv, settings.max_step / settings.dt)
            bound[: 6 if problems["floating_base"] else 0] = np.inf
            self.limits.append(VelocityLimit(self.model, bound))
        elif settings.velocity_limit:
            self.limits.append(VelocityLimit(self.model))
        self.tasks = [
            pink.FrameTask(g["frame"], position_cost=settings.position_cost,
                           orientation_cost=settings.orientation_cost if g["kind"] == "pose" else 0.0,
                           lm_damping=settings.lm_damping, gain=settings.gain)
            for g in problems["goals"]
        ]
        self.frame_ids = [self.model.getFrameId(g["frame"]) for g in problems["goals"]]

    def solve(self, goals: list[dict]) -> dict:
        s = self.settings
        stopper = _Stopper(self.common)
        configuration = self.pink.Configuration(self.model, self.data, self.q0, copy_data=False)
        for task, goal in zip(self.tasks, goals, strict=True):
            task.set_target(_se3(goal))
        iterations, reason = 0, None
        while reason is None:
            reason = stopper.check(goal_errors(configuration.data, self.frame_ids, goals))
            if reason is not None:
                break
            try:
                v = self.pink.solve_ik(configuration, self.tasks, s.dt, solver="daqp", damping=s.damping,
                                       limits=self.limits, safety_break=False)
            except Exception as exc:  # pink's NoSolutionFound and the QP solver's failures alike
                reason = f"error: {type(exc).__name__}"
                break
            configuration.integrate_inplace(v, s.dt)
            iterations += 1
        own = [float(np.linalg.norm(t.compute_error(configuration))) for t in self.tasks]
        return {"q": _to_full(self.q_full0, configuration.q, self.maps), "iterations": iterations, "stop": reason,
                "own_errors": own}


class PlacoPeer:
    """PlaCo's KinematicsSolver with soft tasks, inactive joints masked."""

    name = "placo"

    def __init__(self, problems: dict, settings: PlacoSettings, common: Common):
        import placo

        self.settings, self.common = settings, common
        full = model_of(problems)
        self.q_full0 = np.array(problems["neutral"])
        self.robot = placo.RobotWrapper(str(Path(problems["urdf"]).parent), placo.Flags.ignore_collisions,
                                        _kinematic_urdf(problems["urdf"], settings.continuous_as_revolute))
        model = self.robot.model
        names = [n for n in problems["joint_names"] if n != "root_joint"]
        if list(model.names)[2:] != names:
            raise ValueError(f"PlaCo's model of {problems['urdf']} has other joints than the problems file")
        self.maps = _joint_maps(full, model, problems["joint_names"])  # a free-flyer is PlaCo's root_joint too
        self.q0 = _from_full(pin.neutral(model), self.q_full0, self.maps)
        solver = placo.KinematicsSolver(self.robot)
        solver.mask_fbase(not problems["floating_base"])
        for name in names:
            if name not in problems["active_joints"]:
                solver.mask_dof(name)
        solver.enable_joint_limits(True)
        if settings.max_step > 0:  # the same bound on every joint's step: a box trust region
            self.robot.set_velocity_limits(settings.max_step / settings.dt)
        solver.enable_velocity_limits(bool(settings.velocity_limit or settings.max_step > 0))
        solver.dt = settings.dt
        solver.problem.regularization = settings.regularization
        self.tasks = []
        for g in problems["goals"]:
            if g["kind"] == "pose":
                task = solver.add_frame_task(g["frame"], np.eye(4))
                task.configure(g["frame"], "soft", settings.position_weight, settings.orientation_weight)
            else:
                task = solver.add_position_task(g["frame"], np.zeros(3))
                task.configure(g["frame"], "soft", settings.position_weight)
            self.tasks.append(task)
        self.solver = solver

    def _errors(self, goals: list[dict]) -> np.ndarray:
        return placement_errors([pin.SE3(self.robot.get_T_world_frame(g["frame"])) for g in goals], goals)

    def solve(self, goals: list[dict]) -> dict:
        stopper = _Stopper(self.common)
        self.robot.state.q = self.q0.copy()
        self.robot.update_kinematics()
        for task, goal in zip(self.tasks, goals, strict=True):
            if goal["kind"] == "pose":
                task.T_world_frame = goal["target"]
            else:
                task.target_world = goal["target"]
        iterations, reason = 0, None
        while reason is None:
            reason = stopper.check(self._errors(goals))
            if reason is not None:
                break
            try:
                self.solver.solve(True)
            except Exception as exc:  # PlaCo's QPError (infeasible QP) and the like
                reason = f"error: {type(exc).__name__}"
                break
            self.robot.update_kinematics()
            iterations += 1
        own = []
        for task, goal in zip(self.tasks, goals, strict=True):
            parts = (task.position(), task.orientation()) if goal["kind"] == "pose" else (task,)
            own.extend(float(p.error_norm()) for p in parts)
        return {"q": _to_full(self.q_full0, np.array(self.robot.state.q), self.maps), "iterations": iterations,
                "stop": reason, "own_errors": own}


def _kinematic_urdf(path: str, continuous_as_revolute: bool) -> str:
    """The URDF text without visual and collision elements; continuous joints made revolute with limits 0 and 0
    (PlaCo's "no limit") when asked."""
    root = ET.parse(path).getroot()
    for link in root.iter("link"):
        for tag in ("visual", "collision"):
            for element in link.findall(tag):
                link.remove(element)
    if continuous_as_revolute:
        for joint in root.iter("joint"):
            if joint.get("type") == "continuous":
                joint.set("type", "revolute")
                limit = joint.find("limit")
                if limit is None:
                    limit = ET.SubElement(joint, "limit", {"effort": "0", "velocity": "0"})
                limit.set("lower", "0")
                limit.set("upper", "0")
    return ET.tostring(root, encoding="unicode")


PEERS = {"pink": (PinkPeer, PinkSettings), "placo": (PlacoPeer, PlacoSettings)}


def _versions() -> dict:
    import importlib.metadata as md

    out = {}
    for name in ("pin-pink", "placo", "daqp", "qpsolvers", "pin", "numpy"):
        try:
            out[name] = md.version(name)
        except md.PackageNotFoundError:
            out[name] = None
    return out


def run(problems: dict, peers: list[str], common: Common, overrides: dict[str, list[str]],
        limit: int | None = None, log=print) -> dict:
    """Solve the problems with each named peer; the results dict ``main`` writes as JSON."""
    items = problems["problems"][:limit]
    goals_list = [parse_goals(p["goals"]) for p in items]
    out = {"problems_file_robot": problems["robot"], "n_problems": len(items), "common": dataclasses.asdict(common),
           "versions": _versions(), "peers": {}}
    for name in peers:
        cls, settings_cls = PEERS[name]
        settings = _override(settings_cls(), overrides.get(name, []))
        peer = cls(problems, settings, common)
        answers = []
        for goals in goals_list:
            w0, c0 = time.perf_counter(), time.process_time()
            answer = peer.solve(goals)
            answer["wall_s"], answer["cpu_s"] = time.perf_counter() - w0, time.process_time() - c0
            answer["q"] = np.asarray(answer["q"]).tolist()
            answers.append(answer)
        stops = {}
        for a in answers:
            stops[a["stop"]] = stops.get(a["stop"], 0) + 1
        log(f"{problems['robot']:<8s} {name:<6s} median {1e3 * np.median([a['wall_s'] for a in answers]):6.1f} ms, "
            f"stops {stops}")
        out["peers"][name] = {"settings": dataclasses.asdict(settings), "answers": answers}
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("problems", type=Path, help="problems file (goal_problems.py)")
    parser.add_argument("-o", "--out", type=Path, required=True, help="results file to write (JSON)")
    parser.add_argument("--peers", default="pink,placo", help="comma-separated: pink, placo (default both)")
    parser.add_argument("--limit", type=int, help="solve only the first N problems")
    parser.add_argument("--budget", type=float, default=Common.budget, help="s of wall time per problem")
    parser.add_argument("--stop-tol", type=float, default=Common.stop_tol, help="m and rad")
    parser.add_argument("--pink", action="append", default=[], metavar="KEY=VALUE",
                        help=f"a pink setting: {', '.join(f.name for f in dataclasses.fields(PinkSettings))}")
    parser.add_argument("--placo", action="append", default=[], metavar="KEY=VALUE",
                        help=f"a PlaCo setting: {', '.join(f.name for f in dataclasses.fields(PlacoSettings))}")
    args = parser.parse_args(argv)
    peers = [p.strip() for p in args.peers.split(",") if p.strip()]
    unknown = [p for p in peers if p not in PEERS]
    if unknown or not peers:
        parser.error(f"--peers {args.peers!r}; accepted: a comma-separated list of {', '.join(PEERS)}")
    if args.budget <= 0 or args.stop_tol <= 0:
        parser.error("--budget and --stop-tol must be positive")
    logging.getLogger().setLevel(logging.ERROR)  # pink warns on every iteration a joint touches its limit
    try:
        problems = load_problems(args.problems)
        for name in peers:  # settings checked before any solving
            _override(PEERS[name][1](), getattr(args, name))
        results = run(problems, peers, Common(budget=args.budget, stop_tol=args.stop_tol),
                      {"pink": args.pink, "placo": args.placo}, args.limit)
    except (OSError, ValueError, KeyError) as exc:
        parser.error(str(exc))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(results), encoding="utf-8")
    print(f"written: {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
