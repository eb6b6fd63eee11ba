"""The robot's masses as constants of compiled kernels (:class:`MassConstants`), from the reduced model's inertias
(which hold locked links' bodies). Bodies the reduction leaves on the universe are a constant first moment; bodies
welded to the world in ``full_model`` are left out, as ``pin.centerOfMass(full_model, ...)`` does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["MassConstants", "mass_constants"]


@dataclass(frozen=True)
class MassConstants:
    """The masses of a robot's m physical joints: ``masses`` (m,) kg, ``moments`` (m, 3) kg m (``m_k c_k`` in the
    joint's folded frame), ``subtree`` (m,) kg (a joint's body and all below), ``fixed_mass`` kg and ``fixed_moment``
    (3,) kg m (base frame) of the bodies no active joint moves, ``total`` kg."""

    masses: np.ndarray
    moments: np.ndarray
    subtree: np.ndarray
    fixed_mass: float
    fixed_moment: np.ndarray
    total: float


def mass_constants(robot) -> MassConstants:
    """The :class:`MassConstants` of ``robot`` (see the module docstring)."""
    model, tree = robot.model, robot.tree
    m = tree.m
    masses = np.array([model.inertias[k + 1].mass for k in range(m)], dtype=float)
    moments = np.empty((m, 3))
    for k in range(m):
        inertia = model.inertias[k + 1]
        moments[k] = tree.B[k].T @ (inertia.mass * np.asarray(inertia.lever))
    subtree = masses.copy()
    for k in range(m - 1, -1, -1):  # a joint comes after its parent
        if tree.parent[k] >= 0:
            subtree[tree.parent[k]] += subtree[k]
    held, welded = model.inertias[0], robot.full_model.inertias[0]
    fixed_mass = float(held.mass - welded.mass)
    first = held.mass * np.asarray(held.lever) - welded.mass * np.asarray(welded.lever)  # world frame
    fixed_moment = tree.base_R @ first + fixed_mass * tree.base_p
    if abs(fixed_mass) < 1e-12:  # the same bodies on both sides: no round-off left over
        fixed_mass, fixed_moment = 0.0, np.zeros(3)
    return MassConstants(masses, moments, subtree, fixed_mass, fixed_moment, float(masses.sum() + fixed_mass))
