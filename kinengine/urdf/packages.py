"""Where a ROS package is on disk, found without a ROS installation.

Owns ``$(find pkg)`` (used by :mod:`.xacro`) and ``package://`` / ``file://``
URIs (used for meshes): :func:`resolve_package` and :func:`resolve_uri`. The
search order is an explicit ``packages=`` mapping, then ``ROS_PACKAGE_PATH``,
then the folders above the file being read. A ``package.xml`` is only
scanned for its ``<name>`` with a regular expression, never parsed as XML.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from pathlib import Path
from urllib.parse import unquote, urlsplit

from ..errors import URDFError
from .limits import Limits
from .source import read_bytes_once

SEARCH_DEPTH = 3  # folder levels below each ROS_PACKAGE_PATH root that are searched
_MANIFEST_LIMITS = Limits(max_bytes=1 << 20)  # a larger package.xml is not read
_VALID_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*")
_COMMENT = re.compile(rb"<!--.*?-->", re.DOTALL)
_NAME = re.compile(rb"<name>\s*([^<\s]+)\s*</name>")


def resolve_package(
    name: str, *, packages: Mapping[str, str | os.PathLike[str]] | None = None, start: Path | None = None
) -> Path:
    """The absolute folder of ROS package ``name``; URDFError (one line) if it is nowhere.

    Searched in order: (1) ``packages[name]``, which must be an existing folder;
    (2) each root of the ``ROS_PACKAGE_PATH`` environment variable (``os.pathsep``
    separated): the root itself if its ``package.xml`` names ``name``, else the
    folders up to :data:`SEARCH_DEPTH` levels below it, a folder whose
    ``package.xml`` names ``name`` first, a folder called ``name`` otherwise
    (no search descends into a package); (3) walking up from ``start`` (a folder,
    or a file whose folder is used): the nearest folder whose ``package.xml``
    names ``name``, is called ``name``, or has a subfolder called ``name``.
    """
    if not isinstance(name, str) or not _VALID_NAME.fullmatch(name) or name in (".", ".."):
        raise URDFError(f"{name!r} is not a ROS package name (letters, digits, '_', '-', '.')")
    if packages is not None and name in packages:
        path = Path(os.path.abspath(os.path.expanduser(os.fspath(packages[name]))))
        if not path.is_dir():
            raise URDFError(f"packages= maps ROS package {name!r} to {str(path)!r}, which is not a folder")
        return path
    roots = [r for r in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if r]
    for root in roots:
        found = _search_root(Path(root).expanduser(), name)
        if found is not None:
            return found
    here = None if start is None else Path(os.path.abspath(start))
    if here is not None:
        if not here.is_dir():
            here = here.parent
        for folder in (here, *here.parents):
            if _package_name(folder) == name or folder.name == name:
                return folder
            if (folder / name).is_dir():
                return folder / name
    searched = [
        f"packages= ({', '.join(map(repr, packages)) if packages else 'empty'})",
        f"ROS_PACKAGE_PATH ({os.pathsep.join(roots) if roots else 'unset'})",
        f"the folders above {str(here)!r}" if here is not None else "no file's folders (no start)",
    ]
    raise URDFError(
        f"ROS package {name!r} not found; searched {', '.join(searched)}; pass "
        f"packages={{{name!r}: '/path/to/{name}'}} (CLI: --package {name}=/path/to/{name}) "
        "or add its parent folder to ROS_PACKAGE_PATH"
    )


def resolve_uri(
    uri: str, *, packages: Mapping[str, str | os.PathLike[str]] | None = None, start: Path | None = None
) -> Path:
    """The absolute path a URDF/xacro file name points to; URDFError (one line) otherwise.

    ``package://pkg/rel/path`` is ``resolve_package(pkg, packages=, start=) / rel/path`` with symbolic
    links resolved, which must stay inside the package's folder (``..``, ``%2e%2e`` or a link that
    leads out of it is refused);
    ``file:///abs/path`` (or ``file://localhost/...``) is that path, percent-decoded;
    a plain path is taken relative to ``start`` (a folder, or a file whose folder is
    used; the current directory without one). The file itself need not exist.
    """
    if not isinstance(uri, str) or not uri:
        raise URDFError(f"expected a file name or URI, got {uri!r}")
    parts = urlsplit(uri)
    if parts.scheme == "package":
        rel = parts.path.lstrip("/")
        if not parts.netloc or not rel:
            raise URDFError(f"{uri!r} is not a package URI: expected package://<package>/<path in it>")
        return _inside(resolve_package(parts.netloc, packages=packages, start=start), unquote(rel), uri)
    if parts.scheme == "file":
        if parts.netloc not in ("", "localhost"):
            raise URDFError(f"{uri!r} names a remote host: only local file:// URIs are read")
        return Path(os.path.abspath(unquote(parts.path)))
    if len(parts.scheme) > 1:  # one letter: a Windows drive
        raise URDFError(
            f"{uri!r}: unsupported URI scheme {parts.scheme!r}; use package://, file:// or a path"
        )
    base = Path.cwd() if start is None else Path(os.path.abspath(start))
    if start is not None and not base.is_dir():
        base = base.parent
    return Path(os.path.abspath(base / uri))


def _inside(root: Path, rel: str, uri: str) -> Path:
    """``root / rel`` with symbolic links resolved; URDFError naming ``uri`` if it is not inside ``root``."""
    try:
        base = root.resolve()
        target = (base / rel).resolve()
    except (OSError, ValueError, RuntimeError) as exc:  # ValueError: NUL; RuntimeError: a link loop
        raise URDFError(f"{uri!r} cannot be resolved: {exc}") from None
    if target != base and base not in target.parents:
        raise URDFError(
            f"{uri!r} leads out of the folder of its package ({str(base)!r}) through '..' or a symbolic "
            "link: package:// URIs may only name files inside the package"
        )
    return target


def _package_name(folder: Path) -> str | None:
    """The ``<name>`` in ``folder/package.xml`` (comments skipped), None without one or when it is not
    a regular file (opened without blocking: a FIFO there cannot hang the search) or over 1 MiB."""
    try:
        _, data = read_bytes_once(folder / "package.xml", _MANIFEST_LIMITS)
    except URDFError:
        return None
    text = _COMMENT.sub(b"", data)
    found = _NAME.search(text)
    return found.group(1).decode("utf-8", "replace") if found else None


def _search_root(root: Path, name: str) -> Path | None:
    """Breadth-first, SEARCH_DEPTH levels; a package.xml naming ``name`` wins over a folder so called."""
    if _package_name(root) == name:
        return Path(os.path.abspath(root))
    by_folder_name = None
    level = [root]
    for _ in range(SEARCH_DEPTH):
        below = []
        for folder in level:
            try:
                children = sorted(
                    e.path for e in os.scandir(folder) if e.is_dir() and not e.name.startswith(".")
                )
            except OSError:
                continue
            for child in map(Path, children):
                package = _package_name(child)
                if package == name:
                    return Path(os.path.abspath(child))
                if by_folder_name is None and child.name == name:
                    by_folder_name = Path(os.path.abspath(child))
                if package is None and not (child / "CATKIN_IGNORE").exists():
                    below.append(child)
        level = below
    return by_folder_name
