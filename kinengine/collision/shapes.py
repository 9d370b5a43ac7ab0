"""Obstacles in the world: boxes, spheres, capsules and meshes, each at a fixed pose in the root link frame I.

A shape is a frozen value (it pickles with the Robot that holds it); :meth:`Obstacle.geometry_object`
turns it into Pinocchio's GeometryObject fixed to the universe (joint 0).
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import coal
import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..errors import OptionError, URDFError


def _pose(pose: npt.ArrayLike | None) -> tuple[tuple[float, ...], ...]:
    """A (4, 4) homogeneous pose T_I,shape as nested tuples (identity for None); OptionError otherwise."""
    if pose is None:
        return tuple(map(tuple, np.eye(4)))
    try:
        T = np.asarray(pose, dtype=float)
    except (TypeError, ValueError):
        T = np.zeros(0)
    if T.shape == (3,) and np.isfinite(T).all():  # a position alone
        T = np.vstack([np.hstack([np.eye(3), T[:, None]]), [0.0, 0.0, 0.0, 1.0]])
    if T.shape != (4, 4) or not np.isfinite(T).all():
        raise OptionError(
            f"an obstacle's pose is a (4, 4) homogeneous transform or a position (3,), got {pose!r}"
        )
    C = T[:3, :3]
    if (
        np.abs(C.T @ C - np.eye(3)).max() > 1e-9
        or np.linalg.det(C) < 0
        or not np.allclose(T[3], [0, 0, 0, 1])
    ):
        raise OptionError("an obstacle's pose must hold a rotation matrix in [:3, :3] and (0, 0, 0, 1) below")
    return tuple(map(tuple, T))


def _positive(what: str, value: object) -> float:
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise OptionError(f"{what} must be a finite number > 0 [m], got {value!r}") from None
    if not (math.isfinite(v) and v > 0.0):
        raise OptionError(f"{what} must be a finite number > 0 [m], got {value!r}")
    return v


def convex_hull(bvh: coal.BVHModelBase, name: str) -> coal.CollisionGeometry:
    """The convex hull (coal's qhull) of a triangle mesh; URDFError if it has none (fewer than 4 points
    off one plane)."""
    try:
        bvh.buildConvexHull(True, "Qt")
    except Exception as exc:
        raise URDFError(f"collision mesh {name!r} has no convex hull (flat or empty?): {exc}") from None
    return bvh.convex


class Obstacle:
    """Base of the obstacle shapes: ``pose`` T_I,shape (4, 4) [m] (the shape's centre; a position (3,) or
    None, the identity, are accepted), ``name`` (default: ``obstacle_<k>`` by position in the list)."""

    pose: tuple[tuple[float, ...], ...]
    name: str | None
    _lengths: ClassVar[tuple[str, ...]] = ()
    """The fields that are one length [m] each, checked to be finite and > 0."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "pose", _pose(self.pose))
        if self.name is not None and (not isinstance(self.name, str) or not self.name):
            raise OptionError(f"an obstacle's name is a non-empty string, got {self.name!r}")
        for field in self._lengths:
            value = _positive(f"{type(self).__name__} {field}", getattr(self, field))
            object.__setattr__(self, field, value)

    def shape(self) -> coal.CollisionGeometry:
        raise NotImplementedError

    def geometry_object(self, name: str) -> pin.GeometryObject:
        """Pinocchio's GeometryObject of this shape, fixed to the universe at ``pose``."""
        placement = pin.SE3(np.array(self.pose))
        obj = pin.GeometryObject(name, 0, 0, placement, self.shape())
        obj.meshColor = np.array([0.6, 0.6, 0.6, 0.5])
        return obj


@dataclass(frozen=True)
class Box(Obstacle):
    """A box of edge lengths ``size`` (x, y, z) [m], centred at the pose's origin, along its axes."""

    size: tuple[float, float, float] = (0.1, 0.1, 0.1)
    pose: Any = None
    name: str | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        try:
            s = np.asarray(self.size, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            s = np.zeros(0)
        if s.shape != (3,):
            raise OptionError(f"Box size is three edge lengths (x, y, z) [m], got {self.size!r}")
        object.__setattr__(self, "size", tuple(_positive("Box size", v) for v in s))

    def shape(self) -> coal.CollisionGeometry:
        return coal.Box(*self.size)


@dataclass(frozen=True)
class Sphere(Obstacle):
    """A sphere of ``radius`` [m] centred at the pose's origin."""

    radius: float = 0.05
    pose: Any = None
    name: str | None = None
    _lengths = ("radius",)

    def shape(self) -> coal.CollisionGeometry:
        return coal.Sphere(self.radius)


@dataclass(frozen=True)
class Capsule(Obstacle):
    """A capsule: the points within ``radius`` [m] of a segment of ``length`` [m] along the pose's z axis,
    centred at its origin."""

    radius: float = 0.05
    length: float = 0.1
    pose: Any = None
    name: str | None = None
    _lengths = ("radius", "length")

    def shape(self) -> coal.CollisionGeometry:
        return coal.Capsule(self.radius, self.length)


@dataclass(frozen=True)
class Mesh(Obstacle):
    """A mesh file (STL, DAE, OBJ: what coal's loader reads) scaled by ``scale``, used as its convex hull
    (as the robot's own meshes are, see :mod:`kinengine.collision.geometry`)."""

    path: str = ""
    pose: Any = None
    scale: Any = (1.0, 1.0, 1.0)
    name: str | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        if not isinstance(self.path, (str, os.PathLike)):
            raise OptionError(f"Mesh path is a file name, got {self.path!r}")
        path = os.path.abspath(os.path.expanduser(os.fspath(self.path)))
        if not Path(path).is_file():
            raise URDFError(f"Mesh obstacle file {path!r} does not exist")
        object.__setattr__(self, "path", path)
        try:
            s = np.broadcast_to(np.asarray(self.scale, dtype=float), (3,))
        except (TypeError, ValueError):
            raise OptionError(f"Mesh scale is one number or three, got {self.scale!r}") from None
        object.__setattr__(self, "scale", tuple(_positive("Mesh scale", v) for v in s))

    def shape(self) -> coal.CollisionGeometry:
        try:
            bvh = coal.MeshLoader().load(self.path, np.array(self.scale))
        except Exception as exc:  # coal/assimp report unreadable files with RuntimeError text
            raise URDFError(f"Mesh obstacle {self.path!r} could not be read: {exc}") from None
        return convex_hull(bvh, self.path)


__all__ = ["Box", "Capsule", "Mesh", "Obstacle", "Sphere", "convex_hull"]


def checked_obstacles(obstacles: Iterable[object]) -> tuple[Obstacle, ...]:
    """The obstacles of ``Robot.with_obstacles`` as a tuple; OptionError for anything but a list of them."""
    try:
        items = tuple(obstacles)
    except TypeError:
        raise OptionError(
            f"obstacles is a list of Box, Sphere, Capsule or Mesh, got {obstacles!r:.60}"
        ) from None
    for item in items:
        if not isinstance(item, Obstacle):
            raise OptionError(f"obstacles are Box, Sphere, Capsule or Mesh objects, got {item!r:.60}")
    return tuple(item for item in items if isinstance(item, Obstacle))
