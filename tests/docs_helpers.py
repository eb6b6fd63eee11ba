"""Helpers of tests/test_docs.py and tests/test_docs_examples.py: the documentation's code blocks and commands.

- :func:`python_sections`: the ```python blocks of a Markdown file, grouped by their ``##`` section;
- :func:`run_python_blocks`: a section's blocks, in order, in one fresh interpreter (a process of its own);
- :func:`run_command`: one shell-style command line (``evoik ...``, ``python ...``) in a process of its own, exit
  status 0 expected; a command that serves a meshcat viewer is interrupted with SIGINT (Ctrl-C) once it says so;
- the processes: forks of one interpreter that has evoik_pin and its common kernels loaded (tests/docs_zygote.py: about
  1.3 s of CPU less per section and command), or, with the environment variable EVOIK_DOCS_FRESH_INTERPRETERS=1, each
  a new interpreter (``python -c``, ``python -m evoik_pin.cli``, ``python script.py``) as a user's shell starts it;
- :func:`repo_mirror`: a temporary folder that looks like the repository root (a symbolic link to each of its
  top-level entries), so the docs' relative paths (``examples/...``, ``robots/...``) resolve as from the root while
  the files they write (``maps/``, ``scene.html``, ...) land in the temporary folder, not in the checkout.
"""

from __future__ import annotations

import json
import os
import re
import shlex
import signal
import subprocess
import sys
import tempfile
import threading
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Set to 1: every section and command in a new interpreter of its own, not a fork of docs_zygote's server.
FRESH_INTERPRETERS = "EVOIK_DOCS_FRESH_INTERPRETERS"
#: Seconds one section or one command may take before it counts as hung (a safety net, not a speed check).
HANG_TIMEOUT = 600.0
#: A serving command prints a line containing this when it starts serving (``evoik view``, ``--view``,
#: ``examples/view_solution.py``: "Press Ctrl-C to stop the viewer." / "(Ctrl-C to stop)").
SERVING_MARK = "Ctrl-C"


@dataclass(frozen=True)
class Block:
    """One fenced code block: its file, the ``##`` section it is in, its first code line (1-based) and its text."""

    file: Path
    section: str
    line: int
    code: str


def code_blocks(path: Path, language: str) -> list[Block]:
    """The fenced blocks of ``language`` (e.g. ``"python"``) in a Markdown file, in order.

    A block's section is the last ``## `` heading above it (``""`` before the first one); headings inside code
    blocks (a ``#`` comment) are not headings.
    """
    blocks, section, fence, start, lines = [], "", None, 0, []
    for number, text in enumerate(path.read_text().splitlines(), start=1):
        if fence is None:
            m = re.match(r"^```(\w*)\s*$", text)
            if m:
                fence, start, lines = m.group(1), number + 1, []
            elif text.startswith("## "):
                section = text[3:].strip()
        elif text.startswith("```"):
            if fence == language:
                blocks.append(Block(path, section, start, "\n".join(lines) + "\n"))
            fence = None
        else:
            lines.append(text)
    assert fence is None, f"{path}: a ``` block opened at line {start - 1} is never closed"
    return blocks


def python_sections(path: Path) -> dict[str, list[Block]]:
    """``{section: [its ```python blocks in order]}`` of a Markdown file (sections without one left out)."""
    sections: dict[str, list[Block]] = {}
    for block in code_blocks(path, "python"):
        sections.setdefault(block.section, []).append(block)
    return sections


# Runs in the fresh interpreter: each block compiled under the Markdown file's name with its own line numbers
# (a traceback then points at the line of README.md that failed), all of a section's blocks in one namespace,
# as when they are pasted one after the other into one interpreter.
# (the runner is docs_zygote's, imported from this folder, which leaves sys.path as a new interpreter's)
_RUNNER = (f"import json, sys; sys.path.insert(0, {str(Path(__file__).resolve().parent)!r}); "
           "from docs_zygote import run_blocks; sys.path.pop(0); run_blocks(json.load(sys.stdin))")


def _forks() -> bool:
    """Whether sections and commands run in forks of docs_zygote's server (the default) or in new interpreters."""
    return os.environ.get(FRESH_INTERPRETERS, "") != "1"


_FRESH_PATH: list = []


def _fresh_path() -> list[str]:
    """docs_zygote.fresh_sys_path(), found once."""
    import docs_zygote

    if not _FRESH_PATH:
        _FRESH_PATH.append(docs_zygote.fresh_sys_path())
    return _FRESH_PATH[0]


def run_python_blocks(blocks: list[Block], cwd: Path) -> subprocess.CompletedProcess:
    """Run ``blocks`` top to bottom in one fresh ``python`` process in ``cwd`` (output captured as text)."""
    runs = [[os.path.relpath(b.file, ROOT), b.line, b.code] for b in blocks]
    if not _forks():
        return subprocess.run([sys.executable, "-c", _RUNNER], input=json.dumps(runs), cwd=cwd, capture_output=True,
                              text=True, timeout=HANG_TIMEOUT)
    import docs_zygote

    with tempfile.TemporaryDirectory() as folder:
        out, err = Path(folder, "stdout"), Path(folder, "stderr")
        proc = docs_zygote.context().Process(target=docs_zygote.run,
                                             args=("blocks", runs, str(cwd), str(out), str(err), dict(os.environ),
                                                   _fresh_path()))
        proc.start()
        proc.join(HANG_TIMEOUT)
        if proc.exitcode is None:
            proc.kill()
            proc.join()
            raise subprocess.TimeoutExpired(["python", "-c", "<section>"], HANG_TIMEOUT)
        return subprocess.CompletedProcess(["python", "-c", "<section>"], proc.exitcode, out.read_text(),
                                           err.read_text())


