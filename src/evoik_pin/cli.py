"""The ``evoik`` command line: robots, fk, solve, reach, reproduce, view, retarget (docs/CLI.md); one ``_cmd_*``
function per sub-command. Revolute joint values in degrees unless ``--rad``, prismatic ones and positions in m.
"""

from __future__ import annotations

import argparse
import ast
import json
import os
import re
import sys
import warnings

import numpy as np

from .errors import BvhError, ConfigurationError, EvoikError, GoalsFileError, OptionError, RobotLoadWarning
from .io.datafile import naming
from .robot import BUNDLED_ROBOTS, EXAMPLE_ARMS, WHOLE_ROBOTS, load_robot


def _load(args: argparse.Namespace, goals_file=None):
    """The robot of the robot arguments; with a goals file (:class:`~evoik_pin.io.goals_file.GoalsFile`), its
    ``floating_base`` and ``tips`` fill in the flags not given, and a value given both ways that differs (the
    file's ``robot`` another than ROBOT, ``--floating-base`` on a file saying false, other ``--tips``) is an
    error naming the flag and the file."""
    xacro_args = dict(_name_value(item, "--xacro-arg", "NAME=VALUE") for item in args.xacro_arg)
    aliases = dict(_name_value(item, "--package-alias", "NAME=SHIPPED_AS", lambda _, value: bool(value))
                   for item in args.package_alias)
    tips = args.tips[0] if args.tips == ["all"] else args.tips
    floating_base = args.floating_base
    if goals_file is not None:
        where = f"goals file {str(goals_file.path)!r}"
        if goals_file.floating_base is not None:
            if floating_base and not goals_file.floating_base:
                raise GoalsFileError(f"--floating-base: {where} says floating_base: false")
            floating_base = goals_file.floating_base
        if goals_file.tips is not None:
            if tips is not None and list(args.tips) != goals_file.tips:
                raise GoalsFileError(f"--tips {' '.join(args.tips)}: {where} says tips: {goals_file.tips}; give "
                                     "the same frames or leave --tips out")
            tips = goals_file.tips[0] if goals_file.tips == ["all"] else goals_file.tips
    robot = load_robot(args.robot, tip=args.tip, base=args.base, xacro_args=xacro_args or None,
                       package_dirs=args.package_dir or None, tips=tips, floating_base=floating_base,
                       package_aliases=aliases or None)
    if goals_file is not None and goals_file.robot not in (None, args.robot, robot.name):
        raise GoalsFileError(f"goals file {str(goals_file.path)!r} is for robot {goals_file.robot!r}, not "
                             f"{args.robot!r}: give ROBOT {goals_file.robot} or change the file's robot:")
    return robot


def _name_value(item: str, flag: str, form: str, ok=lambda name, value: True) -> tuple[str, str]:
    """(NAME, VALUE) of a ``flag NAME=VALUE`` (``NAME:=VALUE`` too); OptionError '<flag> needs <form>, got ...' for
    an item without a name, or whose name and value ``ok`` refuses."""
    name, sep, value = item.partition(":=") if ":=" in item else item.partition("=")
    name = name.strip()
    if not sep or not name or not ok(name, value):
        raise OptionError(f"{flag} needs {form}, got {item!r}")
    return name, value


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _joint_values(robot, values: list[float], rad: bool) -> np.ndarray:
    """Joint values typed at the command line in SI: revolute joints in degrees (radians with ``--rad``),
    prismatic joints in m either way. A list of the wrong length is converted whole (the library names it)."""
    q = np.asarray(values, dtype=float)
    if rad:
        return q
    return np.where(robot.revolute, np.radians(q), q) if q.shape == (robot.n,) else np.radians(q)


def _locked_values(robot, items: list[str], rad: bool) -> dict[str, float]:
    """``--locked NAME=VALUE`` flags as {joint: value in SI} (revolute in degrees unless ``--rad``); the library
    checks the names and limits."""
    out = {}
    for item in items:
        name, text = _name_value(item, "--locked", "NAME=VALUE (a joint and a number)", lambda _, v: _is_number(v))
        revolute = name in robot.joint_names and bool(robot.revolute[robot.joint_names.index(name)])
        out[name] = float(np.radians(float(text))) if revolute and not rad else float(text)
    return out


def _shown(robot, q: np.ndarray, rad: bool) -> np.ndarray:
    """Joint values (n,) in SI as the command line shows them: revolute in degrees unless ``--rad``, prismatic in m."""
    q = np.asarray(q, dtype=float)
    return q if rad else np.where(robot.revolute, np.degrees(q), q)


def _q_flag(args: argparse.Namespace, robot) -> np.ndarray:
    """The joint vector (n,) of ``--q`` in rad and m (zeros without it); a ConfigurationError naming ``--q``."""
    with naming("--q", ConfigurationError):
        return robot.check_q(_joint_values(robot, args.q, args.rad)) if args.q else np.zeros(robot.n)


# ------------------------------------------------------------------ the options of the wrapped Python calls
#: Option of the Python call (``solve``, ``solve_all``, ``reachability_map``; the shared problem options; the
#: methods' common options) -> the named flag that sets it: its name in kebab case, but for two. Every other method
#: option: ``--option NAME=VALUE``.
CALL_FLAGS = {**{name: "--" + name.replace("_", "-") for name in (
    "method", "seed", "tolerance", "rotation_tolerance", "q0", "orientation_weight", "pose_metric", "scene", "margin",
    "polish", "population", "max_generations", "timeout", "count", "voxel", "orientations", "backend", "workers",
    "address", "batch_size", "prefer", "locked")}, "bounds": "--lower/--upper", "progress": "--no-progress"}
#: Options of ``solve``'s methods that no command-line value expresses, and why.
NOT_ON_CLI = {"objective": "a Python callable objective(Q, kin) -> (N,) costs",
              "callback": "a Python callable called every generation",
              "objectives": "a list of evoik_pin.objectives.Objective instances"}
#: Problem options ``evoik reach`` does not offer, and why.
REACH_NOT_ON_CLI = {"q0": "every voxel starts from the seed table",
                    "bounds": "the workspace is sampled in the robot's own bounds, so the map keeps them",
                    "objective": NOT_ON_CLI["objective"]}
#: Phrases the library's target checks start their messages with -> the flag that gave the value.
_TARGET_FLAGS = {"target position": "--xyz", "target roll-pitch-yaw": "--rpy"}


#: Options passed on as typed (the rest: q0 and bounds in degrees, scene and margin, the calls' own arguments).
_PLAIN_OPTIONS = ("tolerance", "rotation_tolerance", "orientation_weight", "pose_metric", "polish", "population",
                  "max_generations", "timeout", "count", "prefer")
#: ``--timeout none``: no wall-clock budget (None in Python; argparse's None means "not given").
_NO_LIMIT = "none"


def _seconds(text: str) -> float | str:
    """``--timeout``'s value: seconds, or ``none`` for no wall-clock budget (the library checks the range)."""
    if text.strip().lower() == _NO_LIMIT:
        return _NO_LIMIT
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seconds or 'none', got {text!r}") from None


def _dest(flag: str) -> str:
    return flag.split("/")[0].lstrip("-").replace("-", "_")


def _given_options(args: argparse.Namespace, robot) -> dict[str, tuple[object, str]]:
    """The options the user typed: {library name: (value in SI units, the flag as typed)}."""
    given: dict[str, tuple[object, str]] = {}
    for name in _PLAIN_OPTIONS:
        value = getattr(args, _dest(CALL_FLAGS[name]), None)
        if value is not None and value is not False:
            given[name] = (None if value == _NO_LIMIT else value, CALL_FLAGS[name])
    if getattr(args, "q0", None) is not None:
        given["q0"] = (_joint_values(robot, args.q0, args.rad), "--q0")  # its length is checked by the library
    lower, upper = getattr(args, "lower", None), getattr(args, "upper", None)
    if lower is not None or upper is not None:
        bounds = (robot.lower if lower is None else _joint_values(robot, lower, args.rad),
                  robot.upper if upper is None else _joint_values(robot, upper, args.rad))
        given["bounds"] = (bounds, CALL_FLAGS["bounds"])
    if getattr(args, "locked", None):
        given["locked"] = (_locked_values(robot, args.locked, args.rad), "--locked")
    for item in getattr(args, "option", []):
        name, text = _name_value(item, "--option", "NAME=VALUE with NAME a Python keyword (e.g. runs=5)",
                                 lambda name, _: name.isidentifier())
        flag = f"--option {name}"
        if name in CALL_FLAGS and hasattr(args, _dest(CALL_FLAGS[name])):
            raise OptionError(f"{flag}: use {CALL_FLAGS[name]} (one way to set each option)")
        if name in NOT_ON_CLI or name in given:
            why = NOT_ON_CLI.get(name, "given twice")
            raise OptionError(f"{flag}: not settable from the command line ({why})" if name in NOT_ON_CLI
                              else f"{flag}: {why}")
        try:
            value = ast.literal_eval(text.strip())
        except (ValueError, SyntaxError):
            value = text.strip()  # a bare word: a string (e.g. strategy=rand1bin)
        given[name] = (value, flag)
    return given


def _call_options(args: argparse.Namespace, robot, method: str, pool: list[str] | None = None) -> dict:
    """The keyword options of the wrapped call from the flags, checked against ``method`` (an option it does not take
    names the flag and the methods of ``pool`` that take it; ``pool`` None: the command's one method). Records on
    ``args.typed_flags`` which flag set which option, so that :func:`main` names the flag in the library's errors."""
    from .api import _PROBLEM_OPTIONS
    from .solvers import get_solver

    given = _given_options(args, robot)
    takes = get_solver(method).options
    for name, (_, flag) in given.items():  # an option method does not take: the flag and the methods that take it
        if name in _PROBLEM_OPTIONS or name in ("polish", "prefer", "locked") or name in takes:
            continue
        if pool is None:
            raise OptionError(f"{flag} is not an option of method {method!r} (the solver of evoik {args.command}); "
                              f"it takes: {', '.join(takes)}")
        takers = [m for m in pool if name in get_solver(m).options]
        if takers:
            raise OptionError(f"{flag} is not an option of method {method!r}; methods that take it: "
                              f"{', '.join(takers)}")
        raise OptionError(f"{flag}: no method takes an option {name!r}; method {method!r} takes: {', '.join(takes)}")
    args.typed_flags = {name: flag for name, (_, flag) in given.items()}
    if getattr(args, "goals", None) is None:  # a goals file's targets are not typed as flags
        args.typed_flags.update(_TARGET_FLAGS)
    if getattr(args, "seed", 0):  # the default 0 is always valid; a typed seed the library rejects is named
        args.typed_flags["seed"] = "--seed"
    return {name: value for name, (value, _) in given.items()}


