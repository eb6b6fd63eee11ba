"""First use of evoik_pin's compiled code: whether numba is about to compile an entry (rather than load it from its
disk cache), and the one line that says so.

numba compiles the LM kernel's entries the first time they are called after an install (or after their source
changed) and caches the machine code on disk (``__pycache__/*.nbi``, ``*.nbc``, or ``NUMBA_CACHE_DIR``); later
processes load it in well under a second. A first use that compiles takes tens of seconds, which, unannounced,
looks like a hang. :func:`load` runs a group of entries once on small arguments (outside any time budget: its
callers are the set-up steps) and, when at least one of them is not in numba's cache for those argument types,
first says what is compiled and that it happens once.

The line goes to the ``evoik_pin`` logger at INFO. Without any logging configuration (no handler anywhere: a
script, the ``evoik`` command), it is written to stderr instead, as one line. To silence it, set that logger above
INFO (``logging.getLogger("evoik_pin").setLevel(logging.WARNING)``) or give it a handler of your own.
"""

from __future__ import annotations

import logging
import sys
import time

__all__ = ["LOGGER", "announce", "load", "will_compile"]

#: The logger the compilation notice goes to (INFO).
LOGGER = logging.getLogger("evoik_pin")


def will_compile(dispatcher, args: tuple) -> bool:
    """Whether calling the numba ``dispatcher`` on ``args`` compiles it: no machine code for the arguments' types in
    this process, nor in numba's disk cache for this source (its cache index holds no entry for that signature and
    this build of numba; a stale index, from an older source, holds none). False when that cannot be told (a
    dispatcher without a disk cache, a numba whose internals differ): the notice is then left out, never wrong."""
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


def notice(what: str, seconds: float) -> str:
    """The line said before compiling ``what`` (about ``seconds`` s of one core)."""
    return f"evoik_pin: compiling {what} (once; cached for later runs, about {seconds:.0f} s)"


def load(what: str, calls: list[tuple], seconds: float) -> float:
    """Call each (dispatcher, args) of ``calls`` once, so that numba compiles or loads its machine code now; when
    one of them will compile (:func:`will_compile`), first :func:`announce` that ``what`` is being compiled, about
    ``seconds`` s (a measured figure for one core). Returns the seconds spent. The calls must only write into
    their own arguments (small scratch arrays)."""
    t = time.perf_counter()
    if any(will_compile(dispatcher, args) for dispatcher, args in calls):
        announce(notice(what, seconds))
    for dispatcher, args in calls:
        dispatcher(*args)
    return time.perf_counter() - t
