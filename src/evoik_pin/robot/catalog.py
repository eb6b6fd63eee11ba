"""The robots :func:`~evoik_pin.robot.load_robot` takes by name: the papers' arms shipped with evoik_pin, and the arms
(the chain to their tool frame) and whole robots of ``example-robot-data``."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["BUNDLED_ROBOTS", "EXAMPLE_ARMS", "WHOLE_ROBOTS", "CatalogRobot"]

#: The papers' arms shipped with evoik_pin (``robots/<name>.urdf``), with the paper each comes from.
BUNDLED_ROBOTS: dict[str, str] = {
    "ax18": "000: Crustcrawler AX-18, 4R + tool (standard DH, Table 1)",
    "planar2r": "001: planar 2R elbow arm, a1 = 0.25 m, a2 = 0.16 m",
    "puma3r": "001: PUMA 560 positioning chain (wrist point, eq. 20)",
    "redundant7r": "002: redundant 7R arm (standard DH, eqs. 3-9)",
    "vehicle_arm": "003: planar vehicle (prismatic x, y) carrying a 3R arm",
    "aerial6r": "004: 6R human-like arm of an aerial manipulator (Table 1, standard DH)",
}


@dataclass(frozen=True)
class CatalogRobot:
    """A robot of example-robot-data: its URDF and SRDF below the package's ``robots/``, what it is, an arm's tip."""

    urdf: str
    what: str = ""
    srdf: str | None = None
    tip: str | None = None


#: Arms of example-robot-data, with their default tip frames.
EXAMPLE_ARMS: dict[str, CatalogRobot] = {
    "panda": CatalogRobot("panda_description/urdf/panda.urdf", srdf="panda_description/srdf/panda.srdf",
                          tip="panda_hand_tcp"),
    "ur3": CatalogRobot("ur_description/urdf/ur3_robot.urdf", tip="tool0"),
    "ur5": CatalogRobot("ur_description/urdf/ur5_robot.urdf", srdf="ur_description/srdf/ur5.srdf", tip="tool0"),
    "ur10": CatalogRobot("ur_description/urdf/ur10_robot.urdf", tip="tool0"),
    "kinova": CatalogRobot("kinova_description/robots/kinova.urdf", srdf="kinova_description/srdf/kinova.srdf",
                           tip="j2s6s200_end_effector"),
    "z1": CatalogRobot("z1_description/urdf/z1.urdf", srdf="z1_description/srdf/z1.srdf", tip="gripperStator"),
    "xarm": CatalogRobot("xarm_description/urdf/xarm7.urdf", srdf="xarm_description/srdf/xarm7.srdf", tip="link_eef"),
    "so_arm": CatalogRobot("so_arm_description/urdf/so101.urdf", tip="gripper_frame_link"),
}

#: Whole robots of example-robot-data: (URDF, what it is[, SRDF]) below the package's ``robots/`` directory.
WHOLE_ROBOTS: dict[str, CatalogRobot] = {name: CatalogRobot(*entry) for name, entry in {
    # humanoids
    "talos": ("talos_data/robots/talos_reduced.urdf", "PAL Talos humanoid, 32 joints (arms, legs, torso, head; "
              "grippers fixed)", "talos_data/srdf/talos.srdf"),
    "talos_full": ("talos_data/robots/talos_full_v2.urdf", "PAL Talos humanoid with its grippers' joints",
                   "talos_data/srdf/talos.srdf"),
    "g1": ("g1_description/urdf/g1_29dof_rev_1_0.urdf", "Unitree G1 humanoid, 29 joints"),
    "g1_with_hands": ("g1_description/urdf/g1_29dof_with_hand_rev_1_0.urdf", "Unitree G1 humanoid with its "
                      "three-finger hands"),
    "romeo": ("romeo_description/urdf/romeo.urdf", "SoftBank Romeo humanoid", "romeo_description/srdf/romeo.srdf"),
    "icub": ("icub_description/robots/icub.urdf", "IIT iCub humanoid (hands included)",
             "icub_description/srdf/icub.srdf"),
    "icub_reduced": ("icub_description/robots/icub_reduced.urdf", "IIT iCub humanoid without hands",
                     "icub_description/srdf/icub.srdf"),
    "simple_humanoid": ("simple_humanoid_description/urdf/simple_humanoid.urdf", "a simple humanoid (Pinocchio's "
                        "examples)", "simple_humanoid_description/srdf/simple_humanoid.srdf"),
    "alex": ("alex_description/urdf/alex_nub_hands.urdf", "Boardwalk Robotics Alex upper body",
             "alex_description/srdf/alex_nub_hands.srdf"),
    "bolt": ("bolt_description/robots/bolt.urdf", "ODRI Bolt biped", "bolt_description/srdf/bolt.srdf"),
    # quadrupeds
    "go1": ("go1_description/urdf/go1.urdf", "Unitree Go1 quadruped", "go1_description/srdf/go1.srdf"),
    "go2": ("go2_description/urdf/go2.urdf", "Unitree Go2 quadruped", "go2_description/srdf/go2.srdf"),
    "a1": ("a1_description/urdf/a1.urdf", "Unitree A1 quadruped", "a1_description/srdf/a1.srdf"),
    "b1": ("b1_description/urdf/b1.urdf", "Unitree B1 quadruped", "b1_description/srdf/b1.srdf"),
    "b1_z1": ("b1_description/urdf/b1-z1.urdf", "Unitree B1 quadruped carrying a Z1 arm",
              "b1_description/srdf/b1-z1.srdf"),
    "solo8": ("solo_description/robots/solo.urdf", "ODRI Solo quadruped, 8 joints", "solo_description/srdf/solo.srdf"),
    "solo12": ("solo_description/robots/solo12.urdf", "ODRI Solo quadruped, 12 joints",
               "solo_description/srdf/solo.srdf"),
    "anymal": ("anymal_b_simple_description/robots/anymal.urdf", "ANYbotics ANYmal B quadruped",
               "anymal_b_simple_description/srdf/anymal.srdf"),
    "anymal_c": ("anymal_c_simple_description/urdf/anymal.urdf", "ANYbotics ANYmal C quadruped",
                 "anymal_c_simple_description/srdf/anymal.srdf"),
    "anymal_kinova": ("anymal_b_simple_description/robots/anymal-kinova.urdf", "ANYmal B carrying a Kinova arm",
                      "anymal_b_simple_description/srdf/anymal-kinova.srdf"),
    "hyq": ("hyq_description/robots/hyq_no_sensors.urdf", "IIT HyQ quadruped", "hyq_description/srdf/hyq.srdf"),
    "laikago": ("laikago_description/urdf/laikago.urdf", "Unitree Laikago quadruped"),
    "quadruped": ("quadruped_description/urdf/quadruped.urdf", "a simple quadruped"),
    "centauro": ("centauro_description/urdf/centauro.urdf", "IIT Centauro: four wheeled legs and two arms",
                 "centauro_description/srdf/centauro.srdf"),
    # dual-arm and mobile manipulators
    "baxter": ("baxter_description/urdf/baxter.urdf", "Rethink Baxter, two 7-joint arms",
               "baxter_description/srdf/baxter_manipulation.srdf"),
    "pr2": ("pr2_description/urdf/pr2.urdf", "Willow Garage PR2: torso lift, two 7-joint arms, head, grippers",
            "pr2_description/srdf/pr2.srdf"),
    "tiago": ("tiago_description/robots/tiago.urdf", "PAL TIAGo: torso lift, one arm, head, gripper"),
    "tiago_dual": ("tiago_description/robots/tiago_dual.urdf", "PAL TIAGo++: torso lift, two arms, head"),
    "tiago_no_hand": ("tiago_description/robots/tiago_no_hand.urdf", "PAL TIAGo without its gripper"),
    "tiago_pro": ("tiago_pro_description/robots/tiago_pro.urdf", "PAL TIAGo Pro"),
    "human": ("human_description/robots/human.urdf", "a human body model"),
    # hands, small arms and mechanisms
    "allegro_right": ("allegro_hand_description/urdf/allegro_right_hand.urdf", "Wonik Allegro right hand, four fingers "
                      "of 4 joints"),
    "allegro_left": ("allegro_hand_description/urdf/allegro_left_hand.urdf", "Wonik Allegro left hand"),
    "finger_edu": ("finger_edu_description/robots/finger_edu.urdf", "ODRI Finger Edu, one 3-joint finger",
                   "finger_edu_description/srdf/finger_edu.srdf"),
    "double_pendulum": ("double_pendulum_description/urdf/double_pendulum.urdf", "a double pendulum"),
    "asr_twodof": ("asr_twodof_description/urdf/TwoDofs.urdf", "a two-joint arm"),
    # flying robots
    "hector": ("hector_description/robots/quadrotor_base.urdf", "Hector quadrotor (no joints: a floating base only)"),
    "iris": ("iris_description/robots/iris_simple.urdf", "3DR Iris quadrotor (no joints: a floating base only)"),
    "borinot": ("borinot_description/urdf/borinot_flying_arm_2.urdf", "Borinot drone with a 2-joint arm",
                "borinot_description/srdf/borinot_flying_arm_2.srdf"),
    "hextilt": ("hextilt_description/urdf/hextilt_flying_arm_5.urdf", "hexacopter with a 5-joint arm",
                "hextilt_description/srdf/hextilt_flying_arm_5.srdf"),
}.items()}
