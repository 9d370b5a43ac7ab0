"""Reading an MJCF file as untrusted input, then compiling it with MuJoCo's own compiler.

Before MuJoCo sees anything, the file and every file it includes are read once each and parsed
by kinengine's safe XML parser (:mod:`kinengine.urdf.safe_xml`: no DTD, no entity, bounded size, tags,
depth and attributes by :class:`~kinengine.urdf.Limits`); the total size and tag count of all of them
are bounded as one document's, and every asset file (mesh, texture, ...) must be a regular file within
``Limits.max_bytes``. MuJoCo compiles it through ``mujoco.MjSpec`` with ``<compiler boundmass
boundinertia>`` at :data:`KINEMATIC_BOUND` when the file leaves them unset, so a kinematics-only file
(bodies without geoms or inertials) compiles. The compiled model is then bounded too (bodies, joints,
coordinates).
MuJoCo's compiler errors become an :class:`~kinengine.errors.MJCFError` naming the file. MuJoCo is an
optional extra: ``pip install 'kinengine[mjcf]'``.
"""

from __future__ import annotations

import os
import re
import stat
from pathlib import Path
from typing import Any

from ..errors import MJCFError, URDFError
from ..urdf.limits import LIMITS, Limits
from ..urdf.safe_xml import parse_xml
from ..urdf.source import read_bytes_once

_PROLOG = re.compile(rb"<\?.*?\?>|<!--.*?-->", re.DOTALL)
_ROOT_TAG = re.compile(rb"<([A-Za-z_][\w.:-]*)")
MAX_INCLUDES = 256
"""Files one model may ``<include>`` (directly or not)."""
KINEMATIC_BOUND = 1e-12
"""[kg, kg·m²] ``<compiler boundmass boundinertia>`` when the file leaves them unset: a body without
geoms or ``<inertial>`` gets this mass and inertia, so kinematics-only files compile (poses do not
depend on mass)."""


def mujoco_module() -> Any:
    """The ``mujoco`` package, or an MJCFError naming the extra that installs it."""
    try:
        import mujoco
    except ImportError:
        raise MJCFError(
            "reading an MJCF (MuJoCo XML) model needs MuJoCo: pip install 'kinengine[mjcf]'"
        ) from None
    return mujoco


