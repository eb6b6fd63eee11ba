"""The goal kinds' declarations (a Goal subclass's ``KIND_CODES``, registered when the class is made) and the tables
derived from them. A kind's code is the code of the compiled residual that evaluates it, named by its maths."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["ANGLE_KINDS", "FAMILY_AXES", "FAMILY_BEYOND_FRAME", "FAMILY_FRAME", "KINDS", "KIND_BEYOND_FRAME",
           "ORIENTED_KINDS", "POSITIONLESS_KINDS", "TASK_ROWS", "KindCode", "kind_classes", "register"]

#: The compiled families of the LM kernel (a goal's ``G_FAMILY`` spec column): the one-frame residuals of
#: ``kernel.goal_error``, those of ``solvers/lm/axes.py`` and those beyond one frame of ``solvers/lm/balance.py``.
FAMILY_FRAME, FAMILY_AXES, FAMILY_BEYOND_FRAME = 0, 1, 2

#: The compiled residuals (a goal's kind code, its spec's ``G_KIND`` column), by their maths. One frame: its
#: origin at a point (3 rows), its pose by the SE(3) logarithm (6), planar x, y (2) and with the yaw (3).
POINT, LOG6, PLANAR, PLANAR_YAW = 0, 1, 2, 3
#: One frame, :mod:`evoik_pin.solvers.lm.axes`: the SE(3) logarithm with bands or free axes (6 rows, target frame),
#: a point with bands (3, base frame), a rotation with bands (3), an axis along a direction, an axis at a point.
BANDED_LOG6, BANDED_POINT, BANDED_ROTATION, AXIS_ALONG, AXIS_AT = 4, 5, 6, 7, 8
#: Beyond one frame, :mod:`evoik_pin.solvers.lm.balance` (from :data:`KIND_BEYOND_FRAME` on): the centre of mass at
#: a point, over a support polygon; frame b's pose seen from frame a (the SE(3) logarithm, plain or banded); frame
#: b's position relative to frame a in the world's axes and in frame a's.
COM_POINT, COM_SUPPORT, RELATIVE_LOG6, RELATIVE_BANDED_LOG6 = 10, 11, 12, 13
RELATIVE_POINT_WORLD, RELATIVE_POINT_IN_A = 14, 15
#: Codes from here on are goals that pack themselves against the robot (``goal.pack(robot)``: their ``aux`` and
#: ``support`` rows); :func:`register` holds every kind of :data:`FAMILY_BEYOND_FRAME` to it, and no other.
KIND_BEYOND_FRAME = 10


@dataclass(frozen=True)
class KindCode:
    """One kernel code of a goal kind: ``code`` (a compiled residual above), the ``rows`` (0-5: vx vy vz wx wy wz) of
    the frame's base-frame Jacobian its residual stands on, its ``family``; whether it constrains orientation, puts a
    point somewhere and reports an ``angle`` (rad)."""

    code: int
    rows: tuple
    family: int
    oriented: bool = False
    has_position: bool = True
    angle: bool = False


#: Every registered code's declaration, and the class that declared it (None: a target kind without a goal class).
KINDS: dict[int, KindCode] = {}
_CLASSES: dict[int, type | None] = {}
#: Derived from the declarations: the Jacobian rows of each code; the codes that constrain orientation, put no point
#: anywhere, report an angle.
TASK_ROWS: dict[int, tuple] = {}
ORIENTED_KINDS: set[int] = set()
POSITIONLESS_KINDS: set[int] = set()
ANGLE_KINDS: set[int] = set()


def register(owner: type | None, *codes: KindCode) -> None:
    """Record the declared ``codes`` of the goal class ``owner`` and derive the tables. ValueError for a code declared
    twice or a family contradicting :data:`KIND_BEYOND_FRAME`."""
    for c in codes:
        if c.code in KINDS and _CLASSES[c.code] is not owner and KINDS[c.code] != c:
            raise ValueError(f"kind code {c.code} declared twice: by {_CLASSES[c.code]} and {owner}")
        if (c.family == FAMILY_BEYOND_FRAME) != (c.code >= KIND_BEYOND_FRAME):
            raise ValueError(f"kind code {c.code} of {owner}: the codes of FAMILY_BEYOND_FRAME are those from "
                             f"KIND_BEYOND_FRAME ({KIND_BEYOND_FRAME}) on")
        KINDS[c.code], _CLASSES[c.code] = c, owner
        TASK_ROWS[c.code] = tuple(c.rows)
        for table, flag in ((ORIENTED_KINDS, c.oriented), (POSITIONLESS_KINDS, not c.has_position),
                            (ANGLE_KINDS, c.angle)):
            (table.add if flag else table.discard)(c.code)


def kind_classes() -> list[type]:
    """The registered goal classes, in the order they were declared."""
    return list(dict.fromkeys(cls for cls in _CLASSES.values() if cls is not None))
