"""What the browser viewer draws, computed without a browser: visuals, skeleton, slider ranges, camera.

Owns reading a robot's ``<visual>`` elements (yourdfpy parses the URDF text; trimesh reads STL, DAE and
OBJ meshes found through ``package://`` / ``file://`` / relative file names, see
:func:`kinengine.urdf.packages.resolve_uri`), the skeleton segments, the coordinate slider ranges and the
initial camera. Everything is in the root link frame I (Pinocchio's "world") or in a link frame,
lengths in m. Link poses always come from kinengine (``robot.frame_pose``), never from yourdfpy.
A mesh that cannot be found or read is dropped (the link keeps its skeleton) and reported in
:attr:`Visuals.failures`; :mod:`.viewer` turns those into one warning per load.
"""

from __future__ import annotations

import io
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from ..errors import KinematicsError
from ..urdf.packages import resolve_uri

if TYPE_CHECKING:
    from ..control.robot_like import RobotLike

DEFAULT_COLOR = (170, 170, 180)
"""RGB of a visual whose URDF gives no material colour."""
UNBOUNDED_PRISMATIC = 1.0
"""Slider half-range [m] of a prismatic coordinate without limits (continuous joints get ±π rad)."""


@dataclass(frozen=True)
class Visual:
    """One ``<visual>`` of a link: ``origin`` T_LV (4, 4) in the link frame L [m].

    ``kind`` is "box" (``size`` (3,) [m]), "cylinder" (``size`` = (radius, length) [m], axis z),
    "sphere" (``size`` = (radius,) [m]) or "mesh" (``mesh``: a trimesh.Trimesh already scaled, in V).
    ``color``: RGB 0..255 from the URDF material (None: the mesh's own colours or DEFAULT_COLOR).
    """

    kind: str
    origin: np.ndarray
    size: tuple[float, ...] = ()
    mesh: Any = None
    color: tuple[int, int, int] | None = None


@dataclass
class Visuals:
    """Visuals per link name, the meshes that could not be used: (file name, reason), and why no
    visual at all could be read (``error``, None if they could)."""

    links: dict[str, list[Visual]] = field(default_factory=dict)
    failures: list[tuple[str, str]] = field(default_factory=list)
    error: str | None = None


def read_visuals(
    urdf_text: str,
    source: str,
    *,
    meshes: bool = True,
    packages: Mapping[str, str | os.PathLike] | None = None,
) -> Visuals:
    """The visuals of every link of ``urdf_text``; ``source`` (a file path or "<string>") anchors relative
    file names and ``package://`` searches, ``packages`` maps ROS package names to folders (see
    :func:`kinengine.urdf.packages.resolve_uri`). ``meshes=False`` skips mesh files (primitives only)."""
    import yourdfpy

    from ..reference.tree import plain_urdf

    try:
        urdf = yourdfpy.URDF.load(  # no <collision>: drawn from coal shapes; yourdfpy refuses <capsule>
            io.BytesIO(plain_urdf(urdf_text, source=source, leave_out=("collision",))),
            build_scene_graph=False,
            load_meshes=False,
            build_collision_scene_graph=False,
            load_collision_meshes=False,
        )
    except Exception as exc:  # yourdfpy reports bad attributes with assorted builtin errors
        return Visuals(error=f"yourdfpy could not read them: {type(exc).__name__}: {exc}")
    named = {m.name: _rgb(m) for m in (urdf.robot.materials or []) if m.name}
    start = None if source.startswith("<") else Path(source)
    out = Visuals()
    for link in urdf.robot.links:
        for visual in link.visuals or ():
            origin = np.eye(4) if visual.origin is None else np.asarray(visual.origin, dtype=float)
            color = _rgb(visual.material) if visual.material is not None else None
            if color is None and visual.material is not None:
                color = named.get(visual.material.name)
            g = visual.geometry
            if g.box is not None:
                item = Visual("box", origin, tuple(float(s) for s in g.box.size), color=color)
            elif g.cylinder is not None:
                item = Visual(
                    "cylinder", origin, (float(g.cylinder.radius), float(g.cylinder.length)), color=color
                )
            elif g.sphere is not None:
                item = Visual("sphere", origin, (float(g.sphere.radius),), color=color)
            elif g.mesh is not None and meshes:
                mesh, reason = _load_mesh(g.mesh.filename, g.mesh.scale, start, packages)
                if mesh is None:
                    out.failures.append((g.mesh.filename, reason))
                    continue
                item = Visual("mesh", origin, mesh=mesh, color=color)
            else:
                continue
            out.links.setdefault(link.name, []).append(item)
    return out


def _rgb(material: object) -> tuple[int, int, int] | None:
    color = getattr(material, "color", None)
    rgba = getattr(color, "rgba", None)
    if rgba is None:
        return None
    r, g, b = (round(255 * min(max(float(c), 0.0), 1.0)) for c in list(rgba)[:3])
    return (r, g, b)


