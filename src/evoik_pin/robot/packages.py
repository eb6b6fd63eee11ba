"""Finding the ROS packages a robot file names (``$(find pkg)``, ``package://pkg/...``) without ROS:
:class:`PackageResolver` (docs/ROBOTS.md, "Packages without ROS")."""

from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ET
from collections.abc import Iterable
from pathlib import Path

from ..errors import RobotLoadError, RobotNotFoundError

__all__ = ["CRAWL_DEPTH", "MESH_URI", "SIBLING_SUFFIXES", "PackageResolver", "check_package_aliases",
           "check_package_dirs", "package_uris", "sibling_names"]

#: How deep below a given folder (a) or a ROS_PACKAGE_PATH entry (b) package.xml files are looked for.
CRAWL_DEPTH = 3
#: A ``package://pkg/rel`` URI (groups: the package, the relative path).
MESH_URI = re.compile(r"package://([^/\"'<>\s]+)/([^\"'<>]+)")


def check_package_dirs(package_dirs) -> list[Path]:
    """``package_dirs`` (a folder or a list of them, or None) as resolved paths of existing folders."""
    if package_dirs is None:
        return []
    if isinstance(package_dirs, (str, os.PathLike)):
        package_dirs = [package_dirs]
    try:
        items = list(package_dirs)
    except TypeError:
        raise RobotLoadError(f"package_dirs must be a folder or a list of folders (str or path), got "
                             f"{type(package_dirs).__name__}") from None
    out = []
    for d in items:
        if not isinstance(d, (str, os.PathLike)) or not os.fspath(d):
            raise RobotLoadError(f"package_dirs entries must be folder paths (str or path), got {d!r}")
        p = Path(os.fspath(d)).expanduser()
        if not p.is_dir():
            raise RobotNotFoundError(f"package folder {os.fspath(d)!r} (package_dirs) is not an existing folder")
        out.append(p.resolve())
    return out


def check_package_aliases(aliases) -> dict[str, str]:
    """``aliases`` ({package named in the file: name to look for instead}, or None), checked."""
    if aliases is None:
        return {}
    if not isinstance(aliases, dict):
        raise RobotLoadError("package_aliases must be a dict {package named in the file: the name it is shipped "
                             f"under}}, got {type(aliases).__name__}")
    for name, target in aliases.items():
        for what in (name, target):
            if not isinstance(what, str) or not what or "/" in what or what in (".", ".."):
                raise RobotLoadError(f"package_aliases entry {name!r}: {target!r}: package names must be non-empty "
                                     "strings without '/'")
    return dict(aliases)


def package_uris(xml: str) -> list[str]:
    """The package names of the ``package://pkg/...`` URIs in URDF text, in order of first appearance."""
    return list(dict.fromkeys(pkg for pkg, _ in MESH_URI.findall(xml)))


def _package_name(folder: Path) -> str | None:
    """The ``<name>`` of ``folder/package.xml``, or None (no file, unreadable, no name)."""
    try:
        name = ET.parse(folder / "package.xml").getroot().findtext("name")
    except (ET.ParseError, OSError):
        return None
    return name.strip() if name else None


def _crawl(folder: Path, pkg: str, depth: int) -> Path | None:
    """The first folder (sorted order) at most ``depth`` levels below ``folder`` whose package.xml names ``pkg``."""
    if depth <= 0:
        return None
    try:
        children = sorted(c for c in folder.iterdir() if c.is_dir() and not c.name.startswith("."))
    except OSError:
        return None
    for c in children:
        if _package_name(c) == pkg:
            return c
    for c in children:
        if (c / "package.xml").is_file():
            continue  # ROS does not look for packages inside a package
        found = _crawl(c, pkg, depth - 1)
        if found is not None:
            return found
    return None


#: Suffixes of ROS package names that robot files and their folders use for one another.
SIBLING_SUFFIXES = ("_support", "_description")


