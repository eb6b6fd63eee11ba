"""Shared machinery of the paper reproductions: a paper module's :class:`RunContext` in, its :class:`PaperReport`
(settings, :class:`Table` objects with the paper's numbers beside ours, figures, notes, raw data) out, written as
``report.md``, ``results.json`` and one CSV per table; and machine facts.
"""

from __future__ import annotations

import csv
import json
import math
import os
import platform
import sys
import tempfile
import zlib
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import OutputError, ReproductionError

__all__ = ["Animation", "Figure", "PaperReport", "RunContext", "Table", "check_output_dir", "check_seed", "derive_rng",
           "dress", "fmt", "jsonable", "least_squares_distance", "machine_info", "progress_bar", "tuple_text"]


def check_seed(seed) -> int:
    """``seed`` as a non-negative int, or a :class:`ReproductionError`."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ReproductionError(f"seed must be a non-negative integer, got {seed!r}")
    return int(seed)


def check_output_dir(path) -> Path:
    """``path`` resolved, created (with parents) if needed; OutputError when it is a file, uncreatable or unwritable."""
    out = Path(path).expanduser()
    if out.exists() and not out.is_dir():
        raise OutputError(f"output path {str(out)!r} exists and is not a directory; choose a directory for --out")
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=out, prefix=".evoik-write-test-", delete=True) as fh:
            fh.write(b"ok")
    except OSError as exc:
        raise OutputError(f"output directory {str(out)!r} is not writable ({exc.strerror or exc}); choose another "
                          "with --out") from None
    return out.resolve()


def fmt(value, spec: str | None = None) -> str:
    """A table cell: numbers with ``spec`` (default: 4 significant digits, scientific when tiny or huge)."""
    if value is None:
        return ""
    if isinstance(value, str):
        return value
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, (int, np.integer)):
        return str(int(value)) if spec is None else format(int(value), spec)
    v = float(value)
    if math.isnan(v):
        return "n/a"
    if spec is not None:
        return format(v, spec)
    if v == 0.0:
        return "0"
    return f"{v:.3e}" if abs(v) < 1e-3 or abs(v) >= 1e5 else f"{v:.4g}"


def tuple_text(values, spec: str = ".4g") -> str:
    """``values`` as ``"(v1, v2, ...)"``, each formatted with ``spec``, for table cells."""
    return "(" + ", ".join(format(float(v), spec) for v in values) + ")"


def jsonable(obj: Any) -> Any:
    """``obj`` with numpy scalars / arrays, paths and tuples turned into plain JSON types (NaN -> None)."""
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        return None if not math.isfinite(v) else v
    return str(obj) if isinstance(obj, Path) else obj


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _git_commit() -> str | None:
    """Commit of the evoik_pin checkout (with ``+dirty`` for uncommitted changes), or None outside git."""
    import subprocess

    here = Path(__file__).resolve().parent
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=here, capture_output=True, text=True,
                              timeout=5, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=here,
                               capture_output=True, text=True, timeout=5, check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return head + ("+dirty" if dirty else "") if head else None


def machine_info() -> dict[str, Any]:
    """Facts about the machine and software a run used."""
    import matplotlib
    import pinocchio

    from .. import __version__

    try:
        load = [round(x, 2) for x in os.getloadavg()]
    except (OSError, AttributeError):  # pragma: no cover - not on Linux/macOS
        load = None
    return {"git_commit": _git_commit(), "cpu": _cpu_model(), "cores": os.cpu_count(), "load_average_at_start": load,
            "platform": platform.platform(), "python": sys.version.split()[0], "numpy": np.__version__,
            "pinocchio": pinocchio.__version__, "matplotlib": matplotlib.__version__, "evoik_pin": __version__}


@dataclass
class Table:
    """One table of a reproduction: ``key`` (CSV stem, results.json key), ``title``, ``columns`` (units in the
    names), our ``rows`` of raw cells, the paper's ``paper_rows`` with the same columns (None: no such table in
    the paper; None cells: not reported), markdown ``formats`` per column (None: :func:`fmt`'s) and a ``note``."""

    key: str
    title: str
    columns: list[str]
    rows: list[list]
    paper_rows: list[list] | None = None
    formats: list[str | None] | None = None
    note: str = ""

    def __post_init__(self) -> None:
        for rows in (self.rows, self.paper_rows or []):
            for row in rows:
                if len(row) != len(self.columns):
                    raise ValueError(f"table {self.key}: row {row!r} has {len(row)} cells, expected "
                                     f"{len(self.columns)} ({self.columns})")

    def _markdown_block(self, rows: list[list]) -> list[str]:
        specs = self.formats or [None] * len(self.columns)
        return ["| " + " | ".join(self.columns) + " |", "|" + " --- |" * len(self.columns),
                *("| " + " | ".join(fmt(v, s) for v, s in zip(row, specs, strict=True)) + " |" for row in rows)]

    def markdown(self) -> str:
        """The table as markdown: the paper's block (when given) above ours, same rows and columns."""
        out = [f"**{self.title}**", ""]
        if self.paper_rows is not None:
            out += ["Paper (as reported):", "", *self._markdown_block(self.paper_rows), "", "This reproduction:", ""]
        out += self._markdown_block(self.rows)
        if self.note:
            out += ["", self.note]
        return "\n".join(out)

    def write_csv(self, path: Path) -> Path:
        """CSV with a leading ``source`` column (``paper`` / ``ours``), full-precision numbers."""
        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["source", *self.columns])
            for source, rows in (("paper", self.paper_rows or []), ("ours", self.rows)):
                w.writerows([source, *("" if v is None else v for v in row)] for row in rows)
        return path

    def as_dict(self) -> dict[str, Any]:
        return jsonable({"title": self.title, "columns": self.columns, "rows": self.rows,
                         "paper_rows": self.paper_rows, "note": self.note})


