"""Reproductions of the five papers' experiments: ``evoik reproduce`` and ``scripts/reproduce_NNN.py`` wrap
:func:`run_papers`, which writes ``DIR/NNN/report.md``, ``results.json``, the figures and one CSV per table.

How to add paper NNN: ``evoik_pin/papers/paperNNN.py`` (found by its file name) defines ``PAPER_ID = "NNN"``,
``TITLE`` and ``run(ctx: RunContext) -> PaperReport``, which draws every random number from ``ctx.rng(labels...)``
(or, in a top-level part run by ``ctx.map_parallel``, from ``derive_rng(seed, labels...)``), uses the paper's
settings unless ``ctx.quick`` (well under a minute) and records them in ``report.settings``, saves figures with
``ctx.save_figure``, fills :class:`Table` objects with the paper's rows beside ours (units in the column names,
SI inside), and puts the discussion in ``report.notes``, raw numbers in ``report.data``, optionally an
:class:`Animation`. The framework adds the seed, machine, command and wall time and writes the files. Then add
``scripts/reproduce_NNN.py`` and a section in docs/REPRODUCTION.md; tests/test_reproduce.py runs it quick.
"""

from __future__ import annotations

import importlib
import shlex
import time
from pathlib import Path

from ..errors import ReproductionError
from .reporting import (
    Animation,
    Figure,
    PaperReport,
    RunContext,
    Table,
    check_output_dir,
    check_seed,
    derive_rng,
    machine_info,
)

__all__ = ["PAPERS", "Animation", "Figure", "PaperReport", "RunContext", "Table", "derive_rng", "paper_ids",
           "run_paper", "run_papers"]

#: Default output directory of ``evoik reproduce`` (relative to the working directory).
DEFAULT_OUT = "reproduction"


def _discover() -> dict[str, str]:
    found = sorted(p.stem[len("paper"):] for p in Path(__file__).resolve().parent.glob("paper[0-9][0-9][0-9].py"))
    return {pid: f"{__name__}.paper{pid}" for pid in found}


#: Paper id -> module name, for the paper modules that exist (discovered from ``paperNNN.py`` files).
PAPERS: dict[str, str] = _discover()


def paper_ids() -> list[str]:
    """The paper ids that can be reproduced, in order."""
    return list(PAPERS)


def _resolve_ids(papers) -> list[str]:
    papers = [papers] if isinstance(papers, str) else list(papers)
    if not papers:
        raise ReproductionError(f"name at least one paper: {', '.join(PAPERS)} or all")
    ids: list[str] = []
    for p in (str(p).strip() for p in papers):
        pid = p.zfill(3) if p.isdigit() else p
        if p != "all" and pid not in PAPERS:
            raise ReproductionError(f"unknown paper id {p!r}; valid ids: {', '.join(PAPERS) or '(none)'} or all")
        ids += [i for i in (PAPERS if p == "all" else [pid]) if i not in ids]
    return ids


def run_papers(papers="all", out=DEFAULT_OUT, quick: bool = False, seed: int = 0, progress: bool = True,
               dpi: int = 90, command: str | None = None, jobs: int = 1) -> list[PaperReport]:
    """Reproduce one or more papers, each into ``out/<paper id>/``; returns their :class:`PaperReport` in order.

    Args:
        papers: a paper id (``"002"``, ``"2"``), a list of ids, or ``"all"``.
        quick: reduced-size runs instead of the papers' settings. seed: master seed every random choice derives from.
        progress, dpi: tqdm progress bars; the figures' resolution.
        command: command line recorded in the reports (default: the equivalent ``evoik reproduce``).
        jobs: worker processes a paper may use for its independent parts (the same numbers, faster).

    Raises (before any work):
        ReproductionError: unknown paper id, bad seed or jobs. OutputError: ``out`` is not a writable directory.
    """
    ids = _resolve_ids(papers)
    seed = check_seed(seed)
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ReproductionError(f"jobs must be an integer >= 1, got {jobs!r}")
    out = check_output_dir(out)
    for pid in ids:
        check_output_dir(out / pid)
    reports = []
    for pid in ids:
        module = importlib.import_module(PAPERS[pid])
        if getattr(module, "PAPER_ID", None) != pid or not callable(getattr(module, "run", None)):
            raise ReproductionError(f"module {PAPERS[pid]} does not follow the paper-module contract "
                                    "(PAPER_ID, TITLE, run(ctx) -> PaperReport)")
        default_command = shlex.join(["evoik", "reproduce", pid, *(["--quick"] if quick else []), "--seed", str(seed),
                                      "--out", str(out), *(["--jobs", str(jobs)] if jobs > 1 else [])])
        ctx = RunContext(out_dir=out / pid, quick=quick, seed=seed, progress=progress, dpi=dpi,
                         command=command or default_command, jobs=jobs)
        machine = machine_info()
        t0 = time.perf_counter()
        report = module.run(ctx)
        report.wall_time_s = time.perf_counter() - t0
        report.paper_id, report.quick, report.seed = pid, quick, seed
        report.machine, report.command = machine, ctx.command
        report.write(ctx.out_dir)
        reports.append(report)
    return reports


def run_paper(paper: str, out=DEFAULT_OUT, quick: bool = False, seed: int = 0, progress: bool = True,
              dpi: int = 90, command: str | None = None, jobs: int = 1) -> PaperReport:
    """Reproduce one paper (see :func:`run_papers`); returns its :class:`PaperReport`."""
    if str(paper).strip() == "all":
        raise ReproductionError("run_paper takes one paper id; use run_papers('all') for every paper")
    return run_papers([paper], out=out, quick=quick, seed=seed, progress=progress, dpi=dpi, command=command,
                      jobs=jobs)[0]
