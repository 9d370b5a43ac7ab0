"""One robot's collision model, assembled: geometry (:mod:`.geometry`) and checked pairs (:mod:`.pairs`)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

from ..errors import URDFError
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
    name: str = "",
) -> CollisionChecker:
    """The CollisionChecker of a robot's URDF text on its Kinematics, with ``obstacles`` and without the
    ``disabled`` link pairs. URDFError if the robot ``name`` has no collision shape at all: it would
    otherwise look collision-free everywhere."""
    geometry = build_collision_geometry(kin.model, urdf_text, source, packages, obstacles)
    n_robot = geometry.ngeoms - len(obstacles)
    if n_robot == 0:
        raise URDFError(
            f"robot {name!r} has no <collision> elements, so collisions cannot be checked; add <collision> "
            "geometry to its URDF links (to an MJCF file: geoms with contype or conaffinity non-zero)",
            source=source,
        )
    return CollisionChecker(kin, geometry, default_pairs(kin.model, geometry, n_robot, disabled))


__all__ = ["collision_checker"]