def _name_the_flag(message: str, flags: dict[str, str]) -> str:
    """``message`` of a library error with the option it names replaced by the flag that set it ("population
    must be ..." -> "--population must be ..."), or prefixed with the flag when it names the option later on."""
    names = sorted(flags, key=len, reverse=True)
    for name in names:
        if re.match(rf"{re.escape(name)}(?![\w-])", message):
            return flags[name] + message[len(name):]
    for name in names:
        if re.search(rf"(?<![\w-]){re.escape(name)}(?![\w-])", message):
            return f"{flags[name]}: {message}"
    return message


def _cmd_robots(args: argparse.Namespace) -> int:
    print("Bundled paper arms:")
    for name, what in BUNDLED_ROBOTS.items():
        print(f"  {name:12s} {what}")
    print("example-robot-data arms (default tip frame):")
    for name, arm in EXAMPLE_ARMS.items():
        print(f"  {name:12s} {arm.urdf} (tip {arm.tip})")
    print("example-robot-data whole robots (every joint; floating_base=True adds a free-flying root):")
    for name, whole in WHOLE_ROBOTS.items():
        print(f"  {name:16s} {whole.what}")
    return 0


def _cmd_fk(args: argparse.Namespace) -> int:
    import pinocchio as pin

    robot = _load(args)
    q = _q_flag(args, robot)
    T = robot.fk(q, frame=args.frame)
    info = {"robot": robot.name, "tip": robot.tip, "frame": args.frame or robot.tip, "base": robot.base,
            "q_rad": [float(v) for v in q], "position_m": [float(v) for v in T.translation],
            "rpy_rad": [float(v) for v in pin.rpy.matrixToRpy(T.rotation)], "rotation": np.asarray(T.rotation).tolist()}
    if args.json:
        print(json.dumps(info, indent=2))
        return 0
    what = f"tip {robot.tip!r}" if args.frame is None else f"frame {args.frame!r}"
    print(f"{robot.name}: {robot.n} joints, base {robot.base!r} -> {what}")
    print(f"q ({'rad' if args.rad else 'deg'}):        " + " ".join(f"{v:.4f}" for v in _shown(robot, q, args.rad)))
    print("position (m):   " + " ".join(f"{v:.6f}" for v in info["position_m"]))
    print("rpy (deg):      " + " ".join(f"{np.degrees(v):.4f}" for v in info["rpy_rad"]))
    print("rotation:\n" + "\n".join("  " + " ".join(f"{v:+.6f}" for v in row) for row in info["rotation"]))
    return 0


def _cmd_solve(args: argparse.Namespace) -> int:
    """IK for one target (xyz in m, optional roll-pitch-yaw in degrees) or a goals file; exit 1 when not reached."""
    import pinocchio as pin

    from .api import DEFAULT_ALL_METHOD, DEFAULT_METHOD, GOAL_METHODS, solve
    from .goals import Goal
    from .papers.reporting import check_output_file
    from .problem import Target
    from .solvers import get_solver, methods

    goals_file = _goals_arg(args)
    robot = _load(args, goals_file)
    html = check_output_file(args.html) if args.html else None  # before any work starts
    scene, margin = _load_scene(args, robot)
    method = args.method or (DEFAULT_ALL_METHOD if args.all else DEFAULT_METHOD)
    get_solver(method)  # an unknown method is named before its options are checked
    if goals_file is not None:
        goals_file.bind(robot)  # unknown frames and frames no active joint moves, named by file and goal
    pool = [m for m in (methods() if goals_file is None else GOAL_METHODS)
            if get_solver(m).multi_solution or not args.all]
    options = _call_options(args, robot, method, pool)
    if scene is not None:
        options.update(scene=scene, margin=margin)
    if goals_file is not None:
        target = goals_file.problems[0]
    else:
        position = np.asarray(args.xyz, dtype=float)
        target = position if args.rpy is None else Target.from_rpy(position, np.radians(args.rpy))
    if args.all:
        return _solve_all(args, robot, target, options, html, method, goals_file is not None)
    res = solve(robot, target, method=method, seed=args.seed, **options)
    info = {"robot": robot.name, "method": res.method or method, "success": bool(res.success),
            "message": res.message, "joint_names": list(robot.joint_names), **_q_fields(robot, res.q)}
    if goals_file is None:
        reached = robot.fk(res.q)
        info.update(target_position_m=[float(v) for v in position],
                    target_rpy_deg=None if args.rpy is None else [float(v) for v in args.rpy],
                    reached_position_m=[float(v) for v in reached.translation],
                    reached_rpy_deg=[float(v) for v in np.degrees(pin.rpy.matrixToRpy(reached.rotation))])
        target = Target.coerce(target)
    else:
        target = [g for g in target if isinstance(g, Goal)]  # the preferences have no errors to show
        info.update(floating_base=robot.floating_base, goals_file=str(args.goals),
                    q_pinocchio=[float(v) for v in robot.full_configuration(res.q)],
                    goal_errors=[_goal_row(res, i, g, *e) for i, (g, e) in enumerate(zip(target, res.goal_errors,
                                                                                         strict=True))])
    info.update(position_error_m=res.position_error, orientation_error_rad=res.orientation_error, cost=res.cost,
                generations=res.generations, evaluations=res.evaluations, time_s=res.time_s, seed=args.seed)
    _report(args, robot, res, info, scene, margin)
    if html is not None or args.view:
        _view_solution(robot, res, target, html, args.view, scene=scene, margin=margin)
    return 0 if res.success else 1


