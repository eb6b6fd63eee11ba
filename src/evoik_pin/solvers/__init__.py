"""Solver registry: every method is a function ``solver(problem, rng, **options) -> Result`` registered
by name with :func:`register`. ``evoik_pin.methods()`` lists them.

Option names are checked here against each solver's signature; option values by the solver itself, with
the shared validators of :mod:`.options`.

The solvers are grouped by role: :mod:`.paper` (the papers' methods), :mod:`.lm` (the one LM engine and
``polish``), :mod:`.search` (seed table, ``memetic``, ``memetic-all``), :mod:`.batch` (``solve_many``'s API above
its engines). :mod:`.collision_verdict` is the exact collision check every method's answer passes through."""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

from ..errors import MethodError, OptionError

__all__ = ["SolverInfo", "get_solver", "methods", "register"]


@dataclass(frozen=True)
class SolverInfo:
    """A registered solver: its function, a one-line description and what it can return."""

    name: str
    func: Callable
    description: str
    multi_solution: bool = False
    multi_objective: bool = False

    @property
    def options(self) -> list[str]:
        """Names of the solver-specific keyword options."""
        return list(self._option_names)

    @cached_property
    def _option_names(self) -> tuple[str, ...]:
        # inspect.signature costs tens of microseconds: once per solver, not once per solve
        params = list(inspect.signature(self.func).parameters.values())[2:]
        return tuple(p.name for p in params if p.kind is inspect.Parameter.KEYWORD_ONLY)

    def check_options(self, options: dict) -> None:
        if not options:
            return
        unknown = sorted(set(options) - set(self._option_names))
        if unknown:
            raise OptionError(
                f"unknown option(s) {', '.join(unknown)} for method {self.name!r}; it accepts "
                f"{', '.join(self.options)} (and tolerance, rotation_tolerance, q0, bounds, objective, "
                "orientation_weight, seed)"
            )


_REGISTRY: dict[str, SolverInfo] = {}

# One module per solver family; each registers its methods on import (this order is methods()' order).
_MODULES = ["paper.de", "paper.isade", "paper.pso", "paper.mode", "paper.ga", "paper.hga", "paper.nsga2",
            "paper.analytic", "search.memetic", "search.all_solutions"]
_loaded = False


def register(name: str, description: str, multi_solution: bool = False, multi_objective: bool = False):
    """Decorator registering ``func(problem, rng, *, option=default, ...) -> Result`` under ``name``."""

    def wrap(func: Callable) -> Callable:
        _REGISTRY[name] = SolverInfo(name, func, description, multi_solution, multi_objective)
        return func

    return wrap


def _load_all() -> None:
    global _loaded
    if _loaded:
        return
    for mod in _MODULES:
        importlib.import_module(f"{__name__}.{mod}")
    _loaded = True


def methods() -> list[str]:
    """Names of the registered solvers."""
    _load_all()
    return list(_REGISTRY)


def get_solver(name: str) -> SolverInfo:
    """The registered solver ``name``, or a MethodError listing the known ones."""
    _load_all()
    if name not in _REGISTRY:
        raise MethodError(f"unknown method {name!r}; known methods: {', '.join(_REGISTRY)}")
    return _REGISTRY[name]