@dataclass
class Figure:
    """A PNG written by the run and its one-line caption."""

    path: Path
    caption: str


@dataclass
class Animation:
    """A joint trajectory ``evoik reproduce ... --html/--view`` plays: ``robot`` name, ``q`` (T, n) rad, ``targets``
    (T, 3) m drawn as the path, a ``label`` and the playback ``fps``."""

    robot: str
    q: np.ndarray
    targets: np.ndarray
    label: str
    fps: float = 10.0


@dataclass
class PaperReport:
    """Everything a paper reproduction produced (JSON-able ``settings`` and raw ``data``, tables in the paper's
    order, figures, discussion ``notes``, the run's machine, wall time and command); :meth:`write` saves it."""

    paper_id: str
    title: str
    quick: bool
    seed: int
    settings: dict[str, Any] = field(default_factory=dict)
    tables: list[Table] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    data: dict[str, Any] = field(default_factory=dict)
    machine: dict[str, Any] = field(default_factory=dict)
    wall_time_s: float = float("nan")
    command: str = ""
    animation: Animation | None = None

    def markdown(self, out_dir: Path) -> str:
        """The report as markdown, figure links relative to ``out_dir``."""
        mode = "quick (reduced size)" if self.quick else "full (paper settings)"
        lines = [f"# Paper {self.paper_id}: {self.title}", "",
                 f"- mode: {mode}", f"- seed: {self.seed}", f"- command: `{self.command}`",
                 f"- wall time: {self.wall_time_s:.1f} s",
                 "- machine: " + ", ".join(f"{k} {v}" for k, v in self.machine.items()), "",
                 "## Settings", "", "```json", json.dumps(jsonable(self.settings), indent=1), "```", ""]
        lines += ["## Tables", ""]
        for t in self.tables:
            lines += [t.markdown(), ""]
        if self.figures:
            lines += ["## Figures", ""]
            for f in self.figures:
                lines += [f"![{f.caption}]({os.path.relpath(f.path, out_dir)})", "", f"*{f.caption}*", ""]
        if self.notes:
            lines += ["## Notes", ""] + [f"- {n}" for n in self.notes] + [""]
        return "\n".join(lines)

    def as_dict(self) -> dict[str, Any]:
        return jsonable({
            "paper_id": self.paper_id, "title": self.title, "quick": self.quick, "seed": self.seed,
            "command": self.command, "wall_time_s": self.wall_time_s, "machine": self.machine,
            "settings": self.settings, "tables": {t.key: t.as_dict() for t in self.tables},
            "figures": [{"path": f.path.name, "caption": f.caption} for f in self.figures],
            "notes": self.notes, "data": self.data,
        })

    def write(self, out_dir: Path) -> None:
        """Write ``report.md``, ``results.json`` and ``<table key>.csv`` files into ``out_dir``."""
        out_dir = Path(out_dir)
        for t in self.tables:
            t.write_csv(out_dir / f"{t.key}.csv")
        (out_dir / "results.json").write_text(json.dumps(self.as_dict(), indent=1, allow_nan=False))
        (out_dir / "report.md").write_text(self.markdown(out_dir))


def progress_bar(iterable: Iterable | None = None, total: int | None = None, desc: str = "", enabled: bool = True):
    """A tqdm progress bar on stderr that disappears when done (usable in worker processes)."""
    from tqdm.auto import tqdm

    return tqdm(iterable, total=total, desc=desc, disable=not enabled, leave=False, dynamic_ncols=True, file=sys.stderr)


def derive_rng(seed: int, *labels: str) -> np.random.Generator:
    """A generator for one named part of an experiment that depends only on the master ``seed`` and the part's
    labels: adding a part changes no other's numbers, and a worker process draws what it would serially."""
    keys = [zlib.crc32(str(label).encode()) for label in labels]
    return np.random.default_rng(np.random.SeedSequence([int(seed), *keys]))


