"""`evoik solve` / `evoik reach` offer every option of the Python call they wrap, and errors name the flag typed.

The lists of options come from the Python side (the signatures of ``solve`` and ``reachability_map``, the shared
problem options, the solver registry), so an option added there without a way to set it from the command line
fails ``test_every_option_of_*``.
"""

import inspect
import json

import numpy as np
import pytest

from evoik_pin import api, cli
from evoik_pin.cli import build_parser, main
from evoik_pin.reach import ReachMap, reachability_map
from evoik_pin.robot import load_robot
from evoik_pin.solvers import get_solver, methods

XYZ = ["--xyz", "0.1", "0.1", "0.1"]


def _flags(command: str) -> set[str]:
    """Every option string of the sub-command's parser (``--tolerance``, ``--q0``, ...)."""
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    return {s for action in sub.choices[command]._actions for s in action.option_strings}


def _reachable(command: str, name: str, method: str | None) -> bool:
    """``name`` has a named flag of ``command`` (every part of ``--lower/--upper``), or it is a method option
    that ``--option NAME=VALUE`` hands to ``method``'s call."""
    flags = _flags(command)
    if name in cli.CALL_FLAGS and all(f in flags for f in cli.CALL_FLAGS[name].split("/")):
        return True
    if method is None or "--option" not in flags:
        return False
    argv = ([command, "planar2r", *XYZ, "--method", method] if command == "solve" else
            [command, "planar2r", "--out", "unused"])
    args = build_parser().parse_args([*argv, "--option", f"{name}=7"])
    return cli._call_options(args, load_robot("planar2r"), method if command == "solve" else "memetic")[name] == 7


def test_every_option_of_solve_has_a_flag():
    """The call's own parameters, the shared problem options, polish and every registered method's options."""
    own = [p for p in inspect.signature(api.solve).parameters if p not in ("robot", "target", "options")]
    shared = [*api._PROBLEM_OPTIONS, "polish"]  # polish: taken by every method (api._run pops it)
    missing = [name for name in own + shared if name not in cli.NOT_ON_CLI and not _reachable("solve", name, None)]
    for method in methods():
        missing += [f"{method}:{name}" for name in get_solver(method).options
                    if name not in cli.NOT_ON_CLI and not _reachable("solve", name, method)]
    assert missing == []


def test_every_option_of_reach_has_a_flag():
    """reachability_map's parameters, the problem options its batch engine takes and memetic's options."""
    own = [p for p in inspect.signature(reachability_map).parameters if p not in ("robot", "options")]
    shared = [name for name in api._PROBLEM_OPTIONS if name not in cli.REACH_NOT_ON_CLI]
    missing = [name for name in own + shared if not _reachable("reach", name, None)]
    missing += [name for name in get_solver("memetic").options
                if name not in cli.REACH_NOT_ON_CLI and not _reachable("reach", name, "memetic")]
    assert missing == []


def test_an_option_the_method_does_not_take_names_the_flag_and_the_methods_that_take_it(capsys):
    takers = [m for m in methods() if "max_generations" in get_solver(m).options]
    assert main(["solve", "ax18", *XYZ, "--method", "memetic", "--max-generations", "5"]) == 2
    err = capsys.readouterr().err
    assert err == (f"evoik solve: error: --max-generations is not an option of method 'memetic'; methods that "
                   f"take it: {', '.join(takers)}\n")
    # the generic flag too, named as typed; solve --all offers the multi-solution methods only
    assert main(["solve", "ax18", *XYZ, "--all", "--option", "niches=3"]) == 2
    takers = [m for m in methods() if get_solver(m).multi_solution and "niches" in get_solver(m).options]
    assert capsys.readouterr().err == (f"evoik solve: error: --option niches is not an option of method "
                                       f"'memetic-all'; methods that take it: {', '.join(takers)}\n")


