"""The README's command-line examples run as written: every `evoik solve` line reaches its target (exit 0)."""

import re
import shlex
from pathlib import Path

import pytest

from evoik_pin.cli import main

README = Path(__file__).resolve().parents[1] / "README.md"
SOLVE_LINES = [line.split("#")[0].strip() for line in README.read_text().splitlines()
               if re.match(r"^evoik solve ", line)]


def test_the_readme_has_solve_examples():
    assert len(SOLVE_LINES) >= 2


@pytest.mark.parametrize("line", SOLVE_LINES)
def test_readme_solve_example_reaches_its_target(line, capsys, monkeypatch):
    monkeypatch.chdir(README.parent)  # the README's relative paths (examples/...) are from the repository root
    assert main(shlex.split(line)[1:]) == 0, capsys.readouterr()
