import subprocess
import sys
import time
import types

import numpy as np
import pytest


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture
def reachable_pose():
    """``reachable_pose(robot, seed) -> pin.SE3``: the tip pose of a random in-limits configuration."""

    def pose(robot, seed):
        return robot.fk(robot.random_configurations(1, np.random.default_rng(seed))[0])

    return pose


@pytest.fixture
def thread_cpu_clock(monkeypatch):
    """Make evoik_pin's solvers read the calling thread's CPU time (``time.thread_time``) where they read
    ``time.perf_counter``: their time budgets and ``time_s`` then count the work done, not the time the process
    waited for a core, so a budget's contract can be checked on a loaded machine. Every loaded evoik_pin module
    that imports ``time`` is patched (whatever package the solvers live in)."""
    clock = types.SimpleNamespace(**{k: v for k, v in vars(time).items() if not k.startswith("__")})
    clock.perf_counter = time.thread_time
    for name, module in list(sys.modules.items()):
        if name.startswith("evoik_pin") and getattr(module, "time", None) is time:
            monkeypatch.setattr(module, "time", clock)
    return clock


@pytest.fixture(scope="module")
def root_mirror(tmp_path_factory):
    """A folder mirroring the repository's tracked top-level entries (docs_helpers.repo_mirror): the docs' and
    examples' commands run there as from the root, and what they write lands outside the checkout."""
    from docs_helpers import repo_mirror

    return repo_mirror(tmp_path_factory.mktemp("repo"))


@pytest.fixture(scope="session")
def quick_runs(tmp_path_factory):
    """Every implemented paper reproduced in quick mode at seed 3, once for the whole suite, through the command line
    (``evoik reproduce all --quick``, two worker processes); returns the output folder (one ``<paper id>/`` each).

    test_reproduce.py checks every paper's files and the numbers of 002 and 004, test_reproduce_000_001_003.py the
    numbers of 000, 001 and 003: one run of each paper for both (the reproductions are the suite's slowest set-up).
    """
    from evoik_pin.cli import main

    out = tmp_path_factory.mktemp("reproduction")
    assert main(["reproduce", "all", "--quick", "--seed", "3", "--out", str(out), "--no-progress", "--jobs", "2"]) == 0
    return out


#: Test files that share a session-scoped fixture: one pytest-xdist work unit, so that the fixture is made once.
SHARED_SESSION_FIXTURES = {"tests/test_reproduce.py": "quick_runs", "tests/test_reproduce_000_001_003.py": "quick_runs"}


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """pytest-xdist's ``--dist loadfile`` (pyproject.toml's addopts: ``-n 2 --dist loadfile``) with the files of
    SHARED_SESSION_FIXTURES in one work unit: every test file runs on one worker, so that its module-scoped fixtures
    (robots, solvers, seed tables, clips) are made once as without xdist, and ``quick_runs`` is made once for both
    reproduction files. (``--dist loadgroup`` would need ``xdist_group`` markers, which pytest-xdist 3.8 cannot apply
    under pytest 9: its renaming of the test ids has no effect there.)"""
    if config.getvalue("dist") != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    class SharedFixtureFileScheduling(LoadFileScheduling):
        def _split_scope(self, nodeid):
            path = super()._split_scope(nodeid)
            return SHARED_SESSION_FIXTURES.get(path, path)

    return SharedFixtureFileScheduling(config, log)


#: What two fresh processes compile (or load from numba's cache) side by side before pytest-xdist's workers start
#: (:func:`pytest_sessionstart`): the null-space descent of prefer= and preferences (about 50 s of CPU on a cold
#: cache), and the LM kernel's entries with memetic's guaranteed runs (about 20 s; scripts/compile_time.py). On a cold
#: cache both workers would otherwise compile the same kernels at the same time; on a warm one this loads them (~2 s).
WARM_UP = (
    "from evoik_pin.solvers.lm.nullspace import nullspace_kernel\n"
    "nullspace_kernel()\n",
    "import evoik_pin as ev\n"
    "from evoik_pin.solvers.lm.engine import compiled_kernel\n"
    "compiled_kernel(False)\n"
    "compiled_kernel(True)\n"
    "robot = ev.load_robot('panda')\n"
    "ev.solve(robot, robot.fk((robot.lower + robot.upper) / 2), seed=0)\n",
)


@pytest.hookimpl(tryfirst=True)
def pytest_sessionstart(session):
    """In pytest-xdist's controller of two or more workers, before it starts them: numba's kernels compiled once
    into its disk cache (WARM_UP), from which every worker then loads them. A warm-up that fails is reported and the
    run goes on (the workers compile what they need; the tests say what is broken). Its compile notices are shown."""
    config = session.config
    workers = getattr(config.option, "numprocesses", None)
    if hasattr(config, "workerinput") or not isinstance(workers, int) or workers < 2 or config.option.collectonly:
        return
    runs = [subprocess.Popen([sys.executable, "-c", code], cwd=config.rootpath) for code in WARM_UP]  # notices shown
    for run in runs:
        if run.wait() != 0:
            config.pluginmanager.get_plugin("terminalreporter").write_line(
                f"numba warm-up failed (exit {run.returncode}, above); the workers compile what they need")
