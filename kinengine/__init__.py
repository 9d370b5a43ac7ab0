"""kinengine: URDF-driven robot kinematics on Pinocchio.

>>> import kinengine
>>> robot = kinengine.load("abb_irb120")
>>> T = robot.frame_pose(robot.neutral(), "tool0")            # (4, 4) in the root link frame
>>> J = robot.jacobian(robot.neutral(), "tool0")              # (6, 6), rows [linear; angular]
"""

from .control.frame_task import FrameTask
from .control.ik import IKResult
from .control.ik_batch import IKBatchResult
from .control.manipulability import SingularityReport
from .control.pose_error import pose_error
from .control.qp import DifferentialIK, PoseTarget, PostureTarget
from .control.task import Task
from .errors import (
    ConfigurationError,
    FrameNotFoundError,
    KinematicsError,
    KinematicSingularityError,
    OptionError,
    ParameterizationError,
    RepresentationSingularityError,
    ResourceLimitError,
    URDFError,
)
from .kinematics.handle import FrameHandle
from .loading import load, load_urdf_string
from .model import available_robots
from .robot import Robot

__version__ = "0.1.0"

__all__ = [
    "ConfigurationError",
    "DifferentialIK",
    "FrameHandle",
    "FrameNotFoundError",
    "FrameTask",
    "IKBatchResult",
    "IKResult",
    "KinematicSingularityError",
    "KinematicsError",
    "OptionError",
    "ParameterizationError",
    "PoseTarget",
    "PostureTarget",
    "RepresentationSingularityError",
    "ResourceLimitError",
    "Robot",
    "SingularityReport",
    "Task",
    "URDFError",
    "__version__",
    "available_robots",
    "load",
    "load_urdf_string",
    "pose_error",
]