def is_mjcf(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` names an MJCF model: a name ending in .xml whose root element (the first start tag
    after the XML declaration and comments, in the first 64 KiB) is not ``<robot>``: a URDF may be
    called .xml. True for a .xml file that cannot be read: the MJCF reader names the problem."""
    if not os.fspath(path).lower().endswith(".xml"):
        return False
    try:
        with open(path, "rb") as f:
            head = f.read(1 << 16)
    except (OSError, ValueError):
        return True
    match = _ROOT_TAG.search(_PROLOG.sub(b"", head))
    return match is None or match.group(1) != b"robot"


def compile_mjcf(path: str | os.PathLike[str], *, limits: Limits = LIMITS) -> tuple[str, Any, str]:
    """(the path as text, MuJoCo's compiled ``MjModel``, the ``<compiler meshdir>`` or ``assetdir`` of the
    file or its includes, "" if none) of the MJCF file at ``path``; MJCFError (or URDFError for a missing
    or oversized file) naming the file otherwise."""
    source, data = read_bytes_once(path, limits)
    try:
        root = parse_xml(data, source=source, limits=limits)
    except MJCFError:
        raise
    except URDFError as exc:
        raise MJCFError(str(exc)) from None
    if root.tag != "mujoco":
        raise MJCFError(f"the root element is <{root.tag}>, expected <mujoco>", source=source)
    folder = Path(source).parent
    documents = _check_includes(root, folder, source, limits, len(data))
    dirs: dict[str, str] = {}
    bounds: set[str] = set()
    for document in documents:
        for compiler in document.iter("compiler"):
            dirs.update({k: v for k in ("assetdir", "meshdir", "texturedir") if (v := compiler.get(k))})
            bounds.update(k for k in ("boundmass", "boundinertia") if compiler.get(k) is not None)
    meshdir = dirs.get("meshdir", dirs.get("assetdir", ""))
    _check_asset_files(documents, folder, dirs, source, limits)
    mujoco = mujoco_module()
    try:
        spec = mujoco.MjSpec.from_file(source)
        for name in {"boundmass", "boundinertia"} - bounds:
            setattr(spec.compiler, name, KINEMATIC_BOUND)
        model = spec.compile()
    except Exception as exc:  # MuJoCo raises ValueError with the compiler's message (element, line)
        message = " ".join(str(exc).split())
        raise MJCFError(
            f"MuJoCo's compiler refused the model: {message}{_hint(message, bounds)}", source=source
        ) from None
    _check_size(model, source, limits)
    return source, model, meshdir


def _hint(message: str, bounds: set[str]) -> str:
    """The fix for the compiler errors a kinematics-only file meets ("" for others)."""
    if "mass and inertia" in message:
        if bounds:
            settings = " and ".join(sorted(bounds))
            return (
                f"; the file sets <compiler> {settings}: remove it (kinengine then bounds the mass and "
                "inertia of bodies without geoms at 1e-12) or give each moving body an <inertial> or a <geom>"
            )
        return "; give each moving body an <inertial> or a <geom>"
    return ""


def _check_includes(root: Any, folder: Path, source: str, limits: Limits, size: int) -> list[Any]:
    """``root`` and every document it includes, transitively, read and parsed safely; the files
    together within ``limits.max_bytes`` and ``limits.max_tags``; at most MAX_INCLUDES of them."""
    documents = [root]
    pending = [(root, source)]
    seen = 0
    tags = int(root.xpath("count(//*)"))
    while pending:
        element, where = pending.pop()
        for include in element.iter("include"):
            name = include.get("file")
            if not name:
                raise MJCFError("<include> has no file attribute", source=where, line=include.sourceline)
            seen += 1
            if seen > MAX_INCLUDES:
                raise MJCFError(f"the model includes more than {MAX_INCLUDES} files", source=source)
            included, data = read_bytes_once(folder / name, limits)
            size += len(data)
            if size > limits.max_bytes:
                raise MJCFError(
                    f"the model and its includes are {size} bytes or more, more than Limits.max_bytes = "
                    f"{limits.max_bytes}",
                    source=source,
                )
            try:
                sub = parse_xml(data, source=included, limits=limits)
            except URDFError as exc:
                raise MJCFError(str(exc)) from None
            tags += int(sub.xpath("count(//*)"))
            if tags > limits.max_tags:
                raise MJCFError(
                    f"the model and its includes have more than Limits.max_tags = {limits.max_tags} elements",
                    source=source,
                )
            pending.append((sub, included))
            documents.append(sub)
    return documents


def _check_asset_files(
    documents: list[Any], folder: Path, dirs: dict[str, str], source: str, limits: Limits
) -> None:
    """Every file an asset names (mesh, texture, height field, skin, ...) that exists is a regular file of
    at most ``limits.max_bytes``: MuJoCo reads each whole, so /dev/zero or a FIFO would never end."""
    for document in documents:
        for element in document.iter():
            name = element.get("file") if element.tag != "include" else None
            if not name:
                continue
            kind = "texturedir" if element.tag in ("texture", "hfield") else "meshdir"
            base = dirs.get(kind, dirs.get("assetdir", ""))
            for candidate in (folder / base / name, folder / name):
                try:
                    info = os.stat(candidate)
                except (OSError, ValueError):
                    continue
                if not stat.S_ISREG(info.st_mode):
                    raise MJCFError(
                        f"<{element.tag} file={name!r}> is not a regular file",
                        source=source,
                        line=element.sourceline,
                    )
                if info.st_size > limits.max_bytes:
                    raise MJCFError(
                        f"<{element.tag} file={name!r}> is {info.st_size} bytes, more than "
                        f"Limits.max_bytes = {limits.max_bytes}",
                        source=source,
                        line=element.sourceline,
                    )
                break


def _check_size(model: Any, source: str, limits: Limits) -> None:
    """The compiled model within the limits a URDF must respect (bodies as links, joints, coordinates)."""
    for count, limit, what in (
        (model.nbody + model.nsite, limits.max_links, "links"),
        (model.njnt + model.nbody + model.nsite, limits.max_joints, "joints"),
        (model.njnt, limits.max_movable_joints, "movable_joints"),
    ):
        if count > limit:
            raise MJCFError(
                f"the model makes {count} {what.replace('_', ' ')} (bodies, sites and joints), more than "
                f"Limits.max_{what} = {limit}; pass load(..., limits=Limits(max_{what}=...)) to allow more",
                source=source,
            )


__all__ = ["KINEMATIC_BOUND", "MAX_INCLUDES", "compile_mjcf", "is_mjcf", "mujoco_module"]
