"""Frame look-up in a Pinocchio model: names to ids, the URDF's root link, its deepest link; and locking joints.

URDF links become BODY frames; a joint and a link may share a name, and then the BODY frame is the one
meant (a tip or a base is a link). The look-up helpers only read the model's frame list (no ``Data``, no
kinematics); :class:`~evoik_pin.robot.kinematics.Robot` and the viewer use them. :func:`reduced_model` is
``pin.buildReducedModel`` made safe for such shared names.
"""

from __future__ import annotations

import pinocchio as pin

__all__ = ["body_frame_names", "deepest_body", "find_frame", "reduced_model", "root_link"]


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


def reduced_model(model: pin.Model, locked: list[int], q_ref, geometry_models: tuple = ()):
    """``pin.buildReducedModel(model, [geometry_models,] locked, q_ref)`` for models whose frames share names.

    Pinocchio's reduction looks frames up by name alone, and fails with "Several frames match the filter" when
    a joint and a link share one (anymal_c's ``LF_HAA`` joint and link, b1-z1's fixed joint and link
    ``gripperStator``), whichever frame the user asked for. So the reduction runs on a copy in which every
    non-BODY frame (and its joint) with a repeated name is renamed uniquely, and the names are put back in the
    result. Returns the reduced model, or (model, list of geometry models) when ``geometry_models`` are given.
    """
    counts: dict[str, int] = {}
    for f in model.frames:
        counts[f.name] = counts.get(f.name, 0) + 1
    renamed: dict[str, str] = {}
    work = model
    if any(c > 1 for c in counts.values()):
        work = pin.Model(model)
        taken = set(counts)
        for i, f in enumerate(model.frames):
            if counts[f.name] > 1 and f.type != pin.FrameType.BODY:
                k = 0
                while (alias := f"{f.name}#{f.type.name.lower()}{k}") in taken:
                    k += 1
                taken.add(alias)
                renamed[alias] = f.name
                work.frames[i].name = alias
                if f.type == pin.FrameType.JOINT:
                    work.names[f.parentJoint] = alias
    if geometry_models:
        out, geoms = pin.buildReducedModel(work, list(geometry_models), locked, q_ref)
    else:
        out, geoms = pin.buildReducedModel(work, locked, q_ref), []
    if renamed:
        for j in range(out.njoints):
            out.names[j] = renamed.get(out.names[j], out.names[j])
        for i in range(len(out.frames)):
            out.frames[i].name = renamed.get(out.frames[i].name, out.frames[i].name)
    return (out, list(geoms)) if geometry_models else out
