"""First use of evoik_pin's compiled code: :func:`load` runs a group of numba entries once on small arguments, first
saying so in one line when one is about to compile rather than load from numba's disk cache (tens of seconds, once
per install, would otherwise look like a hang)."""

from __future__ import annotations

import logging
import sys
import time

__all__ = ["LOGGER", "announce", "compiled_entry", "load", "will_compile"]

#: The logger the compilation notice goes to (INFO).
LOGGER = logging.getLogger("evoik_pin")


def will_compile(dispatcher, args: tuple) -> bool:
    """Whether calling the numba ``dispatcher`` on ``args`` compiles it: no machine code for the arguments' types in
    this process nor in numba's disk cache for this source. False when that cannot be told (the notice is then left
    out, never wrong)."""
    try:
        sig = tuple(dispatcher.typeof_pyval(a) for a in args)
        if sig in dispatcher.overloads:
            return False
        cache = dispatcher._cache
        index = cache._cache_file._load_index()
        return cache._index_key(sig, dispatcher.targetctx.codegen()) not in index
    except Exception:  # noqa: BLE001 - numba's internals: no notice rather than a failed solve
        return False


def announce(message: str) -> None:
    """Tell the user ``message`` (one line): through the ``evoik_pin`` logger at INFO where logging is configured
    (a handler on the logger or above it), else on stderr; nothing when the logger is set above INFO or disabled."""
    if LOGGER.disabled or LOGGER.level > logging.INFO:
        return
    if LOGGER.hasHandlers():
        LOGGER.info(message)
    else:
        print(message, file=sys.stderr, flush=True)


def load(what: str, calls: list[tuple], seconds: float) -> float:
    """Call each (dispatcher, args) of ``calls`` once, so that numba compiles or loads its machine code now, first
    announcing that ``what`` is compiled (about ``seconds`` s of one core) when one will compile. Returns the seconds
    spent. The calls must only write into their own arguments."""
    t = time.perf_counter()
    if any(will_compile(dispatcher, args) for dispatcher, args in calls):
        announce(f"evoik_pin: compiling {what} (once; cached for later runs, about {seconds:.0f} s)")
    for dispatcher, args in calls:
        dispatcher(*args)
    return time.perf_counter() - t


def compiled_entry(dispatcher, args: tuple):
    """The machine-code entry of the numba ``dispatcher`` for ``args``' types (compiled or loaded already: call it on
    them first), which a hot path calls without numba's dispatch typing every argument on every call; None where this
    numba does not expose it (the caller then calls the dispatcher)."""
    try:
        from numba import typeof

        return dispatcher.overloads[tuple(typeof(a) for a in args)].entry_point
    except (AttributeError, KeyError, ImportError):
        return None
