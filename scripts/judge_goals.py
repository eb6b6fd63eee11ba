#!/usr/bin/env python
"""Judge answers to whole-robot IK problems by plain Pinocchio forward kinematics.

    python scripts/judge_goals.py /tmp/goals/talos.json /tmp/peers/talos.json      # problems, then results
    python scripts/judge_goals.py --dir /tmp/goals --results-dir /tmp/peers        # every ROBOT.json pair

An answer (Pinocchio's ``q``, ``nq`` numbers) solves a problem when every goal's position error is at most the
tolerance in m and every pose goal's rotation error ``||log3(R_target^T R)||`` at most the tolerance in rad, the
configuration is valid (unit quaternion of a free-flyer, unit (cos, sin) of a continuous joint, within
``VALID_TOL``) and every bounded joint is within its limits (``LIMIT_TOL`` rad or m of slack for rounding).
:func:`judge` is the function ``bench_goals.py`` calls so that evoik_pin's answers are judged by the same code as
the peers' (results files written by ``peers_runner.py``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin

sys.path.insert(0, str(Path(__file__).resolve().parent))
from goal_problems import frame_id, goal_errors, limits_of, load_problems, model_of, parse_goals  # noqa: E402

#: Success tolerance (m and rad) of the benchmark, and the looser ones reported for context.
TOLERANCES = (1e-6, 1e-5, 1e-4)
#: Slack (rad or m) allowed beyond a joint limit: rounding of a solver that stops exactly on the limit.
LIMIT_TOL = 1e-9
#: Largest departure of a quaternion's or a (cos, sin) pair's norm from 1 in a valid configuration.
VALID_TOL = 1e-9


def _unit_blocks(model: pin.Model) -> list[slice]:
    """Slices of ``q`` that must have unit norm: free-flyer quaternions, continuous joints' (cos, sin)."""
    blocks = []
    for joint in model.joints[1:]:
        if joint.nq == 7 and joint.nv == 6:
            blocks.append(slice(joint.idx_q + 3, joint.idx_q + 7))
        elif joint.nq == 2 and joint.nv == 1:
            blocks.append(slice(joint.idx_q, joint.idx_q + 2))
    return blocks


def judge(problems: dict, q_list, tol: float = 1e-6, model: pin.Model | None = None) -> list[dict]:
    """Judge one answer per problem.

    Args:
        problems: a problems file as loaded by ``goal_problems.load_problems`` (a dict).
        q_list: one answer per problem, each a configuration of shape (nq,) or None (no answer: a failure).
        tol: success tolerance, m for positions and rad for rotations.
        model: the Pinocchio model of the file (built from the file when None).

    Returns:
        One dict per problem: ``position_m`` and ``rotation_rad`` (lists, one per goal; rotation 0 for position
        goals), ``max_position_m``, ``max_rotation_rad``, ``limit_violation`` (largest excess beyond a limit, rad
        or m; 0 within), ``within_limits``, ``valid`` (unit quaternions and (cos, sin) pairs, right length),
        ``success`` (all of these within ``tol``), and ``answered``. A missing or malformed answer has
        infinite errors.

    Raises:
        ValueError: ``q_list`` is not one entry per problem.
    """
    if len(q_list) != len(problems["problems"]):
        raise ValueError(f"{len(q_list)} answers for {len(problems['problems'])} problems; accepted: one each")
    model = model_of(problems) if model is None else model
    data = model.createData()
    lower, upper = limits_of(problems)
    blocks = _unit_blocks(model)
    out = []
    for problem, q in zip(problems["problems"], q_list, strict=True):
        goals = parse_goals(problem["goals"])
        n_goals = len(goals)
        row = {"answered": q is not None, "valid": False, "within_limits": False, "limit_violation": np.inf,
               "position_m": [np.inf] * n_goals, "rotation_rad": [np.inf] * n_goals,
               "max_position_m": np.inf, "max_rotation_rad": np.inf, "success": False}
        q = None if q is None else np.asarray(q, dtype=float)
        if q is not None and q.shape == (model.nq,) and np.all(np.isfinite(q)):
            row["valid"] = all(abs(np.linalg.norm(q[b]) - 1.0) <= VALID_TOL for b in blocks)
            excess = np.maximum(q - upper, lower - q)
            row["limit_violation"] = float(max(0.0, np.max(excess[np.isfinite(excess)], initial=0.0)))
            row["within_limits"] = row["limit_violation"] <= LIMIT_TOL
            pin.framesForwardKinematics(model, data, q)
            err = goal_errors(data, [frame_id(model, g["frame"]) for g in goals], goals)
            row["position_m"], row["rotation_rad"] = err[:, 0].tolist(), err[:, 1].tolist()
            row["max_position_m"], row["max_rotation_rad"] = float(err[:, 0].max()), float(err[:, 1].max())
        row["success"] = bool(row["valid"] and row["within_limits"] and row["max_position_m"] <= tol
                              and row["max_rotation_rad"] <= tol)
        out.append(row)
    return out


