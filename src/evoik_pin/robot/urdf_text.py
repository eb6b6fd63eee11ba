"""Turning a file's bytes into URDF text: :func:`decode_xml`, :func:`expand_xacro` (xacro without ROS) and
:func:`captured_stderr` (the C++ parsers' messages, for our errors)."""

from __future__ import annotations

import codecs
import contextlib
import io
import os
import re
import sys
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path

from ..errors import RobotLoadError
from .packages import PackageResolver

__all__ = ["captured_stderr", "decode_xml", "expand_xacro", "is_xacro"]

# Byte-order marks and the XML spec's (appendix F) signatures of "<?" in UTF-16 / UTF-32 without a mark.
_SIGNATURES = ((codecs.BOM_UTF32_BE, "utf-32"), (codecs.BOM_UTF32_LE, "utf-32"), (codecs.BOM_UTF8, "utf-8-sig"),
               (codecs.BOM_UTF16_BE, "utf-16"), (codecs.BOM_UTF16_LE, "utf-16"), (b"\x00\x00\x00<", "utf-32-be"),
               (b"<\x00\x00\x00", "utf-32-le"), (b"\x00<\x00?", "utf-16-be"), (b"<\x00?\x00", "utf-16-le"))
_DECLARED = re.compile(rb"""^\s*<\?xml\s[^>]*?encoding\s*=\s*["']([A-Za-z][A-Za-z0-9._-]*)["']""")
_CONTROL = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f]")
_XACRO = re.compile(r"<xacro:[A-Za-z]|\$\{|\$\(")
_COMMENT = re.compile(r"<!--.*?-->", re.S)
_STDERR_LOCK = threading.RLock()


def decode_xml(data: bytes, where: str) -> str:
    """Text of the XML document ``data`` read from ``where``, decoded as an XML parser would (byte-order mark, else
    the declared encoding, else UTF-8); RobotLoadError for empty, binary or undecodable input."""
    if not data.strip():
        raise RobotLoadError(f"{where} is empty: expected URDF XML (a <robot name=...> element)")
    encoding = next((enc for sig, enc in _SIGNATURES if data.startswith(sig)), None)
    declared = False
    if encoding is None:
        m = _DECLARED.match(data[:1024])
        encoding, declared = (m.group(1).decode("ascii"), True) if m else ("utf-8", False)
    try:
        codecs.lookup(encoding)
    except LookupError:
        raise RobotLoadError(f"{where} declares an unknown encoding {encoding!r} in its <?xml ...?> declaration; use "
                             "UTF-8 or a standard name such as ISO-8859-1") from None
    source = f"{encoding} (declared in its <?xml ...?> line)" if declared else encoding
    try:
        text = data.decode(encoding)
    except UnicodeDecodeError as exc:
        head = data[:1024]  # binary: NUL bytes or many control bytes in the first KiB (no UTF-16/32 signature matched)
        binary = b"\x00" in head or sum(b < 32 and b not in (9, 10, 13) for b in head) > len(head) // 20
        kind = "a binary file, not URDF XML: " if binary else ""
        raise RobotLoadError(f"{where} is {kind}not decodable as {source}: byte {data[exc.start]:#04x} at offset "
                             f"{exc.start}. A URDF is XML text; declare a non-UTF-8 encoding in its first line, e.g. "
                             "<?xml version=\"1.0\" encoding=\"ISO-8859-1\"?>") from None
    text = text.lstrip("\ufeff")
    bad = _CONTROL.search(text)  # XML allows no control characters but tab, newline and carriage return
    if bad is not None:
        raise RobotLoadError(f"{where} is a binary file, not URDF XML: control character {ord(bad.group()):#04x} at "
                             f"character {bad.start()}")
    return text


def is_xacro(path: Path | None, text: str) -> bool:
    """True for ``*.xacro`` files (``arm.urdf.xacro``) and for ``text`` holding ``<xacro:...>``, ``${...}`` or
    ``$(...)`` outside comments (the xacro namespace alone is not enough: generated URDFs keep it)."""
    if path is not None and path.suffix.lower() == ".xacro":
        return True
    return _XACRO.search(_COMMENT.sub("", text)) is not None  # comments often keep xacro source around


