"""``solve``'s choices beyond one answer: ``prefer=``, preferences in the goal list and ``locked=``
(:func:`solve_choosing`, which :func:`evoik_pin.solve` hands such calls to; the search itself is
:mod:`evoik_pin.solvers.search.choose`)."""

from __future__ import annotations

from .errors import MethodError

__all__ = ["has_choices", "solve_choosing"]


def has_choices(target, options: dict) -> bool:
    """Whether a solve call needs :func:`solve_choosing`: ``prefer`` or ``locked`` given, or preferences among the
    goals."""
    if options.get("prefer") is not None or options.get("locked") is not None:
        return True
    if isinstance(target, (list, tuple)) and target:
        from .goals.preferences import Preference

        return any(isinstance(x, Preference) for x in target)
    return False


def solve_choosing(robot, target, method: str, seed, prefer: str | None = None, locked=None, **options):
    """:func:`evoik_pin.solve` with ``prefer`` (``"first"``, ``"nearest"``, ``"manipulability"``), preferences
    among the goals, and ``locked`` ({joint: value}: those joints fixed for this call; ``q0``, ``bounds`` and the
    answer ``q`` stay in ``robot``'s layout, the locked joints at their values)."""
    from . import api
    from .goals.preferences import split_preferences
    from .robot.locking import expand_q, locked_robot, shrink_q
    from .solvers.collision_verdict import with_collision_verdict
    from .solvers.search.choose import bind_preferences, check_prefer, choose, refine

    robot = api._robot(robot)
    prefer = check_prefer("first" if prefer is None else prefer)
    if locked:
        sub = locked_robot(robot, locked)
        values = {k: float(v) for k, v in locked.items()}
        if options.get("q0") is not None:
            options["q0"] = shrink_q(robot, sub, options["q0"])
        if options.get("bounds") is not None:
            lower, upper = options["bounds"]
            options["bounds"] = (shrink_q(robot, sub, lower), shrink_q(robot, sub, upper))
        result = solve_choosing(sub, target, method, seed, prefer=prefer, **options)
        result.q = expand_q(robot, sub, values, result.q)
        for s in result.solutions or ():
            s.q = expand_q(robot, sub, values, s.q)
        result.message += f"; joints locked: {', '.join(f'{k}={v:g}' for k, v in values.items())}"
        return result
    goals, prefs = split_preferences(target)
    if prefer == "first" and not prefs:
        return api.solve(robot, goals, method, seed, **options)
    problem, solver_options = api.make_problem(robot, goals, **options)
    rng = api._rng(seed)
    if method != "memetic" or prefer == "first":
        # preferences after the method's own search: the same answers as without them, then refined (the refinement
        # keeps a step only when every goal is met after it), so they never cost success
        if prefer != "first":
            raise MethodError(f"prefer={prefer!r} collects answers with method 'memetic'; {method!r} gives one "
                              "(use prefer='first', the default)")
        criterion = bind_preferences(problem, prefs)  # bad preferences fail before the solve
        result = api._run(problem, method, rng, solver_options)
        if result.success:  # the preferences in the goals' null space, from the method's answer
            from .solvers.lm import LevenbergMarquardt

            target = problem
            if problem.goals is not None and problem.goal_sets:  # refine on the members the answer meets
                choices, P, R = problem.variant_targets()
                k = choices.index(tuple(problem.chosen(result.q)))
                target = problem.variant(choices[k], P[k], R[k])
            q, _, _ = refine(target, LevenbergMarquardt(target), result.q, criterion, None)
            pos, rot, cost = problem.assess(q)
            result.q, result.position_error, result.orientation_error, result.cost = q, pos, rot, cost
            result.goal_errors = None
            if problem.goals is not None:
                result = api._with_goal_verdict(problem, result)
            result = with_collision_verdict(problem, result)
        return result
    solver_options.pop("polish", None)
    from .solvers import get_solver

    get_solver("memetic").check_options(solver_options)  # unknown option names
    result = choose(problem, rng, prefer=prefer, preferences=prefs, **solver_options)
    if problem.goals is not None:
        result = api._with_goal_verdict(problem, result)
    return with_collision_verdict(problem, result)
