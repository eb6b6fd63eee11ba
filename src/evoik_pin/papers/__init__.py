"""Reproductions of the five papers' experiments with evoik_pin's solvers.

``evoik reproduce 002 [--quick] [--seed S] [--out DIR]`` and ``scripts/reproduce_NNN.py`` are thin
wrappers over :func:`run_papers`. Each paper writes into ``DIR/NNN/``: ``report.md`` (settings, seed,
machine, the paper's tables next to ours, figures, discussion), ``results.json`` (everything, including
raw per-point numbers), one ``<table>.csv`` per table (a ``source`` column says ``paper`` or ``ours``)
and the figures as PNG.

Contract for a paper module (how to add paper NNN)
--------------------------------------------------
Create ``evoik_pin/papers/paperNNN.py``; it is discovered by its file name (:data:`PAPERS` lists
exactly the modules that exist, so nothing else needs registering) and must define:

* ``PAPER_ID = "NNN"`` and ``TITLE = "..."`` (short title of the paper);
* ``run(ctx: RunContext) -> PaperReport``, which

  - takes every random choice from ``ctx.rng("label", ...)`` (independent streams derived from
    ``ctx.seed``; pass the generator as ``seed=`` to :func:`evoik_pin.solve`), never from global state;
  - uses the paper's settings when ``ctx.quick`` is False, and a reduced size (fewer points / runs) that
    finishes in well under a minute when it is True; records every setting in ``report.settings``;
  - wraps long loops in ``ctx.bar(...)`` (tqdm, disabled with ``progress=False``);
  - may run independent parts in ``ctx.jobs`` worker processes with ``ctx.map_parallel(func, specs,
    desc)`` (results in the order of ``specs``): ``func`` is a top-level function whose random streams
    come from ``derive_rng(spec seed, labels...)`` only, so results do not depend on the number of
    processes;
  - makes figures with ``fig, ax = ctx.new_figure(...)`` (Agg backend) and saves them with
    ``ctx.save_figure(fig, "figN_name", caption)``, appending the returned :class:`Figure`;
  - fills :class:`Table` objects with our rows and, where the paper has the same table, ``paper_rows``
    with the paper's numbers in the same columns (units in the column names; SI inside, cm / mm / deg /
    ms only in tables);
  - puts the honest discussion (deviations, inconsistencies in the paper, floating-point floors) in
    ``report.notes``, and raw numbers in ``report.data``;
  - optionally sets ``report.animation`` (an :class:`Animation`) for ``--html`` / ``--view``.

  The framework fills in the seed, quick flag, machine facts, command line and wall time, and writes
  the files; the module only computes.
* Add ``scripts/reproduce_NNN.py`` (three lines, like ``scripts/reproduce_002.py``) and a section in
  ``docs/REPRODUCTION.md``; ``tests/test_reproduce.py`` runs every paper in :data:`PAPERS` in quick mode.
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

__all__ = [
    "PAPERS",
    "Animation",
    "Figure",
    "PaperReport",
    "RunContext",
    "Table",
    "derive_rng",
    "paper_ids",
    "run_paper",
    "run_papers",
]

#: Default output directory of ``evoik reproduce`` (relative to the working directory).
DEFAULT_OUT = "reproduction"


def _discover() -> dict[str, str]:
    here = Path(__file__).resolve().parent
    found = sorted(p.stem[len("paper"):] for p in here.glob("paper[0-9][0-9][0-9].py"))
    return {pid: f"{__name__}.paper{pid}" for pid in found}


#: Paper id -> module name, for the paper modules that exist (discovered from ``paperNNN.py`` files).
PAPERS: dict[str, str] = _discover()


def paper_ids() -> list[str]:
    """The paper ids that can be reproduced, in order."""
    return list(PAPERS)


def _resolve_ids(papers) -> list[str]:
    if isinstance(papers, str):
        papers = [papers]
    papers = list(papers)
    if not papers:
        raise ReproductionError(f"name at least one paper: {', '.join(PAPERS)} or all")
    ids: list[str] = []
    for p in papers:
        p = str(p).strip()
        if p == "all":
            ids += [pid for pid in PAPERS if pid not in ids]
            continue
        pid = p.zfill(3) if p.isdigit() else p
        if pid not in PAPERS:
            raise ReproductionError(
                f"unknown paper id {p!r}; valid ids: {', '.join(PAPERS) or '(none)'} or all"
            )
        if pid not in ids:
            ids.append(pid)
    return ids


def _default_command(pid: str, quick: bool, seed: int, out: Path, jobs: int) -> str:
    parts = ["evoik", "reproduce", pid, *(["--quick"] if quick else []), "--seed", str(seed), "--out", str(out),
             *(["--jobs", str(jobs)] if jobs > 1 else [])]
    return shlex.join(parts)


def run_papers(papers="all", out=DEFAULT_OUT, quick: bool = False, seed: int = 0, progress: bool = True,
               dpi: int = 90, command: str | None = None, jobs: int = 1) -> list[PaperReport]:
    """Reproduce one or more papers; each writes into ``out/<paper id>/``.

    Args:
        papers: a paper id (``"002"``, ``"2"``), a list of ids, or ``"all"``.
        out: output directory (created; must be writable).
        quick: reduced-size runs (well under a minute per paper) instead of the papers' settings.
        seed: master seed (non-negative int); every random choice derives from it.
        progress: show tqdm progress bars.
        dpi: resolution of the figures.
        command: command line recorded in the reports (default: the equivalent ``evoik reproduce``).
        jobs: worker processes a paper may use for its independent parts (same numbers as 1, faster).

    Returns:
        The :class:`PaperReport` of each paper, in order.

    Raises:
        ReproductionError: unknown paper id or bad seed. OutputError: ``out`` is not a writable
        directory. Both before any work starts.
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
        ctx = RunContext(out_dir=out / pid, quick=quick, seed=seed, progress=progress, dpi=dpi,
                         command=command or _default_command(pid, quick, seed, out, jobs), jobs=jobs)
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
