"""Frame look-up in a Pinocchio model: names to ids, the URDF's root link, its deepest link, whether its movable
joints branch (a tree, not a serial chain); and locking joints.

URDF links become BODY frames; a joint and a link may share a name, and then the BODY frame is the one
meant (a tip or a base is a link). The look-up helpers only read the model's frame list (no ``Data``, no
kinematics). :func:`reduced_model` is ``pin.buildReducedModel`` made safe for such shared names.
"""

from __future__ import annotations

import pinocchio as pin

__all__ = ["body_frame_names", "closest_names", "deepest_body", "find_frame", "frame_names", "is_branched",
           "reduced_model", "restore_frame_names", "root_link", "unique_frame_names"]


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


def is_branched(model: pin.Model, coupling: dict[int, tuple[int, float, float]]) -> bool:
    """True when the movable joints of ``model`` form a real tree: two of its links are each moved by a joint
    that does not move the other (legs and arms, or fingers moving on their own), so that no single chain holds
    every joint. False for a serial chain, also one ending in a gripper whose fingers follow one joint.

    ``coupling``: ``{mimic joint id: (followed joint id, multiplier, offset)}``
    (:func:`~evoik_pin.robot.joints.couplings`); a mimic joint counts as the joint it follows, so a second
    finger that mimics the first is no branch of its own.
    """
    def moved_by(j: int) -> frozenset[int]:  # the independent joints that move joint j's link
        return frozenset(coupling.get(k, (k,))[0] for k in list(model.supports[j])[1:])

    # a chain iff these sets are nested; sorted by size, each must then hold the one before it
    nested = sorted({moved_by(j) for j in range(model.njoints)}, key=len)
    return any(not smaller <= larger for smaller, larger in zip(nested, nested[1:], strict=False))


def reduced_model(model: pin.Model, locked: list[int], q_ref, geometry_models: tuple = ()):
    """``pin.buildReducedModel(model, [geometry_models,] locked, q_ref)`` for models whose frames share names.

    Pinocchio's reduction looks frames up by name alone, and fails with "Several frames match the filter" when
    a joint and a link share one (anymal_c's ``LF_HAA`` joint and link, b1-z1's fixed joint and link
    ``gripperStator``), whichever frame the user asked for. So the reduction runs on a copy in which every
    non-BODY frame (and its joint) with a repeated name is renamed uniquely (:func:`unique_frame_names`), and the
    names are put back in the result. Returns the reduced model, or (model, list of geometry models) when
    ``geometry_models`` are given.
    """
    work, renamed = unique_frame_names(model)
    if geometry_models:
        out, geoms = pin.buildReducedModel(work, list(geometry_models), locked, q_ref)
    else:
        out, geoms = pin.buildReducedModel(work, locked, q_ref), []
    restore_frame_names(out, renamed)
    return (out, list(geoms)) if geometry_models else out


def unique_frame_names(model: pin.Model) -> tuple[pin.Model, dict[str, str]]:
    """(model, {}) when no two frames share a name; else (a copy in which every non-BODY frame with a repeated name,
    and its joint for a JOINT frame, has a unique alias, {alias: name}): what Pinocchio's algorithms that look
    frames up by name alone (``buildReducedModel``, ``appendModel``) need. :func:`restore_frame_names` undoes it."""
    counts: dict[str, int] = {}
    for f in model.frames:
        counts[f.name] = counts.get(f.name, 0) + 1
    renamed: dict[str, str] = {}
    if not any(c > 1 for c in counts.values()):
        return model, renamed
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
    return work, renamed


def restore_frame_names(model: pin.Model, renamed: dict[str, str]) -> None:
    """Put back in ``model`` (in place) the names :func:`unique_frame_names` replaced by aliases."""
    if not renamed:
        return
    for j in range(model.njoints):
        model.names[j] = renamed.get(model.names[j], model.names[j])
    for i in range(len(model.frames)):
        model.frames[i].name = renamed.get(model.frames[i].name, model.frames[i].name)

def frame_names(model: pin.Model) -> list[str]:
    """Names of every frame of ``model`` but the universe (links, joint frames, fixed and operational frames), in
    model order, each once."""
    seen: dict[str, None] = {}
    for f in list(model.frames)[1:]:
        seen.setdefault(f.name, None)
    return list(seen)


def closest_names(name: str, names: list[str], count: int = 5) -> list[str]:
    """Up to ``count`` of ``names`` closest to ``name`` (difflib's ratio; a name containing ``name`` or contained in
    it counts as close too), closest first."""
    import difflib

    close = difflib.get_close_matches(name, names, n=count, cutoff=0.6)
    low = name.lower()
    close += [x for x in names if x not in close and low and (low in x.lower() or x.lower() in low)]
    return close[:count]
