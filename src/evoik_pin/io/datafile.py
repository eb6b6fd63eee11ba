"""YAML and JSON data files, read and written alike by evoik_pin's file formats (format by extension, syntax errors
with line and column, UTF-8). Each function takes the ``where`` its errors start with and the error class to raise."""

from __future__ import annotations

import json
import math
import re
from contextlib import contextmanager
from pathlib import Path

import numpy as np

__all__ = ["DATA_SUFFIXES", "Flow", "data_format", "floats", "naming", "number", "numbers", "read_mapping",
           "unknown_keys", "write_data"]

#: A number as YAML 1.2 writes it (PyYAML, a YAML 1.1 reader, returns ``1e-6`` as a string).
_NUMBER_TEXT = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")

#: File extensions and the format each selects.
DATA_SUFFIXES = {".yaml": "yaml", ".yml": "yaml", ".json": "json"}


class Flow(dict):
    """A mapping :func:`write_data` writes on one line in YAML (e.g. a pose)."""


def floats(values) -> list[float]:
    """The numbers of ``values`` (any shape, flattened) as plain floats to write, -0.0 as 0.0."""
    return [float(v) + 0.0 for v in np.asarray(values, dtype=float).reshape(-1)]


def data_format(path: Path, where: str, error: type[Exception]) -> str:
    """``"yaml"`` or ``"json"`` by ``path``'s extension; ``error`` naming the accepted extensions otherwise."""
    fmt = DATA_SUFFIXES.get(path.suffix.lower())
    if fmt is None:
        raise error(f"{where}: unknown extension {path.suffix!r}; use {', '.join(DATA_SUFFIXES)} (YAML or JSON)")
    return fmt


def read_mapping(path: Path, where: str, error: type[Exception], keys: tuple[str, ...], empty: str,
                 list_key: str | None = None) -> dict:
    """The top-level mapping of the data file ``path`` (YAML: PyYAML's safe loader), its keys among ``keys``; with
    ``list_key``, a top-level list stands for ``{list_key: the list}``. ``error`` starting with ``where`` for a
    missing or unreadable file, a syntax error, an empty file (``empty``: what it should hold), another top level,
    or an unknown key."""
    data = _parse(path, where, error)
    if data is None:
        raise error(f"{where}: the file is empty; expected {empty}")
    if list_key is not None and isinstance(data, list):
        data = {list_key: data}
    if not isinstance(data, dict):
        raise error(f"{where}: the top level must be a mapping ({', '.join(keys)})"
                    + (f" or a list of {list_key}" if list_key else "") + f", got a {type(data).__name__}")
    unknown_keys(data, keys, f"{where}: top level", error=error)
    return data


def _parse(path: Path, where: str, error: type[Exception]):
    fmt = data_format(path, where, error)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise error(f"{where}: not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(f"{where}: cannot read it: {exc}") from None
    if fmt == "json":
        try:
            return json.loads(text)
        except json.JSONDecodeError as exc:
            raise error(f"{where}: JSON syntax error at line {exc.lineno}, column {exc.colno}: {exc.msg}") from None
    import yaml

    try:
        return yaml.safe_load(text)
    except yaml.MarkedYAMLError as exc:
        mark, begun, context = exc.problem_mark or exc.context_mark, exc.context_mark, exc.context
        at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        if context and begun is not None and begun is not mark:
            context += f" (begun at line {begun.line + 1}, column {begun.column + 1})"
        what = ": ".join(filter(None, [context, exc.problem]))
        raise error(f"{where}: YAML syntax error{at}: {what}") from None
    except yaml.YAMLError as exc:
        raise error(f"{where}: YAML error: {exc}") from None


@contextmanager
def naming(where: str, error: type[Exception], catch: tuple[type[Exception], ...] = ()):
    """Re-raise an ``error`` (or one of ``catch``) raised in the block as an ``error`` starting with ``where``."""
    try:
        yield
    except (error, *catch) as exc:
        raise error(f"{where}: {exc}") from None


def write_data(path: Path, data, header: str, what: str, error: type[Exception]) -> Path:
    """Write ``data`` to ``path`` (UTF-8) as its extension says and return the path: YAML keeps the mappings' order,
    writes lists of numbers and :class:`Flow` mappings on one line and starts with ``header`` (comment lines).
    ``error`` ("cannot write the {what} ...") when it cannot be written."""
    if data_format(path, f"{what} {str(path)!r}", error) == "json":
        text = json.dumps(data, indent=2) + "\n"
    else:
        import yaml

        Dumper = type("Dumper", (yaml.SafeDumper,), {})  # a representer of its own, not SafeDumper's
        Dumper.add_representer(Flow, lambda d, v: d.represent_mapping("tag:yaml.org,2002:map", v, flow_style=True))
        text = header + yaml.dump(data, Dumper=Dumper, sort_keys=False, default_flow_style=None)
    try:
        path.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise error(f"cannot write the {what} {str(path)!r}: {exc.strerror or exc}") from None
    return path


def number(value, what: str, positive: bool = False, *, error: type[Exception]) -> float:
    """A finite number (int, float, or YAML 1.1's text of one such as ``1e-6``; not a bool), > 0 when ``positive``."""
    if isinstance(value, str) and _NUMBER_TEXT.fullmatch(value.strip()):
        value = float(value)
    if (isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value)
            or (positive and value <= 0)):
        raise error(f"{what} must be a finite number{' > 0' if positive else ''}, got {value!r}")
    return float(value)


def numbers(value, count: int, what: str, positive: bool = False, *, error: type[Exception]) -> np.ndarray:
    """A list of ``count`` :func:`number` s as a float array (count,)."""
    if not isinstance(value, list) or len(value) != count:
        raise error(f"{what} must be a list of {count} numbers{' > 0' if positive else ''}, got {value!r}")
    return np.array([number(v, f"{what}[{k}]", positive, error=error) for k, v in enumerate(value)])


def unknown_keys(entry: dict, accepted, what: str, *, error: type[Exception]) -> None:
    """An ``error`` naming the keys of ``entry`` not among ``accepted``, and the accepted ones."""
    unknown = [k for k in entry if k not in accepted]
    if unknown:
        raise error(f"{what}: unknown key(s) {', '.join(map(repr, unknown))}; accepted: {', '.join(accepted)}")