def solved_at(rows: list[dict], tol: float) -> np.ndarray:
    """Boolean array: which judged answers (rows of :func:`judge`) are within ``tol`` m and rad."""
    return np.array([r["valid"] and r["within_limits"] and r["max_position_m"] <= tol
                     and r["max_rotation_rad"] <= tol for r in rows], dtype=bool)


def summary_line(name: str, rows: list[dict], times_s) -> str:
    """One line: success rates at :data:`TOLERANCES`, median / p90 time, median time on solved problems (ms)."""
    times = np.asarray(times_s, dtype=float) * 1e3
    ok = solved_at(rows, TOLERANCES[0])
    rates = "  ".join(f"{100 * solved_at(rows, t).mean():5.1f}%" for t in TOLERANCES)
    solved = f"{np.median(times[ok]):7.1f}" if ok.any() else "    n/a"
    limits = sum(not r["within_limits"] for r in rows if r["answered"])
    return (f"{name:<8s} {rates}   {np.median(times):7.1f} {np.percentile(times, 90):7.1f} {solved}"
            f"   {limits:3d}")


HEADER = (f"{'peer':<8s} {'1e-6':>6s}  {'1e-5':>6s}  {'1e-4':>6s}   {'median':>7s} {'p90':>7s} {'solved':>7s}"
          "   out-of-limits\n" + " " * 33 + "(ms, wall; 'solved': median on the problems solved at 1e-6)")


def judge_results(problems: dict, results: dict) -> str:
    """The summary table of a results file (``peers_runner.py``'s) against its problems file."""
    model = model_of(problems)
    problems = {**problems, "problems": problems["problems"][: results["n_problems"]]}  # a runner's --limit
    lines = [f"{problems['robot']} ({len(problems['problems'])} problems)", HEADER]
    for peer, entry in results["peers"].items():
        answers = entry["answers"]
        rows = judge(problems, [a["q"] for a in answers], model=model)
        lines.append(summary_line(peer, rows, [a["wall_s"] for a in answers]))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("problems", nargs="?", type=Path, help="a problems file (goal_problems.py)")
    parser.add_argument("results", nargs="?", type=Path, help="its results file (peers_runner.py)")
    parser.add_argument("--dir", type=Path, help="directory of problems files ROBOT.json")
    parser.add_argument("--results-dir", type=Path, help="directory of results files ROBOT.json")
    args = parser.parse_args(argv)
    if args.dir is not None:
        if args.results_dir is None:
            parser.error("--dir needs --results-dir")
        pairs = [(p, args.results_dir / p.name) for p in sorted(args.dir.glob("*.json"))
                 if (args.results_dir / p.name).is_file()]
        if not pairs:
            parser.error(f"no ROBOT.json in {args.dir} has a results file of the same name in {args.results_dir}")
    elif args.problems is not None and args.results is not None:
        pairs = [(args.problems, args.results)]
    else:
        parser.error("give PROBLEMS RESULTS, or --dir DIR --results-dir DIR")
    for problems_path, results_path in pairs:
        try:
            problems = load_problems(problems_path)
            results = json.loads(results_path.read_text(encoding="utf-8"))
            if results.get("problems_file_robot") != problems["robot"]:
                raise ValueError(f"{results_path} holds results for {results.get('problems_file_robot')!r}, "
                                 f"not for {problems['robot']!r}")
            print(judge_results(problems, results))
        except (OSError, ValueError, KeyError) as exc:
            parser.error(str(exc))
        print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
