"""scripts/bench_goals.py: evoik_pin's answers mapped onto the problems file's model, judged like the peers'."""

import json
import sys
from pathlib import Path

import numpy as np
import pytest

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"
sys.path.insert(0, str(SCRIPTS))

import bench_goals as bg  # noqa: E402
import goal_problems as gp  # noqa: E402
import judge_goals as jg  # noqa: E402


@pytest.fixture(scope="module")
def go2_problems(tmp_path_factory):
    path = tmp_path_factory.mktemp("goals") / "go2.json"
    path.write_text(json.dumps(gp.make_problems("go2", 3, seed=2)), encoding="utf-8")
    return gp.load_problems(path)


def test_our_configurations_are_the_files_and_the_generating_ones_are_judged_solved(go2_problems):
    robot = bg.load_evoik_robot(go2_problems)
    model = gp.model_of(go2_problems)
    assert bg.check_same_model(robot, go2_problems, model) <= 1e-12
    run = bg.run_evoik(robot, go2_problems, {"timeout": None, "max_restarts": 5})
    rows = jg.judge(go2_problems, run["q"], model=model)
    assert all(r["success"] for r in rows), [m for m in run["messages"]]
    assert len(run["wall_s"]) == 3 and all(t > 0 for t in run["wall_s"])


def test_a_model_other_than_the_files_is_refused(go2_problems):
    fixed = {**go2_problems, "floating_base": False}
    robot = bg.ek.load_robot("go2", tips=[g["frame"] for g in go2_problems["goals"]])  # no free-flyer
    with pytest.raises(ValueError, match="full_configuration gives|differ"):
        bg.check_same_model(robot, fixed, gp.model_of(go2_problems))


def test_the_report_names_the_faster_peer_on_the_problems_both_solve(go2_problems):
    model = gp.model_of(go2_problems)
    good = [p["q_generating"] for p in go2_problems["problems"]]
    neutral = go2_problems["neutral"]
    evoik = {"q": good, "wall_s": [1e-3, 2e-3, 3e-3], "messages": ["ok"] * 3, "setup_s": 0.1}
    answers = {"slow": [{"q": q, "wall_s": 0.01} for q in good],
               "fast": [{"q": q, "wall_s": 0.001} for q in (good[0], neutral, good[2])]}
    peers = {"peers": {name: {"answers": a} for name, a in answers.items()}}
    text, numbers = bg.robot_report(go2_problems, evoik, peers, model, (1.0, 1.0))
    assert numbers["faster_peer"] == "fast"
    assert numbers["both"] == {"n": 2, "evoik_ms": pytest.approx(2.0), "peer_ms": pytest.approx(1.0)}
    assert numbers["fast"]["success"] == pytest.approx(2 / 3) and numbers["evoik_pin (memetic)"]["success"] == 1.0
    assert "0.5x (faster peer)" in text
    assert np.isfinite(numbers["slow"]["median_ms"])
