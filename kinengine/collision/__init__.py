"""Collisions: the URDF's ``<collision>`` geometry as Pinocchio's GeometryModel (coal shapes), self- and
obstacle pairs, signed distances with witness points, and a distance constraint for differential IK.

Frames: every point and pose is in the root link frame I (Pinocchio's "world"); distances in [m].
"""

from .avoidance import CollisionAvoidance
from .checker import CollisionChecker, Distances
from .geometry import build_collision_geometry, checked_packages
from .model import collision_checker
from .pairs import (
    adjacent_pairs,
    default_pairs,
    read_disabled_pairs,
    sample_pairs,
    warn_unknown_links,
    write_srdf,
)
from .shapes import Box, Capsule, Mesh, Obstacle, Sphere, checked_obstacles

__all__ = [
    "Box",
    "Capsule",
    "CollisionAvoidance",
    "CollisionChecker",
    "Distances",
    "Mesh",
    "Obstacle",
    "Sphere",
    "adjacent_pairs",
    "build_collision_geometry",
    "checked_obstacles",
    "checked_packages",
    "collision_checker",
    "default_pairs",
    "read_disabled_pairs",
    "sample_pairs",
    "warn_unknown_links",
    "write_srdf",
]