def _load_mesh(
    filename: str, scale: object, start: Path | None, packages: Mapping[str, str | os.PathLike] | None
) -> tuple[object, str]:
    """(trimesh.Trimesh scaled, "") or (None, why not)."""
    import trimesh

    try:
        path = resolve_uri(filename, packages=packages, start=start)
    except KinematicsError as exc:
        return None, str(exc)
    if not path.is_file():
        return None, f"no such file {str(path)!r}"
    try:
        loaded = trimesh.load(path, force=None)
        mesh = loaded.to_geometry() if isinstance(loaded, trimesh.Scene) else loaded
    except Exception as exc:  # trimesh and its format readers raise assorted errors on bad files
        return None, f"trimesh could not read {str(path)!r}: {type(exc).__name__}: {exc}"
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        return None, f"{str(path)!r} holds no triangles"
    if scale is not None:
        s = np.broadcast_to(np.asarray(scale, dtype=float), (3,))
        mesh.apply_transform(np.diag([*s, 1.0]))
    return mesh, ""


def link_poses(robot: RobotLike, q: np.ndarray, links: tuple[str, ...]) -> dict[str, np.ndarray]:
    """T_IL (4, 4) [m] of each link at q (dof,), from kinengine's forward kinematics."""
    return {name: robot.frame_pose(q, name) for name in links}


def skeleton(robot: RobotLike, poses: dict[str, np.ndarray]) -> npt.NDArray[np.float64]:
    """(M, 2, 3) [m]: parent link origin -> child link origin of every URDF joint (fixed ones included)."""
    segments = [(poses[j.parent][:3, 3], poses[j.child][:3, 3]) for j in robot.description.joints]
    return np.array(segments, dtype=float).reshape(-1, 2, 3)


def slider_ranges(robot: RobotLike) -> list[tuple[float, float]]:
    """(min, max) per coordinate [rad or m]: the joint limits; ±π for a continuous joint,
    ±UNBOUNDED_PRISMATIC for a prismatic joint without limits."""
    kinds = {j.name: j.type for j in robot.description.joints}
    out = []
    for name, lo, hi in zip(robot.joint_names, robot.lower_limits, robot.upper_limits, strict=True):
        half = UNBOUNDED_PRISMATIC if kinds.get(name) == "prismatic" else math.pi
        out.append((float(lo) if np.isfinite(lo) else -half, float(hi) if np.isfinite(hi) else half))
    return out


def camera(points: np.ndarray, fov: float) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """(position, look_at) [m] of a camera with vertical field of view ``fov`` [rad] that sees
    ``points`` (N, 3) whole, from the direction (1.6, 1.0, 0.9) (in front of +x, to the left, above), z up.
    The points sit left of the image centre, clear of the control panel on the right."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    low, high = points.min(axis=0), points.max(axis=0)
    center = 0.5 * (low + high)
    radius = max(float(np.linalg.norm(high - low)) / 2.0, 0.05)
    direction = np.array([1.6, 1.0, 0.9])
    direction /= np.linalg.norm(direction)
    distance = 1.8 * radius / math.sin(fov / 2.0)
    right = np.cross(-direction, [0.0, 0.0, 1.0])
    look_at = center + right / np.linalg.norm(right) * 0.4 * distance * math.tan(fov / 2.0)
    return look_at + distance * direction, look_at


def project(
    points: np.ndarray, position: np.ndarray, look_at: np.ndarray, fov: float, width: int, height: int
) -> npt.NDArray[np.float64]:
    """Pixel (column, row) (N, 2) of points (N, 3) [m] for a pinhole camera at ``position`` looking at
    ``look_at`` with z up and vertical field of view ``fov`` [rad] (three.js' PerspectiveCamera)."""
    forward = np.asarray(look_at, float) - np.asarray(position, float)
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    rel = np.asarray(points, float).reshape(-1, 3) - np.asarray(position, float)
    depth = rel @ forward
    f = (height / 2.0) / math.tan(fov / 2.0)
    return np.stack([width / 2.0 + f * (rel @ right) / depth, height / 2.0 - f * (rel @ up) / depth], axis=1)


def wxyz(C: np.ndarray) -> npt.NDArray[np.float64]:
    """Unit quaternion (w, x, y, z), w >= 0, of a rotation matrix C (3, 3) (scipy's Rotation)."""
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(C).as_quat()
    return np.array([w, x, y, z]) if w >= 0 else -np.array([w, x, y, z])


def node_name(name: str) -> str:
    """A scene-tree name for a link or frame name (characters other than letters, digits, _-. become _)."""
    return "".join(c if c.isalnum() or c in "_-." else "_" for c in name)


def unit_sphere() -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Vertices (V, 3) float32 and faces (F, 3) uint32 of a unit icosphere (the ellipsoid's template)."""
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=3)
    return np.asarray(sphere.vertices, dtype=np.float32), np.asarray(sphere.faces, dtype=np.uint32)


__all__ = [
    "DEFAULT_COLOR",
    "UNBOUNDED_PRISMATIC",
    "Visual",
    "Visuals",
    "camera",
    "link_poses",
    "node_name",
    "project",
    "read_visuals",
    "skeleton",
    "slider_ranges",
    "unit_sphere",
    "wxyz",
]
