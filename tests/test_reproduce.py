"""Paper reproductions (evoik_pin.papers, ``evoik reproduce``): quick runs produce sane tables and figures.

The quick runs are conftest.py's ``quick_runs`` (``evoik reproduce all --quick --seed 3``, once for the suite): the
generic checks below cover every paper; paper-specific numbers of 002 and 004 are checked here, those of 000, 001
and 003 in test_reproduce_000_001_003.py.
"""

import csv
import importlib
import json
import math
from pathlib import Path

import numpy as np
import pytest

from evoik_pin.cli import main
from evoik_pin.errors import OutputError, ReproductionError
from evoik_pin.papers import PAPERS, RunContext, Table, paper_ids, run_paper, run_papers
from evoik_pin.papers.reporting import check_output_file, fmt

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _csv(path: Path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def _ours(rows: list[dict], column: str) -> dict:
    return {r[column]: r for r in rows if r["source"] == "ours"}


# ------------------------------------------------------------------------------------------- contract


def test_registry_lists_existing_modules_with_the_contract():
    assert {"002", "004"} <= set(PAPERS)
    assert paper_ids() == sorted(PAPERS)
    for pid, module_name in PAPERS.items():
        module = importlib.import_module(module_name)
        assert module.PAPER_ID == pid and module.TITLE and callable(module.run)
        assert (SCRIPTS / f"reproduce_{pid}.py").is_file(), f"scripts/reproduce_{pid}.py missing"


def test_context_streams_depend_on_seed_and_labels_only(tmp_path):
    a = RunContext(tmp_path, seed=1).rng("002", "x").random(3)
    assert np.array_equal(a, RunContext(tmp_path, seed=1).rng("002", "x").random(3))
    assert not np.array_equal(a, RunContext(tmp_path, seed=2).rng("002", "x").random(3))
    assert not np.array_equal(a, RunContext(tmp_path, seed=1).rng("002", "y").random(3))


@pytest.mark.parametrize("jobs", [1, 2])
def test_map_parallel_returns_results_in_spec_order_and_raises_part_errors(tmp_path, jobs):
    ctx = RunContext(tmp_path, progress=False, jobs=jobs)
    assert ctx.map_parallel(math.sqrt, [9.0, 0.25, 4.0, 16.0, 1.0], "test") == [3.0, 0.5, 2.0, 4.0, 1.0]
    assert ctx.map_parallel(math.sqrt, [], "test") == []
    with pytest.raises(ValueError, match="math domain error"):
        ctx.map_parallel(math.sqrt, [4.0, -1.0, 9.0], "test")


def test_table_markdown_and_csv(tmp_path):
    t = Table("t", "T", ["name", "error (m)"], [["a", 1.5e-14]], paper_rows=[["a", None]])
    md = t.markdown()
    assert "Paper (as reported)" in md and "1.500e-14" in md
    rows = _csv(t.write_csv(tmp_path / "t.csv"))
    assert [r["source"] for r in rows] == ["paper", "ours"] and float(rows[1]["error (m)"]) == 1.5e-14
    with pytest.raises(ValueError, match="cells"):
        Table("t", "T", ["a", "b"], [[1]])
    assert fmt(0.0) == "0" and fmt(float("nan")) == "n/a" and fmt(True) == "yes"


# ----------------------------------------------------------------------------------------- bad input


def test_unknown_paper_id_lists_valid_ones(tmp_path, capsys):
    with pytest.raises(ReproductionError, match="valid ids: .*002.*004"):
        run_paper("005", out=tmp_path)
    assert main(["reproduce", "7", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "unknown paper id '7'" in err and "002" in err
    assert not any(tmp_path.iterdir()), "no work (no output) before the error"


def test_unwritable_output_is_refused_before_work(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(OutputError, match="not a directory"):
        run_papers("002", out=blocker)
    with pytest.raises(OutputError, match="not writable"):
        run_papers("004", out=blocker / "sub")
    assert main(["reproduce", "002", "--out", str(blocker / "sub")]) == 2
    assert "not writable" in capsys.readouterr().err
    with pytest.raises(OutputError, match="does not exist"):
        check_output_file(tmp_path / "missing" / "scene.html")
    assert main(["reproduce", "002", "--out", str(tmp_path / "o"), "--html", str(tmp_path)]) == 2
    assert "is a directory" in capsys.readouterr().err
    with pytest.raises(ReproductionError, match="seed"):
        run_papers("002", out=tmp_path, seed=-1)
    with pytest.raises(ReproductionError, match="jobs"):
        run_papers("002", out=tmp_path, jobs=0)


# ------------------------------------------------------------------------------------ quick runs


@pytest.mark.parametrize("pid", sorted(PAPERS))
def test_quick_run_writes_report_json_csv_and_figures(quick_runs, pid):
    d = quick_runs / pid
    results = json.loads((d / "results.json").read_text())
    assert results["paper_id"] == pid and results["quick"] is True and results["seed"] == 3
    assert results["machine"]["cores"] >= 1 and results["wall_time_s"] > 0
    assert results["tables"] and results["figures"]
    for key, table in results["tables"].items():
        with open(d / f"{key}.csv", newline="") as fh:
            header, *rows = list(csv.reader(fh))
        assert header == ["source", *table["columns"]]
        assert sum(r[0] == "ours" for r in rows) == len(table["rows"])
        assert table["rows"] or key == "scenario3_unreachable"  # only that one may be empty in quick mode
    import matplotlib.image as mpimg

    for fig in results["figures"]:
        path = d / fig["path"]
        assert path.read_bytes()[:8] == PNG_MAGIC
        img = mpimg.imread(path)
        assert img.shape[0] > 100 and img.shape[1] > 100 and np.ptp(img[..., :3]) > 0  # not blank
    md = (d / "report.md").read_text()
    assert f"seed: {results['seed']}" in md and "machine:" in md and "Paper (as reported)" in md


def test_quick_002_numbers_are_sane(quick_runs):
    d = quick_runs / "002"
    t4 = _ours(_csv(d / "table4.csv"), "method")
    assert set(t4) == {"PSO", "DE", "ISADE"}
    # DE at the paper's settings reaches its 1e-15 m fitness value (the floor) on random points
    assert float(t4["DE"]["max error (m)"]) <= 1e-14
    for row in t4.values():
        assert float(row["max error (m)"]) < 1e-4
        assert 0 < float(row["avg. iteration"]) <= 600 and float(row["avg. execution time (s)"]) > 0
    t5 = _ours(_csv(d / "table5.csv"), "method")
    assert {"PSO", "DE", "ISADE", "Pro-PSO", "Pro-DE", "Pro-ISADE"} <= set(t5)
    smooth = _ours(_csv(d / "joint_smoothness.csv"), "variant")
    for name in ("Pro-PSO", "Pro-DE", "Pro-ISADE"):  # the Pro box bounds every step by pi/100
        assert float(smooth[name]["max joint jump (deg)"]) <= 1.8 + 1e-9
    t3 = _ours(_csv(d / "table3.csv"), "method")
    assert float(t3["DE"]["position error (m)"]) < 1e-6  # 85 generations of DE/best/1
    results = json.loads((d / "results.json").read_text())
    q = np.array(results["data"]["scenario3_q"]["Pro-ISADE"])
    assert q.shape == (results["settings"]["scenario3_points"], 7)


def test_quick_004_numbers_are_sane(quick_runs):
    d = quick_runs / "004"
    check = _ours(_csv(d / "table5_check.csv"), "target")
    assert len(check) == 3
    assert all(float(r["miss: position (cm)"]) > 10 for r in check.values())  # the paper's inconsistency
    t6 = [r for r in _csv(d / "table6.csv") if r["source"] == "ours"]
    big = [r for r in t6 if r["goal"] == "FK of paper joints" and r["population"] == "30"]
    assert len(big) == 3 and all(float(r["reached (fraction)"]) >= 0.5 for r in big)
    assert all(float(r["pos. error (cm)"]) < 0.1 for r in big)
    t4 = _ours(_csv(d / "table4.csv"), "test")
    assert len(t4) == 14 and all(float(r["J (best)"]) > 0.1 for r in t4.values())  # unreachable in our model


def test_animation_exports_html(tmp_path):
    viz = pytest.importorskip("evoik_pin.viz")
    from evoik_pin.errors import EvoikError
    from evoik_pin.papers.paper002 import spiral_targets
    from evoik_pin.papers.reporting import Animation, show_animation

    anim = Animation("redundant7r", np.zeros((3, 7)) + np.linspace(0, 0.1, 3)[:, None], spiral_targets(3), "test")
    try:
        path = show_animation(anim, html=tmp_path / "spiral.html")
    except EvoikError as exc:  # no meshcat server possible here
        pytest.skip(f"viewer unavailable: {exc}")
    assert viz is not None and path.is_file() and path.stat().st_size > 1000
