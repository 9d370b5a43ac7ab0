"""The analytic layer: pose parameters χ_e and analytic Jacobians J_A = E(χ)·J_e0 (Robot Dynamics
lecture notes, ETH Zurich, section 2.8) on top of the kinematics layer."""

from .evaluate import analytic_batch, analytic_function, analytic_single
from .pose_map import DEFAULT_SINGULARITY_THRESHOLD, PoseMap, as_rows, pose_map

__all__ = [
    "DEFAULT_SINGULARITY_THRESHOLD",
    "PoseMap",
    "analytic_batch",
    "analytic_function",
    "analytic_single",
    "as_rows",
    "pose_map",
]