def _goal_row(res, i: int, goal, pos, rot) -> dict:
    """Goal ``i``'s line of a goal-list answer (``evoik solve --goals --json``'s ``goal_errors``)."""
    from .io.goals_file import goal_kind_name

    row = {"frame": goal.frame, "kind": goal_kind_name(goal), "position_error_m": pos, "rotation_error_rad": rot,
           "met": bool(goal.met(pos, rot)), "tolerance_m": goal.tolerance if goal.has_position else None,
           "rotation_tolerance_rad": goal.rotation_tolerance if goal.reports_angle else None, "weight": goal.weight}
    if goal.label != goal.frame:  # a centre of mass (no frame), a relative pose (frame_a -> frame)
        row["label"] = goal.label
        if getattr(goal, "frame_a", None):
            row["frame_a"] = goal.frame_a
    if goal.alternatives is not None:  # a goal set: the member met
        row["chosen"] = res.chosen[i]
    return row


def _q_fields(robot, q) -> dict:
    """An answer's joint values for JSON output: ``q_rad`` and ``q_deg`` (revolute in degrees, prismatic in m)."""
    return {"q_rad": [float(v) for v in q], "q_deg": [float(v) for v in _shown(robot, q, False)]}


def _solve_all(args: argparse.Namespace, robot, target, options: dict, html, method: str, goal_list: bool) -> int:
    """``evoik solve --all``: every solution of the target or goal list (``solve_all``), one line each or as JSON;
    exit 1 when there is none. ``--html`` / ``--view``: the first solution (or the best approximation), the others
    as ghosts."""
    from .api import solve_all
    from .problem import Target

    sols = solve_all(robot, target, method=method, seed=args.seed, **options)
    res = sols.result
    scene = options.get("scene")
    rows = [_q_fields(robot, s.q) for s in sols]
    info = {"robot": robot.name, "method": res.method or method, "success": bool(sols), "count": len(sols),
            "message": sols.message, "joint_names": list(robot.joint_names), "solutions": rows,
            "time_s": res.time_s, "seed": args.seed}
    if goal_list:
        for row, s in zip(rows, sols, strict=True):
            row.update(q_pinocchio=[float(v) for v in robot.full_configuration(s.q)], goal_errors=[
                {"frame": g.frame, "position_error_m": p, "rotation_error_rad": o, "met": bool(g.met(p, o))}
                for g, (p, o) in zip(target, s.goal_errors, strict=True)])
        info.update(floating_base=robot.floating_base, goals_file=str(args.goals))
        found = f"{len(sols)} solution(s) of {len(target)} goals"
    else:
        for row, s in zip(rows, sols, strict=True):
            row.update(position_error_m=s.position_error, orientation_error_rad=s.orientation_error)
            if scene is not None:  # solve_all keeps the collision-free solutions only
                row.update(collision_free=bool(s.collision_free), min_distance_m=float(s.min_distance))
        info.update(target_position_m=[float(v) for v in args.xyz],
                    target_rpy_deg=None if args.rpy is None else [float(v) for v in args.rpy])
        if scene is not None:
            info.update(scene=str(args.scene), margin_m=options["margin"])
        found = f"{len(sols)} solution(s)"
    if args.json:
        print(json.dumps(info, indent=2))
    else:
        print(f"{robot.name} ({robot.n} joints), method {info['method']}: {found} in {res.time_s * 1e3:.2f} ms "
              f"({sols.message})")
        if sols:
            print(f"  #  q ({'rad' if args.rad else 'deg'}): {' '.join(robot.joint_names)}")
        for k, s in enumerate(sols):
            if goal_list:
                rot = "" if s.orientation_error is None else f", rotation {s.orientation_error:.1e} rad"
                errors = f"every goal met; largest errors: position {s.position_error:.1e} m{rot}"
            else:
                rot = "" if s.orientation_error is None else f", orientation error {s.orientation_error:.1e} rad"
                free = "" if scene is None else f", collision-free, min distance {s.min_distance * 1e3:.1f} mm"
                errors = f"position error {s.position_error:.1e} m{rot}{free}"
            print(f"{k:3d}  " + " ".join(f"{v:.4f}" for v in _shown(robot, s.q, args.rad)) + f"  ({errors})")
    if html is not None or args.view:
        _view_solution(robot, sols[0] if sols else res, target if goal_list else Target.coerce(target), html,
                       args.view, ghosts=sols, scene=scene, margin=options.get("margin", 0.0))
    return 0 if sols else 1


def _view_solution(robot, res, target, html, view: bool, ghosts=None, scene=None, margin: float = 0.0) -> None:
    """Show a solve's answer and its target (a :class:`Target`, or a goal list: its goals' markers) in meshcat, with
    ``ghosts`` (e.g. every solution of ``--all``) as translucent robots and a ``scene``'s obstacles (the links in
    collision red); write ``html`` and/or serve until Ctrl-C."""
    from .viz import Viewer

    with Viewer(robot) as viewer:
        if isinstance(target, list):
            viewer.show_solution(res, target, scene=scene, margin=margin)
        else:
            viewer.show(res, scene=scene, margin=margin)
        if ghosts:
            viewer.show_solutions(ghosts)
        if not isinstance(target, list):
            viewer.show_target(target.position, target.rotation)
        if html is not None:
            print(f"wrote {viewer.save_html(html)}", file=sys.stderr)
        if view:
            viewer.block(f"meshcat viewer of {robot.name}: {viewer.url} (Ctrl-C to stop)", file=sys.stderr)


