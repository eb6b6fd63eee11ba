"""The documentation's code runs as written.

- Every ```python block of README.md and docs/*.md: the blocks of one ``##`` section run top to bottom in ONE fresh
  interpreter (a fork of one with evoik_pin loaded, see docs_helpers; a block may build on the blocks above it in its
  section, never on another section's), from the repository root (a mirror of it, see docs_helpers.repo_mirror),
  and the section must exit 0. A failure names the file, the section and the block's line, with the interpreter's
  stderr.
- Every command line of the ```bash blocks of README.md and of the reference pages docs/API.md, docs/CLI.md,
  docs/GOALS.md and docs/ROBOTS.md (``evoik ...``, ``python ...``) exits 0, except the set-up lines at the top of
  README.md (a venv and ``pip install``) and the ones listed in NOT_RUN with the reason; a command that serves a
  viewer is sent Ctrl-C once it says it serves and must then exit 0. A line written on several pages runs once.
- README.md opens with the two set-up commands (install and solve; install the dev extras and test), stays a page
  a newcomer reads (at most README_MAX_LINES lines), and every relative link of the docs names a file that exists.
"""

from __future__ import annotations

import importlib.util
import re
import shlex

import pytest
from docs_helpers import ROOT, code_blocks, python_sections, run_command, run_python_blocks

DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
SECTIONS = [(path, section, blocks) for path in DOCS for section, blocks in python_sections(path).items()]

README = ROOT / "README.md"
#: The pages whose ```bash command lines run: the README and the reference pages it sends a newcomer to.
COMMAND_PAGES = [README, *(ROOT / "docs" / name for name in ("API.md", "CLI.md", "GOALS.md", "ROBOTS.md"))]
#: README.md's length limit (issue 30: what evoik_pin is, the two commands, three examples, the CLI, where to read
#: on; the reference lives in docs/).
README_MAX_LINES = 300
# Command lines not run here, each with the reason (the text up to the first "#" comment of the line).
NOT_RUN = {
    "evoik reproduce 002 004 --seed 0 --out runs": "the papers' full settings: minutes per paper",
    "evoik reproduce 002 --quick": "tests/conftest.py's quick_runs runs every paper's --quick run",
    "evoik reproduce all --quick --out runs": "tests/conftest.py runs it (quick_runs), once for the suite",
    "evoik reproduce 002 --html spiral.html": "paper 002's full settings: minutes",
    "evoik reach panda --voxel 0.05 --out maps": "874,000 pose targets: minutes on a loaded 2-core machine; the "
                                                 "planar2r line above it runs the same command",
    "python scripts/reproduce_004.py --quick": "the same run_paper call as the tests' quick run of "
                                               "004 (quick_runs), seconds more for no new code",
}


def page_commands(path) -> list[str]:
    """The command lines of a Markdown page's ```bash blocks, without their comments; the set-up lines (``python3 -m
    venv ...``) are left out."""
    lines = []
    for block in code_blocks(path, "bash"):
        for text in block.code.splitlines():
            words = shlex.split(text, comments=True)
            if words and not text.startswith("python3 -m venv"):
                lines.append(" ".join(shlex.quote(w) for w in words))
    return lines


README_COMMANDS = page_commands(README)
COMMANDS = list(dict.fromkeys(line for page in COMMAND_PAGES for line in page_commands(page)))



def test_the_docs_have_python_sections_and_commands():
    files = {path.name for path, _, _ in SECTIONS}
    assert {"README.md", "SCALE.md", "API.md", "GOALS.md", "ROBOTS.md"} <= files
    assert len(SECTIONS) >= 8
    assert sum(line.startswith("evoik solve ") for line in README_COMMANDS) >= 4
    assert {"robots", "fk", "solve", "view", "reach", "reproduce"} <= {
        line.split()[1] for line in page_commands(ROOT / "docs" / "CLI.md") if line.startswith("evoik ")}
    assert set(NOT_RUN) <= set(COMMANDS), "a NOT_RUN line is no longer on a command page: update NOT_RUN"


def test_readme_opens_with_the_two_commands_and_stays_short():
    text = README.read_text()
    first = code_blocks(README, "bash")[0].code.splitlines()
    assert text.index("```bash") < text.index("\n## "), "the set-up commands come before the first section"
    assert len(first) == 2, first
    install, dev = first
    assert install.startswith("python3 -m venv .venv") and "pip install -e . &&" in install
    assert "&& evoik solve " in install
    assert dev.startswith("python3 -m venv .venv") and dev.endswith("pip install -e '.[dev]' && pytest")
    assert len(text.splitlines()) <= README_MAX_LINES


def test_relative_links_of_the_docs_name_files_that_exist():
    missing = []
    for path in DOCS:
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", path.read_text()):
            if "://" not in target and not (path.parent / target).exists():
                missing.append(f"{path.relative_to(ROOT)}: {target}")
    assert not missing, "links to files that do not exist:\n" + "\n".join(missing)


@pytest.mark.parametrize(("path", "section", "blocks"), SECTIONS,
                         ids=[f"{path.name}:{section[:40]}" for path, section, _ in SECTIONS])
def test_python_blocks_of_a_section_run(path, section, blocks, root_mirror):
    if any(re.search(r"\bbackend=\"ray\"", b.code) for b in blocks) and importlib.util.find_spec("ray") is None:
        pytest.skip("this section uses Ray (backend=\"ray\"); the optional 'ray' package is not installed")
    done = run_python_blocks(blocks, root_mirror)
    failed = re.search(r"FAILED: the block at (\S+):(\d+)", done.stderr)
    block = next((b for b in blocks if failed and b.line == int(failed.group(2))), None)
    assert done.returncode == 0, (
        f"{path.name}, section {section!r}: exit status {done.returncode}\n"
        + (f"--- the block (line {block.line}) ---\n{block.code}" if block else "")
        + f"--- stderr ---\n{done.stderr[-6000:]}")


@pytest.mark.parametrize("line", [c for c in COMMANDS if c not in NOT_RUN])
def test_documented_command_exits_0(line, root_mirror):
    run = run_command(line, root_mirror)
    assert run.returncode == 0, f"{line!r}: exit status {run.returncode}\n{run.output[-6000:]}"
