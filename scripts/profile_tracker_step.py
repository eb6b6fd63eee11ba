#!/usr/bin/env python
"""Where a Tracker step's time goes: the whole ``Tracker.step`` against the compiled LM call inside it.

    python scripts/profile_tracker_step.py            # Panda (a tip pose, 1 kHz) and Talos (four poses, 500 Hz)

Each robot follows a smooth joint path (tests/velocity_paths.py; 400 steps, three passes). Then, on the prepared
step's own arrays (the solver's ``BoxStep`` for that goal structure), the compiled LM entry is called alone on each
step of the path (box and targets written as the step writes them) with 0, 1, 2 and 3 iterations: 0 iterations is
one error pass plus the call itself (its ~22 arrays unboxed), the iteration count the path needs is the step's
compiled share; the rest of a step is Python (the structure's key, the targets, the verdicts, the Result).
Prints median microseconds; run it on a quiet machine (it measures one core's wall time)."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

import evoik_pin as ek

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from velocity_paths import TALOS_FRAMES, pose_goals, smooth_path  # noqa: E402

from evoik_pin.solvers.lm.layout import P_ITERATIONS  # noqa: E402


def profile(robot, targets: list, Q: np.ndarray, dt: float) -> str:
    """One robot's line: the whole step's median (us) and the compiled LM call's at 0-3 iterations."""
    steps = []
    for _ in range(3):
        tracker = ek.Tracker(robot, dt=dt, q0=Q[0], seed=0)
        for goals in targets:
            t0 = time.perf_counter()
            tracker.step(goals)
            steps.append(time.perf_counter() - t0)
    prepared = [s for s in tracker._solver._box_steps.values() if s is not None][0]
    step = tracker.max_step
    parts = []
    for iterations in (0, 1, 2, 3):
        times, evaluations = [], []
        for i in range(len(Q) - 1):
            keyed = targets[i + 1] if isinstance(targets[i + 1], list) else (targets[i + 1].translation.copy(),
                                                                               targets[i + 1].rotation.copy())
            prepared._write_targets(keyed)
            prepared._write_step(prepared._box, Q[i], step, *prepared._bounds, prepared._poses, prepared._posed,
                                 prepared._pt, prepared._Rt, False)
            prepared._params[P_ITERATIONS] = iterations
            q = np.empty(robot.n)
            t0 = time.perf_counter()
            out = prepared._run(*prepared._head, Q[i], *prepared._args, prepared._params, q, prepared._g_err)
            times.append(time.perf_counter() - t0)
            evaluations.append(out[4])
        parts.append(f"{iterations} it: {np.median(times) * 1e6:5.2f} us ({np.median(evaluations):.0f} evaluations)")
    return f"{robot.name:6s} n={robot.n:3d} step {np.median(steps[len(targets):]) * 1e6:6.2f} us | " + " | ".join(parts)


def main() -> int:
    panda = ek.load_robot("panda")
    Q = smooth_path(panda, 400, 0.001, seed=1)
    print(profile(panda, [panda.fk(q) for q in Q], Q, 0.001), flush=True)
    talos = ek.load_robot("talos", floating_base=True)
    Q = smooth_path(talos, 400, 0.002, seed=1)
    print(profile(talos, pose_goals(talos, Q, TALOS_FRAMES), Q, 0.002), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