def _goals_arg(args: argparse.Namespace):
    """The :class:`~evoik_pin.io.goals_file.GoalsFile` of ``--goals FILE`` (None without it), after checking that
    the target is given one way: ``--goals`` or ``--xyz`` (with ``--rpy``), and that no flag of a one-target
    solve comes with it."""
    if args.goals is None:
        if args.xyz is None:
            raise OptionError("evoik solve needs a target: --xyz X Y Z (m; with --rpy R P Y in degrees for a pose) "
                              "or --goals FILE (a goals file: frames, kinds, targets)")
        return None
    given = [flag for flag, value in (("--xyz", args.xyz), ("--rpy", args.rpy)) if value is not None]
    if given:
        raise OptionError(f"--goals and {'/'.join(given)}: give the targets one way, --goals FILE (every goal in "
                          "the file) or --xyz X Y Z [--rpy R P Y] (one target for the tip)")
    for flag, value in (("--tolerance", args.tolerance), ("--rotation-tolerance", args.rotation_tolerance)):
        if value is not None:
            raise OptionError(f"{flag} and --goals: each goal has its own tolerances, the goals file's tolerance: "
                              "(m) and rotation_tolerance: (rad) of the goal (default 1e-6)")
    from .io.goals_file import read_goals_file

    goals_file = read_goals_file(args.goals)
    if goals_file.several:
        raise GoalsFileError(f"goals file {args.goals!r} holds {len(goals_file.problems)} problems (problems:); "
                             "evoik solve solves one goal list (goals:): in Python, evoik_pin.io.goals_file."
                             "load_problems with solve_many or solve_trajectory")
    return goals_file


def _report(args: argparse.Namespace, robot, res, info: dict, scene, margin: float) -> None:
    """Print a solve's answer: ``info`` as JSON with ``--json``, else as text (one line per goal of its
    ``goal_errors``); with a scene, the verdict of the exact mesh check on the answer too."""
    if scene is not None:
        pairs = [list(p) for p in scene.colliding_pairs(res.q, margin)]  # each pair of names once
        info.update(scene=str(args.scene), margin_m=margin, collision_free=bool(res.collision_free),
                    min_distance_m=float(res.min_distance), colliding_pairs=pairs)
    if args.json:
        print(json.dumps(info, indent=2))
        return
    unit = "rad" if args.rad else "deg"
    print(f"{robot.name} ({robot.n} joints), method {info['method']}: "
          f"{'reached' if res.success else 'NOT reached'} ({res.message})")
    print(f"q ({unit}):            " + " ".join(f"{v:.6f}" for v in _shown(robot, res.q, args.rad)))
    print(f"position error (m):   {res.position_error:.3e}")
    if res.orientation_error is not None:
        print(f"orientation error:    {res.orientation_error:.3e} rad ({np.degrees(res.orientation_error):.3e} deg)")
    print(f"generations:          {res.generations}")
    print(f"evaluations:          {res.evaluations}")
    print(f"time:                 {res.time_s * 1e3:.2f} ms")
    if "goal_errors" in info:
        _print_goal_errors(info["goal_errors"])
    if scene is not None:
        where = f"scene {info['scene']}" + (f", margin {margin:g} m" if margin > 0 else "")
        print(f"collision-free: {'yes' if res.collision_free else 'no'} (min distance "
              f"{info['min_distance_m'] * 1e3:.3f} mm; {where})")
        if pairs:
            print("in collision:   " + ", ".join(f"{a} - {b}" for a, b in pairs))


def _print_goal_errors(rows: list[dict]) -> None:
    """One line per goal: frame, kind, position error (m), rotation error (rad, or "free"), met."""
    names = [r.get("label", r["frame"]) for r in rows]  # a centre of mass has no frame; a relative pose two
    width = max(len("frame"), *(len(name) for name in names))
    kw = max(len("kind"), *(len(r["kind"]) for r in rows))  # orientation, look_at, ...
    print(f"  #  {'frame':{width}s}  {'kind':{kw}s}  position error (m)  rotation error (rad)  met")
    for k, (r, name) in enumerate(zip(rows, names, strict=True)):
        rot = "free" if r["rotation_error_rad"] is None else f"{r['rotation_error_rad']:.3e}"
        pos = "free" if r["position_error_m"] is None else f"{r['position_error_m']:.3e}"  # orientation, pointing
        print(f"{k:3d}  {name:{width}s}  {r['kind']:{kw}s}  {pos:<18s}  {rot:<20s}  {'yes' if r['met'] else 'NO'}")


def _load_scene(args: argparse.Namespace, robot):
    """(Scene of ``--scene FILE`` or None, ``--margin`` in m (default 0)); OptionError for a margin without a
    scene or below 0, SceneError (exit 2) for a bad scene file."""
    margin = getattr(args, "margin", None)
    if args.scene is None:
        if margin is not None:
            raise OptionError("--margin needs --scene FILE: it is the clearance (m) kept from the scene's obstacles "
                              "and the robot's own links")
        return None, 0.0
    if margin is not None and not (np.isfinite(margin) and margin >= 0):
        raise OptionError(f"--margin must be a finite clearance >= 0 in m, got {margin:g}")
    from .scene import Scene

    return Scene.from_file(robot, args.scene), 0.0 if margin is None else float(margin)


