"""Length units of motion files, and the inference of a file's unit from the size of its skeleton.

Mocap files carry no unit: CMU's BVH conversions are in the ASF unit (1/0.45 inch: ``length 0.45`` in the ASF
header turns inches into file units), LAFAN1 and Xsens exports in cm, others in m, mm or inches. A human's standing
height is about 1.7 m, and the candidate units differ by factors of 2.2 or more, so the unit whose metres put the
skeleton's size closest to 1.7 m (on a log scale) is the file's unit; ``unit=`` overrides this for a child, a
giant or a file in another unit.
"""

from __future__ import annotations

import math

from ..errors import BvhError
from .motion import positive_number

__all__ = ["HUMAN_HEIGHT_M", "UNITS", "infer_unit", "unit_scale"]

#: Metres per file unit, by name. "cmu": CMU's ASF/AMC unit and its BVH conversions, 1/0.45 inch.
UNITS: dict[str, float] = {"m": 1.0, "cm": 0.01, "mm": 0.001, "inch": 0.0254, "cmu": 0.0254 / 0.45}

#: The size (m) the inference aims a skeleton at: an adult's standing height.
HUMAN_HEIGHT_M = 1.7


def unit_scale(unit) -> float:
    """Metres per file unit for ``unit``: a name of :data:`UNITS` or a finite number > 0 (m per unit)."""
    if isinstance(unit, str):
        if unit in UNITS:
            return UNITS[unit]
        raise BvhError(f"unknown unit {unit!r}; accepted: one of {list(UNITS)} or a number of m per file unit")
    return positive_number(unit, f"unit must be one of {list(UNITS)} or a finite number > 0 of m per file unit; "
                           f"got {unit!r}", BvhError)


def infer_unit(size: float) -> str:
    """The name in :data:`UNITS` that turns a skeleton ``size`` (file units; its standing height or span) into the
    metres closest to :data:`HUMAN_HEIGHT_M` on a log scale."""
    if not (math.isfinite(size) and size > 0.0):
        raise BvhError(f"cannot infer the unit of a skeleton of size {size} (all its joints at one point?); "
                       f"pass unit= (one of {list(UNITS)} or m per file unit)")
    return min(UNITS, key=lambda u: abs(math.log(size * UNITS[u] / HUMAN_HEIGHT_M)))
