"""Safe URDF parsing and structural validation (no C++ parser involved)."""

from .description import Inertial, Joint, Link, Mimic, RobotDescription

__all__ = ["Inertial", "Joint", "Link", "Mimic", "RobotDescription"]
