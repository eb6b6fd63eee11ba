"""The whole robots of the ``example-robot-data`` package that load by name: humanoids, legged robots, dual-arm
and mobile manipulators, hands.

Loaded by name, such a robot's active joints are its whole tree (every revolute and prismatic joint; fixed-base,
unless ``floating_base=True``) unless ``tip``, ``tips`` or ``joints`` say less. The names follow the package's own
loader (``example_robot_data.load(name)``); the arms it also ships (panda, ur5, ...) are
:data:`~evoik_pin.robot.loading.EXAMPLE_ARMS`, serial chains to their tool frame.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["WHOLE_ROBOTS", "WholeRobot"]


@dataclass(frozen=True)
class WholeRobot:
    """A whole robot of example-robot-data: its URDF and SRDF below the package's ``robots/`` directory, what it
    is, and whether it stands or flies free (a floating base is what its users usually add)."""

    urdf: str
    what: str
    srdf: str | None = None
    legged: bool = False


#: Whole robots reachable by name (see the module docstring).
WHOLE_ROBOTS: dict[str, WholeRobot] = {
    # humanoids
    "talos": WholeRobot("talos_data/robots/talos_reduced.urdf", "PAL Talos humanoid, 32 joints (arms, legs, torso, "
                        "head; grippers fixed)", "talos_data/srdf/talos.srdf", True),
    "talos_full": WholeRobot("talos_data/robots/talos_full_v2.urdf", "PAL Talos humanoid with its grippers' "
                             "joints", "talos_data/srdf/talos.srdf", True),
    "g1": WholeRobot("g1_description/urdf/g1_29dof_rev_1_0.urdf", "Unitree G1 humanoid, 29 joints", None, True),
    "g1_with_hands": WholeRobot("g1_description/urdf/g1_29dof_with_hand_rev_1_0.urdf", "Unitree G1 humanoid with "
                                "its three-finger hands", None, True),
    "romeo": WholeRobot("romeo_description/urdf/romeo.urdf", "SoftBank Romeo humanoid",
                        "romeo_description/srdf/romeo.srdf", True),
    "icub": WholeRobot("icub_description/robots/icub.urdf", "IIT iCub humanoid (hands included)",
                       "icub_description/srdf/icub.srdf", True),
    "icub_reduced": WholeRobot("icub_description/robots/icub_reduced.urdf", "IIT iCub humanoid without hands",
                               "icub_description/srdf/icub.srdf", True),
    "simple_humanoid": WholeRobot("simple_humanoid_description/urdf/simple_humanoid.urdf", "a simple humanoid "
                                  "(Pinocchio's examples)", "simple_humanoid_description/srdf/simple_humanoid.srdf",
                                  True),
    "alex": WholeRobot("alex_description/urdf/alex_nub_hands.urdf", "Boardwalk Robotics Alex upper body",
                       "alex_description/srdf/alex_nub_hands.srdf"),
    "bolt": WholeRobot("bolt_description/robots/bolt.urdf", "ODRI Bolt biped", "bolt_description/srdf/bolt.srdf",
                       True),
    # quadrupeds
    "go1": WholeRobot("go1_description/urdf/go1.urdf", "Unitree Go1 quadruped", "go1_description/srdf/go1.srdf",
                      True),
    "go2": WholeRobot("go2_description/urdf/go2.urdf", "Unitree Go2 quadruped", "go2_description/srdf/go2.srdf",
                      True),
    "a1": WholeRobot("a1_description/urdf/a1.urdf", "Unitree A1 quadruped", "a1_description/srdf/a1.srdf", True),
    "b1": WholeRobot("b1_description/urdf/b1.urdf", "Unitree B1 quadruped", "b1_description/srdf/b1.srdf", True),
    "b1_z1": WholeRobot("b1_description/urdf/b1-z1.urdf", "Unitree B1 quadruped carrying a Z1 arm",
                        "b1_description/srdf/b1-z1.srdf", True),
    "solo8": WholeRobot("solo_description/robots/solo.urdf", "ODRI Solo quadruped, 8 joints",
                        "solo_description/srdf/solo.srdf", True),
    "solo12": WholeRobot("solo_description/robots/solo12.urdf", "ODRI Solo quadruped, 12 joints",
                         "solo_description/srdf/solo.srdf", True),
    "anymal": WholeRobot("anymal_b_simple_description/robots/anymal.urdf", "ANYbotics ANYmal B quadruped",
                         "anymal_b_simple_description/srdf/anymal.srdf", True),
    "anymal_c": WholeRobot("anymal_c_simple_description/urdf/anymal.urdf", "ANYbotics ANYmal C quadruped",
                           "anymal_c_simple_description/srdf/anymal.srdf", True),
    "anymal_kinova": WholeRobot("anymal_b_simple_description/robots/anymal-kinova.urdf", "ANYmal B carrying a "
                                "Kinova arm", "anymal_b_simple_description/srdf/anymal-kinova.srdf", True),
    "hyq": WholeRobot("hyq_description/robots/hyq_no_sensors.urdf", "IIT HyQ quadruped",
                      "hyq_description/srdf/hyq.srdf", True),
    "laikago": WholeRobot("laikago_description/urdf/laikago.urdf", "Unitree Laikago quadruped", None, True),
    "quadruped": WholeRobot("quadruped_description/urdf/quadruped.urdf", "a simple quadruped", None, True),
    "centauro": WholeRobot("centauro_description/urdf/centauro.urdf", "IIT Centauro: four wheeled legs and two "
                           "arms", "centauro_description/srdf/centauro.srdf", True),
    # dual-arm and mobile manipulators
    "baxter": WholeRobot("baxter_description/urdf/baxter.urdf", "Rethink Baxter, two 7-joint arms",
                         "baxter_description/srdf/baxter_manipulation.srdf"),
    "pr2": WholeRobot("pr2_description/urdf/pr2.urdf", "Willow Garage PR2: torso lift, two 7-joint arms, head, "
                      "grippers", "pr2_description/srdf/pr2.srdf"),
    "tiago": WholeRobot("tiago_description/robots/tiago.urdf", "PAL TIAGo: torso lift, one arm, head, gripper"),
    "tiago_dual": WholeRobot("tiago_description/robots/tiago_dual.urdf", "PAL TIAGo++: torso lift, two arms, head"),
    "tiago_no_hand": WholeRobot("tiago_description/robots/tiago_no_hand.urdf", "PAL TIAGo without its gripper"),
    "tiago_pro": WholeRobot("tiago_pro_description/robots/tiago_pro.urdf", "PAL TIAGo Pro"),
    "human": WholeRobot("human_description/robots/human.urdf", "a human body model", None, True),
    # hands, small arms and mechanisms
    "allegro_right": WholeRobot("allegro_hand_description/urdf/allegro_right_hand.urdf", "Wonik Allegro right hand, "
                                "four fingers of 4 joints"),
    "allegro_left": WholeRobot("allegro_hand_description/urdf/allegro_left_hand.urdf", "Wonik Allegro left hand"),
    "finger_edu": WholeRobot("finger_edu_description/robots/finger_edu.urdf", "ODRI Finger Edu, one 3-joint "
                             "finger", "finger_edu_description/srdf/finger_edu.srdf"),
    "double_pendulum": WholeRobot("double_pendulum_description/urdf/double_pendulum.urdf", "a double pendulum"),
    "asr_twodof": WholeRobot("asr_twodof_description/urdf/TwoDofs.urdf", "a two-joint arm"),
    # flying robots
    "hector": WholeRobot("hector_description/robots/quadrotor_base.urdf", "Hector quadrotor (no joints: a "
                         "floating base only)", None, True),
    "iris": WholeRobot("iris_description/robots/iris_simple.urdf", "3DR Iris quadrotor (no joints: a floating "
                       "base only)", None, True),
    "borinot": WholeRobot("borinot_description/urdf/borinot_flying_arm_2.urdf", "Borinot drone with a 2-joint arm",
                          "borinot_description/srdf/borinot_flying_arm_2.srdf", True),
    "hextilt": WholeRobot("hextilt_description/urdf/hextilt_flying_arm_5.urdf", "hexacopter with a 5-joint arm",
                          "hextilt_description/srdf/hextilt_flying_arm_5.srdf", True),
}
