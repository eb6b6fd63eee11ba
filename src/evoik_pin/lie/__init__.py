"""One home for rotation and rigid-motion maths: SO(3) and SE(3) logarithms, exponentials and their Jacobians.

Two forms side by side, the same closed forms (Pinocchio's, written out):

* :mod:`.so3` and :mod:`.se3`: NumPy, vectorized over a batch (leading axis N), for populations and tests;
* :mod:`.compiled`: numba, one rotation at a time on caller-owned buffers, for compiled kernels
  (:mod:`evoik_pin.solvers.lm.kernel`).

Conventions (Pinocchio's): ``log3(R)`` is the rotation vector (rad) whose norm is the rotation angle in
[0, pi]; ``log6(M)`` of a pose ``M = (R, t)`` is the twist ``(v, w)`` (m, rad) with ``w = log3(R)``;
``Jlog3`` / ``Jlog6`` are the derivatives of ``log(M exp(d))`` at ``d = 0`` (right perturbation). Every
function is tested against ``pin.log3``, ``pin.log6``, ``pin.Jlog3``, ``pin.Jlog6``, ``pin.exp3``,
``pin.exp6`` at random, near 0 and near pi (tests/test_lie.py). Nothing else in evoik_pin computes a
rotation angle.
"""

from .se3 import exp6, jlog6, log6
from .so3 import (
    angle,
    exp3,
    jlog3,
    log3,
    relative_angle,
    rotation_to_z,
    rpy,
    skew,
    wrap_angle,
    yaw,
)

__all__ = ["angle", "exp3", "exp6", "jlog3", "jlog6", "log3", "log6", "relative_angle", "rotation_to_z", "rpy",
           "skew", "wrap_angle", "yaw"]