def _cmd_view(args: argparse.Namespace) -> int:
    from .viz import Viewer

    robot = _load(args)
    q = _q_flag(args, robot)
    if args.no_block and not args.html:
        raise OptionError("--no-block without --html shows nothing: the viewer stops when evoik exits; add "
                          "--html PATH to keep the scene as a file")
    scene, _ = _load_scene(args, robot)
    with Viewer(robot) as viewer:
        pairs = viewer.show(q, scene=scene)
        viewer.show_target(robot.fk(q))
        if scene is not None:
            print(f"collision-free: {'no' if pairs else 'yes'} (scene {args.scene}"
                  + (f"; in collision: {', '.join(f'{a} - {b}' for a, b in pairs)})" if pairs else ")"), flush=True)
        if args.no_block:  # the server stops when we return: the file is what stays
            print(f"wrote {viewer.save_html(args.html)} (a self-contained page; the meshcat server "
                  f"{viewer.url} that rendered it stops when evoik exits)", flush=True)
            return 0
        print(f"meshcat viewer of {robot.name}: {viewer.url}", flush=True)
        if args.html:
            print(f"wrote {viewer.save_html(args.html)}")
        viewer.block("Press Ctrl-C to stop the viewer.")
    return 0


def _cmd_reach(args: argparse.Namespace) -> int:
    """``evoik reach``: a reachability map written to OUT (npz, png slices, meshcat html)."""
    from .reach import output_dir, reachability_map

    robot = _load(args)
    output_dir(args.out)  # before the work: an unwritable OUT fails at once
    scene, margin = _load_scene(args, robot)
    options = _call_options(args, robot, "memetic")  # the batch engine runs memetic's LM rounds
    if scene is not None:
        options["margin"] = margin
    rmap = reachability_map(robot, voxel=args.voxel, orientations=args.orientations, scene=scene,
                            backend=args.backend, workers=args.workers, seed=args.seed, progress=not args.no_progress,
                            address=args.address, batch_size=args.batch_size, **options)
    paths = rmap.save(args.out, html=not args.no_html, robot=robot)
    reached = int(rmap.reached.sum())
    mean = float(rmap.index[rmap.reached].mean()) if reached else 0.0
    print(f"{robot.name}: {reached} of {rmap.index.size} voxels of {args.voxel:g} m reached ({rmap.kind} map, "
          f"{rmap.orientations} orientation(s) per voxel, mean index of those {mean:.3f}) in {rmap.time_s:.1f} s",
          flush=True)
    for path in paths.values():
        print(f"wrote {path}")
    return 0


def _cmd_reproduce(args: argparse.Namespace) -> int:
    from .papers import run_papers
    from .papers.reporting import check_output_file, show_animation

    html = check_output_file(args.html) if args.html else None  # before any work starts
    reports = run_papers(args.paper, out=args.out, quick=args.quick, seed=args.seed, progress=not args.no_progress,
                         jobs=args.jobs)
    for r in reports:
        mode = "quick" if r.quick else "full"
        print(f"paper {r.paper_id} ({mode}, seed {r.seed}): {r.wall_time_s:.1f} s -> {args.out}/{r.paper_id}/report.md",
              flush=True)
    if html is not None or args.view:
        shown = [r for r in reports if r.animation is not None]
        if not shown:
            print("no reproduced paper has an animation to show (paper 002 has the spiral)", file=sys.stderr)
        for r in shown:
            path = html if html is None or len(shown) == 1 else html.with_name(f"{html.stem}_{r.paper_id}{html.suffix}")
            written = show_animation(r.animation, html=path, view=args.view)
            if written is not None:
                print(f"wrote {written}")
    return 0


def _cmd_retarget(args: argparse.Namespace) -> int:
    """``evoik retarget``: a BVH file (or a bundled clip's name) retargeted onto a humanoid, written to --out."""
    from pathlib import Path

    from .motion import list_clips, load_bvh, load_clip
    from .motion.clip import SAVE_FORMATS
    from .motion.retarget import retarget

    out = Path(args.out)
    if out.suffix.lower() not in SAVE_FORMATS:  # before the work: a wrong suffix fails at once
        raise OptionError(f"--out {args.out!r}: accepted file types {', '.join(SAVE_FORMATS)}")
    source = Path(args.file)
    if not source.exists() and args.file not in list_clips():  # a mistyped clip name as much as a missing file
        raise BvhError(f"{args.file!r} is neither a BVH file nor a bundled clip ({', '.join(list_clips())})")
    motion = load_clip(args.file) if args.file in list_clips() and not source.is_file() else load_bvh(source)
    robot = load_robot(args.robot, floating_base=True)
    scale = "auto" if args.scale is None else args.scale
    clip = retarget(robot, motion, mapping=args.mapping, scale=scale, self_collision=not args.no_self_collision,
                    velocity_limits=not args.no_velocity_limits, seed=args.seed, progress=args.progress)
    report = clip.report
    angles = ", ".join(f"{g} {v['mean']:.1f}" for g, v in report["limb_angle_deg"].items())
    print(f"{robot.name}: {len(clip)} frames at {clip.fps:g} fps retargeted at {report['fps']:.0f} frames/s "
          f"(scale {report['scale']:.3f}); every goal met in {report['success_rate']:.0%} of the frames")
    print(f"self-collision frames {len(report['collision_frames'])}, joint-limit frames "
          f"{len(report['joint_limit_frames'])}, velocity-limit frames {len(report['velocity_limit_frames'])}; "
          f"foot skating {report['foot_skating_mm']['mean']:.2f} mm/frame (max {report['foot_skating_mm']['max']:.2f})"
          f", ground penetration {report['ground_penetration_mm']:.1f} mm; mean limb angle (deg): {angles}")
    print(f"wrote {clip.save(out)}")
    if args.html:
        from .viz import save_clip_html

        print(f"wrote {save_clip_html(robot, clip, args.html)}")
    return 0


