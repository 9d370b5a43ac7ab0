"""The visible geoms of a compiled MJCF model as URDF ``<visual>`` elements, for the viewer.

A geom is visible when its group is 0, 1 or 2 (MuJoCo's viewer shows those by default; Menagerie puts
collision geoms in group 3) and its colour is not fully transparent. Sphere, cylinder and box map to
URDF one to one (MuJoCo's sizes are radii and half-lengths); a capsule is a cylinder and two spheres;
a mesh is its file at the geom's pose times the inverse of the
transform MuJoCo's compiler applied to the file's vertices (``mesh_pos``/``mesh_quat``, after
``mesh_scale``), so the file's vertices land where MuJoCo draws them. Planes, height fields and
ellipsoids are not drawn. Colours come from the geom's material, else the geom's ``rgba``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np
import numpy.typing as npt

from ..model.editing import rpy_from_matrix
from .convert import pose_matrix, translation

SPHERE, CAPSULE, CYLINDER, BOX, MESH = 2, 3, 5, 6, 7  # mjtGeom
VISIBLE_GROUPS = (0, 1, 2)


def visual_elements(
    model: Any, body_links: dict[int, str], folder: Path, meshdir: str
) -> dict[str, list[str]]:
    """Link name -> its ``<visual>`` elements (XML text), for the bodies in ``body_links`` (index -> link)."""
    out: dict[str, list[str]] = {}
    for g in range(model.ngeom):
        body = int(model.geom_bodyid[g])
        if body not in body_links or int(model.geom_group[g]) not in VISIBLE_GROUPS:
            continue
        material = int(model.geom_matid[g])
        rgba = model.mat_rgba[material] if material >= 0 else model.geom_rgba[g]
        if rgba[3] <= 0:
            continue
        T = pose_matrix(model.geom_pos[g], model.geom_quat[g])
        size = [float(s) for s in model.geom_size[g]]
        kind = int(model.geom_type[g])
        shapes: list[tuple[npt.NDArray[np.float64], str]] = []
        if kind == SPHERE:
            shapes.append((T, f'<sphere radius="{size[0]!r}"/>'))
        elif kind in (CYLINDER, CAPSULE):
            shapes.append((T, f'<cylinder radius="{size[0]!r}" length="{2 * size[1]!r}"/>'))
            for end in (-1.0, 1.0) if kind == CAPSULE else ():
                shapes.append(
                    (T @ translation(np.array([0.0, 0.0, end * size[1]])), f'<sphere radius="{size[0]!r}"/>')
                )
        elif kind == BOX:
            shapes.append((T, f'<box size="{2 * size[0]!r} {2 * size[1]!r} {2 * size[2]!r}"/>'))
        elif kind == MESH and int(model.geom_dataid[g]) >= 0:
            mesh = int(model.geom_dataid[g])
            start = int(model.mesh_pathadr[mesh])
            if start < 0:
                continue
            name = bytes(model.paths[start : model.paths.index(b"\0", start)]).decode("utf-8", "replace")
            path = _mesh_file(name, folder, meshdir)
            offset = pose_matrix(model.mesh_pos[mesh], model.mesh_quat[mesh])
            scale = " ".join(repr(float(s)) for s in model.mesh_scale[mesh])
            element = f"<mesh filename={quoteattr(str(path))} scale={quoteattr(scale)}/>"
            shapes.append((T @ np.linalg.inv(offset), element))
        color = " ".join(repr(float(c)) for c in rgba)
        for pose, geometry in shapes:
            xyz = " ".join(repr(float(v)) for v in pose[:3, 3])
            rpy = " ".join(repr(v) for v in rpy_from_matrix(pose[:3, :3]))
            out.setdefault(body_links[body], []).append(
                f'<visual><origin xyz="{xyz}" rpy="{rpy}"/><geometry>{geometry}</geometry>'
                f'<material name=""><color rgba="{color}"/></material></visual>'
            )
    return out


def _mesh_file(name: str, folder: Path, meshdir: str) -> Path:
    """The mesh file MuJoCo read: its recorded path (MuJoCo 3.3+ records it with the model's folder and
    meshdir, relative to the working directory), else that path under meshdir, or under the model's folder."""
    candidates = [Path(name), folder / meshdir / name, folder / name]
    for candidate in candidates:
        if candidate.is_file():
            return candidate.resolve()
    return candidates[1]


__all__ = ["visual_elements"]
