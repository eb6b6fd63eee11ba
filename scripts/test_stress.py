"""Run the README's test command N times with K busy CPU processes beside it; half the runs on fresh clones.

    python scripts/test_stress.py                       # N=10, K=2, this checkout at HEAD
    python scripts/test_stress.py -n 2 --append docs/TESTING.md
    python scripts/test_stress.py --repo /path/to/checkout --commit abc1234 -k 2

Odd runs (1, 3, ...) are "fresh": a ``git clone`` of ``--repo`` at ``--commit`` (default: its HEAD) into a temporary
directory, run with an empty numba cache (``NUMBA_CACHE_DIR`` in a new temporary directory), so the compiled LM
kernel is compiled during the run, as on a fresh install. Even runs are "warm": the checkout ``--repo`` itself (its
working tree, with whatever numba cache it has). Each run is ``python -m pytest`` with this interpreter (the current
virtual environment) in the run's directory, ``PYTHONPATH`` pointing at its ``src``: the README's ``pytest``.

K processes spinning ``while True: pass`` load the CPUs for the whole time; they are killed when the script ends,
however it ends (normal exit, an exception, Ctrl-C, SIGTERM).

Prints a Markdown table (run, fresh clone?, passed/failed/errors, wall time, failing test ids) and with ``--append
FILE`` adds it, under a heading with the date, commit, N, K and the machine's cores, to FILE (docs/TESTING.md's
"Reliability runs" section is the end of that file). Exit status 0 when every run passed, 1 otherwise.
"""

from __future__ import annotations

import argparse
import atexit
import datetime
import os
import signal
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


@dataclass
class Run:
    """One pytest run: counts from its JUnit XML, wall time in s, the ids of the failing or erroring tests."""

    index: int
    fresh: bool
    passed: int = 0
    failed: int = 0
    errors: int = 0
    skipped: int = 0
    wall_s: float = 0.0
    returncode: int = 0
    failing: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.returncode == 0 and not self.failed and not self.errors


class BusyCPUs:
    """K processes spinning on a core each; ``stop()`` kills them (idempotent; also registered at exit and on
    SIGTERM, so they never outlive the script)."""

    def __init__(self, k: int):
        self.procs = [subprocess.Popen([sys.executable, "-c", "while True: pass"], stdin=subprocess.DEVNULL)
                      for _ in range(k)]
        atexit.register(self.stop)

    def stop(self) -> None:
        for p in self.procs:
            if p.poll() is None:
                p.kill()
            p.wait()


def _junit(path: Path) -> tuple[int, int, int, int, list[str]]:
    """(passed, failed, errors, skipped, failing ids) of a pytest JUnit XML file."""
    root = ET.parse(path).getroot()
    failing, counts = [], {"failed": 0, "errors": 0, "skipped": 0, "tests": 0}
    for case in root.iter("testcase"):
        counts["tests"] += 1
        kinds = {child.tag for child in case}
        node = f"{case.get('classname', '').replace('.', '/')}.py::{case.get('name')}"
        if "failure" in kinds:
            counts["failed"] += 1
            failing.append(node)
        elif "error" in kinds:
            counts["errors"] += 1
            failing.append(node + " (error)")
        elif "skipped" in kinds:
            counts["skipped"] += 1
    passed = counts["tests"] - counts["failed"] - counts["errors"] - counts["skipped"]
    return passed, counts["failed"], counts["errors"], counts["skipped"], failing


def _clone(repo: Path, commit: str, into: Path) -> Path:
    subprocess.run(["git", "clone", "-q", "--no-checkout", str(repo), str(into)], check=True)
    subprocess.run(["git", "-C", str(into), "checkout", "-q", commit], check=True)
    return into


