"""Pinocchio's GeometryModel of a robot's ``<collision>`` elements, placed with kinengine's own model.

The URDF text is the one the Robot was loaded from (edited alike by ``locked`` / ``with_frame``), its link
names are the frames of kinengine's Pinocchio model (:mod:`kinengine.model.pinocchio_model`: one joint per
movable URDF joint, mimic joints included; locked joints are fixed ones), so ``pin.buildGeomFromUrdfString``
on that model hangs each shape on the right joint, and kinengine's q maps to Pinocchio's q as everywhere else
(q_pin = M q + b, :mod:`kinengine.model.coordinates`). Mesh file names go through kinengine's package
resolution (:func:`kinengine.urdf.packages.resolve_uri`, as the viewer's) before Pinocchio reads them; a
missing file is a URDFError naming every missing file. Primitives (box, cylinder, sphere) are kept as they
are; ``<capsule radius length>`` (not in the URDF standard, but written by Drake's and Gazebo's users and by
kinengine's MJCF reader: the axis is z, ``length`` the cylinder's) becomes coal's Capsule (Pinocchio's
URDF reader knows no capsule: it stands as a cylinder there until the build is done); any other element
in a ``<geometry>`` is a URDFError naming the link (Pinocchio would drop the link's collisions silently);
meshes are replaced by their convex hulls (coal's qhull), as MuJoCo does for collisions: distances are
then signed (penetration depth by EPA), continuous in q, and several times faster than mesh-to-mesh queries.
A concave collision mesh is thereby made conservative (its hull).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import MappingProxyType

import coal
import pinocchio as pin
from lxml import etree

from ..errors import OptionError, URDFError
from ..model.stack import call_with_big_stack, stack_for_depth, stack_needed
from ..urdf.packages import resolve_uri
from ..urdf.safe_xml import parse_xml
from .shapes import Obstacle, convex_hull

SHAPES = ("box", "cylinder", "sphere", "mesh", "capsule")
"""The elements a collision ``<geometry>`` may hold."""


def collision_xml(
    urdf_text: str, source: str, packages: Mapping[str, str] | None
) -> tuple[str, dict[str, tuple[float, float]]]:
    """(``urdf_text`` with every ``<collision>`` mesh file name resolved to an absolute path, every capsule a
    cylinder and the ``<visual>`` elements dropped (Pinocchio would read their meshes too), the name
    Pinocchio gives each capsule's GeometryObject -> (radius, length) [m]); URDFError naming every missing
    collision mesh, or a geometry Pinocchio cannot read."""
    root = parse_xml(urdf_text, source=source)
    start = None if source in ("", "<string>") else Path(source)
    missing: list[str] = []
    capsules: dict[str, tuple[float, float]] = {}
    for link in root.iter("link"):
        for visual in link.findall("visual"):
            link.remove(visual)
        for k, collision in enumerate(link.iterfind("collision")):
            geometry = collision.find("geometry")
            shapes = [] if geometry is None else [child for child in geometry if isinstance(child.tag, str)]
            if len(shapes) != 1 or shapes[0].tag not in SHAPES:
                raise URDFError(
                    f"a <collision> of link {link.get('name')!r} holds {[s.tag for s in shapes]} in its "
                    f"<geometry>; it takes one of {', '.join(SHAPES)}",
                    source=source,
                )
            if shapes[0].tag == "capsule":
                shapes[
                    0
                ].tag = "cylinder"  # a stand-in of the same radius and length, replaced after the build
                capsules[f"{link.get('name')}_{k}"] = _capsule_size(shapes[0], link.get("name"), source)
        for mesh in link.iterfind("collision/geometry/mesh"):
            name = mesh.get("filename") or ""
            try:
                path = resolve_uri(name, packages=packages, start=start)
            except URDFError as exc:
                missing.append(f"{name!r} of link {link.get('name')!r} ({exc})")
                continue
            if not path.is_file():
                missing.append(f"{name!r} of link {link.get('name')!r} (looked for {str(path)!r})")
            mesh.set("filename", str(path))
    if missing:
        raise URDFError(
            f"{len(missing)} collision mesh file{'s' if len(missing) > 1 else ''} not found: "
            + "; ".join(missing)
            + "; pass packages={'<package>': '/path/to/it'} or fix the file names",
            source=source,
        )
    return etree.tostring(root, encoding="unicode"), capsules


def _capsule_size(element: etree._Element, link: str | None, source: str) -> tuple[float, float]:
    try:
        radius, length = float(element.get("radius", "")), float(element.get("length", ""))
    except ValueError:
        radius = length = math.nan
    if not (math.isfinite(radius) and math.isfinite(length) and radius > 0 and length >= 0):
        raise URDFError(
            f"the <capsule> of link {link!r} needs radius > 0 and length >= 0 [m], got radius="
            f"{element.get('radius')!r} length={element.get('length')!r}",
            source=source,
        )
    return radius, length


def build_collision_geometry(
    model: pin.Model,
    urdf_text: str,
    source: str,
    packages: Mapping[str, str] | None = None,
    obstacles: Sequence[Obstacle] = (),
) -> pin.GeometryModel:
    """Pinocchio's GeometryModel of the ``<collision>`` elements on ``model`` (kinengine's Pinocchio model
    of the same URDF), meshes as convex hulls (module doc), then the ``obstacles`` fixed to the universe
    (named ``obstacle_<k>`` unless they have a name). No collision pairs are set."""
    xml, capsules = collision_xml(urdf_text, source, packages)
    depth = len(model.frames)
    try:
        geometry = call_with_big_stack(
            lambda: pin.buildGeomFromUrdfString(model, xml, pin.GeometryType.COLLISION),
            stack_for_depth(depth),
            stack_needed(depth),
        )
    except Exception as exc:  # Pinocchio reports with ValueError/RuntimeError text
        raise URDFError(f"Pinocchio could not build the collision geometry: {exc}", source=source) from None
    for obj in geometry.geometryObjects:
        if isinstance(obj.geometry, coal.BVHModelBase):
            obj.geometry = convex_hull(obj.geometry, obj.meshPath)
        elif obj.name in capsules:
            radius, length = capsules[obj.name]
            obj.geometry = coal.Capsule(radius, length)
    taken = {obj.name for obj in geometry.geometryObjects}
    for k, obstacle in enumerate(obstacles):
        name = obstacle.name or f"obstacle_{k}"
        if name in taken:
            raise URDFError(f"obstacle name {name!r} is taken by another collision shape; rename it")
        taken.add(name)
        geometry.addGeometryObject(obstacle.geometry_object(name))
    return geometry


__all__ = ["build_collision_geometry", "collision_xml"]


def checked_packages(packages: object) -> Mapping[str, str]:
    """``packages`` of ``Robot.collision_geometry`` (ROS package name -> folder) as a read-only mapping."""
    if not (
        isinstance(packages, Mapping)
        and all(isinstance(k, str) and isinstance(v, (str, os.PathLike)) for k, v in packages.items())
    ):
        raise OptionError(
            f"packages maps ROS package names to folders, e.g. {{'my_pkg': '/path/to/my_pkg'}}, got "
            f"{type(packages).__name__}"
        )
    return MappingProxyType({k: os.fspath(v) for k, v in packages.items()})
