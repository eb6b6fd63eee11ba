"""YAML and JSON data files, read and written alike by evoik_pin's file formats (format by extension, syntax errors
with line and column, UTF-8). Each function takes the ``where`` its errors start with and the error class to raise.
"""

from __future__ import annotations

import json
from pathlib import Path

__all__ = ["DATA_SUFFIXES", "Flow", "data_format", "dump_data", "parse_data", "read_data", "write_text"]

#: File extensions and the format each selects.
DATA_SUFFIXES = {".yaml": "yaml", ".yml": "yaml", ".json": "json"}


class Flow(dict):
    """A mapping :func:`dump_data` writes on one line in YAML (e.g. a pose)."""


def data_format(path: Path, where: str, error: type[Exception]) -> str:
    """``"yaml"`` or ``"json"`` by ``path``'s extension; ``error`` naming the accepted extensions otherwise."""
    fmt = DATA_SUFFIXES.get(path.suffix.lower())
    if fmt is None:
        raise error(f"{where}: unknown extension {path.suffix!r}; use {', '.join(DATA_SUFFIXES)} (YAML or JSON)")
    return fmt


def parse_data(path: Path, text: str, where: str, error: type[Exception]):
    """The data of ``text`` (dicts, lists, numbers, strings), parsed as ``path``'s extension says (YAML with
    PyYAML's safe loader); ``error`` with the line and column of a syntax error."""
    if data_format(path, where, error) == "json":
        try:
            return json.loads(text)
        except json.JSONDecodeError as exc:
            raise error(f"{where}: JSON syntax error at line {exc.lineno}, column {exc.colno}: {exc.msg}") from None
    import yaml

    try:
        return yaml.safe_load(text)
    except yaml.MarkedYAMLError as exc:
        mark, begun = exc.problem_mark or exc.context_mark, exc.context_mark
        at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        context = exc.context
        if context and begun is not None and begun is not mark:
            context += f" (begun at line {begun.line + 1}, column {begun.column + 1})"
        what = ": ".join(filter(None, [context, exc.problem]))
        raise error(f"{where}: YAML syntax error{at}: {what}") from None
    except yaml.YAMLError as exc:
        raise error(f"{where}: YAML error: {exc}") from None


def read_data(path: Path, where: str, error: type[Exception]):
    """The parsed data of the file ``path`` (:func:`parse_data`); ``error`` for a missing or unreadable file."""
    data_format(path, where, error)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise error(f"{where}: not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(f"{where}: cannot read it: {exc}") from None
    return parse_data(path, text, where, error)


def dump_data(data, fmt: str, header: str = "") -> str:
    """``data`` as the text of a ``fmt`` file (``"yaml"`` or ``"json"``): YAML keeps the mappings' order, writes
    lists of numbers and :class:`Flow` mappings on one line and starts with ``header`` (comment lines)."""
    if fmt == "json":
        return json.dumps(data, indent=2) + "\n"
    import yaml

    class Dumper(yaml.SafeDumper):
        pass

    Dumper.add_representer(Flow, lambda d, v: d.represent_mapping("tag:yaml.org,2002:map", v, flow_style=True))
    return header + yaml.dump(data, Dumper=Dumper, sort_keys=False, default_flow_style=None)


def write_text(path: Path, text: str, what: str, error: type[Exception]) -> Path:
    """Write ``text`` to ``path`` (UTF-8) and return it; ``error`` ("cannot write the {what} ...") otherwise."""
    try:
        path.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise error(f"cannot write the {what} {str(path)!r}: {exc.strerror or exc}") from None
    return path
