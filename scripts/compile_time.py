#!/usr/bin/env python
"""CPU and wall time of the numba code's first compilation, from an empty cache: the LM kernel's entries
(``compiled_kernel``), memetic's compiled guaranteed runs (a first solve) and the null-space descent and task rows of
``prefer=`` / preferences (``nullspace_kernel``).

    python scripts/compile_time.py     # compiles into a fresh temporary NUMBA_CACHE_DIR (the real cache untouched)

numba reads ``NUMBA_CACHE_DIR`` when it is imported, so the script sets it and runs the measurement in a child
process. CPU time (user + system, the child's own) is the figure to compare: wall time on a shared machine mostly
measures the other processes.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile

CHILD = r"""
import resource, time
import numpy as np

def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime

c, w = cpu(), time.perf_counter()
rows = []
def lap(name):
    global c, w
    c2, w2 = cpu(), time.perf_counter()
    rows.append((name, c2 - c, w2 - w))
    c, w = c2, w2

import evoik_pin as ev
from evoik_pin.solvers.lm.engine import compiled_kernel
from evoik_pin.solvers.lm.nullspace import nullspace_kernel
lap("import evoik_pin")
compiled_kernel()
lap("LM kernel entries (compiled_kernel)")
robot = ev.load_robot("panda")
q = (robot.lower + robot.upper) / 2
ev.solve(robot, robot.fk(q), seed=0)
lap("first solve (seed table, memetic's guaranteed runs)")
nullspace_kernel()
lap("prefer= / preferences (nullspace_kernel)")
for name, cs, ws in rows:
    print(f"| {name} | {cs:.1f} | {ws:.1f} |")
print(f"| total | {sum(r[1] for r in rows):.1f} | {sum(r[2] for r in rows):.1f} |")
"""


def main() -> int:
    with tempfile.TemporaryDirectory(prefix="evoik_numba_cache_") as cache:
        print(f"load average {os.getloadavg()[0]:.1f}; NUMBA_CACHE_DIR={cache}")
        print("| step | CPU s | wall s |\n|---|---:|---:|")
        sys.stdout.flush()
        done = subprocess.run([sys.executable, "-c", CHILD], env={**os.environ, "NUMBA_CACHE_DIR": cache})
        print(f"load average {os.getloadavg()[0]:.1f}")
        return done.returncode


if __name__ == "__main__":
    raise SystemExit(main())
