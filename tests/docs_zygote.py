"""One interpreter that has imported evoik_pin and loaded its common compiled kernels, forked for each documented
section and command (tests/docs_helpers.py) instead of a new interpreter for each.

A new interpreter spends about 1.3 s of CPU importing evoik_pin, Pinocchio and numba and loading the compiled kernels
from numba's disk cache before a documented command does its (mostly tiny) work; the docs run about fifty of them.
A fork of this server starts with that done. Each fork is still a process of its own, run as the interpreter would run
it: its own working directory, ``sys.argv`` and ``sys.path[0]``, ``__main__`` namespace, standard streams, Ctrl-C's
default handler, the atexit functions at its end, and its exit status (``SystemExit``'s code; 1 and a traceback for
an uncaught exception; killed by SIGINT for an uncaught Ctrl-C). Only the loaded modules and kernels are shared, and
nothing a section or command does reaches another one or the server.

The server is multiprocessing's fork server with this module and docs_zygote_preload preloaded (:func:`context`);
:func:`run` is what a fork runs.
"""

from __future__ import annotations

import atexit
import json
import multiprocessing
import os
import runpy
import signal
import subprocess
import sys
import traceback

#: What one fork runs: ``"module"`` (``python -m NAME ARGS``), ``"script"`` (``python PATH ARGS``) or ``"blocks"``
#: (a list of ``[file name, first line, code]`` run top to bottom in one namespace, as docs_helpers' runner does).
KINDS = ("module", "script", "blocks")

_CONTEXT: list = []


def context() -> multiprocessing.context.BaseContext:
    """multiprocessing's fork-server context, its server started (once) with this module, docs_zygote_preload and
    pytest (which every fork of a test run imports before its target) preloaded."""
    if not _CONTEXT:
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload([__name__, "docs_zygote_preload", *(["pytest"] if "pytest" in sys.modules else [])])
        # The server's sys.path is a new interpreter's (Python 3.11 does not pass the caller's): this folder on
        # PYTHONPATH lets it import the preloaded modules; each fork sets its own environment and sys.path (run).
        saved = os.environ.get("PYTHONPATH")
        os.environ["PYTHONPATH"] = os.pathsep.join([os.path.dirname(os.path.abspath(__file__)), *filter(None, [saved])])
        try:
            from multiprocessing import forkserver

            forkserver.ensure_running()
        finally:
            if saved is None:
                del os.environ["PYTHONPATH"]
            else:
                os.environ["PYTHONPATH"] = saved
        _CONTEXT.append(ctx)
        atexit.register(_stop_server)
    return _CONTEXT[0]


def fresh_sys_path() -> list[str]:
    """``sys.path`` of a new interpreter started now by this one (``python -c``), less its first entry (which
    depends on how it is started: ``''``, the working directory, the script's folder)."""
    done = subprocess.run([sys.executable, "-c", "import json, sys; print(json.dumps(sys.path[1:]))"],
                          capture_output=True, text=True, check=True)
    return json.loads(done.stdout)


def _stop_server() -> None:
    """At the test run's end: the fork server stopped and waited for, so that no process is left behind and the CPU
    time of the server and its forks counts in the test run's own (``time pytest``), as new interpreters' does."""
    from multiprocessing import forkserver

    stop = getattr(forkserver._forkserver, "_stop", None)  # CPython's own way to stop it (its tests use it)
    if stop is not None:
        stop()


def run_blocks(blocks: list) -> None:
    """Run ``[file name, first line, code]`` blocks top to bottom in one ``__main__`` namespace; exit 1 with the
    traceback and the failing block's place at the first that raises."""
    namespace = {"__name__": "__main__"}
    for name, line, code in blocks:
        try:
            exec(compile("\n" * (line - 1) + code, name, "exec"), namespace)
        except BaseException:
            traceback.print_exc()
            print(f"FAILED: the block at {name}:{line}", file=sys.stderr)
            sys.exit(1)


def run(kind: str, what, cwd: str, stdout, stderr, environ: dict, path: list[str]) -> None:
    """In the fork: run ``what`` (see :data:`KINDS`; for ``"module"`` and ``"script"`` the argv after ``python``)
    in ``cwd``, with the environment ``environ`` and a new interpreter's ``sys.path`` (``path``: see
    :func:`fresh_sys_path`), standard input empty and standard output and error on ``stdout`` and ``stderr`` (each
    a file's path, or a multiprocessing Connection: a pipe's writing end), then end the process with the exit status
    the interpreter would give. Never returns."""
    signal.signal(signal.SIGINT, signal.default_int_handler)  # a background test run ignores Ctrl-C; a user has it
    os.environ.clear()
    os.environ.update(environ)
    os.chdir(cwd)
    for stream in (sys.stdout, sys.stderr):
        stream.flush()
    os.dup2(os.open(os.devnull, os.O_RDONLY), 0)
    for fd, target in ((1, stdout), (2, stderr)):
        os.dup2(os.open(target, os.O_WRONLY | os.O_CREAT | os.O_TRUNC) if isinstance(target, str) else target.fileno(),
                fd)
    code = 0
    try:
        if kind == "module":
            sys.argv = ["-m", *what[1:]]
            sys.path[:] = [cwd, *path]
            runpy.run_module(what[0], run_name="__main__", alter_sys=True)
        elif kind == "script":
            sys.argv = list(what)
            sys.path[:] = [os.path.dirname(os.path.abspath(what[0])), *path]
            runpy.run_path(what[0], run_name="__main__")
        elif kind == "blocks":
            sys.argv = ["-c"]
            sys.path[:] = ["", *path]
            run_blocks(what)
        else:
            raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    except SystemExit as exc:
        if exc.code is None:
            code = 0
        elif isinstance(exc.code, int):
            code = exc.code
        else:
            print(exc.code, file=sys.stderr)
            code = 1
    except KeyboardInterrupt:  # as the interpreter does: killed by the signal
        _finish()
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGINT)
    except BaseException:
        traceback.print_exc()
        code = 1
    _finish()
    os._exit(code)


def _finish() -> None:
    """What the interpreter does at its end: the atexit functions, the standard streams flushed."""
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass

