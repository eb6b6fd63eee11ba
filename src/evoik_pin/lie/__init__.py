"""One home for rotation and rigid-motion maths, Pinocchio's closed forms and conventions: over a batch (:mod:`.so3`,
:mod:`.se3`) and in numba on caller-owned buffers (:mod:`.compiled`): ``log3(R)`` the rotation vector (rad), ``log6``
the twist ``(v, w)`` (m, rad), ``Jlog3`` / ``Jlog6`` the derivatives of ``log(M exp(d))`` at ``d = 0``."""

from .se3 import exp6, jlog3, jlog6, log6
from .so3 import angle, exp3, is_rotation, log3, relative_angle, rotation_to_z, rpy, skew, wrap_angle, yaw

__all__ = ["angle", "exp3", "exp6", "is_rotation", "jlog3", "jlog6", "log3", "log6", "relative_angle",
           "rotation_to_z", "rpy", "skew", "wrap_angle", "yaw"]