def command_argv(line: str) -> list[str]:
    """The argv of a documented command line: its words (shell quoting, ``#`` comments dropped), with ``python``
    and ``evoik`` run by this interpreter (so the command runs in the environment the tests run in)."""
    argv = shlex.split(line, comments=True)
    if argv and argv[0] in ("python", "python3"):
        return [sys.executable, *argv[1:]]
    if argv and argv[0] == "evoik":
        return [sys.executable, "-m", "evoik_pin.cli", *argv[1:]]
    return argv


def _default_sigint() -> None:
    """In the child before exec: Ctrl-C's default action, so Python installs its KeyboardInterrupt handler. A test
    run started in the background by a non-interactive shell (``pytest &``, CI) ignores SIGINT, children inherit
    that, and the SIGINT sent to a serving command would be lost; a user at a terminal has the default."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@dataclass
class CommandRun:
    returncode: int
    output: str  # stdout and stderr, interleaved
    served: bool  # it said it serves a viewer (SERVING_MARK) and was sent SIGINT


def run_command(line: str, cwd: Path) -> CommandRun:
    """Run one documented command line in ``cwd``; a command that prints :data:`SERVING_MARK` while it runs is
    sent SIGINT (Ctrl-C) at that moment and is expected to stop by itself (exit status 0)."""
    argv = command_argv(line)
    if _forks() and argv[0] == sys.executable and len(argv) > 1 and (argv[1] == "-m" or not argv[1].startswith("-")):
        proc = _ForkedCommand(argv[1:], cwd)
    else:
        proc = subprocess.Popen(argv, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, text=True, preexec_fn=_default_sigint)
    out: list[str] = []
    event = threading.Event()  # set when the command says it serves, or when its output ends (it exited)
    served = threading.Event()

    def read():
        for text in proc.stdout:
            out.append(text)
            if SERVING_MARK in text:
                served.set()
                event.set()
        event.set()

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    try:
        if not event.wait(HANG_TIMEOUT):
            raise AssertionError(f"{line!r} neither ended nor said it serves within {HANG_TIMEOUT:g} s:\n"
                                 + "".join(out))
        if served.is_set() and proc.poll() is None:
            proc.send_signal(signal.SIGINT)
        returncode = proc.wait(timeout=HANG_TIMEOUT)
    finally:
        if proc.poll() is None:  # only when an assertion above fired: leave no process behind
            proc.kill()
            proc.wait()
    reader.join(timeout=10)
    return CommandRun(returncode, "".join(out), served.is_set())


class _ForkedCommand:
    """``python -m MODULE ARGS`` or ``python SCRIPT ARGS`` (``args``: what follows ``python``) run in a fork of
    docs_zygote's server, with the part of :class:`subprocess.Popen`'s interface :func:`run_command` uses: ``stdout``
    (text lines of standard output and error, interleaved), ``poll``, ``wait``, ``send_signal``, ``kill``."""

    def __init__(self, args: list[str], cwd: Path):
        import docs_zygote

        context = docs_zygote.context()
        read, write = context.Pipe(duplex=False)
        kind, what = ("module", args[1:]) if args[0] == "-m" else ("script", args)
        self._proc = context.Process(target=docs_zygote.run, args=(kind, what, str(cwd), write, write, dict(os.environ),
                                                                   _fresh_path()))
        self._proc.start()
        write.close()  # the fork holds the only writing end: the lines end when it (and what it started) ends
        self.stdout = open(os.dup(read.fileno()))  # noqa: SIM115 - read to its end by run_command's reader
        read.close()

    def poll(self) -> int | None:
        return self._proc.exitcode

    def wait(self, timeout: float | None = None) -> int:
        self._proc.join(timeout)
        if self._proc.exitcode is None:
            raise subprocess.TimeoutExpired("forked command", timeout)
        return self._proc.exitcode

    def send_signal(self, sig: int) -> None:
        os.kill(self._proc.pid, sig)

    def kill(self) -> None:
        self._proc.kill()


def repo_mirror(path: Path) -> Path:
    """Fill the empty folder ``path`` with a symbolic link to each top-level entry of the repository (not ``.git``)
    and return it: a working directory where the docs' relative paths work and what they write stays out of the
    checkout."""
    try:  # the tracked entries: an untracked output folder of an earlier run (maps/, runs/) is not linked
        names = set(subprocess.run(["git", "-C", str(ROOT), "ls-tree", "--name-only", "HEAD"], capture_output=True,
                                   text=True, check=True).stdout.split())
    except (OSError, subprocess.CalledProcessError):  # not a git checkout (an sdist): every entry
        names = {entry.name for entry in ROOT.iterdir()} - {".git"}
    for name in sorted(names):
        if (ROOT / name).exists():
            (path / name).symlink_to(ROOT / name)
    return path
