"""Goals files: goal lists (:mod:`evoik_pin.goals`) as YAML or JSON (:func:`load_goals`, :func:`save_goals`).

The format is chosen by the extension (``.yaml`` / ``.yml``, read with PyYAML's safe loader, or ``.json``).
Positions in metres, in the robot's base frame (the URDF root; with a floating base, the world), as ``Pose`` and
``Position`` take them::

    robot: talos              # optional: what the file is for (see "The robot" below)
    floating_base: true       # optional
    tips: [left_sole_link, right_sole_link, arm_left_7_link, arm_right_7_link]   # optional
    goals:
      - frame: left_sole_link             # any frame of the robot (link, joint or fixed frame)
        kind: pose                        # pose | position
        target: {position: [0.0, 0.085, 0.0], rpy: [0, 0, 0]}      # rpy in degrees, R = Rz(y) Ry(p) Rx(r)
      - frame: arm_left_7_link
        kind: pose
        target: {position: [0.26, 0.41, 0.94], rpy_rad: [0.7, -1.1, -0.65]}   # or rpy_rad: radians
        weight: 0.5                       # optional, > 0 (default 1)
        tolerance: 1e-5                   # optional, m (default 1e-6)
        rotation_tolerance: 1e-4          # optional, rad (pose only; default: tolerance)
      - frame: arm_right_7_link
        kind: position
        target: {position: [0.26, -0.41, 0.94]}
      - frame: right_sole_link
        kind: pose
        target: {matrix: [[1, 0, 0, 0.0], [0, 1, 0, -0.085], [0, 0, 1, 0.0], [0, 0, 0, 1]]}   # or a 4 x 4 pose

More kinds (:mod:`evoik_pin.goals`)::

      - frame: tool0
        kind: pose
        target: {position: [0.4, 0.1, 0.3], rpy: [180, 0, 0]}
        free: rz                          # optional: axes left free, any of x y z rx ry rz (a string or a list)
      - frame: tool0
        kind: pose
        target: {position: [0.4, 0.1, 0.3], rpy: [180, 0, 0]}
        tolerance: [0.002, 0.002, 0.002, 0.087, 0.087, .inf]   # per-axis half-widths (m x3, rad x3; .inf: free)
      - frame: tool0
        kind: orientation                 # target: rpy / rpy_rad alone, or a 3 x 3 (or 4 x 4) matrix
        target: {rpy: [180, 0, 0]}
      - frame: tool0
        kind: direction                   # the frame's axis along a direction (base frame)
        axis: [0, 0, 1]
        target: {direction: [0, 0, -1]}
      - frame: gaze
        kind: look_at                     # the frame's axis pointing at a point (m, base frame)
        axis: [1, 0, 0]
        target: {point: [0.5, 0.0, 1.2]}

A position's ``tolerance`` may be 3 half-widths (base frame x y z), an orientation's 3 (rx ry rz) with ``free``
among rx ry rz; direction and look_at take ``weight`` and ``tolerance`` (rad). In JSON write ``"inf"`` for an
infinite half-width.

A pose's target is ``position`` with one of ``rpy`` (degrees, as ``evoik solve --rpy``) and ``rpy_rad``
(radians), or a ``matrix`` (4 x 4 homogeneous, m) alone; a position's target is ``position`` alone. The top level
may also be the bare list of goals. Numbers written ``1e-6`` (which YAML 1.1 reads as text) are read as numbers.
Unknown keys are errors (a misspelt ``tolerence`` is not silently ignored). Every error is a
:class:`~evoik_pin.errors.GoalsFileError` naming the file, the goal (index from 0, and frame) and the field.

Beyond one frame: the robot's centre of mass (no ``frame``) at a point, on chosen axes, or over a support polygon
(contact points in each support frame, m, or the frames alone: their collision geometry's), and one frame's pose
seen from another (``frame_a``; ``frame`` is frame b)::

      - kind: center_of_mass
        target: {position: [0.0, 0.0, 0.0]}
        axes: xy                          # optional: any of x, y, z (default xyz)
      - kind: center_of_mass
        support: [left_sole_link, right_sole_link]      # or {left_sole_link: [[0.1, 0.05, 0], ...], ...}
        margin: 0.02                      # optional, m (default 0)
      - frame_a: left_gripper
        frame: right_gripper
        kind: relative_pose
        target: {position: [0, 0, 0.3], rpy: [180, 0, 0]}
        free: rz                          # optional: tolerance, rotation_tolerance and free as a pose's (target frame)
A goal set (any one of several targets will do; ``Pose(frame, [T1, ...])``) has ``targets:``, a list of targets,
instead of ``target:``. Preferences (:mod:`evoik_pin.goals.preferences`) are entries of the goal list too, with no
frame and target: ``{kind: posture, q_ref: [...]}`` (rad or m) or ``{kind: posture, joints: {name: value}}``,
``{kind: joint_limit_margin, margin: 0.1}``, ``{kind: manipulability}`` (optional ``frame``),
``{kind: minimal_displacement}``, each with an optional ``weight``.

Several problems: ``problems:`` instead of ``goals:``, a list of goal lists (each a list of goals as above), for
:func:`evoik_pin.solve_many` or, in time order, :func:`evoik_pin.solve_trajectory`; read them with
:func:`load_problems` (which reads a ``goals:`` file as one problem). :func:`load_goals` reads one goal list and
refuses a ``problems:`` file, so a file of several problems is never silently cut to its first.

The robot: ``robot``, ``floating_base`` and ``tips`` say what the file was written for. :func:`load_goals` does not
load robots; ``evoik solve ROBOT --goals FILE`` uses them to fill in the flags not given (``--floating-base``,
``--tips``), and a value given both ways that differs (another ROBOT, ``--tips`` other frames) is an error naming
the flag and the file: a goals file is not silently used on a robot it was not written for.

:func:`save_goals` writes the same format: a pose's target as its exact ``matrix`` (floats written in full, so
reading the file back gives the same targets bit for bit), a position's as ``position``; ``weight``,
``tolerance`` and ``rotation_tolerance`` only where they differ from their defaults.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from ..errors import FrameError, GoalsFileError, OptionError, TargetError
from ..goals import Goal, bind, is_goal_list
from ..goals.file_entries import FIELD_READERS, FileKind, field_entries, number, unknown_keys
from ..goals.preferences import JointLimitMargin, Manipulability, MinimalDisplacement, Posture, Preference
from ..goals.registry import kind_classes
from .datafile import data_format, dump_data, read_data, write_text

__all__ = ["GOAL_KINDS", "GoalsFile", "goal_kind_name", "load_goals", "load_problems", "read_goals_file", "save_goals"]

_TOP_KEYS = ("robot", "floating_base", "tips", "goals", "problems")


@dataclass(frozen=True)
class GoalsFile:
    """What a goals file holds, checked: ``path``; ``robot`` (a name or None), ``floating_base`` (bool or None)
    and ``tips`` (frame names or None) as the file gives them; ``problems``, its goal lists (one for a ``goals:``
    file); ``several``: whether the file has ``problems:``."""

    path: Path
    robot: str | None
    floating_base: bool | None
    tips: list[str] | None
    problems: list[list[Goal]]
    several: bool

    def bind(self, robot) -> None:
        """Check every goal list against ``robot`` (:func:`evoik_pin.goals.bind`: frames that exist and that an
        active joint moves, no frame with two targets); GoalsFileError naming this file and the goal."""
        for p, goals in enumerate(self.problems):
            goals = [g for g in goals if isinstance(g, Goal)]  # preferences are checked when solving
            try:
                bind(robot, goals)
            except (FrameError, TargetError) as exc:
                where = self._where(p)
                for i, g in enumerate(goals):  # the goal that fails alone, when one does (a clash needs two)
                    try:
                        bind(robot, [g])
                    except (FrameError, TargetError):
                        where = self._where(p, i, g.frame)
                        break
                raise GoalsFileError(f"{where}: {exc}") from None

    def _where(self, problem: int | None = None, index: int | None = None, frame: str | None = None) -> str:
        text = f"goals file {str(self.path)!r}"
        if self.several and problem is not None:
            text += f": problem {problem}"
        if index is not None:
            text += f"{',' if self.several else ':'} goal {index}" + (f" ({frame})" if frame else "")
        return text


# ------------------------------------------------------------------ reading
#: The goal kinds a goals file takes, by their ``kind:`` name: what each kind class declares (its ``file_kind()``),
#: in the order the kinds were declared.
GOAL_KINDS = {fk.name: fk for fk in (cls.file_kind() for cls in kind_classes()) if fk is not None}


#: Preferences a goal list may hold (:mod:`evoik_pin.goals.preferences`), by their ``kind:`` name: (class, fields).
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
    unknown_keys(entry, ("frame", "kind", "target", *kind.fields, "targets"), f"{what}, a {kind_name} goal")
    if "targets" in entry:  # a goal set: any one of several targets
        return _goal_set(entry, what, kind)
    for key in ("frame", "target"):
        if key not in entry:
            raise GoalsFileError(f"{what}: missing field {key!r} (every goal has frame, kind and target, or targets "
                                 "for a goal set)")
    if not isinstance(frame, str) or not frame:
        raise GoalsFileError(f"{what}: frame must be a frame name (a non-empty string), got {frame!r}")
    if not isinstance(entry["target"], dict):
        raise GoalsFileError(f"{what}: target must be a mapping (position, rpy / rpy_rad, matrix), got "
                             f"{entry['target']!r}")
    try:
        target = kind.read_target(entry["target"])
    except (GoalsFileError, TargetError) as exc:
        text = str(exc)
        raise GoalsFileError(f"{what}: {text if text.startswith('target') else 'target: ' + text}") from None
    options = {key: FIELD_READERS.get(key, number)(entry[key], f"{what}: {key}") for key in kind.fields
               if key in entry}
    try:
        return (kind.make or kind.cls)(frame, target, **options)
    except (OptionError, TargetError, GoalsFileError) as exc:
        raise GoalsFileError(f"{what}: {exc}") from None


def _goal_set(entry: dict, what: str, kind: FileKind) -> Goal:
    """A goal set (``targets:``, a non-empty list of targets, instead of ``target:``)."""
    frame, targets = entry.get("frame"), entry["targets"]
    if "target" in entry:
        raise GoalsFileError(f"{what}: give target (one) or targets (a goal set: any one will do), not both")
    if not isinstance(frame, str) or not frame:
        raise GoalsFileError(f"{what}: frame must be a frame name (a non-empty string), got {frame!r}")
    if not isinstance(targets, list) or not targets:
        raise GoalsFileError(f"{what}: targets must be a non-empty list of targets (a goal set), got {targets!r}")
    read = []
    for k, t in enumerate(targets):
        if not isinstance(t, dict):
            raise GoalsFileError(f"{what}: targets[{k}] must be a mapping (position, rpy / rpy_rad, matrix), got {t!r}")
        try:
            read.append(kind.read_target(t))
        except (GoalsFileError, TargetError) as exc:
            raise GoalsFileError(f"{what}: targets[{k}]: {exc}") from None
    options = {key: number(entry[key], f"{what}: {key}") for key in kind.fields if key in entry}
    if kind.set_member is not None:
        read = [kind.set_member(t) for t in read]
    try:
        return kind.cls(frame, read, **options)
    except (OptionError, TargetError) as exc:
        raise GoalsFileError(f"{what}: {exc}") from None


def _preference(entry: dict, what: str, kind_name: str):
    """A preference entry (``kind: posture | joint_limit_margin | manipulability | minimal_displacement``)."""
    cls, fields = PREFERENCE_KINDS[kind_name]
    unknown_keys(entry, ("kind", *fields), f"{what}, a {kind_name} preference")
    args = {}
    for key in fields:
        if key not in entry:
            continue
        value = entry[key]
        if key == "q_ref":
            if not isinstance(value, list):
                raise GoalsFileError(f"{what}: q_ref must be a list of joint values (rad or m), got {value!r}")
            value = [number(v, f"{what}: q_ref[{k}]") for k, v in enumerate(value)]
        elif key == "joints":
            if not isinstance(value, dict) or not value:
                raise GoalsFileError(f"{what}: joints must be a mapping {{joint name: value (rad or m)}}, got "
                                     f"{value!r}")
            value = {str(k): number(v, f"{what}: joints.{k}") for k, v in value.items()}
        elif key == "frame":
            if not isinstance(value, str) or not value:
                raise GoalsFileError(f"{what}: frame must be a frame name, got {value!r}")
        else:
            value = number(value, f"{what}: {key}")
        args[key] = value
    if kind_name == "posture":
        if ("q_ref" in args) == ("joints" in args):
            raise GoalsFileError(f"{what}: a posture needs one of q_ref (a joint vector) and joints ({{name: value}})")
        args["q_ref"] = args.pop("q_ref", None) or args.pop("joints")
    if kind_name == "joint_limit_margin" and "margin" not in args:
        raise GoalsFileError(f"{what}: a joint_limit_margin needs margin (rad or m)")
    try:
        return cls(**args)
    except (OptionError, TargetError, ValueError) as exc:
        raise GoalsFileError(f"{what}: {exc}") from None


def _goal_list(entries, what: str, several: bool) -> list[Goal]:
    key = "each problem" if several else "goals"
    if not isinstance(entries, list):
        raise GoalsFileError(f"{what}: {key} must be a list of goals (frame, kind, target), got {entries!r}")
    if not entries:
        raise GoalsFileError(f"{what}: {key} is empty; give at least one goal (frame, kind, target)")
    sep = ", " if several else ": "
    return [_goal(entry, f"{what}{sep}goal {i}" if several else f"goal {i}") for i, entry in enumerate(entries)]


def read_goals_file(path: str | os.PathLike) -> GoalsFile:
    """Everything a goals file holds (format: the module docstring), checked; GoalsFileError naming the file,
    the goal and the field. The goals' frames are checked against a robot by :meth:`GoalsFile.bind`."""
    path = Path(os.fspath(path)).expanduser()
    where = f"goals file {str(path)!r}"
    data = read_data(path, where, GoalsFileError)
    if data is None:
        raise GoalsFileError(f"{where}: the file is empty; expected a goals: list (or problems:)")
    if isinstance(data, list):
        data = {"goals": data}
    if not isinstance(data, dict):
        raise GoalsFileError(f"{where}: the top level must be a mapping ({', '.join(_TOP_KEYS)}) or a list of "
                             f"goals, got a {type(data).__name__}")
    try:
        unknown_keys(data, _TOP_KEYS, "top level")
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
    except GoalsFileError as exc:
        raise GoalsFileError(f"{where}: {exc}") from None
    return GoalsFile(path, robot, floating_base, tips, problems, several)