def run_once(index: int, fresh: bool, repo: Path, commit: str, log_dir: Path,
             extra: list[str] | None = None) -> Run:
    """One run of the test command (fresh: in a new clone with an empty numba cache; warm: in ``repo``)."""
    with tempfile.TemporaryDirectory(prefix="evoik-stress-") as tmp:
        tmp = Path(tmp)
        env = dict(os.environ)
        if fresh:
            where = _clone(repo, commit, tmp / "clone")
            env["NUMBA_CACHE_DIR"] = str(tmp / "numba-cache")  # empty: the kernel is compiled in this run
        else:
            where = repo
        env["PYTHONPATH"] = os.pathsep.join([str(where / "src"), *filter(None, [os.environ.get("PYTHONPATH")])])
        xml = tmp / "junit.xml"
        log = log_dir / f"run{index:02d}.log"
        t0 = time.monotonic()
        with open(log, "w") as out:
            proc = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", f"--junitxml={xml}",
                                   "-rfE", *(extra or [])], cwd=where, env=env, stdout=out, stderr=subprocess.STDOUT,
                                  stdin=subprocess.DEVNULL)
        run = Run(index, fresh, wall_s=time.monotonic() - t0, returncode=proc.returncode)
        if xml.is_file():
            run.passed, run.failed, run.errors, run.skipped, run.failing = _junit(xml)
        else:  # pytest stopped before writing its report (collection error, crash)
            run.failing = [f"(no report; exit {proc.returncode}, see {log})"]
        return run


def table(runs: list[Run]) -> str:
    lines = ["| run | fresh clone? | passed / failed / errors (skipped) | wall time (s) | failing tests |",
             "| ---: | --- | --- | ---: | --- |"]
    for r in runs:
        lines.append(f"| {r.index} | {'yes' if r.fresh else 'no'} | {r.passed} / {r.failed} / {r.errors} "
                     f"({r.skipped}) | {r.wall_s:.0f} | {', '.join(f'`{t}`' for t in r.failing) or '-'} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-n", "--runs", type=int, default=10, help="runs of the test command (default 10)")
    ap.add_argument("-k", "--busy", type=int, default=2, help="busy CPU processes beside it (default 2)")
    ap.add_argument("--repo", type=Path, default=ROOT, help="checkout to test (default: this one)")
    ap.add_argument("--commit", help="commit the fresh clones check out (default: the checkout's HEAD)")
    ap.add_argument("--append", type=Path, metavar="FILE", help="also append the table to FILE (docs/TESTING.md)")
    ap.add_argument("--logs", type=Path, help="directory for each run's pytest output (default: a temporary one)")
    ap.add_argument("pytest_args", nargs="*", help="after --: extra pytest arguments (a test file for a quick try; "
                    "the reliability runs use none)")
    args = ap.parse_args(argv)
    if args.runs < 1 or args.busy < 0:
        ap.error("--runs must be >= 1 and --busy >= 0")
    repo = args.repo.resolve()
    commit = args.commit or subprocess.run(["git", "-C", str(repo), "rev-parse", "HEAD"], check=True,
                                           capture_output=True, text=True).stdout.strip()
    log_dir = args.logs or Path(tempfile.mkdtemp(prefix="evoik-stress-logs-"))
    log_dir.mkdir(parents=True, exist_ok=True)
    # SIGTERM ends the script through SystemExit, so the finally below (and atexit) kill the busy processes
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    busy = BusyCPUs(args.busy)
    runs: list[Run] = []
    try:
        for i in range(1, args.runs + 1):
            run = run_once(i, fresh=i % 2 == 1, repo=repo, commit=commit, log_dir=log_dir, extra=args.pytest_args)
            runs.append(run)
            print(f"run {i}/{args.runs} ({'fresh clone' if run.fresh else 'warm'}): {run.passed} passed, "
                  f"{run.failed} failed, {run.errors} errors in {run.wall_s:.0f} s", file=sys.stderr, flush=True)
    finally:
        busy.stop()
    good = sum(r.ok for r in runs)
    head = (f"### {datetime.date.today().isoformat()}: commit {commit[:10]}, {good} of {len(runs)} runs passed, "
            f"{args.busy} busy CPU process(es) beside, {os.cpu_count()} cores")
    text = f"{head}\n\n{table(runs)}\n\nLogs: {log_dir}\n"
    print(text)
    if args.append:
        with open(args.append, "a", encoding="utf-8") as f:
            f.write("\n" + text.replace(f"\nLogs: {log_dir}\n", "\n"))
    return 0 if good == len(runs) else 1


if __name__ == "__main__":
    sys.exit(main())
