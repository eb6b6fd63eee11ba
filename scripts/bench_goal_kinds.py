#!/usr/bin/env python
"""Issue 23's benchmark of goal kinds, every part in one command: each part is its own script (run alone for its
options), run here one after the other in fresh interpreters, their reports printed in turn.

    python scripts/bench_goal_kinds.py              # 200 problems per part, stdout
    python scripts/bench_goal_kinds.py --n 30       # quick
    python scripts/bench_goal_kinds.py --parts axes prefer
    python scripts/bench_goal_kinds.py --parts preferences --n 100

Parts:

* ``axes`` (scripts/bench_goal_kinds_axes.py): UR5 ``free="rz"`` against the full pose, a +-2 mm / +-5 degree
  band, Romeo's gaze ``LookAt`` with a wrist pose; judged by geometry.
* ``balance`` (scripts/bench_goal_kinds_balance.py): Talos standing (soles fixed, centre of mass over their
  support polygon, both hands), Baxter holding a 0.3 m box (``RelativePose``); Pinocchio as the judge.
* ``prefer`` (scripts/bench_goal_kinds_prefer.py): ``prefer="nearest"`` / ``"manipulability"`` on Panda and UR10
  against TRAC-IK's Distance / Manip1, goal sets of 10 Panda grasps of which 7 are unreachable, preferences never
  costing success.
* ``preferences`` (scripts/bench_goal_kinds_preferences.py): every benchmark above (the same problems, made by the
  parts' own functions) solved alone, with ``Posture`` and with ``JointLimitMargin`` added, interleaved problem by
  problem, under each benchmark's time budget and a fixed one (``timeout=None, max_restarts=5``): success, time and
  what the preference changed.

Each part's section of docs/BENCHMARKS.md is written by that part's script (see its docstring).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
#: Each part's script and the flags that make it print its report without writing docs/BENCHMARKS.md.
PARTS = {"axes": ("bench_goal_kinds_axes.py", ["--no-docs"]),
         "balance": ("bench_goal_kinds_balance.py", []),
         "prefer": ("bench_goal_kinds_prefer.py", []),
         "preferences": ("bench_goal_kinds_preferences.py", [])}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=200, help="problems per part (default 200)")
    ap.add_argument("--parts", nargs="+", choices=list(PARTS), default=list(PARTS), help="parts to run (default all)")
    args = ap.parse_args(argv)
    failed = []
    for name in args.parts:
        script, flags = PARTS[name]
        print(f"## part {name}: python scripts/{script} --n {args.n} {' '.join(flags)}".rstrip(), flush=True)
        rc = subprocess.call([sys.executable, str(HERE / script), "--n", str(args.n), *flags])
        if rc:
            failed.append(f"{name} (exit code {rc})")
    if failed:
        print(f"parts that failed: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