_JOINT_UNITS = "revolute joints in degrees, or radians with --rad; prismatic joints in m"
#: The flags several sub-commands share, as ``add_argument`` takes them (a sub-command may replace their help);
#: docs/CLI.md says more.
_FLAGS = {
    "robot": dict(help="bundled or example-robot-data name, or a URDF or xacro path"),
    "--tip": dict(help="tip frame (default: the arm's tool frame)"),
    "--base": dict(help="base frame (default: the URDF root)"),
    "--tips": dict(nargs="+", metavar="FRAME", help="frames whose chains are the active joints ('all': every joint)"),
    "--floating-base": dict(action="store_true", help="a free-flying root: six more joints at the front of q (x, y, "
                            "z in m; yaw, pitch, roll), poses in the world"),
    "--xacro-arg": dict(action="append", default=[], metavar="NAME=VALUE", help="a xacro argument (repeatable)"),
    "--package-dir": dict(action="append", default=[], metavar="DIR", help="a folder of ROS packages (repeatable)"),
    "--package-alias": dict(action="append", default=[], metavar="NAME=SHIPPED_AS",
                            help="a package the robot file names, shipped under another name (repeatable)"),
    "--q": dict(type=float, nargs="+", help=f"joint values ({_JOINT_UNITS}); default 0"),
    "--rad": dict(action="store_true", help="joint values in radians (input and output)"),
    "--json": dict(action="store_true", help="machine-readable output"),
    "--html": dict(metavar="PATH", help="also write the result as a self-contained HTML page"),
    "--view": dict(action="store_true", help="show the result in meshcat until Ctrl-C"),
    "--seed": dict(type=int, default=0, help="seed of every random draw (default 0): same seed, same answer"),
    "--scene": dict(metavar="FILE", help="collision scene (YAML or JSON): answers free of collisions"),
    "--margin": dict(type=float, metavar="M", help="with --scene: clearance in m kept from collisions (default 0)"),
    "--no-progress": dict(action="store_true", help="no progress bar"),
    # the problem options every method takes
    "--tolerance": dict(type=float, help="success threshold in m (and rad for pose targets); default 1e-6"),
    "--rotation-tolerance": dict(type=float, metavar="RAD", help="orientation threshold (default: --tolerance)"),
    "--orientation-weight": dict(type=float, metavar="M_PER_RAD", help="m per rad in the pose cost (default 1)"),
    "--pose-metric": dict(help="the pose cost: sum (default) or euclidean"),
    "--q0": dict(type=float, nargs="+", help=f"initial configuration ({_JOINT_UNITS})"),
    "--lower": dict(type=float, nargs="+", metavar="Q", help=f"lower search bounds ({_JOINT_UNITS}); default: robot's"),
    "--upper": dict(type=float, nargs="+", metavar="Q", help=f"upper search bounds ({_JOINT_UNITS}); default: robot's"),
    "--option": dict(action="append", default=[], metavar="NAME=VALUE", help="any option of the method as its Python "
                     "keyword, in SI units (repeatable); VALUE read as a Python literal, else a string"),
}
_ROBOT = ["robot", "--tip", "--base", "--tips", "--floating-base", "--xacro-arg", "--package-dir", "--package-alias"]
_PROBLEM = ["--tolerance", "--rotation-tolerance", "--orientation-weight", "--pose-metric"]
#: Sub-command -> (its function, its help, its flags in order: a name of :data:`_FLAGS`, or (flag, what
#: ``add_argument`` takes beyond or instead of its :data:`_FLAGS` entry)).
_COMMANDS = {
    "robots": (_cmd_robots, "list the robots that load by name", []),
    "fk": (_cmd_fk, "forward kinematics: tip pose at a joint vector", [
        *_ROBOT, "--q", "--rad", "--json",
        ("--frame", dict(metavar="NAME", help="the frame whose pose is printed (default the tip)"))]),
    "solve": (_cmd_solve, "inverse kinematics for one target or a goals file (exit 1 when not reached)", [
        *_ROBOT,
        ("--xyz", dict(type=float, nargs=3, metavar=("X", "Y", "Z"), help="target tip position in m (base frame)")),
        ("--rpy", dict(type=float, nargs=3, metavar=("R", "P", "Y"),
                       help="target roll, pitch, yaw in degrees (R = Rz(Y) Ry(P) Rx(R)); omit for position only")),
        ("--goals", dict(metavar="FILE", help="a goals file (YAML or JSON) instead of --xyz/--rpy")),
        ("--method", dict(help="solver (evoik_pin.methods(); default: the memetic solver)")),
        "--seed", *_PROBLEM, "--q0", "--lower", "--upper", "--option",
        ("--polish", dict(action="store_true", help="polish the method's answer with Levenberg-Marquardt")),
        ("--population", dict(type=int, help="population size of population-based solvers")),
        ("--max-generations", dict(type=int, help="generation budget of population-based solvers")),
        ("--timeout", dict(type=_seconds, metavar="S", help="wall-clock budget in s (memetic: default 0.005; "
                           "memetic-all: 0.02), or none for no limit")),
        ("--count", dict(type=int, help="with --all: solutions wanted on a redundant arm (default 8)")),
        "--rad", "--json", "--html", "--view",
        ("--all", dict(action="store_true", help="every distinct solution (solve_all); exit 1 when there is none")),
        "--scene", "--margin",
        ("--prefer", dict(help="which answer: first (default), nearest (nearest --q0) or manipulability, among "
                          "those found within --timeout (default 0.4 ms on redundant goals, else 0.6 / 0.45 ms)")),
        ("--locked", dict(action="append", default=[], metavar="NAME=VALUE",
                          help=f"hold joint NAME at VALUE (repeatable; {_JOINT_UNITS})"))]),
    "view": (_cmd_view, "meshcat web preview of a robot at a joint vector (tip pose as a triad)", [
        *_ROBOT, "--q", "--rad", "--html", "--scene",
        ("--no-block", dict(action="store_true", help="write --html PATH and return at once"))]),
    "reach": (_cmd_reach, "reachability map: fraction of orientations IK reaches per voxel (npz, png, html)", [
        *_ROBOT,
        ("--voxel", dict(type=float, default=0.05, help="voxel edge in m (default 0.05)")),
        ("--out", dict(required=True, help="output directory: OUT/<robot>_reach.npz, .png and .html")),
        ("--orientations", dict(type=int, default=32, help="orientations asked per voxel of 6-D arms (default 32)")),
        "--scene", "--margin", ("--seed", dict(help="seed of the workspace sampling (default 0)")),
        ("--backend", dict(choices=["local", "ray"], default="local", help="local (threads) or ray (actors)")),
        ("--workers", dict(type=int, help="threads or Ray actors (default: every core / every CPU of the cluster)")),
        ("--address", dict(help="Ray cluster address (default: RAY_ADDRESS, else a local Ray instance)")),
        ("--batch-size", dict(type=int, default=50_000, help="targets per call of the batch engine (default 50000)")),
        *_PROBLEM, "--option", "--no-progress",
        ("--no-html", dict(action="store_true", help="skip the meshcat HTML page"))]),
    "retarget": (_cmd_retarget, "retarget a human motion (BVH file or bundled clip) onto a humanoid: joint trajectory "
                 "as npz, csv or pkl", [
        ("file", dict(help="a BVH file, or a bundled clip's name (walk, run, jump, dance, getup)")),
        ("--robot", dict(required=True, help="humanoid name or URDF path; loaded with a floating base")),
        ("--mapping", dict(default="cmu", help="keypoint mapping preset: cmu (BVH skeletons, default) or smpl")),
        ("--out", dict(required=True, help="output file: .npz, .csv or .pkl (GMR's layout)")),
        ("--html", dict(help="also write a self-contained HTML page playing the clip")),
        ("--scale", dict(type=float, help="source-to-robot length factor (default: leg lengths' ratio)")),
        ("--no-self-collision", dict(action="store_true", help="do not keep the frames free of self-collision")),
        ("--no-velocity-limits", dict(action="store_true", help="do not bound each step by the joint velocity limits")),
        "--seed", ("--progress", dict(action="store_true", help="print progress every 30 frames"))]),
    "reproduce": (_cmd_reproduce, "re-run a paper's experiments: tables (md, csv, json) and figures (png)", [
        ("paper", dict(nargs="+", help="paper id(s): 000 001 002 003 004 (those implemented), or all")),
        ("--quick", dict(action="store_true", help="reduced-size runs (well under a minute per paper)")),
        "--seed", ("--out", dict(default="reproduction", help="output directory; each paper writes OUT/<id>/")),
        "--no-progress",
        ("--jobs", dict(type=int, default=min(2, os.cpu_count() or 1),
                        help="worker processes (default: 2 if available); any value, the same numbers")),
        ("--html", dict(help="save the paper's animation (002: Pro-ISADE spiral) as HTML")), "--view"]),
}


