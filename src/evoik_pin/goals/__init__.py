"""Goals of an IK problem on a whole robot: which frame goes where, with which weight and tolerances.

A problem is a list of goals, each on one frame of the robot (a link, a joint frame or a fixed frame), its target
in the robot's base frame (for a floating base: the world frame)::

    from evoik_pin.goals import Pose, Position
    goals = [Pose("left_sole_link", T_lf), Pose("right_sole_link", T_rf), Position("arm_right_7_link", p_rh)]
    result = evoik_pin.solve(talos, goals)

The kinds, each in its own module: :class:`Pose`, :class:`Position`, :class:`Orientation`, :class:`Direction`,
:class:`LookAt`, :class:`CenterOfMass`, :class:`RelativePose`, :class:`RelativePosition` (per-axis bands and free
axes: :mod:`.bands`); goal sets, any one member of which will do (:mod:`.goal`); preferences, met as well as the
goals allow (:mod:`.preferences`). Each kind declares itself in :mod:`.registry`; :func:`bind` checks a goal list
against a robot and packs it into the LM kernel's goal stack (:mod:`.stack`). A goal's ``weight`` (> 0) scales its
rows by ``sqrt(weight)``, so goals that cannot all be met settle on the compromise the weights make. User guide:
docs/GOALS.md.
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
