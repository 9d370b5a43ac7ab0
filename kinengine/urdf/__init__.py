"""Safe URDF parsing and structural validation (no C++ parser involved).

``parse_urdf`` / ``read_urdf_file`` turn URDF text or a file into a validated
:class:`RobotDescription`, refusing anything malformed, unsafe, oversized
(see :data:`LIMITS`) or unsupported with a :class:`~kinengine.errors.URDFError`.
"""

from .description import Inertial, Joint, Link, Mimic, RobotDescription
from .limits import LIMITS, Limits
from .parser import parse_urdf, read_urdf_file

__all__ = [
    "LIMITS",
    "Inertial",
    "Joint",
    "Limits",
    "Link",
    "Mimic",
    "RobotDescription",
    "parse_urdf",
    "read_urdf_file",
]
