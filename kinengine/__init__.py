"""kinengine: URDF-driven robot kinematics on Pinocchio.

>>> import kinengine
>>> robot = kinengine.load("abb_irb120")
>>> T = robot.frame_pose(robot.neutral(), "tool0")            # (4, 4) in the root link frame
>>> J = robot.jacobian(robot.neutral(), "tool0")              # (6, 6), rows [linear; angular]

The control layer's public names (Task, DifferentialIK, IKResult, ...) are imported on first use
(PEP 562 ``__getattr__``), so ``import kinengine; kinengine.load(...)`` does not pay for inverse
kinematics or the QP solver; ``from kinengine import Task`` works as ever.
"""

from importlib import import_module
from typing import TYPE_CHECKING

from .errors import (
    ConfigurationError,
    FrameNotFoundError,
    KinematicsError,
    KinematicSingularityError,
    MJCFError,
    OptionError,
    ParameterizationError,
    RepresentationSingularityError,
    ResourceLimitError,
    URDFError,
    pinocchio_import_hint,
)

try:  # Pinocchio before anything uses it, so that a broken install is named (errors.pinocchio_import_hint)
    import pinocchio as _pinocchio  # noqa: F401
except ImportError as _exc:
    _hint = pinocchio_import_hint(_exc)
    if _hint is None:
        raise
    raise ImportError(_hint) from _exc

from .kinematics import compiler as _compiler
from .kinematics.compiler import accelerator_status
from .kinematics.handle import FrameHandle
from .loading import load, load_urdf_string
from .model import accelerator as _accelerator
from .model import available_robots
from .robot import Robot

ACCELERATED: bool = _accelerator.AVAILABLE and _compiler.KERNEL is not None
"""True when kinengine's optional C accelerator of the hot path runs: built by ``pip install`` where a C
compiler is present, off with the environment variable ``KINENGINE_PURE_PYTHON=1``. It runs the input check
of a single q and a frame handle's plain ``pose`` / ``jacobian`` / ``kinematics`` calls in C, with results
equal bit for bit to the pure-Python path (about 0.4 µs slower per call), and batches of poses and
Jacobians (2 configurations or more) on a C chain, equal to the pure-Python numpy chain and to Pinocchio
to rounding (1e-14)."""

if TYPE_CHECKING:
    from .collision import Box, Capsule, CollisionAvoidance, Distances, Mesh, Sphere
    from .control.damped import damped_solve
    from .control.frame_task import FrameTask
    from .control.ik import IKResult
    from .control.ik_batch import IKBatchResult
    from .control.ik_multi import MultiIKResult
    from .control.ik_solutions import IKSolutions
    from .control.manipulability import SingularityReport
    from .control.pose_error import pose_error
    from .control.qp import DifferentialIK, DiffIKStatus, PoseTarget, PostureTarget, StallWarning
    from .control.task import Task
    from .workspace import BasePlacements, ReachabilityMap, base_placements, reachability_map

__version__ = "0.1.0"

# Public name -> the module (below kinengine) that defines it, imported on first access.
_LAZY = {
    "DiffIKStatus": "control.qp",
    "Box": "collision.shapes",
    "Capsule": "collision.shapes",
    "CollisionAvoidance": "collision.avoidance",
    "Distances": "collision.checker",
    "Mesh": "collision.shapes",
    "Sphere": "collision.shapes",
    "DifferentialIK": "control.qp",
    "FrameTask": "control.frame_task",
    "IKBatchResult": "control.ik_batch",
    "IKResult": "control.ik",
    "IKSolutions": "control.ik_solutions",
    "MultiIKResult": "control.ik_multi",
    "PoseTarget": "control.qp",
    "PostureTarget": "control.qp",
    "SingularityReport": "control.manipulability",
    "StallWarning": "control.qp",
    "damped_solve": "control.damped",
    "Task": "control.task",
    "pose_error": "control.pose_error",
    "BasePlacements": "workspace",
    "ReachabilityMap": "workspace",
    "base_placements": "workspace",
    "reachability_map": "workspace",
}

__all__ = [
    "ACCELERATED",
    "BasePlacements",
    "Box",
    "Capsule",
    "CollisionAvoidance",
    "ConfigurationError",
    "DiffIKStatus",
    "DifferentialIK",
    "Distances",
    "FrameHandle",
    "FrameNotFoundError",
    "FrameTask",
    "IKBatchResult",
    "IKResult",
    "IKSolutions",
    "KinematicSingularityError",
    "KinematicsError",
    "MJCFError",
    "Mesh",
    "MultiIKResult",
    "OptionError",
    "ParameterizationError",
    "PoseTarget",
    "PostureTarget",
    "ReachabilityMap",
    "RepresentationSingularityError",
    "ResourceLimitError",
    "Robot",
    "SingularityReport",
    "Sphere",
    "StallWarning",
    "Task",
    "URDFError",
    "__version__",
    "accelerator_status",
    "available_robots",
    "base_placements",
    "damped_solve",
    "load",
    "load_urdf_string",
    "pose_error",
    "reachability_map",
]


def __getattr__(name: str) -> object:
    """A lazily imported public name (see the module doc), then cached in the module."""
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
