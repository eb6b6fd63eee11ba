"""Frame look-up in a Pinocchio model: names to ids, the URDF's root link, its deepest link.

URDF links become BODY frames; a joint and a link may share a name, and then the BODY frame is the one
meant (a tip or a base is a link). These helpers only read the model's frame list (no ``Data``, no
kinematics); :class:`~evoik_pin.robot.kinematics.Robot` and the viewer use them.
"""

from __future__ import annotations

import pinocchio as pin

__all__ = ["body_frame_names", "deepest_body", "find_frame", "root_link"]


def find_frame(model: pin.Model, name: str) -> int:
    """Frame id of ``name`` in ``model``, preferring the BODY frame when a joint and a link share the name;
    -1 when no frame has that name."""
    ids = [i for i, f in enumerate(model.frames) if f.name == name]
    if not ids:
        return -1
    bodies = [i for i in ids if model.frames[i].type == pin.FrameType.BODY]
    return (bodies or ids)[0]


def body_frame_names(model: pin.Model) -> list[str]:
    """Names of the BODY frames (the URDF's links) in model order, each once."""
    seen: dict[str, None] = {}
    for f in model.frames:
        if f.type == pin.FrameType.BODY:
            seen.setdefault(f.name, None)
    return list(seen)


def root_link(model: pin.Model) -> str:
    """Name of the URDF's root link (the first body frame fixed to the universe)."""
    for f in model.frames:
        if f.type == pin.FrameType.BODY and f.parentJoint == 0:
            return f.name
    return model.frames[0].name


def deepest_body(model: pin.Model) -> str:
    """Name of the body frame with the most joints above it (the last such one: a tool link fixed after the
    last joint's link wins over that link)."""
    best, depth = model.frames[0].name, -1
    for f in model.frames:
        if f.type == pin.FrameType.BODY:
            d = len(model.supports[f.parentJoint])
            if d >= depth:  # last deepest wins: a tool link fixed after the last joint's link
                best, depth = f.name, d
    return best
