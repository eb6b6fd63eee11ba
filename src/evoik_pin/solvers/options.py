"""Option validators shared by every solver: each check takes the option's ``name`` (as the user typed it) and its
``value``, returns the value in canonical form and otherwise raises :class:`~evoik_pin.errors.OptionError` naming the
option, the accepted values and what was given. Booleans are refused wherever a number is expected.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from ..errors import OptionError

__all__ = ["check_callback", "check_choice", "check_fraction", "check_int", "check_nonnegative",
           "check_nonnegative_vector", "check_number", "check_positive"]


def check_int(name: str, value, minimum: int = 1, maximum: int | None = None) -> int:
    """``value`` as an ``int`` in [minimum, maximum] (no upper limit when ``maximum`` is None): Python and NumPy
    integers, not ``bool`` or floats; OptionError otherwise."""
    # type(...) is int first: the common case, without isinstance's walk over numpy's abstract classes
    ok = type(value) is int or (not isinstance(value, bool) and isinstance(value, (int, np.integer)))
    if ok and value >= minimum and (maximum is None or value <= maximum):
        return int(value)
    accepted = f">= {minimum}" if maximum is None else f"in [{minimum}, {maximum}]"
    raise OptionError(f"{name} must be an integer {accepted}, got {value!r}")


def _range_text(low: float, high: float, open_low: bool, open_high: bool) -> str:
    """``"> 0"``, ``"in (0, 2]"``, ``"<= 1"`` or ``""`` for the interval between low and high."""
    if np.isfinite(low) and np.isfinite(high):
        return f"in {'(' if open_low else '['}{low:g}, {high:g}{')' if open_high else ']'}"
    if np.isfinite(low):
        return f"{'>' if open_low else '>='} {low:g}"
    if np.isfinite(high):
        return f"{'<' if open_high else '<='} {high:g}"
    return ""


def check_number(name: str, value, low: float = -np.inf, high: float = np.inf, *, open_low: bool = False,
                 open_high: bool = False, unit: str = "") -> float:
    """``value`` as a finite ``float`` (anything ``float()`` takes but ``bool``) between ``low`` and ``high``, closed
    unless ``open_low`` / ``open_high`` (infinite ends: no limit); ``unit`` (``"m"``, ``"rad"``) shown in the error.
    OptionError: ``"<name> must be a finite number in (low, high] <unit>, got <value>"``."""
    if not isinstance(value, bool):
        try:
            v = float(value)
        except (TypeError, ValueError):
            pass
        else:
            above = v > low if open_low else v >= low
            below = v < high if open_high else v <= high
            if above and below and math.isfinite(v):
                return v
    # the message only on failure: formatting it costs more than the check (this runs on every solve)
    accepted = " ".join(filter(None, ["a finite number", _range_text(low, high, open_low, open_high), unit]))
    raise OptionError(f"{name} must be {accepted}, got {value!r}")


def check_positive(name: str, value, upper: float = np.inf, unit: str = "") -> float:
    """``value`` as a finite ``float`` in (0, upper] (> 0 when ``upper`` is infinite); see :func:`check_number`."""
    return check_number(name, value, 0.0, upper, open_low=True, unit=unit)


def check_nonnegative(name: str, value, upper: float = np.inf, unit: str = "") -> float:
    """``value`` as a finite ``float`` in [0, upper] (>= 0 when ``upper`` is infinite); see :func:`check_number`."""
    return check_number(name, value, 0.0, upper, unit=unit)


def check_fraction(name: str, value) -> float:
    """``value`` as a ``float`` in [0, 1]: a probability, a rate or a share; see :func:`check_number`."""
    return check_number(name, value, 0.0, 1.0)


def check_choice(name: str, value, choices: Sequence):
    """``value`` if it equals one of ``choices``; OptionError ``"<name> <value> is not one of <choices>"``."""
    try:
        ok = value in choices
    except (TypeError, ValueError):  # e.g. an array compared with strings
        ok = False
    if not ok:
        raise OptionError(f"{name} {value!r} is not one of {', '.join(repr(c) for c in choices)}")
    return value


def check_callback(callback, signature: str = "callback(generation, population)") -> Callable | None:
    """``callback`` if it is None or callable (called as ``signature``); OptionError otherwise."""
    if callback is not None and not callable(callback):
        raise OptionError(f"callback must be None or callable as {signature}, got {callback!r}")
    return callback


def check_nonnegative_vector(name: str, value, size: int) -> np.ndarray:
    """``value`` as a float array (size,) of finite values >= 0 (e.g. per-joint ``gains``); OptionError otherwise."""
    try:
        arr = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise OptionError(f"{name} must be {size} finite numbers >= 0 (one per joint), got {value!r}") from None
    if arr.shape != (size,):
        raise OptionError(f"{name} must have {size} values (one per joint), got {arr.size}")
    if not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise OptionError(f"{name} must be finite values >= 0, got {arr.tolist()}")
    return arr