def load_goals(path: str | os.PathLike) -> list[Goal]:
    """The goal list of the goals file ``path`` (YAML or JSON; format: the module docstring), ready for
    ``evoik_pin.solve(robot, goals)``. GoalsFileError naming the file, the goal and the field; a file of several
    problems (``problems:``) is refused: read it with :func:`load_problems`."""
    spec = read_goals_file(path)
    if spec.several:
        raise GoalsFileError(f"goals file {str(spec.path)!r} holds {len(spec.problems)} problems (problems:): read "
                             "them with load_problems (for solve_many / solve_trajectory)")
    return spec.problems[0]


def load_problems(path: str | os.PathLike) -> list[list[Goal]]:
    """The goal lists of the goals file ``path``: those of its ``problems:``, or its ``goals:`` as one list, for
    ``evoik_pin.solve_many(robot, problems)`` or ``solve_trajectory``."""
    return read_goals_file(path).problems


# ------------------------------------------------------------------ writing
def _kind_of(goal) -> tuple[str, FileKind]:
    for name, kind in GOAL_KINDS.items():
        if type(goal) is kind.cls:
            return name, kind
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
    entry = {"frame": goal.frame, "kind": name, "target": kind.write_target(goal)}
    if goal.alternatives is not None:  # a goal set
        del entry["target"]
        entry["targets"] = [kind.write_target(m) for m in goal.alternatives]
    return entry | field_entries(goal, kind.fields)


