"""Goals files: goal lists (:mod:`evoik_pin.goals`) as YAML or JSON by the extension (:func:`load_goals`,
:func:`save_goals`, :func:`load_problems`); the guide and an example are in docs/GOALS.md ("Goals files"). Beyond::

    goals:                        # or problems: [[goal, ...], ...] (load_problems; load_goals refuses them)
      - frame: arm_right_7_link   # a kind of GOAL_KINDS with the optional fields of its class (weight, free, ...)
        kind: position
        targets: [{position: [0.26, -0.41, 0.94]}, {position: [0.3, -0.4, 0.9]}]   # a goal set: any one will do
      - {kind: posture, joints: {arm_left_4_joint: -0.5}}                          # a preference of PREFERENCE_KINDS

Positions in m in the robot's base frame; numbers written ``1e-6`` are numbers; unknown keys are errors. Every
error is a :class:`~evoik_pin.errors.GoalsFileError` naming the file, the goal (index from 0, and frame) and the
field. :func:`save_goals` writes pose targets as exact matrices (read back bit for bit) and optional fields only
where they differ from their defaults.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from ..errors import FrameError, GoalsFileError, OptionError, TargetError
from ..goals import Goal, bind, is_goal_list
from ..goals.file_entries import FIELD_READERS, FileKind, field_entries, name_entry, number, unknown_keys
from ..goals.preferences import JointLimitMargin, Manipulability, MinimalDisplacement, Posture, Preference
from ..goals.registry import kind_classes
from .datafile import data_format, naming, read_mapping, write_data

__all__ = ["GOAL_KINDS", "GoalsFile", "goal_kind_name", "load_goals", "load_problems", "read_goals_file", "save_goals"]

_TOP_KEYS = ("robot", "floating_base", "tips", "goals", "problems")


@dataclass(frozen=True)
class GoalsFile:
    """A goals file, checked: ``robot``, ``floating_base``, ``tips`` as given (or None), ``problems`` its goal lists
    (one for a ``goals:`` file), ``several`` whether it has ``problems:``."""

    path: Path
    robot: str | None
    floating_base: bool | None
    tips: list[str] | None
    problems: list[list[Goal]]
    several: bool

    def bind(self, robot) -> None:
        """Check every goal list against ``robot`` (:func:`evoik_pin.goals.bind`); GoalsFileError naming the goal."""
        for p, goals in enumerate(self.problems):
            goals = [g for g in goals if isinstance(g, Goal)]  # preferences are checked when solving
            try:
                bind(robot, goals)
            except (FrameError, TargetError) as exc:
                where = f"goals file {str(self.path)!r}" + (f": problem {p}" if self.several else "")
                for i, g in enumerate(goals):  # the goal that fails alone, when one does
                    try:
                        bind(robot, [g])
                    except (FrameError, TargetError):
                        where += f"{',' if self.several else ':'} goal {i}" + (f" ({g.frame})" if g.frame else "")
                        break
                raise GoalsFileError(f"{where}: {exc}") from None


# ------------------------------------------------------------------ reading
#: The goal kinds a goals file takes, by ``kind:`` name.
GOAL_KINDS = {fk.name: fk for fk in (cls.file_kind() for cls in kind_classes()) if fk is not None}

#: Preferences a goal list may hold, by their ``kind:`` name: (class, fields).
PREFERENCE_KINDS = {
    "posture": (Posture, ("q_ref", "joints", "weight")),
    "joint_limit_margin": (JointLimitMargin, ("margin", "weight")),
    "manipulability": (Manipulability, ("frame", "weight")),
    "minimal_displacement": (MinimalDisplacement, ("weight",)),
}


def _goal(entry, what: str) -> Goal:
    if not isinstance(entry, dict):
        raise GoalsFileError(f"{what}: expected a mapping with frame, kind and target, got {entry!r}")
    frame = entry.get("frame")
    if frame is not None:
        what += f" ({frame})"
    kind_name = entry.get("kind")
    if kind_name in PREFERENCE_KINDS:
        return _preference(entry, what, kind_name)
    if kind_name not in GOAL_KINDS:
        raise GoalsFileError(f"{what}: kind: " + ("missing" if kind_name is None else f"unknown kind {kind_name!r}")
                             + f"; accepted kinds: {', '.join([*GOAL_KINDS, *PREFERENCE_KINDS])}")
    kind = GOAL_KINDS[kind_name]
    if kind.read is not None:  # kinds whose entries are not (frame, target, numbers)
        return kind.read(entry, what)
    frames = ("frame_a", "frame") if kind.pair else ("frame",)
    unknown_keys(entry, (*frames, "kind", "target", *kind.fields, *(() if kind.pair else ("targets",))),
                 f"{what}, a {kind_name} goal")
    several = "targets" in entry  # a goal set: any one of several targets
    if several and "target" in entry:
        raise GoalsFileError(f"{what}: give target (one) or targets (a goal set: any one will do), not both")
    for key in (*frames, "targets" if several else "target"):
        if key not in entry:
            raise GoalsFileError(f"{what}: missing field {key!r} (every goal has {', '.join(frames)}, kind and "
                                 "target, or targets for a goal set)")
    for key in frames:
        if not isinstance(entry[key], str) or not entry[key]:
            raise GoalsFileError(f"{what}: {key} must be a frame name (a non-empty string), got {entry[key]!r}")
    raw = entry["targets"] if several else [entry["target"]]
    if several and (not isinstance(raw, list) or not raw):
        raise GoalsFileError(f"{what}: targets must be a non-empty list of targets (a goal set), got {raw!r}")
    read = []
    for k, t in enumerate(raw):
        label = f"targets[{k}]" if several else "target"
        if not isinstance(t, dict):
            raise GoalsFileError(f"{what}: {label} must be a mapping (position, rpy / rpy_rad, matrix), got {t!r}")
        try:
            read.append(kind.read_target(t))
        except (GoalsFileError, TargetError) as exc:
            text = str(exc)
            raise GoalsFileError(f"{what}: {text if text.startswith(label) else label + ': ' + text}") from None
    options = {key: FIELD_READERS.get(key, number)(entry[key], f"{what}: {key}") for key in kind.fields
               if key in entry}
    if several and kind.set_member is not None:
        read = [kind.set_member(t) for t in read]
    with naming(what, GoalsFileError, catch=(OptionError, TargetError, FrameError)):
        return (kind.cls if several else kind.make or kind.cls)(*(entry[key] for key in frames),
                                                                read if several else read[0], **options)


def _joint_list(value, what: str) -> list[float]:
    if not isinstance(value, list):
        raise GoalsFileError(f"{what} must be a list of joint values (rad or m), got {value!r}")
    return [number(v, f"{what}[{k}]") for k, v in enumerate(value)]


def _joint_map(value, what: str) -> dict[str, float]:
    if not isinstance(value, dict) or not value:
        raise GoalsFileError(f"{what} must be a mapping {{joint name: value (rad or m)}}, got {value!r}")
    return {str(k): number(v, f"{what}.{k}") for k, v in value.items()}


#: How a preference's fields other than numbers are read.
_PREFERENCE_READERS = {"q_ref": _joint_list, "joints": _joint_map, "frame": name_entry}


def _preference(entry: dict, what: str, kind_name: str):
    """A preference entry (``kind: posture | joint_limit_margin | manipulability | minimal_displacement``)."""
    cls, fields = PREFERENCE_KINDS[kind_name]
    unknown_keys(entry, ("kind", *fields), f"{what}, a {kind_name} preference")
    args = {key: _PREFERENCE_READERS.get(key, number)(entry[key], f"{what}: {key}") for key in fields if key in entry}
    if kind_name == "posture":
        if ("q_ref" in args) == ("joints" in args):
            raise GoalsFileError(f"{what}: a posture needs one of q_ref (a joint vector) and joints ({{name: value}})")
        args["q_ref"] = args.pop("q_ref") if "q_ref" in args else args.pop("joints")
    if kind_name == "joint_limit_margin" and "margin" not in args:
        raise GoalsFileError(f"{what}: a joint_limit_margin needs margin (rad or m)")
    with naming(what, GoalsFileError, catch=(OptionError, TargetError, ValueError)):
        return cls(**args)


def _goal_list(entries, what: str, several: bool) -> list[Goal]:
    key = "each problem" if several else "goals"
    if not isinstance(entries, list):
        raise GoalsFileError(f"{what}: {key} must be a list of goals (frame, kind, target), got {entries!r}")
    if not entries:
        raise GoalsFileError(f"{what}: {key} is empty; give at least one goal (frame, kind, target)")
    return [_goal(entry, f"{what}, goal {i}" if several else f"goal {i}") for i, entry in enumerate(entries)]


def read_goals_file(path: str | os.PathLike) -> GoalsFile:
    """Everything a goals file holds, checked (frames only by :meth:`GoalsFile.bind`); GoalsFileError."""
    path = Path(os.fspath(path)).expanduser()
    where = f"goals file {str(path)!r}"
    data = read_mapping(path, where, GoalsFileError, _TOP_KEYS, "a goals: list (or problems:)", list_key="goals")
    with naming(where, GoalsFileError):
        robot = data.get("robot")
        if robot is not None and (not isinstance(robot, str) or not robot):
            raise GoalsFileError(f"robot must be a robot name or URDF path, got {robot!r}")
        floating_base = data.get("floating_base")
        if floating_base is not None and not isinstance(floating_base, bool):
            raise GoalsFileError(f"floating_base must be true or false, got {floating_base!r}")
        tips = data.get("tips")
        if tips is not None and (not isinstance(tips, list) or not tips
                                 or not all(isinstance(t, str) and t for t in tips)):
            raise GoalsFileError(f"tips must be a list of frame names, got {tips!r}")
        if ("goals" in data) == ("problems" in data):
            raise GoalsFileError("give one of goals: (a goal list) and problems: (a list of goal lists), got "
                                 + ("both" if "goals" in data else "neither"))
        several = "problems" in data
        if several:
            problems = data["problems"]
            if not isinstance(problems, list) or not problems:
                raise GoalsFileError(f"problems must be a non-empty list of goal lists, got {problems!r}")
            problems = [_goal_list(goals, f"problem {p}", True) for p, goals in enumerate(problems)]
        else:
            problems = [_goal_list(data["goals"], "goals", False)]
    return GoalsFile(path, robot, floating_base, tips, problems, several)


def load_goals(path: str | os.PathLike) -> list[Goal]:
    """The goal list of the goals file ``path``, for ``evoik_pin.solve(robot, goals)``; GoalsFileError, also for a
    file of several problems (:func:`load_problems` reads those)."""
    spec = read_goals_file(path)
    if spec.several:
        raise GoalsFileError(f"goals file {str(spec.path)!r} holds {len(spec.problems)} problems (problems:): read "
                             "them with load_problems (for solve_many / solve_trajectory)")
    return spec.problems[0]


def load_problems(path: str | os.PathLike) -> list[list[Goal]]:
    """The goal lists of the goals file ``path`` (``goals:`` as one), for ``solve_many`` or ``solve_trajectory``."""
    return read_goals_file(path).problems


# ------------------------------------------------------------------ writing
def _kind_of(goal) -> tuple[str, FileKind]:
    kind = next((k for k in GOAL_KINDS.values() if type(goal) is k.cls), None)
    if kind is not None:
        return kind.name, kind
    raise GoalsFileError(f"cannot write a {type(goal).__name__} to a goals file; goals files take "
                         f"{', '.join(k.cls.__name__ for k in GOAL_KINDS.values())}")


def _preference_entry(pref: Preference) -> dict:
    """A preference as a goals file writes it."""
    name = next(k for k, (cls, _) in PREFERENCE_KINDS.items() if type(pref) is cls)
    entry: dict = {"kind": name}
    if name == "posture":
        if isinstance(pref.q_ref, dict):
            entry["joints"] = {k: float(v) for k, v in pref.q_ref.items()}
        else:
            entry["q_ref"] = [float(v) for v in pref.q_ref]
    elif name == "joint_limit_margin":
        entry["margin"] = float(pref.margin)
    elif name == "manipulability" and pref.frame is not None:
        entry["frame"] = pref.frame
    if pref.weight != 1.0:
        entry["weight"] = float(pref.weight)
    return entry


def _entry(goal: Goal) -> dict:
    if isinstance(goal, Preference):
        return _preference_entry(goal)
    name, kind = _kind_of(goal)
    if kind.write is not None:
        return kind.write(goal)
    entry = ({"frame_a": goal.frame_a} if kind.pair else {}) | {"frame": goal.frame, "kind": name,
                                                                 "target": kind.write_target(goal)}
    if goal.alternatives is not None:  # a goal set
        del entry["target"]
        entry["targets"] = [kind.write_target(m) for m in goal.alternatives]
    return entry | field_entries(goal, kind.fields)


def save_goals(goals, path: str | os.PathLike, robot=None, floating_base: bool | None = None,
               tips: list[str] | None = None) -> Path:
    """Write ``goals`` (a goal list, or a list of goal lists: ``problems:``) to the goals file ``path`` and return
    the path; :func:`load_goals` reads it back bit for bit. ``robot``: a name or a Robot (its name, and its
    ``floating_base`` unless given); ``floating_base``, ``tips``: written as given."""
    path = Path(os.fspath(path)).expanduser()
    data_format(path, f"goals file {str(path)!r}", GoalsFileError)  # before any other check
    goals = list(goals) if isinstance(goals, (list, tuple)) else goals
    several = isinstance(goals, list) and bool(goals) and all(isinstance(g, (list, tuple)) for g in goals)
    problems = [list(g) for g in goals] if several else [goals]
    for p, problem in enumerate(problems):
        if not isinstance(problem, (list, tuple)) or not problem or not is_goal_list(
                [g for g in problem if not isinstance(g, Preference)]):
            what = f"problem {p}" if several else "goals"
            raise GoalsFileError(f"save_goals: {what} must be a non-empty list of goals (Pose, Position) or a list "
                                 f"of such lists, got {problem!r}")
    data: dict = {}
    if robot is not None:
        data["robot"] = robot if isinstance(robot, str) else robot.name
        if floating_base is None and not isinstance(robot, str):
            floating_base = bool(robot.floating_base)
    if floating_base is not None:
        data["floating_base"] = bool(floating_base)
    if tips is not None:
        data["tips"] = [str(t) for t in tips]
    lists = [[_entry(g) for g in problem] for problem in problems]
    data["problems" if several else "goals"] = lists if several else lists[0]
    header = "# evoik_pin goals (m and rad, in the robot's base frame; format: evoik_pin/io/goals_file.py)\n"
    return write_data(path, data, header, "goals file", GoalsFileError)


def goal_kind_name(goal: Goal) -> str:
    """The ``kind:`` a goals file writes for ``goal`` (``"pose"``, ``"position"``, ...)."""
    return _kind_of(goal)[0]
