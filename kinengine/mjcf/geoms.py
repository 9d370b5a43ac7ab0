"""A compiled MJCF model's geoms as URDF ``<visual>`` and ``<collision>`` elements of their body's link.

Visual: a geom whose group is 0, 1 or 2 (MuJoCo's viewer shows those by default; Menagerie puts
collision geoms in group 3) and whose colour is not fully transparent; drawn by the viewer. Collision: a
geom MuJoCo collides, i.e. with ``contype`` or ``conaffinity`` non-zero, whatever its group; the collision
queries (:mod:`kinengine.collision`) check it. Sphere, cylinder and box map to URDF one to one (MuJoCo's
sizes are radii and half-lengths); a capsule is drawn as a cylinder and two spheres and collided as a
``<capsule>`` (coal's Capsule, :mod:`kinengine.collision.geometry`);
a mesh is its file at the geom's pose times the inverse of the transform MuJoCo's compiler applied to
the file's vertices (``mesh_pos``/``mesh_quat``, after ``mesh_scale``), so the file's vertices land where
MuJoCo puts them; kinengine collides its convex hull, as MuJoCo does. Planes, height fields, ellipsoids
and SDFs have no URDF counterpart: not drawn, and a collision geom of one of those types is left out with
a warning naming it. Geoms of the world body are the scene, not the robot: left out (add obstacles with
:meth:`kinengine.Robot.with_obstacles`). Colours come from the geom's material, else the geom's ``rgba``.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np
import numpy.typing as npt

from ..model.editing import rpy_from_matrix
from .convert import pose_matrix, translation

SPHERE, CAPSULE, CYLINDER, BOX, MESH = 2, 3, 5, 6, 7  # mjtGeom
VISIBLE_GROUPS = (0, 1, 2)


def geom_elements(
    model: Any, body_links: dict[int, str], folder: Path, meshdir: str, source: str
) -> dict[str, list[str]]:
    """Link name -> its ``<visual>`` and ``<collision>`` elements (XML text), for the bodies in
    ``body_links`` (index -> link) other than the world body; a UserWarning naming the collision geoms
    left out (module doc)."""
    out: dict[str, list[str]] = {}
    left_out: list[str] = []
    for g in range(model.ngeom):
        body = int(model.geom_bodyid[g])
        if body == 0 or body not in body_links:
            continue
        material = int(model.geom_matid[g])
        rgba = model.mat_rgba[material] if material >= 0 else model.geom_rgba[g]
        visible = int(model.geom_group[g]) in VISIBLE_GROUPS and rgba[3] > 0
        collides = int(model.geom_contype[g]) != 0 or int(model.geom_conaffinity[g]) != 0
        if not (visible or collides):
            continue
        elements = out.setdefault(body_links[body], [])
        color = " ".join(repr(float(c)) for c in rgba)
        for pose, geometry in _shapes(model, g, folder, meshdir, capsule=False) if visible else ():
            paint = f'<material name=""><color rgba="{color}"/></material>'
            elements.append(f"<visual>{_origin(pose)}<geometry>{geometry}</geometry>{paint}</visual>")
        shapes = _shapes(model, g, folder, meshdir, capsule=True) if collides else []
        for pose, geometry in shapes:
            elements.append(f"<collision>{_origin(pose)}<geometry>{geometry}</geometry></collision>")
        if collides and not shapes:
            left_out.append(f"{_geom_name(model, g)} of body {body_links[body]!r}")
    if left_out:
        warnings.warn(
            f"{source}: {len(left_out)} collision geom{'s' if len(left_out) > 1 else ''} of a type kinengine "
            f"cannot collide (plane, height field, ellipsoid, SDF) left out: {', '.join(left_out)}",
            UserWarning,
            stacklevel=2,
        )
    return out


def _origin(pose: npt.NDArray[np.float64]) -> str:
    xyz = " ".join(repr(float(v)) for v in pose[:3, 3])
    return f'<origin xyz="{xyz}" rpy="{" ".join(repr(v) for v in rpy_from_matrix(pose[:3, :3]))}"/>'


def _shapes(
    model: Any, g: int, folder: Path, meshdir: str, capsule: bool
) -> list[tuple[npt.NDArray[np.float64], str]]:
    """(pose in the body frame, URDF ``<geometry>`` content) of geom ``g``; [] for a type URDF lacks. A
    capsule is a ``<capsule>`` if ``capsule``, else a cylinder and two spheres."""
    T = pose_matrix(model.geom_pos[g], model.geom_quat[g])
    size = [float(s) for s in model.geom_size[g]]
    kind = int(model.geom_type[g])
    if kind == SPHERE:
        return [(T, f'<sphere radius="{size[0]!r}"/>')]
    if kind == CAPSULE and capsule:
        return [(T, f'<capsule radius="{size[0]!r}" length="{2 * size[1]!r}"/>')]
    if kind in (CYLINDER, CAPSULE):
        ends = (-1.0, 1.0) if kind == CAPSULE else ()
        return [(T, f'<cylinder radius="{size[0]!r}" length="{2 * size[1]!r}"/>')] + [
            (T @ translation(np.array([0.0, 0.0, end * size[1]])), f'<sphere radius="{size[0]!r}"/>')
            for end in ends
        ]
    if kind == BOX:
        return [(T, f'<box size="{2 * size[0]!r} {2 * size[1]!r} {2 * size[2]!r}"/>')]
    if kind == MESH and int(model.geom_dataid[g]) >= 0:
        mesh = int(model.geom_dataid[g])
        start = int(model.mesh_pathadr[mesh])
        if start < 0:
            return []
        name = bytes(model.paths[start : model.paths.index(b"\0", start)]).decode("utf-8", "replace")
        path = _mesh_file(name, folder, meshdir)
        offset = pose_matrix(model.mesh_pos[mesh], model.mesh_quat[mesh])
        scale = " ".join(repr(float(s)) for s in model.mesh_scale[mesh])
        return [
            (T @ np.linalg.inv(offset), f"<mesh filename={quoteattr(str(path))} scale={quoteattr(scale)}/>")
        ]
    return []


def _geom_name(model: Any, g: int) -> str:
    start = int(model.name_geomadr[g])
    name = bytes(model.names[start : model.names.index(b"\0", start)]).decode("utf-8", "replace")
    return repr(name) if name else f"geom {g}"


def _mesh_file(name: str, folder: Path, meshdir: str) -> Path:
    """The mesh file MuJoCo read: its recorded path (MuJoCo 3.3+ records it with the model's folder and
    meshdir, relative to the working directory), else that path under meshdir, or under the model's folder."""
    candidates = [Path(name), folder / meshdir / name, folder / name]
    for candidate in candidates:
        if candidate.is_file():
            return candidate.resolve()
    return candidates[1]


__all__ = ["geom_elements"]
