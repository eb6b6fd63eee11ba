"""``evoik solve --scene FILE [--margin M]`` and ``evoik view --scene FILE``: the verdict printed and in JSON, exit
codes (1 when the answer collides, 2 on a bad scene file), obstacles and red links in the HTML page."""

import json
from pathlib import Path

import numpy as np
import pytest

from evoik_pin.cli import main
from evoik_pin.robot import load_robot
from evoik_pin.scene import Scene
from evoik_pin.viz import COLLISION_RGBA, html_commands

ROOT = Path(__file__).resolve().parents[1]
SHELF = str(ROOT / "examples" / "panda_shelf.yaml")
IN_SHELF = ["--xyz", "0.6", "0.1", "0.3", "--rpy", "0", "90", "0"]  # the hand inside the shelf, pointing in
#: Only the hand can be at this configuration's tip pose, and a crate around it is in the way of every answer.
Q_CRATE = np.array([0.0, 0.3, 0.0, -1.8, 0.0, 2.1, 0.8])
#: The material colour of a link in collision (Pinocchio's visualizer: int(255 c) per channel).
RED = sum(int(c * 255) << s for c, s in zip(COLLISION_RGBA[:3], (16, 8, 0), strict=True))


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


@pytest.fixture(scope="module")
def crate(panda, tmp_path_factory):
    """(scene file with a crate around the hand at Q_CRATE, that tip pose as --xyz/--rpy arguments)."""
    import pinocchio as pin

    T = panda.fk(Q_CRATE)
    path = tmp_path_factory.mktemp("crate") / "crate.json"
    path.write_text(json.dumps({"obstacles": [{"name": "crate", "kind": "box", "size": [0.3, 0.3, 0.3],
                                               "pose": {"xyz": T.translation.tolist()}}]}))
    rpy = np.degrees(pin.rpy.matrixToRpy(T.rotation))
    return str(path), ["--xyz", *(f"{v:.12f}" for v in T.translation), "--rpy", *(f"{v:.12f}" for v in rpy)]


def _solve(capsys, *args):
    code = main(["solve", "panda", *args])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_a_collision_free_answer_prints_yes_and_its_clearance(panda, capsys):
    code, out, _ = _solve(capsys, *IN_SHELF, "--scene", SHELF, "--json")
    info = json.loads(out)
    assert code == 0 and info["success"] and info["collision_free"] and info["colliding_pairs"] == []
    scene = Scene.from_file(panda, SHELF)
    q = np.array(info["q_rad"])
    assert not scene.in_collision(q)  # re-checked here
    assert info["min_distance_m"] == pytest.approx(scene.distance(q), abs=1e-12) and info["min_distance_m"] > 0
    assert (info["scene"], info["margin_m"]) == (SHELF, 0.0)

    code, out, _ = _solve(capsys, *IN_SHELF, "--scene", SHELF)
    assert code == 0
    line = next(line for line in out.splitlines() if line.startswith("collision-free: "))
    assert line.startswith(f"collision-free: yes (min distance {info['min_distance_m'] * 1e3:.3f} mm; scene {SHELF})")
    assert "in collision" not in out


def test_a_margin_is_kept(panda, capsys):
    code, out, _ = _solve(capsys, *IN_SHELF, "--scene", SHELF, "--margin", "0.03", "--json")
    info = json.loads(out)
    assert code == 0 and info["collision_free"] and info["margin_m"] == 0.03
    assert info["min_distance_m"] >= 0.03
    assert not Scene.from_file(panda, SHELF).in_collision(np.array(info["q_rad"]), margin=0.03)