def build_parser() -> argparse.ArgumentParser:
    """The ``evoik`` argument parser: one sub-parser per entry of :data:`_COMMANDS`."""
    parser = argparse.ArgumentParser(prog="evoik", description="Inverse kinematics by evolutionary computation on "
                                     "Pinocchio.")
    sub = parser.add_subparsers(dest="command", required=True)
    for command, (func, what, flags) in _COMMANDS.items():
        p = sub.add_parser(command, help=what)
        for item in flags:
            flag, spec = (item, {}) if isinstance(item, str) else item
            p.add_argument(flag, **{**_FLAGS.get(flag, {}), **spec})
        p.set_defaults(func=func)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run one ``evoik`` command; exit status 0 (done, target reached), 1 (target not reached), 2 (bad input:
    the message on stderr, no traceback)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    with warnings.catch_warnings():  # restores warnings.showwarning on exit
        default_show = warnings.showwarning

        def show(message, category, filename, lineno, file=None, line=None):
            if issubclass(category, RobotLoadWarning):  # one line, no source location
                print(f"evoik {args.command}: warning: {message}", file=sys.stderr)
            else:
                default_show(message, category, filename, lineno, file, line)

        warnings.showwarning = show
        try:
            return int(args.func(args) or 0)
        except EvoikError as exc:  # the option the library names is shown as the flag the user typed
            print(f"evoik {args.command}: error: {_name_the_flag(str(exc), getattr(args, 'typed_flags', {}))}",
                  file=sys.stderr)
            return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
