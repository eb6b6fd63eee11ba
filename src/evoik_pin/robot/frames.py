"""Frame look-up in a Pinocchio model and :func:`reduced_model`. When a joint and a link share a name, the BODY frame
(the link) is the one meant."""

from __future__ import annotations

import difflib
from collections import Counter

import pinocchio as pin

__all__ = ["closest_hint", "closest_names", "deepest_body", "find_frame", "frame_names", "is_branched", "listed",
           "reduced_model", "restore_frame_names", "root_link", "unique_frame_names"]


def find_frame(model: pin.Model, name: str) -> int:
    """Frame id of ``name`` in ``model`` (the BODY frame first), or -1."""
    ids = [i for i, f in enumerate(model.frames) if f.name == name]
    if not ids:
        return -1
    bodies = [i for i in ids if model.frames[i].type == pin.FrameType.BODY]
    return (bodies or ids)[0]


def root_link(model: pin.Model) -> str:
    """Name of the URDF's root link (the first body frame fixed to the universe)."""
    for f in model.frames:
        if f.type == pin.FrameType.BODY and f.parentJoint == 0:
            return f.name
    return model.frames[0].name


def deepest_body(model: pin.Model) -> str:
    """Name of the body frame with the most joints above it (the last such one)."""
    best, depth = model.frames[0].name, -1
    for f in model.frames:
        if f.type == pin.FrameType.BODY:
            d = len(model.supports[f.parentJoint])
            if d >= depth:  # last deepest wins: a tool link fixed after the last joint's link
                best, depth = f.name, d
    return best


def is_branched(model: pin.Model, coupling: dict[int, tuple[int, float, float]]) -> bool:
    """True when no single chain holds every movable joint of ``model``, a mimic joint counting as the joint it
    follows (``coupling``: :func:`~evoik_pin.robot.joints.couplings`)."""
    def moved_by(j: int) -> frozenset[int]:  # the independent joints that move joint j's link
        return frozenset(coupling.get(k, (k,))[0] for k in list(model.supports[j])[1:])

    # a chain iff these sets are nested; sorted by size, each must then hold the one before it
    nested = sorted({moved_by(j) for j in range(model.njoints)}, key=len)
    return any(not smaller <= larger for smaller, larger in zip(nested, nested[1:], strict=False))


def reduced_model(model: pin.Model, locked: list[int], q_ref, geometry_models: tuple = ()):
    """``pin.buildReducedModel(model, [geometry_models,] locked, q_ref)`` safe for frames sharing a name (Pinocchio
    fails with "Several frames match the filter", e.g. anymal_c's ``LF_HAA``). Returns the model, or (model, list of
    geometry models) when given some."""
    work, renamed = unique_frame_names(model)
    if geometry_models:
        out, geoms = pin.buildReducedModel(work, list(geometry_models), locked, q_ref)
    else:
        out, geoms = pin.buildReducedModel(work, locked, q_ref), []
    restore_frame_names(out, renamed)
    return (out, list(geoms)) if geometry_models else out


def unique_frame_names(model: pin.Model) -> tuple[pin.Model, dict[str, str]]:
    """(model, {}) when no two frames share a name; else (a copy in which every non-BODY frame with a repeated name,
    and a JOINT frame's joint, has a unique alias, {alias: name}). :func:`restore_frame_names` undoes it."""
    counts = Counter(f.name for f in model.frames)
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


def frame_names(model: pin.Model, bodies: bool = False) -> list[str]:
    """Names of every frame (with ``bodies``: BODY frame) of ``model`` but the universe, in model order, each once."""
    return list(dict.fromkeys(f.name for f in list(model.frames)[1:] if not bodies or f.type == pin.FrameType.BODY))


def closest_names(name: str, names: list[str], count: int = 5) -> list[str]:
    """Up to ``count`` of ``names`` closest to ``name`` (difflib, then containing or contained names)."""
    close = difflib.get_close_matches(name, names, n=count, cutoff=0.6)
    low = name.lower()
    close += [x for x in names if x not in close and low and (low in x.lower() or x.lower() in low)]
    return close[:count]


def closest_hint(name, names: list[str]) -> str:
    """' (closest: a, b)' for a ``name`` not among ``names`` (:func:`closest_names`), or '' when none is close."""
    close = closest_names(str(name), names)
    return f" (closest: {', '.join(close)})" if close else ""


def listed(names: list[str], most: int = 40) -> str:
    """The first ``most`` names, comma-separated, and how many more there are."""
    more = f", ... ({len(names) - most} more)" if len(names) > most else ""
    return ", ".join(names[:most]) + more