@dataclass
class RunContext:
    """What a paper module's ``run(ctx)`` gets: its checked ``out_dir``, the ``quick`` flag, the master ``seed``,
    the ``progress`` switch, the figures' ``dpi``, the ``command`` shown and the worker processes ``jobs``."""

    out_dir: Path
    quick: bool = False
    seed: int = 0
    progress: bool = True
    dpi: int = 90
    command: str = ""
    jobs: int = 1

    def rng(self, *labels: str) -> np.random.Generator:
        """An independent generator for one named part of the experiment: :func:`derive_rng` of the seed."""
        return derive_rng(self.seed, *labels)

    def bar(self, iterable=None, total: int | None = None, desc: str = ""):
        """A tqdm progress bar (disabled when :attr:`progress` is False); see :func:`progress_bar`."""
        return progress_bar(iterable, total, desc, self.progress)

    def map_parallel(self, func: Callable[[Any], Any], specs: list, desc: str) -> list:
        """``[func(spec) for spec in specs]``, in :attr:`jobs` spawned worker processes when ``jobs > 1``, in the
        order of ``specs``. ``func`` must be top-level and draw only from ``derive_rng(spec seed, ...)``, so the
        numbers do not depend on ``jobs``; a part that raises cancels the rest and raises here."""
        workers = min(self.jobs, len(specs))
        if workers <= 1:
            return [func(spec) for spec in self.bar(specs, desc=desc)]
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor, as_completed

        with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            futures = [pool.submit(func, spec) for spec in specs]
            try:
                for fut in self.bar(as_completed(futures), total=len(futures), desc=f"{desc} ({workers} processes)"):
                    fut.result()  # a failed part raises now, not after all the others
            except BaseException:
                for fut in futures:
                    fut.cancel()
                raise
            return [fut.result() for fut in futures]

    def new_figure(self, *args, **kwargs):
        """``matplotlib.pyplot.subplots`` on the non-interactive Agg backend."""
        import matplotlib

        matplotlib.use("Agg", force=True)
        import matplotlib.pyplot as plt

        return plt.subplots(*args, **kwargs)

    def save_figure(self, fig, name: str, caption: str) -> Figure:
        """Lay ``fig`` out tightly, save it as ``<out_dir>/<name>.png`` at :attr:`dpi`, close it; a :class:`Figure`."""
        import matplotlib.pyplot as plt

        path = self.out_dir / f"{name}.png"
        fig.tight_layout()
        fig.savefig(path, dpi=self.dpi)
        plt.close(fig)
        return Figure(path, caption)


def dress(ax, xlabel: str = "", ylabel: str = "", title: str = "", legend: float | None = None,
          grid: str = "major") -> None:
    """Label a figure's axes ``ax``: axis labels, a 9 pt ``title``, a light grid on the ``grid`` ticks ("major" or
    "both") and, when ``legend`` (a font size) is given, a legend."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title, fontsize=9)
    ax.grid(True, which=grid, alpha=0.3)
    if legend is not None:
        ax.legend(fontsize=legend)


def check_output_file(path) -> Path:
    """Check that a file can be written at ``path`` (its directory exists and is writable, it is no directory)."""
    p = Path(path).expanduser()
    if p.is_dir():
        raise OutputError(f"{str(p)!r} is a directory; give a file path such as {str(p / 'scene.html')!r}")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise OutputError(f"directory {str(parent)!r} of {str(p)!r} does not exist")
    if not os.access(parent, os.W_OK):
        raise OutputError(f"directory {str(parent)!r} is not writable; cannot write {str(p)!r}")
    return p.resolve()


def show_animation(animation: Animation, html=None, view: bool = False) -> Path | None:
    """Play ``animation`` in the meshcat viewer (``view``: until Ctrl-C) and/or save it as HTML (the path returned)."""
    from ..robot import load_robot
    from ..viz import Viewer

    robot = load_robot(animation.robot)
    written = None
    with Viewer(robot) as viewer:
        viewer.draw_path(np.asarray(animation.targets), name="targets")
        viewer.show_target(np.asarray(animation.targets)[-1])
        viewer.animate(np.asarray(animation.q), dt=1.0 / animation.fps)
        if html is not None:
            written = viewer.save_html(html)
        if view:
            viewer.block(f"{animation.label}: {viewer.url} (Ctrl-C to stop)")
    return written


def least_squares_distance(robot, p, lower, upper, rng, starts: int, x0=None) -> float:
    """Smallest distance (m) from ``p`` found in the box [lower, upper], a reachability check independent of the
    solvers under test: bounded least squares from ``starts`` starts (the first ``x0`` when given), then, unless
    within 1e-13 m, ``memetic`` with 30 restarts (whose seed table covers the box far better)."""
    from scipy.optimize import least_squares

    from ..api import solve

    best = np.inf
    for k in range(starts):
        x = np.clip(x0, lower, upper) if (k == 0 and x0 is not None) else rng.uniform(lower, upper)
        sol = least_squares(lambda q: robot.fk(q).translation - p, x, jac=lambda q: robot.jacobian(q)[:3],
                            bounds=(lower, upper), xtol=1e-15, ftol=1e-15, gtol=1e-15)
        best = min(best, float(np.linalg.norm(sol.fun)))
        if best <= 1e-13:
            return best
    res = solve(robot, p, method="memetic", seed=rng, bounds=(lower, upper), tolerance=1e-13, timeout=None,
                max_restarts=30, q0=None if x0 is None else np.clip(x0, lower, upper))
    return min(best, res.position_error)
