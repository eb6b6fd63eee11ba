"""What the goal-kind tests share: the compiled kernel's task rows of a goal list, and central differences."""

import numpy as np

from evoik_pin.goals import bind
from evoik_pin.solvers.lm.population_rows import task_rows


def rows(robot, goals, q):
    """(e, E, goal errors (G, 2)) of the compiled kernel at q for a goal list."""
    _, stack, pt, Rt = bind(robot, goals)
    e, E, ge = np.empty(stack.rows), np.empty((stack.rows, robot.n)), np.empty((len(goals), 2))
    task_rows(np.asarray(q, dtype=float), *robot.tree_constants(), *stack.arrays, pt, Rt, e, E, ge)
    return e, E, ge


def numeric_jacobian(f, q, h=1e-6):
    """Central differences (rows, n) of f at q."""
    cols = []
    for k in range(q.size):
        d = np.zeros_like(q)
        d[k] = h
        cols.append((f(q + d) - f(q - d)) / (2 * h))
    return np.array(cols).T