def save_goals(goals, path: str | os.PathLike, robot=None, floating_base: bool | None = None,
               tips: list[str] | None = None) -> Path:
    """Write ``goals`` to the goals file ``path`` (YAML or JSON by the extension) and return the path;
    :func:`load_goals` reads it back to the same goals (targets bit for bit).

    Args:
        goals: a goal list (written as ``goals:``), or a list of goal lists (``problems:``, read back by
            :func:`load_problems`).
        path: the file to write.
        robot: optional, what the file is for: a robot name, or a :class:`~evoik_pin.robot.Robot` (its name, and
            its ``floating_base`` unless given).
        floating_base, tips: optional, written as the file's ``floating_base`` and ``tips``.
    """
    path = Path(os.fspath(path)).expanduser()
    fmt = data_format(path, f"goals file {str(path)!r}", GoalsFileError)
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
    if several:
        data["problems"] = lists
    else:
        data["goals"] = lists[0]
    header = "# evoik_pin goals (m and rad, in the robot's base frame; format: evoik_pin/io/goals_file.py)\n"
    return write_text(path, dump_data(data, fmt, header), "goals file", GoalsFileError)


def goal_kind_name(goal: Goal) -> str:
    """The ``kind:`` a goals file writes for ``goal`` (``"pose"``, ``"position"``, ``"orientation"``,
    ``"direction"``, ``"look_at"``)."""
    return _kind_of(goal)[0]
