"""The model layer: the catalog of shipped robots, the coordinate map q -> Pinocchio's q, and
Pinocchio's model of a validated description (one plain joint per movable URDF joint)."""

from .catalog import CatalogEntry, available_robots, catalog_entry, find_entry, shipped_robots_dir
from .coordinates import CoordinateMap
from .mimics import mimic_roots
from .pinocchio_model import build_pinocchio_model, check_pinocchio_model, pinocchio_xml

__all__ = [
    "CatalogEntry",
    "CoordinateMap",
    "available_robots",
    "build_pinocchio_model",
    "catalog_entry",
    "check_pinocchio_model",
    "find_entry",
    "mimic_roots",
    "pinocchio_xml",
    "shipped_robots_dir",
]
