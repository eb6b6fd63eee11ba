"""The robot's masses as constants of compiled kernels: each physical joint's body (mass, centre of mass in the
joint's folded frame), each joint's subtree mass, and the bodies no active joint moves (see :class:`MassConstants`).

Masses and centres come from the Pinocchio model's inertias (``model.inertias``). The robot's reduced model
already holds, on each physical joint, the bodies of the links on fixed or locked joints below it (Pinocchio's
``buildReducedModel`` merges them into their parent joint's inertia), and a floating base's root body sits on its
last (roll) joint. The bodies the reduction leaves on the universe (those above the base, or on locked branches
hanging from it) are a constant first moment; the bodies welded to the world in :attr:`Robot.full_model` (a fixed
base's root link) are left out, as ``pin.centerOfMass(full_model, ...)`` leaves them out: the centre of mass is
that of every body the robot's joints (active or locked) carry.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["MassConstants", "mass_constants"]


@dataclass(frozen=True)
class MassConstants:
    """The masses of a robot's m physical joints (``Robot.tree_constants``).

    Attributes:
        masses: (m,) kg, the body each physical joint carries (0 for a massless one).
        moments: (m, 3) kg m, each body's first moment ``m_k c_k`` in its joint's folded frame.
        subtree: (m,) kg, the mass of each joint's body and of every body below it.
        fixed_mass: kg, and fixed_moment: (3,) kg m in the base frame: the bodies no active joint moves.
        total: kg, the whole robot's mass (of the bodies counted).
    """

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
