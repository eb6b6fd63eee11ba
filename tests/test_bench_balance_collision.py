"""Helpers of scripts/bench_balance_humanoids.py (each humanoid's stance) and scripts/bench_collision.py (the bin
scene, a configuration's nearest joint limit, memetic's message read)."""

import sys
from pathlib import Path

import numpy as np
import pytest

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"
sys.path.insert(0, str(SCRIPTS))

import bench_balance_humanoids as bb  # noqa: E402
import bench_collision as bc  # noqa: E402

import evoik_pin as ek  # noqa: E402
from evoik_pin.goals.center_of_mass import com_of, polygon_distance  # noqa: E402
from evoik_pin.scene import Scene  # noqa: E402


@pytest.mark.parametrize("name", ["g1", "icub"])
def test_the_stance_stands_on_its_soles_with_the_com_inside(name):
    soles, hands, z = bb.HUMANOIDS[name]
    robot = ek.load_robot(name, floating_base=True)
    q = bb.stance_q(robot, soles, z)
    ground = bb.ground_points(robot, q, soles)
    assert abs(ground[:, 2].min()) < 1e-9  # soles on z = 0
    assert robot.within_bounds(q)
    assert polygon_distance(com_of(robot, q)[:2], ground, bb.MARGIN) == 0.0
    stance = bb.stance_goals(robot, soles, q)
    assert [g.frame for g in stance[:2]] == list(soles) and stance[2].margin == bb.MARGIN
    assert all(f in robot.frames for f in hands)


def test_the_judge_accepts_the_stance_and_refuses_a_moved_sole():
    soles, _, z = bb.HUMANOIDS["g1"]
    robot = ek.load_robot("g1", floating_base=True)
    q = bb.stance_q(robot, soles, z)
    stance = bb.stance_goals(robot, soles, q)
    assert bb.judged(robot, q, soles, stance[:2]) == (True, 0.0)
    moved = q.copy()
    moved[0] += 1e-3
    assert not bb.judged(robot, moved, soles, stance[:2])[0]


def test_lm_runs_reads_memetic_messages():
    assert bb.lm_runs("time budget (0.005 s) exhausted after 12 LM run(s) and 0 restart(s); best") == 12
    assert bb.lm_runs("tolerance reached by LM from seed table (3 LM run(s), 1 restart(s))") == 3
    assert bb.lm_runs("no runs here") == -1
    assert bc._stage("time budget (0.005 s) exhausted after 18 LM run(s) and 1 restart(s)") == "18 runs, 1 restarts"
    assert bc._stage("tolerance reached by LM from seed table (21 LM run(s), 1 restart(s))") == "21 runs, 1 restarts"


def test_the_bin_is_open_and_its_interior_reachable_free():
    robot = ek.load_robot("panda")
    scene = bc.add_table_and_bin(Scene(robot))
    assert {"table", "bin_front", "bin_back", "bin_left", "bin_right"} <= set(scene.obstacles)
    Q = bc.free_configurations(scene, 3, np.random.default_rng(0), bc.BIN_INTERIOR)
    assert len(Q) == 3
    lo, hi = bc.BIN_INTERIOR
    for q in Q:
        p = robot.fk(q).translation
        assert np.all(p >= lo) and np.all(p <= hi) and not scene.in_collision(q)


def test_limit_gap_names_the_nearest_bound():
    robot = ek.load_robot("panda")
    q = 0.5 * (robot.lower + robot.upper)
    q[3] = robot.upper[3] - 0.01
    gap, j = bc.limit_gap(robot, q)
    assert j == 3 and gap == pytest.approx(0.01)
