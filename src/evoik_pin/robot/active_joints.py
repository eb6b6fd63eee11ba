"""Which joints of a URDF a :class:`~evoik_pin.robot.Robot` moves (:func:`choose_joints`)."""

from __future__ import annotations

from dataclasses import dataclass

import pinocchio as pin

from ..errors import FrameError, RobotLoadError
from .frames import closest_hint, deepest_body, find_frame, frame_names, listed, root_link

__all__ = ["MAX_CHAIN_JOINTS", "ActiveJoints", "choose_joints"]

#: Most physical joints a Robot accepts: Pinocchio's ``Data`` of an n-joint chain takes O(n^3) memory.
MAX_CHAIN_JOINTS = 200


@dataclass(frozen=True)
class ActiveJoints:
    """What :func:`choose_joints` chose (joint ids of the kinematic model): frame names ``tip``, ``tips``, ``base``;
    ``above_base`` (the joints holding the base), ``dofs`` (the joints of q), ``physical`` (every joint q moves) and
    ``follow``, for each physical joint, (the joint of q it follows, multiplier, offset)."""

    tip: str
    tips: tuple[str, ...]
    base: str
    above_base: set[int]
    dofs: list[int]
    physical: list[int]
    follow: list[tuple[int, float, float]]


def choose_joints(kin: pin.Model, full_model: pin.Model, name: str, tip: str | None, tips, base: str | None,
                  joints: list[str] | None, coupling: dict[int, tuple[int, float, float]]) -> ActiveJoints:
    """The active joints of ``kin`` (``full_model``, behind a floating base's six joints if any) for
    :func:`~evoik_pin.robot.load_robot`'s ``tip``, ``tips``, ``base``, ``joints``; ``coupling``: its mimics. FrameError
    for unknown or unconnected frames and joints; RobotLoadError for joints that are not 1-DOF, none to move, or more
    than :data:`MAX_CHAIN_JOINTS`."""
    whole = isinstance(tips, str) and tips == "all"
    if tips is None or whole:
        tip_names = None if whole else [tip if tip is not None else deepest_body(full_model)]
    else:
        tip_names = list(tips) if hasattr(tips, "__iter__") and not isinstance(tips, str) else []
        if not tip_names or not all(isinstance(t, str) for t in tip_names):
            raise FrameError(f"tips must be a list of frame names (a non-empty list of strings) or 'all', got {tips!r}")
    if tip is None:
        tip = tip_names[0] if tip_names else deepest_body(full_model)
    root_name = root_link(full_model) if base is None else base
    named = ([("base", base)] if base is not None else []) + [("tip", t) for t in [tip, *(tip_names or [])]]
    for what, frame in named:
        if find_frame(kin, frame) < 0:
            raise FrameError(f"unknown {what} frame {frame!r}{closest_hint(frame, frame_names(kin))}; frames of "
                             f"{name}: {listed(frame_names(full_model, bodies=True))}")
    base_joint = kin.frames[0 if base is None else find_frame(kin, base)].parentJoint

    if whole:
        active = [j for j in range(1, kin.njoints) if j != base_joint and base_joint in kin.supports[j]]
    else:
        chosen: set[int] = set()
        for t in tip_names:
            support = list(kin.supports[kin.frames[find_frame(kin, t)].parentJoint])
            if base_joint not in support:
                raise FrameError(f"tip frame {t!r} is not downstream of base frame {root_name!r}: no kinematic "
                                 "chain joins them from base to tip")
            chosen.update(support[support.index(base_joint) + 1:])
        active = sorted(chosen)
    where = (f"the chain {root_name!r} -> {tip_names[0]!r}" if tip_names and len(tip_names) == 1
             else f"the joints below {root_name!r}" if whole else f"the chains {root_name!r} -> {tip_names}")
    bad = [kin.names[j] for j in active if kin.joints[j].nv != 1]
    if bad:
        raise RobotLoadError(f"joints {bad} of {where} are not 1-DOF revolute or prismatic joints; only those are "
                             "supported (lock them with joints=[...])")
    above_base = set(kin.supports[base_joint])

    def follows(j: int) -> tuple[int | None, float, float]:
        """(joint whose q moves physical joint j, multiplier, offset); None when j is constant."""
        c = coupling.get(j)
        if c is None:
            return j, 1.0, 0.0
        driver, m, off = c
        return (None if driver in above_base or m == 0.0 else driver), m, off

    dofs = [d for d in dict.fromkeys(follows(j)[0] for j in active) if d is not None]
    dof_names = [kin.names[d] for d in dofs]
    if joints is not None:
        unknown = [j for j in joints if j not in dof_names]
        if unknown:
            coupled = [f"{u!r} mimics {kin.names[coupling[kin.getJointId(u)][0]]!r}"
                       for u in unknown if kin.existJointName(u) and kin.getJointId(u) in coupling]
            hint = f" ({'; '.join(coupled)}: name the joint it follows)" if coupled else ""
            raise FrameError(f"joints {unknown} are not on {where}; its joints are "
                             f"{', '.join(dof_names) or '(none)'}{hint}")
        dofs = [d for d in dofs if kin.names[d] in joints]
    # every joint q moves below the base, mimics included: each link where full_configuration(q) puts it
    physical = [j for j in range(1, kin.njoints) if j not in above_base and follows(j)[0] in dofs]
    if not physical:
        raise RobotLoadError(f"{where} of {name} has no movable joint; pick another tip or base")
    if len(physical) > MAX_CHAIN_JOINTS:
        raise RobotLoadError(f"{where} of {name} has {len(physical)} joints; at most {MAX_CHAIN_JOINTS} are "
                             "supported (Pinocchio's data for an n-joint chain takes O(n^3) memory): pick nearer "
                             "tips, a farther base, or keep fewer joints free with joints=[...]")
    return ActiveJoints(tip, tuple(tip_names) if tip_names else (tip,), root_name, above_base, dofs, physical,
                        [follows(j) for j in physical])

