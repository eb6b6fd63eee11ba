"""Example scenes (a table with an open shelf, or with an open-top bin, in front of an arm) and random collision-free
configurations."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from .scene import Scene

__all__ = ["BIN_INTERIOR", "SHELF_INTERIOR", "add_table_and_bin", "add_table_and_shelf", "free_configurations"]

#: The shelf's free interior (m, base frame): (lower corner, upper corner), 2 cm inside its panels.
SHELF_INTERIOR = (np.array([0.47, -0.28, 0.22]), np.array([0.74, 0.28, 0.58]))
#: The bin's free interior (m, base frame), 1 cm inside its walls and above its floor.
BIN_INTERIOR = (np.array([0.43, -0.19, 0.01]), np.array([0.67, 0.19, 0.20]))


def _at(x: float, y: float, z: float) -> pin.SE3:
    return pin.SE3(np.eye(3), np.array([x, y, z]))


def add_table_and_shelf(scene: Scene) -> Scene:
    """Add a 1.6 x 1.6 m table 1 cm below the base frame and on it an open shelf 0.45-0.77 m in front (x), 0.64 m
    wide, its interior 0.2-0.6 m high, open towards the arm (a Panda-class arm's reach); returns the scene."""
    scene.add_box("table", (1.6, 1.6, 0.04), _at(0.3, 0.0, -0.03))
    scene.add_box("shelf_bottom", (0.32, 0.64, 0.02), _at(0.6, 0.0, 0.19))
    scene.add_box("shelf_top", (0.32, 0.64, 0.02), _at(0.6, 0.0, 0.61))
    scene.add_box("shelf_left", (0.32, 0.02, 0.44), _at(0.6, 0.31, 0.40))
    scene.add_box("shelf_right", (0.32, 0.02, 0.44), _at(0.6, -0.31, 0.40))
    scene.add_box("shelf_back", (0.02, 0.64, 0.44), _at(0.77, 0.0, 0.40))
    return scene


def add_table_and_bin(scene: Scene) -> Scene:
    """Add the shelf's table and on it an open-top bin 0.42-0.68 m in front (x), 0.40 m wide (y), 0.22 m high, 1 cm
    walls, its floor on the table: the arm reaches down into it over a wall; returns the scene."""
    scene.add_box("table", (1.6, 1.6, 0.04), _at(0.3, 0.0, -0.03))
    scene.add_box("bin_front", (0.01, 0.40, 0.22), _at(0.42 + 0.005, 0.0, 0.10))
    scene.add_box("bin_back", (0.01, 0.40, 0.22), _at(0.68 - 0.005, 0.0, 0.10))
    scene.add_box("bin_left", (0.26, 0.01, 0.22), _at(0.55, 0.20 - 0.005, 0.10))
    scene.add_box("bin_right", (0.26, 0.01, 0.22), _at(0.55, -0.20 + 0.005, 0.10))
    return scene


def free_configurations(scene: Scene, count: int, rng: np.random.Generator, tip_box=None,
                        batch: int = 20000, max_draws: int = 2_000_000) -> np.ndarray:
    """Up to ``count`` configurations (count, n) drawn in the robot's bounds, collision-free in ``scene`` and, with
    ``tip_box`` = (lower (3,), upper (3,)) m, putting the tip inside it; fewer when ``max_draws`` did not suffice."""
    robot, out, drawn = scene.robot, [], 0
    while sum(len(x) for x in out) < count and drawn < max_draws:
        Q = robot.random_configurations(batch, rng)
        drawn += batch
        if tip_box is not None:
            P, _ = robot.fk_batch(Q)
            Q = Q[((P >= tip_box[0]) & (P <= tip_box[1])).all(axis=1)]
        out.append(Q[~scene.collides(Q)])
    return np.concatenate(out)[:count] if out else np.zeros((0, robot.n))
