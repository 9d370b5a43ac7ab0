"""One robot's collision model, assembled: geometry (:mod:`.geometry`) and checked pairs (:mod:`.pairs`)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

from ..kinematics.engine import Kinematics
from .checker import CollisionChecker
from .geometry import build_collision_geometry
from .pairs import default_pairs
from .shapes import Obstacle


def collision_checker(
    kin: Kinematics,
    urdf_text: str,
    source: str,
    packages: Mapping[str, str] | None = None,
    obstacles: Sequence[Obstacle] = (),
    disabled: Iterable[frozenset[str]] = (),
) -> CollisionChecker:
    """The CollisionChecker of a robot's URDF text on its Kinematics, with ``obstacles`` and without the
    ``disabled`` link pairs."""
    geometry = build_collision_geometry(kin.model, urdf_text, source, packages, obstacles)
    n_robot = geometry.ngeoms - len(obstacles)
    return CollisionChecker(kin, geometry, default_pairs(kin.model, geometry, n_robot, disabled))


__all__ = ["collision_checker"]
