"""What the kernel tests share: the compiled tree kinematics of a robot's frames, the compiled kernel's task rows
of a goal list, and central differences."""

import numpy as np

from evoik_pin.goals import bind
from evoik_pin.solvers.lm import chain as C
from evoik_pin.solvers.lm import tree_kinematics as T
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


def compiled_frames(robot, q, frames):
    """Poses (R, p) in the base frame and folded world-frame Jacobians (6, n) of ``frames`` at q, by the compiled
    tree kinematics alone."""
    parent, FR, Fp, rev, index, scale, offset = robot.tree_constants()
    m = parent.size
    x = np.empty(m)
    C.expand(index, scale, offset, q, x)
    Rj, pj, Z, O = np.empty((m, 3, 3)), np.empty((m, 3)), np.empty((m, 3)), np.empty((m, 3))
    T.tree_forward(parent, FR, Fp, rev, x, Rj, pj, Z, O)
    out = []
    for f in frames:
        j, Rf, pf = robot.frame_constants(f)
        R, p = np.empty((3, 3)), np.empty(3)
        T.frame_pose(Rj, pj, j, Rf, pf, R, p)
        support = np.zeros(m, dtype=bool)
        support[robot.tree.ancestors(j)] = True
        Jx, J = np.empty((6, m)), np.empty((6, robot.n))
        T.frame_jacobian(rev, support, p, Z, O, Jx)
        C.fold(index, scale, Jx, J)
        out.append((R, p, J))
    return out
