"""Every command written in a file under examples/ runs as written and exits 0.

Marker convention: a line of any file under examples/ whose text (after the indentation and, in a comment, the
``#``) starts with ``$ `` is a command, run from the repository root (a mirror of it, docs_helpers.repo_mirror)::

    #   $ evoik solve panda --xyz 0.6 0.0 0.5 --rpy 0 90 0 --scene examples/panda_shelf.yaml     (a YAML header)
        $ python examples/view_solution.py ax18 --html ax18.html --no-block                      (a docstring)

The rest of the line after an unquoted ``#`` is a comment. A command that serves a viewer prints a line with
"Ctrl-C" when it starts serving; it is then sent SIGINT (Ctrl-C) and must exit 0 as well. A line that looks like a
command (``evoik ...``, ``python ...``) without the ``$ `` marker fails test_every_command_line_is_marked, so a new
example's commands cannot be left out of the test by accident.
"""

from __future__ import annotations

import re
import shlex

import pytest
from docs_helpers import ROOT, run_command

EXAMPLES = ROOT / "examples"
MARKED = re.compile(r"^\s*(?:#\s*)?\$ (.+)$")
LOOKS_LIKE_A_COMMAND = re.compile(r"^\s*(?:#\s*)?(?:evoik|python3?) \S")


def _text_files() -> list:
    files = []
    for path in sorted(p for p in EXAMPLES.rglob("*") if p.is_file()):
        try:
            files.append((path, path.read_text()))
        except UnicodeDecodeError:  # a mesh or another binary file: no commands in it
            continue
    return files


def example_commands() -> list[tuple[str, str]]:
    """``(file:line, command)`` of every ``$ `` line under examples/."""
    found = []
    for path, text in _text_files():
        for number, line in enumerate(text.splitlines(), start=1):
            m = MARKED.match(line)
            if m:
                found.append((f"{path.relative_to(ROOT)}:{number}", m.group(1).strip()))
    return found


COMMANDS = example_commands()



def test_every_example_file_names_its_commands():
    files = {where.split(":")[0] for where, _ in COMMANDS}
    assert {"examples/panda_shelf.yaml", "examples/view_solution.py"} <= files


def test_every_command_line_is_marked():
    unmarked = [f"{path.relative_to(ROOT)}:{number}: {line.strip()}" for path, text in _text_files()
                for number, line in enumerate(text.splitlines(), start=1)
                if LOOKS_LIKE_A_COMMAND.match(line) and not MARKED.match(line)]
    assert not unmarked, "command lines without the '$ ' marker (tests run only marked ones):\n" + "\n".join(unmarked)


@pytest.mark.parametrize(("where", "line"), COMMANDS,
                         ids=[f"{w}:{' '.join(shlex.split(c, comments=True))}" for w, c in COMMANDS])
def test_example_command_exits_0(where, line, root_mirror):
    run = run_command(line, root_mirror)
    assert run.returncode == 0, f"{where}: {line!r}: exit status {run.returncode}\n{run.output[-6000:]}"