def sibling_names(pkg: str) -> list[str]:
    """Other names package ``pkg`` may be shipped under (``kuka_kr10_support`` -> ``kuka_kr10``,
    ``kuka_kr10_description``; ``abb_irb140`` -> ``abb_irb140_description``)."""
    stem = next((pkg[: -len(x)] for x in SIBLING_SUFFIXES if pkg.endswith(x) and len(pkg) > len(x)), pkg)
    return [name for name in dict.fromkeys((stem, stem + "_description")) if name != pkg]


class PackageResolver:
    """Finds the packages one robot file ``path`` (None for a string: no rules (c), (d)) names, with the checked
    ``package_dirs`` and ``aliases``, first match wins: (a) the ``package_dirs``, (b) the folders of
    ``ROS_PACKAGE_PATH`` (read at each load), (c) a folder named ``pkg`` among the file's ancestor folders or inside
    one of them, nearest first, (d) a ``package.xml`` naming ``pkg`` in the file's folder or above it. In a folder
    ``D`` of (a) and (b), ``pkg`` is ``D/pkg``, ``D`` itself, or a folder up to :data:`CRAWL_DEPTH` levels below
    ``D`` whose ``package.xml`` names it. An alias makes the rules look for another name; without one, a package
    none finds is looked for under its :func:`sibling_names`."""

    def __init__(self, path: Path | None, package_dirs: Iterable[Path] = (), aliases: dict | None = None) -> None:
        self.path = path
        self.user_dirs = list(package_dirs)
        self.aliases = dict(aliases or {})
        entries = os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep)  # read at each load
        self.ros_dirs = [Path(e).expanduser().resolve() for e in entries if e.strip() and Path(e).expanduser().is_dir()]
        self.ancestors = [path.parent.resolve(), *path.parent.resolve().parents] if path is not None else []
        self._found: dict[str, Path | None] = {}

    def find(self, pkg: str) -> Path | None:
        """The folder of package ``pkg`` (or its alias, else its sibling names), or None."""
        if pkg not in self._found:
            name = self.aliases.get(pkg, pkg)
            names = [name] if name in self.aliases.values() else [name, *sibling_names(name)]
            self._found[pkg] = next((found for found in map(self._search_name, names) if found is not None), None)
        return self._found[pkg]

    def _search_name(self, pkg: str) -> Path | None:
        if not pkg or "/" in pkg or pkg in (".", ".."):
            return None
        for d in (*self.user_dirs, *self.ros_dirs):  # (a), (b)
            if (d / pkg).is_dir():
                return d / pkg
            if d.name == pkg:
                return d
            crawled = _crawl(d, pkg, CRAWL_DEPTH)
            if crawled is not None:
                return crawled
        for a in self.ancestors:  # (c): the file's own tree, nearest first
            if a.name == pkg or (a / pkg).is_dir():
                return a if a.name == pkg else a / pkg
        for a in self.ancestors:  # (d): a package.xml naming it
            if _package_name(a) == pkg:
                return a
        return None

    def not_found(self, pkg: str, named_in: str, how: str) -> str:
        """Message of a package not found, named in file ``named_in`` as ``how``."""
        looked_for = f" (looked for as {self.aliases[pkg]!r}: package_aliases)" if pkg in self.aliases else ""
        searched = [f"package_dirs {[str(d) for d in self.user_dirs]}"] if self.user_dirs else []
        searched.append(f"ROS_PACKAGE_PATH {[str(d) for d in self.ros_dirs]}" if self.ros_dirs
                        else "ROS_PACKAGE_PATH (not set)")
        if self.ancestors:
            searched.append(f"the folders above the file ({self.ancestors[0]} up to {self.ancestors[-1]}) and the "
                            "folders inside them, by name or by a package.xml naming it")
        return (f"package {pkg!r} not found{looked_for} (used as {how}), named in {named_in}; searched: "
                f"{'; '.join(searched)}. Give the folder that holds {pkg}/ with package_dirs=[...] (--package-dir DIR "
                f"on the command line) or ROS_PACKAGE_PATH, or, when it is shipped under another name, "
                f"package_aliases={{{pkg!r}: 'that_name'}} (--package-alias {pkg}=that_name)")
