"""Goals of an IK problem on a whole robot: which frame goes where, with which weight and tolerances.

A problem is a list of goals, each on one frame of the robot (any Pinocchio frame: a link, a joint frame, a fixed
frame), with its target expressed in the robot's base frame (for a floating base: the world frame)::

    from evoik_pin.goals import Pose, Position
    goals = [Pose("left_sole_link", T_lf), Pose("right_sole_link", T_rf), Position("arm_right_7_link", p_rh)]
    result = evoik_pin.solve(talos, goals)

* :class:`Pose`: position and orientation (6 residual rows: the SE(3) logarithm of the frame seen from the
  target, m and rad); its target a (4, 4) homogeneous matrix, a ``pin.SE3`` or a :class:`~evoik_pin.problem.Target`
  with a rotation;
* :class:`Position`: position only (3 rows, m); its target a 3-vector (m);
* :class:`Orientation`: orientation only (3 rows, rad); its target a rotation (3 x 3, ``pin.SE3``, 4 x 4);
* :class:`Direction`: a frame axis along a direction (3 rows; error the angle between them, rad);
* :class:`LookAt`: a frame axis pointing at a point (3 rows; error the angle to the line to the point, rad);
* :class:`CenterOfMass`: the whole robot's centre of mass at a point (on chosen axes), or its ground projection
  inside the support polygon of contact points (``support={frame: points}`` or ``support=[frames]``), at least
  ``margin`` (m) inside its edges;
* :class:`RelativePose`: one frame's pose seen from another (``frame_a``, ``frame_b``, T: two hands holding a box);
* :class:`RelativePosition`: one frame's origin relative to another's (``frame_a``, ``frame_b``, p, m), in frame a's
  axes or the world's (``expressed_in="a" | "world"``).

``Pose``, ``Position`` and ``Orientation`` also take per-axis tolerance bands and free axes (``tolerance=`` 6 or 3
half-widths, ``free="rz"``; :mod:`.bands`): met when every component of the error is within its band.

A goal set, ``Pose(frame, [T1, ..., Tk])`` or ``Position(frame, [p1, ..., pk])``, is met by any one of its members
(:func:`.goal.init_set`; ``Result.chosen``). Preferences (:mod:`.preferences`: :class:`Posture`,
:class:`JointLimitMargin`, :class:`Manipulability`, :class:`MinimalDisplacement`) may join the list: met as well as
the goals allow, never at their expense.

Each goal checks its inputs when made (an :mod:`evoik_pin.errors` class naming what is wrong) and packs itself into
the LM kernel's goal stack (:class:`.stack.GoalStack`: kind, frame, weight, tolerances; each kind declares itself,
:mod:`.registry`);
:func:`bind` checks a goal list against a robot (frames that exist and that some active joint moves, the same frame
twice with clashing targets). A goal's ``weight`` (> 0) scales its rows by ``sqrt(weight)``, so goals that cannot
all be met settle on the compromise the weights make; it is met when its position error is within ``tolerance``
(m) and, for a pose, its rotation angle within ``rotation_tolerance`` (rad; default: ``tolerance``).
"""

# The kinds in the order they are declared (registered: evoik_pin.goals.registry), which goals files list them in.
from .pose import Pose  # noqa: I001
from .position import Position
from .orientation import Orientation
from .direction import Direction
from .look_at import LookAt
from .center_of_mass import CenterOfMass
from .relative_pose import RelativePose
from .relative_position import RelativePosition
from .goal import DEFAULT_GOAL_TOLERANCE, Goal
from .preferences import JointLimitMargin, Manipulability, MinimalDisplacement, Posture, Preference
from .stack import bind, is_goal_list

__all__ = ["DEFAULT_GOAL_TOLERANCE", "Direction", "Goal", "JointLimitMargin", "LookAt", "Manipulability",
           "MinimalDisplacement", "Orientation", "Pose", "Position", "Posture", "Preference", "bind", "is_goal_list"]
__all__ += ["CenterOfMass", "RelativePose", "RelativePosition"]
