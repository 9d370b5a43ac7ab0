"""The Robot's methods for derivatives, singularities and inverse kinematics: thin wrappers that check
their inputs once and call the kinematics, analytic and control layers (see those modules for the math).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..analytic import DEFAULT_SINGULARITY_THRESHOLD, pose_map
from ..analytic.hessian import analytic_hessian as _analytic_hessian
from ..control import ik as _ik
from ..control import manipulability as _manipulability
from ..control.ik import IKResult
from ..control.ik_batch import IKBatchResult
from ..control.manipulability import DEFAULT_TOLERANCE, Rows, SingularityReport, VelocityEllipsoid
from ..kinematics import derivatives as _derivatives
from ..kinematics import resolve_reference
from ..kinematics.options import checked_parameterization, checked_threshold

if TYPE_CHECKING:
    from ..robot import Robot


class AnalysisMethods:
    """Derivatives (J̇, kinematic and analytic Hessians), singularity measures and inverse kinematics."""

    # -- derivatives, singularities, inverse kinematics ----------------------------------------
    def jacobian_time_variation(
        self: Robot,
        q: object,
        qdot: object,
        frame: str | None = None,
        reference: object = "local_world_aligned",
    ) -> np.ndarray:
        """J̇ = dJ/dt of the geometric Jacobian in ``reference`` along q̇, (6, dof). See
        :mod:`kinengine.kinematics.derivatives`."""
        ref, fid = (
            resolve_reference(reference),
            self.engine.frame_id(self.end_effector if frame is None else frame),
        )
        q = self.engine.coordinates.check(q, allow_batch=False)
        qdot = self.engine.coordinates.check(qdot, name="qdot", allow_batch=False)
        return _derivatives.jacobian_time_variation(self.engine, q, qdot, fid, ref)

    def kinematic_hessian(
        self: Robot, q: object, frame: str | None = None, reference: object = "local_world_aligned"
    ) -> np.ndarray:
        """∂J/∂q, (6, dof, dof) with H[:, :, k] = ∂J/∂q_k, in ``reference``. See
        :mod:`kinengine.kinematics.derivatives`."""
        ref, fid = (
            resolve_reference(reference),
            self.engine.frame_id(self.end_effector if frame is None else frame),
        )
        return _derivatives.kinematic_hessian(
            self.engine, self.engine.coordinates.check(q, allow_batch=False), fid, ref
        )

    def analytic_hessian(
        self: Robot,
        q: object,
        frame: str | None = None,
        position: str | None = "cartesian",
        rotation: str | None = "euler_zyx",
        *,
        rows: Sequence[str | int] | None = None,
        singularity_threshold: float = DEFAULT_SINGULARITY_THRESHOLD,
    ) -> np.ndarray:
        """∂J_A/∂q, (m, dof, dof) with [:, :, k] = ∂J_A/∂q_k. See :mod:`kinengine.analytic.hessian`."""
        pmap, fid = (
            pose_map(*checked_parameterization(position, rotation, rows)),
            self.engine.frame_id(self.end_effector if frame is None else frame),
        )
        singularity_threshold = checked_threshold(singularity_threshold)
        return _analytic_hessian(
            self.engine, self.engine.coordinates.check(q, allow_batch=False), fid, pmap, singularity_threshold
        )

    def singularity_report(
        self: Robot,
        q: object,
        frame: str | None = None,
        rows: Rows = "all",
        *,
        tolerance: float = DEFAULT_TOLERANCE,
    ) -> SingularityReport:
        """Singular values, manipulability, condition number and lost directions of J_e0 (kinematic
        singularities)."""
        return _manipulability.singularity_report(self, q, frame, rows, tolerance=tolerance)

    def manipulability(
        self: Robot, q: object, frame: str | None = None, rows: Rows = "all"
    ) -> float | np.ndarray:
        """Yoshikawa's sqrt(det(J Jᵀ)) of the chosen rows of J_e0; (N,) for q (N, dof)."""
        return _manipulability.manipulability(self, q, frame, rows)

    def velocity_ellipsoid(self: Robot, q: object, frame: str | None = None) -> VelocityEllipsoid:
        """Axes and semi-axes [m/s per unit joint speed] of {J_v u : |u| <= 1} in the root frame."""
        return _manipulability.velocity_ellipsoid(self, q, frame)

    def require_regular(
        self: Robot,
        q: object,
        frame: str | None = None,
        rows: Rows = "all",
        *,
        tolerance: float = DEFAULT_TOLERANCE,
    ) -> SingularityReport:
        """The singularity report, or KinematicSingularityError if J_e0 (rows) loses rank."""
        return _manipulability.require_regular(self, q, frame, rows, tolerance=tolerance)

    def inverse_kinematics(
        self: Robot,
        target: object,
        frame: str | None = None,
        q0: object = None,
        *,
        position: str | None = None,
        rotation: str | None = None,
        rows: Sequence[str | int] | None = None,
        weights: Sequence[float] | None = None,
        tol_position: float = 1e-6,
        tol_rotation: float = 1e-6,
        max_iterations: int = 100,
        restarts: int = 3,
        rng: np.random.Generator | int | None = None,
        nullspace_target: object = None,
        nullspace_gain: float = 0.1,
        min_damping: float = 1e-6,
    ) -> IKResult | IKBatchResult:
        """Differential IK (damped least squares) to a 4x4 pose, a batch of poses (N, 4, 4) (an IKBatchResult
        of N results, solved vectorized) or a parameter target χ. See
        :func:`kinengine.control.ik.inverse_kinematics` for the options."""
        return _ik.inverse_kinematics(
            self,
            target,
            frame,
            q0,
            position=position,
            rotation=rotation,
            rows=rows,
            weights=weights,
            tol_position=tol_position,
            tol_rotation=tol_rotation,
            max_iterations=max_iterations,
            restarts=restarts,
            rng=rng,
            nullspace_target=nullspace_target,
            nullspace_gain=nullspace_gain,
            min_damping=min_damping,
        )