def test_an_answer_in_collision_exits_1_naming_the_pairs_and_is_red_in_the_page(crate, tmp_path, capsys):
    path, target = crate
    code, out, _ = _solve(capsys, *target, "--scene", path, "--json")
    info = json.loads(out)
    assert code == 1 and not info["success"] and info["collision_free"] is False
    assert info["min_distance_m"] <= 0 and any("crate" in pair for pair in info["colliding_pairs"])
    assert len(info["colliding_pairs"]) == len({tuple(p) for p in info["colliding_pairs"]})  # each pair once

    html = tmp_path / "crate.html"
    code, out, err = _solve(capsys, *target, "--scene", path, "--html", str(html))
    assert code == 1 and "NOT reached" in out and "in collision" in out
    lines = out.splitlines()
    verdict = next(k for k, line in enumerate(lines) if line.startswith("collision-free: "))
    assert lines[verdict].startswith("collision-free: no (min distance -")
    assert lines[verdict + 1].startswith("in collision:   ") and " - crate" in lines[verdict + 1]
    assert str(html) in err
    objects = {c["path"]: c["object"] for c in html_commands(html.read_text()) if c["type"] == "set_object"}
    assert "/meshcat/scene/visuals/crate" in objects
    red = {p.rsplit("/", 1)[1] for p, o in objects.items() if p.startswith("/meshcat/robot/visuals/")
           and o.get("materials") and o["materials"][0]["color"] == RED}
    in_collision = {a for a, b in info["colliding_pairs"]} | {b for a, b in info["colliding_pairs"]}
    assert red and {name.rsplit("_", 1)[0] for name in red} <= in_collision


def test_all_solutions_with_a_scene_are_collision_free(panda, capsys):
    code, out, _ = _solve(capsys, *IN_SHELF, "--scene", SHELF, "--all", "--json")
    info = json.loads(out)
    assert code == 0 and info["count"] >= 2 and info["scene"] == SHELF
    scene = Scene.from_file(panda, SHELF)
    for row in info["solutions"]:
        assert row["collision_free"] and row["min_distance_m"] > 0
        assert not scene.in_collision(np.array(row["q_rad"]))
    code, out, _ = _solve(capsys, *IN_SHELF, "--scene", SHELF, "--all")
    assert code == 0 and out.count("collision-free, min distance") == info["count"]


@pytest.mark.parametrize(("scene_text", "args", "message"), [
    ("obstacles:\n  - {name: ball, kind: ball, radius: 0.1, pose: {xyz: [0, 0, 1]}}\n", [],
     r"error: scene file '.*bad.yaml': obstacle 0 \('ball'\): unknown kind 'ball'; accepted kinds: box, sphere"),
    ("obstacles:\n  - {name: ball, kind: sphere, radius: 0.1, pose: {xyz: [0, 0]}\n", [],
     r"error: scene file '.*bad.yaml': YAML syntax error at line 3, column 1: while parsing a flow mapping "
     r"\(begun at line 2, column 5\): expected ',' or '}'"),
    (None, [], r"error: scene file '.*bad.yaml': not found"),
    ("obstacles: []\n", ["--margin", "-0.01"], r"error: --margin must be a finite clearance >= 0 in m, got -0.01"),
])
def test_bad_scene_input_exits_2_with_a_message(tmp_path, capsys, scene_text, args, message):
    import re

    path = tmp_path / "bad.yaml"
    if scene_text is not None:
        path.write_text(scene_text)
    code, out, err = _solve(capsys, *IN_SHELF, "--scene", str(path), *args)
    assert code == 2 and out == "" and "Traceback" not in err
    assert re.search(message, err), err


def test_a_margin_without_a_scene_exits_2(capsys):
    code, _, err = _solve(capsys, *IN_SHELF, "--margin", "0.01")
    assert code == 2 and "--margin needs --scene FILE" in err


def test_view_draws_the_scene_and_the_links_in_collision(tmp_path, capsys):
    html = tmp_path / "view.html"
    q_deg = [f"{v:.6f}" for v in np.degrees([0.0, 0.5, 0.0, -1.2, 0.0, 1.7, 0.8])]  # through the shelf's top
    assert main(["view", "panda", "--q", *q_deg, "--scene", SHELF, "--html", str(html), "--no-block"]) == 0
    out = capsys.readouterr().out
    assert f"collision-free: no (scene {SHELF}; in collision: panda_link5 - shelf_top, panda_link6 - shelf_top)" in out
    objects = {c["path"] for c in html_commands(html.read_text()) if c["type"] == "set_object"}
    assert {f"/meshcat/scene/visuals/{name}" for name in ("table", "shelf_top", "shelf_back")} <= objects
    assert main(["view", "panda", "--scene", str(tmp_path / "none.yaml")]) == 2
    assert "not found" in capsys.readouterr().err
