#!/usr/bin/env python
"""GMR's retargeting method, per-frame differential IK, with pink, in the peers' own virtual environment.

    /work/peers-venv/bin/python scripts/retarget_pink.py targets.npz -o out.npz --steps 5

Imports none of evoik_pin (the peers' venv cannot): ``scripts/bench_retarget.py`` writes the targets file and
judges the answer with ``scripts/judge_retarget.py``. GMR (General Motion Retargeting) retargets each frame by a
few differential-IK steps from the previous frame's answer, with frame tasks on the mapped robot frames; this is
that method with pink's QP (solver daqp) on the whole free-flyer model:

- a ``FrameTask`` per mapped frame: position cost 1 (per m) on the frame's target position, orientation cost 0,
  except the frames the file gives orientations for (``oriented``: the base, from the source pelvis's hips and
  spine; optionally the feet), whose orientation cost is ``--orientation-cost`` (per rad);
- a ``PostureTask`` (``--posture-cost``, per rad; small) towards ``q_init``'s joints, which only decides what the
  frame tasks leave free (a wrist's roll, the elbow's swivel);
- pink's ``ConfigurationLimit`` (the URDF position limits; pink's default gain 0.5) and ``VelocityLimit`` (the
  URDF velocity limits; the free-flyer has none);
- per frame, ``--steps K`` QP steps, each ``solve_ik`` then ``integrate_inplace`` over dt / K (dt = 1 / fps), so
  that K steps together move each joint at most its velocity limit x dt: the answer is never too fast for the
  clip's frame rate, whatever K;
- the first frame starts from ``q_init`` and is first settled by ``--settle`` steps of a full dt each (the time
  the robot would take to walk into the first pose), then its K steps. Its wall time includes the settling.

Input (.npz): ``urdf_path`` (str), ``frames`` (JSON list of M robot frame names), ``targets`` (N, M, 3) m,
``fps``, ``q_init`` (nq,) in the layout of ``pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer())``, and
optionally ``oriented`` (JSON list of J mapped frames) with ``rotations`` (N, J, 3, 3), their world
orientations. Output (.npz): ``configurations`` (N, nq), ``wall_s`` (N,) per frame, ``joint_names`` (JSON),
``settings`` (JSON), ``failures`` (QP steps that failed and were skipped).
"""

from __future__ import annotations

import os

# One thread per process: the machine is shared, and a BLAS thread pool would make CPU time exceed wall time.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import importlib.metadata as md  # noqa: E402
import json  # noqa: E402
import logging  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402


def retarget(urdf_path: str, frames: list[str], targets: np.ndarray, fps: float, q_init: np.ndarray, *,
             steps: int = 5, settle: int = 50, posture_cost: float = 1e-2, oriented: list[str] = (),
             rotations: np.ndarray | None = None, orientation_cost: float = 0.5, damping: float = 1e-6) -> dict:
    """Per-frame differential IK (see the module docstring). Returns configurations (N, nq), wall_s (N,),
    joint_names and the number of failed QP steps."""
    import pink
    from pink.limits import ConfigurationLimit, VelocityLimit
    from pink.tasks import FrameTask, PostureTask

    model = pin.buildModelFromUrdf(str(urdf_path), pin.JointModelFreeFlyer())
    data = model.createData()
    targets = np.asarray(targets, dtype=float)
    n = targets.shape[0]
    if targets.shape[1:] != (len(frames), 3):
        raise ValueError(f"targets must be (N, M={len(frames)}, 3) m; got {targets.shape}")
    q = np.asarray(q_init, dtype=float).copy()
    if q.shape != (model.nq,):
        raise ValueError(f"q_init must have nq={model.nq} numbers; got {q.shape}")
    oriented = list(oriented) if rotations is not None else []
    if oriented and np.shape(rotations) != (n, len(oriented), 3, 3):
        raise ValueError(f"rotations must be (N={n}, J={len(oriented)}, 3, 3); got {np.shape(rotations)}")
    tasks = [FrameTask(f, position_cost=1.0, orientation_cost=orientation_cost if f in oriented else 0.0)
             for f in frames]
    posture = PostureTask(cost=posture_cost)
    posture.set_target(q)
    limits = [ConfigurationLimit(model), VelocityLimit(model)]
    configuration = pink.Configuration(model, data, q, copy_data=False)
    dt = 1.0 / float(fps)
    out = np.empty((n, model.nq))
    wall = np.empty(n)
    failures = 0

    def step(h: float) -> None:
        nonlocal failures
        try:
            v = pink.solve_ik(configuration, [*tasks, posture], h, solver="daqp", damping=damping, limits=limits)
        except Exception:  # pink's NoSolutionFound and the QP solver's failures alike: keep the pose, count it
            failures += 1
            return
        configuration.integrate_inplace(v, h)

    for i in range(n):
        t0 = time.perf_counter()
        for k, task in enumerate(tasks):
            f = frames[k]
            rotation = rotations[i, oriented.index(f)] if f in oriented else np.eye(3)
            task.set_target(pin.SE3(np.asarray(rotation, dtype=float), targets[i, k]))
        if i == 0:
            for _ in range(settle):
                step(dt)
        for _ in range(steps):
            step(dt / steps)
        out[i] = configuration.q
        wall[i] = time.perf_counter() - t0
    return {"configurations": out, "wall_s": wall, "joint_names": list(model.names)[1:], "failures": failures}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("targets", help=".npz written by bench_retarget.py (see the module docstring)")
    parser.add_argument("-o", "--output", required=True, help=".npz to write")
    parser.add_argument("--steps", type=int, default=5, help="QP steps per frame (K)")
    parser.add_argument("--settle", type=int, default=50, help="extra steps of dt on the first frame")
    parser.add_argument("--posture-cost", type=float, default=1e-2, help="PostureTask cost per rad")
    parser.add_argument("--orientation-cost", type=float, default=0.5, help="per rad, oriented frames only")
    parser.add_argument("--damping", type=float, default=1e-6, help="solve_ik's Tikhonov damping")
    args = parser.parse_args(argv)
    if args.steps < 1 or args.settle < 0:
        parser.error("--steps must be >= 1 and --settle >= 0")
    logging.getLogger().setLevel(logging.ERROR)  # pink warns on every step a joint touches its limit
    z = np.load(args.targets, allow_pickle=False)
    rotations = z["rotations"] if "rotations" in z.files else None
    oriented = json.loads(str(z["oriented"])) if "oriented" in z.files else []
    settings = {"steps": args.steps, "settle": args.settle, "posture_cost": args.posture_cost,
                "orientation_cost": args.orientation_cost, "oriented": oriented, "damping": args.damping,
                "position_cost": 1.0, "solver": "daqp", "limits": "ConfigurationLimit(gain 0.5), VelocityLimit"}
    result = retarget(str(z["urdf_path"]), json.loads(str(z["frames"])), z["targets"], float(z["fps"]), z["q_init"],
                      steps=args.steps, settle=args.settle, posture_cost=args.posture_cost,
                      oriented=oriented, rotations=rotations, orientation_cost=args.orientation_cost,
                      damping=args.damping)
    versions = {name: md.version(name) for name in ("pin-pink", "daqp", "pin", "numpy")}
    np.savez(args.output, configurations=result["configurations"], wall_s=result["wall_s"],
             joint_names=json.dumps(result["joint_names"]), failures=result["failures"],
             settings=json.dumps({**settings, "versions": versions}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