def expand_xacro(text: str, where: str, path: Path | None, args: dict | None,
                 packages: PackageResolver | None = None) -> str:
    """URDF text of the xacro document ``text`` (read from ``path``, or None for a string), ``args`` setting its
    ``<xacro:arg>`` values, ``$(find pkg)`` found through ``packages``; RobotLoadError naming ``where`` on failure."""
    import xacro  # xacrodoc's
    from xacrodoc import XacroDoc
    from xacrodoc import packages as xacro_packages

    mappings = {str(k): str(v) for k, v in (args or {}).items()}
    resolver = packages if packages is not None else PackageResolver(path)
    missing: list[tuple[str, str]] = []  # (package, file naming it) of failed look-ups

    def find(pkg: str) -> str:
        found = resolver.find(pkg)
        if found is None:
            naming = xacro.filestack[-1] if xacro.filestack else None
            missing.append((pkg, str(naming) if naming else where))
            raise xacro_packages.PackageNotFoundError(pkg)
        return found.as_posix()

    # xacro and xacrodoc keep module-level state (the stack of files being read, the package finders and cache):
    # each expansion sets it up and restores it.
    finder = xacro_packages._finder
    saved_finders, saved_cache = list(finder.finder_funcs), dict(finder.package_cache)
    failure: Exception | None = None
    with captured_stderr() as err:  # which holds _STDERR_LOCK: xacro's state is this expansion's alone
        try:
            xacro.init_stacks(str(path) if path is not None else None)
            finder.package_cache.clear()
            finder.finder_funcs.insert(0, (find, xacro_packages.PackageNotFoundError))
            doc = XacroDoc.from_string(text, subargs=mappings, resolve_packages=False,
                                       rootdir=path.parent if path is not None else None)
            urdf = doc.dom.toxml()
        except Exception as exc:  # xacro raises XacroException, NameError, ValueError, ExpatError, ...
            failure = exc
        finally:
            xacro.init_stacks(None)
            finder.finder_funcs[:] = saved_finders
            finder.package_cache.clear()
            finder.package_cache.update(saved_cache)
    if failure is not None:
        raise RobotLoadError(_xacro_message(failure, where, err[0], resolver, missing)) from None
    return urdf


def _xacro_message(exc: Exception, where: str, err: str, resolver: PackageResolver,
                   missing: list[tuple[str, str]]) -> str:
    """The RobotLoadError message of a failed xacro expansion."""
    cause = getattr(exc, "exc", None) or exc
    if type(cause).__name__ == "PackageNotFoundError":
        pkg = cause.args[0] if cause.args else "?"
        naming = next((f for p, f in reversed(missing) if p == pkg), where)
        return f"cannot expand xacro file {where}: {resolver.not_found(pkg, naming, f'$(find {pkg})')}"
    text = str(exc).strip() or type(exc).__name__
    if cause is not exc and str(cause).strip() and str(cause).strip() not in text:
        text += f" ({str(cause).strip()})"
    missing = re.search(r"[Uu]ndefined substitution argument (\S+)", text)
    if missing:
        arg = missing.group(1)
        text += f"; give it with xacro_args={{{arg!r}: value}} (or --xacro-arg {arg}=VALUE on the command line)"
    noise = err.strip()
    if noise:
        text += f"\nxacro said: {noise}"
    return f"cannot expand xacro file {where}: {text}"


@contextlib.contextmanager
def captured_stderr() -> Iterator[list[str]]:
    """Redirect file descriptor 2 and ``sys.stderr`` while the block runs (urdfdom prints its errors there); the
    yielded list then holds the captured text. Process-wide, serialized by a lock."""
    out: list[str] = []
    with _STDERR_LOCK, tempfile.TemporaryFile() as tmp:
        py_err = io.StringIO()
        with contextlib.suppress(AttributeError, OSError, ValueError):  # a closed or odd sys.stderr
            sys.stderr.flush()
        try:
            saved = os.dup(2)
        except OSError:  # pragma: no cover - no fd 2 to redirect
            saved = None
        if saved is not None:
            os.dup2(tmp.fileno(), 2)
        try:
            with contextlib.redirect_stderr(py_err):
                yield out
        finally:
            if saved is not None:
                os.dup2(saved, 2)
                os.close(saved)
            tmp.seek(0)
            out.append(tmp.read().decode("utf-8", "replace") + py_err.getvalue())