def test_an_option_no_method_takes_is_named_with_what_the_method_takes(capsys):
    assert main(["solve", "ax18", *XYZ, "--method", "de", "--option", "populaton=40"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("evoik solve: error: --option populaton: no method takes an option 'populaton'; method "
                          "'de' takes: ") and "population" in err
    assert main(["solve", "ax18", *XYZ, "--option", "population"]) == 2
    assert "--option needs NAME=VALUE" in capsys.readouterr().err
    assert main(["solve", "ax18", *XYZ, "--option", "tolerance=1e-3"]) == 2  # one way to set an option
    assert "--option tolerance: use --tolerance" in capsys.readouterr().err
    assert main(["solve", "ax18", *XYZ, "--method", "de", "--option", "callback=print"]) == 2
    assert "--option callback: not settable from the command line" in capsys.readouterr().err


def test_q0_of_the_wrong_length_names_the_flag_the_length_and_n(capsys):
    assert main(["solve", "ax18", *XYZ, "--q0", "1", "2"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("evoik solve: error: --q0: ") and "has 4 joints" in err and "shape (2,)" in err


@pytest.mark.parametrize(("argv", "start"), [
    (["--method", "isade", "--population", "-4"], "--population must be an integer >= 6, got -4"),
    (["--tolerance", "-1"], "--tolerance must be a finite number >= 0"),
    (["--rotation-tolerance", "-1"], "--rotation-tolerance must be a finite number >= 0"),
    (["--timeout", "-1"], "--timeout (s; or None) must be a finite number > 0"),
    (["--timeout", "none"], "--timeout: memetic needs a finite budget"),
    (["--method", "de", "--option", "F=-3"], "--option F must be"),
    (["--pose-metric", "manhattan"], "--pose-metric 'manhattan' is not one of"),
    (["--lower", "0", "0", "0", "0", "--upper", "-1", "0", "0", "0"], "--lower/--upper: inverted bounds"),
    (["--lower", "0", "0"], "--lower/--upper need 4 values each"),
    (["--xyz", "0.1", "0.1", "nan"], "--xyz contains NaN or inf"),
])
def test_library_errors_name_the_flag(capsys, argv, start):
    assert main(["solve", "ax18", *XYZ, *argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"evoik solve: error: {start}"), err


def test_the_new_flags_reach_the_call(capsys):
    robot = load_robot("planar2r")
    lower, upper = [0.0, 10.0], [60.0, 90.0]  # deg: of the two elbow solutions only q = (30, 45) deg is inside
    xyz = robot.fk(np.radians([30.0, 45.0])).translation
    assert main(["solve", "planar2r", "--xyz", *map(repr, map(float, xyz)), "--timeout", "0.5",
                 "--lower", *map(str, lower), "--upper", *map(str, upper), "--polish", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["success"] and np.all(np.array(info["q_deg"]) >= lower) and np.all(np.array(info["q_deg"]) <= upper)
    assert np.allclose(info["q_deg"], [30.0, 45.0], atol=1e-3)
    args = build_parser().parse_args(["solve", "planar2r", *XYZ, "--method", "de", "--rotation-tolerance", "0.01",
                                      "--orientation-weight", "0.5", "--pose-metric", "euclidean", "--option",
                                      "strategy=rand1bin", "--option", "stall_generations=None"])
    assert cli._call_options(args, robot, "de") == {"rotation_tolerance": 0.01, "orientation_weight": 0.5,
                                                    "pose_metric": "euclidean", "strategy": "rand1bin",
                                                    "stall_generations": None}
    args = build_parser().parse_args(["solve", "planar2r", *XYZ, "--timeout", "none", "--option", "max_restarts=3"])
    assert cli._call_options(args, robot, "memetic") == {"timeout": None, "max_restarts": 3}
    args = build_parser().parse_args(["solve", "planar2r", *XYZ, "--option", "gains=[1, 2]"])
    assert cli._call_options(args, robot, "nsga2") == {"gains": [1, 2]}


def test_reach_takes_the_ik_options(tmp_path, capsys):
    assert main(["reach", "planar2r", "--voxel", "0.1", "--out", str(tmp_path), "--no-progress", "--no-html",
                 "--tolerance", "1e-4", "--batch-size", "7", "--option", "table_seeds=2"]) == 0
    settings = ReachMap.load(tmp_path / "planar2r_reach.npz").settings
    assert settings["batch_size"] == 7 and settings["options"] == {"tolerance": 1e-4, "table_seeds": 2}
    assert main(["reach", "planar2r", "--out", str(tmp_path), "--option", "max_generations=3"]) == 2
    assert capsys.readouterr().err.startswith("evoik reach: error: --option max_generations is not an option of method "
                                              "'memetic' (the solver of evoik reach); it takes: ")
    assert main(["reach", "planar2r", "--out", str(tmp_path), "--no-progress", "--tolerance", "-1"]) == 2
    assert capsys.readouterr().err.startswith("evoik reach: error: --tolerance must be")
