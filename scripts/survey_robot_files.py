#!/usr/bin/env python
"""Survey the robot files of another package: which load, and how many reachable poses each solves.

Finds the URDF and xacro files (``*.urdf``, ``*.xacro``) under a folder whose ``<robot>`` element has a
``name`` (macro-only xacro files have none), and for each one:

* loads it with :func:`evoik_pin.load_robot` and nothing else (the default tip: the deepest link of the URDF;
  the default base: its root), plus ``package_dirs`` when ``--package-dir`` is given;
* draws ``--poses`` configurations with ``robot.random_configurations`` (uniformly within the robot's bounds,
  near-unbounded joints within ``robot.sampling_box()``; ``numpy.random.default_rng(--seed)``), takes their
  forward kinematics as 6-D pose targets (so each is
  reachable) and solves each with :func:`evoik_pin.solve` at its defaults (memetic, tolerance 1e-6 m and
  1e-6 rad, seed = the pose's index);
* counts ``Result.success``.

It prints one row per file: file, loads?, solved/poses, n (joints), tip, and the error message when it did not
load. The default folder is the installed ``rtb-data`` wheel's ``rtbdata/`` (``pip install rtb-data``, a
``bench`` extra).

    python scripts/survey_robot_files.py                      # every named robot file of rtb-data
    python scripts/survey_robot_files.py --only ridgeback kr5  # files whose path contains one of these
    python scripts/survey_robot_files.py --root DIR --package-dir DIR2 --json out.json
"""

from __future__ import annotations

import argparse
import importlib.util
import inspect
import json
import re
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import evoik_pin as ev
from evoik_pin.errors import EvoikError

_ROBOT_TAG = re.compile(rb"<robot\b[^>]*>", re.S)
_NAME = re.compile(rb"""\sname\s*=\s*["']([^"']*)["']""")


def rtb_data_root() -> Path:
    """The ``rtbdata/`` folder of the installed rtb-data wheel."""
    spec = importlib.util.find_spec("rtbdata")
    if spec is None or not spec.submodule_search_locations:
        sys.exit("rtb-data is not installed: pip install rtb-data (or give --root DIR)")
    return Path(next(iter(spec.submodule_search_locations))).resolve()


def robot_name(path: Path) -> str | None:
    """The ``name`` of the file's first ``<robot ...>`` element, or None (no element, or no name)."""
    m = _ROBOT_TAG.search(path.read_bytes())
    if m is None:
        return None
    name = _NAME.search(m.group())
    return name.group(1).decode("utf-8", "replace") if name and name.group(1).strip() else None


def robot_files(root: Path) -> list[Path]:
    """URDF and xacro files under ``root`` whose <robot> has a name, sorted by path."""
    files = sorted(p for p in root.rglob("*") if p.is_file() and p.suffix.lower() in (".urdf", ".xacro"))
    return [p for p in files if robot_name(p) is not None]


def survey_one(path: Path, poses: int, seed: int, package_dirs: list[str]) -> dict:
    """Load ``path`` and solve ``poses`` reachable pose targets; a dict row for the table."""
    kw = {"package_dirs": package_dirs} if package_dirs else {}
    row = {"file": str(path), "loads": False, "solved": 0, "poses": poses, "n": None, "tip": None, "error": ""}
    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            robot = ev.load_robot(str(path), **kw)
    except EvoikError as exc:
        row["error"] = f"{type(exc).__name__}: {exc}"
        return row
    except Exception as exc:  # a raw exception from a dependency is a finding in itself: report it
        row["error"] = f"UNCAUGHT {type(exc).__name__}: {exc}"
        return row
    row.update(loads=True, n=robot.n, tip=robot.tip)
    rng = np.random.default_rng(seed)
    Q = robot.random_configurations(poses, rng)  # uniform within the bounds; a mobile base's +-999999 m joints near it
    failures = []
    for i, q in enumerate(Q):
        try:
            res = ev.solve(robot, robot.fk(q), seed=i)
        except Exception as exc:  # noqa: BLE001 - reported in the table
            failures.append(f"pose {i}: {type(exc).__name__}: {exc}")
            continue
        if res.success:
            row["solved"] += 1
        elif len(failures) < 2:
            failures.append(f"pose {i}: position error {res.position_error:.2e} m, orientation error "
                            f"{res.orientation_error:.2e} rad ({res.message})")
    row["error"] = "; ".join(failures)
    row["time_s"] = round(time.perf_counter() - t0, 1)
    return row


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--root", type=Path, default=None, help="folder to search (default: rtb-data's rtbdata/)")
    ap.add_argument("--package-dir", action="append", default=[], metavar="DIR",
                    help="a folder holding ROS packages, passed to load_robot(package_dirs=...) (repeatable)")
    ap.add_argument("--poses", type=int, default=20, help="reachable pose targets per robot (default 20)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the random configurations (default 0)")
    ap.add_argument("--only", nargs="*", default=None, help="keep files whose path contains one of these")
    ap.add_argument("--json", type=Path, default=None, help="also write the rows as JSON")
    args = ap.parse_args(argv)
    if args.package_dir and "package_dirs" not in inspect.signature(ev.load_robot).parameters:
        sys.exit("this evoik_pin's load_robot takes no package_dirs")
    root = (args.root or rtb_data_root()).resolve()
    files = robot_files(root)
    if args.only:
        files = [f for f in files if any(s in str(f) for s in args.only)]
    print(f"# {len(files)} named robot files under {root}; evoik_pin from {Path(ev.__file__).parent}", flush=True)
    rows = []
    for f in files:
        row = survey_one(f, args.poses, args.seed, args.package_dir)
        row["file"] = str(f.relative_to(root))
        rows.append(row)
        shown = row["error"].replace("\n", " ")
        print(f"{row['file']} | {'yes' if row['loads'] else 'no'} | {row['solved']}/{row['poses']} | "
              f"n={row['n']} tip={row['tip']} | {shown[:300]}", flush=True)
    loaded = sum(r["loads"] for r in rows)
    full = sum(r["loads"] and r["solved"] == r["poses"] for r in rows)
    print(f"# files: {len(rows)}, load: {loaded}, solve {args.poses}/{args.poses}: {full}")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
