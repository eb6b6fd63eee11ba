"""Solver registry: every method is a function ``solver(problem, rng, **options) -> Result`` registered by name
with :func:`register`; ``evoik_pin.methods()`` lists them. Option names are checked here against each solver's
signature, option values by the solver (and its ``check=``, before any work) with :mod:`.options`' validators."""

from __future__ import annotations

import functools
import importlib
import inspect
from collections.abc import Callable
from dataclasses import dataclass

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
    #: ``check(n=..., **options)``: the solver's own value checks (every keyword, defaults filled in, and the
    #: robot's joint count ``n``), the very function the solver calls first; OptionError on a bad value.
    check: Callable | None = None

    @property
    def options(self) -> list[str]:
        """Names of the solver-specific keyword options."""
        return list(self._defaults)

    @functools.cached_property
    def _defaults(self) -> dict:
        """The keyword options and their defaults (inspect.signature costs tens of microseconds: once per solver,
        not once per solve)."""
        params = list(inspect.signature(self.func).parameters.values())[2:]
        return {p.name: p.default for p in params if p.kind is inspect.Parameter.KEYWORD_ONLY}

    def check_options(self, options: dict, n: int | None = None) -> None:
        """OptionError for an option the solver does not take; with ``n`` (the robot's joints), also for a value
        the solver would refuse (its ``check``, when registered), so that a call solving many targets fails
        before any work, with the message :func:`evoik_pin.solve` gives."""
        unknown = sorted(set(options) - set(self._defaults))
        if unknown:
            raise OptionError(
                f"unknown option(s) {', '.join(unknown)} for method {self.name!r}; it accepts "
                f"{', '.join(self.options)} (and tolerance, rotation_tolerance, q0, bounds, objective, "
                "orientation_weight, seed)"
            )
        if n is not None and self.check is not None:
            self.check(n=n, **{**self._defaults, **options})


_REGISTRY: dict[str, SolverInfo] = {}

# One module per solver family; each registers its methods on import (this order is methods()' order).
_MODULES = ["paper.de", "paper.isade", "paper.pso", "paper.mode", "paper.ga", "paper.hga", "paper.nsga2",
            "paper.analytic", "search.memetic", "search.answer_choice", "search.all_solutions"]


def register(name: str, description: str, multi_solution: bool = False, multi_objective: bool = False,
             check: Callable | None = None):
    """Decorator registering ``func(problem, rng, *, option=default, ...) -> Result`` under ``name``; ``check``:
    see :attr:`SolverInfo.check`."""

    def wrap(func: Callable) -> Callable:
        _REGISTRY[name] = SolverInfo(name, func, description, multi_solution, multi_objective, check)
        return func

    return wrap


@functools.cache
def _load_all() -> None:
    for mod in _MODULES:
        importlib.import_module(f"{__name__}.{mod}")


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
