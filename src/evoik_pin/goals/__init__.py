"""Goals of an IK problem on a whole robot, each on one frame, its target in the robot's base frame
(``evoik_pin.solve(talos, [Pose("left_sole_link", T_lf), Position("arm_right_7_link", p_rh)])``): one module per kind
(bands and free axes: :mod:`.bands`; goal sets: :mod:`.goal`), :func:`bind` packs a goal list for the LM kernel
(:mod:`.stack`). A goal's ``weight`` (> 0) scales its rows by ``sqrt(weight)``. User guide: docs/GOALS.md."""

# The kinds in the order they are declared (registered: evoik_pin.goals.registry), which goals files list them in.
from .pose import Pose  # noqa: I001
from .position import Position
from .planar import Planar
from .orientation import Orientation
from .pointing import Direction, LookAt
from .center_of_mass import CenterOfMass
from .relative_pose import RelativePose, RelativePosition
from .goal import DEFAULT_GOAL_TOLERANCE, Goal
from .preferences import JointLimitMargin, Manipulability, MinimalDisplacement, Posture, Preference
from .stack import bind, is_goal_list

__all__ = ["DEFAULT_GOAL_TOLERANCE", "Direction", "Goal", "JointLimitMargin", "LookAt", "Manipulability",
           "MinimalDisplacement", "Orientation", "Pose", "Position", "Posture", "Preference", "bind", "is_goal_list"]
__all__ += ["CenterOfMass", "Planar", "RelativePose", "RelativePosition"]
