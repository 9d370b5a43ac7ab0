"""The viewer's collision layer: the robot's collision shapes and obstacles, drawn on demand and coloured by
contact (red: the shape is in a colliding pair at the shown q; green otherwise).

Owns turning coal shapes into triangle meshes (boxes, spheres, cylinders, capsules with trimesh's primitives;
convex hulls from their points) and placing them at their poses in the root link frame I after one collision
pass (:meth:`kinengine.collision.CollisionChecker.colliding_pairs`). Imported by :mod:`.viewer` only when
``show_collisions`` is called.
"""

from __future__ import annotations

from typing import Any

import coal
import numpy as np
import trimesh

from ..collision import CollisionChecker
from . import viewer_scene as scene

FREE, HIT = (60, 180, 90), (220, 30, 30)
ROOT = "/collisions"


def shape_mesh(shape: coal.CollisionGeometry) -> trimesh.Trimesh | None:
    """A triangle mesh of a coal shape in its own frame [m] (None for a kind not drawn)."""
    if isinstance(shape, coal.Box):
        return trimesh.creation.box(extents=2.0 * np.asarray(shape.halfSide))
    if isinstance(shape, coal.Sphere):
        return trimesh.creation.icosphere(subdivisions=2, radius=shape.radius)
    if isinstance(shape, coal.Capsule):
        return trimesh.creation.capsule(height=2.0 * shape.halfLength, radius=shape.radius)
    if isinstance(shape, coal.Cylinder):
        return trimesh.creation.cylinder(radius=shape.radius, height=2.0 * shape.halfLength)
    if isinstance(shape, coal.ConvexBase):
        return trimesh.convex.convex_hull(np.asarray(shape.points()))
    return None


class CollisionLayer:
    """Scene nodes of every collision shape; :meth:`update` places and colours them at q."""

    def __init__(self, server: Any, checker: CollisionChecker) -> None:
        self.checker = checker
        self.nodes: dict[int, tuple[Any, Any]] = {}  # shape index -> (free node, hit node)
        for i, obj in enumerate(checker.geometry.geometryObjects):
            mesh = shape_mesh(obj.geometry)
            if mesh is None:
                continue
            v, f = np.asarray(mesh.vertices), np.asarray(mesh.faces)
            name = f"{ROOT}/{i}_{obj.name}"
            free = server.scene.add_mesh_simple(f"{name}/free", v, f, color=FREE, opacity=0.5)
            hit = server.scene.add_mesh_simple(f"{name}/hit", v, f, color=HIT, opacity=0.8, visible=False)
            self.nodes[i] = (free, hit)
        self.colliding: list[tuple[str, str]] = []

    def update(self, q: np.ndarray) -> None:
        """Place every shape at q and colour the shapes of colliding pairs; :attr:`colliding` names them."""
        hit = self.checker.colliding_pairs(q)
        _, gdata = self.checker.data()
        touched = {i for k in np.flatnonzero(hit) for i in self.checker.index_pairs[int(k)]}
        self.colliding = [self.checker.links[int(k)] for k in np.flatnonzero(hit)]
        for i, (free, red) in self.nodes.items():
            T = gdata.oMg[i]
            for node in (free, red):
                node.position, node.wxyz = np.asarray(T.translation), scene.wxyz(np.asarray(T.rotation))
            red.visible, free.visible = i in touched, i not in touched

    def remove(self) -> None:
        for free, hit in self.nodes.values():
            free.remove()
            hit.remove()
        self.nodes.clear()


__all__ = ["CollisionLayer", "shape_mesh"]
