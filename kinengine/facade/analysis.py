"""The Robot's methods for derivatives, singularities and inverse kinematics: thin wrappers that check
their inputs once and call the kinematics, analytic and control layers (see those modules for the math).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, cast

import numpy as np

from ..analytic import DEFAULT_SINGULARITY_THRESHOLD, pose_map
from ..analytic.hessian import analytic_hessian as _analytic_hessian
from ..arrays import ArrayLike, FloatArray, Reference
from ..control import manipulability as _manipulability
from ..control.manipulability import DEFAULT_TOLERANCE, Rows, SingularityReport, VelocityEllipsoid
from ..kinematics import derivatives as _derivatives
from ..kinematics import resolve_reference
from ..kinematics.options import checked_parameterization, checked_threshold

if TYPE_CHECKING:
    from ..control.ik import IKResult
    from ..control.ik_batch import IKBatchResult
    from ..robot import Robot


class AnalysisMethods:
    """Derivatives (J̇, kinematic and analytic Hessians), singularity measures and inverse kinematics."""

    # -- derivatives, singularities, inverse kinematics ----------------------------------------
    def jacobian_time_variation(
        self,
        q: ArrayLike,
        qdot: ArrayLike,
        frame: str | None = None,
        reference: Reference = "local_world_aligned",
    ) -> FloatArray:
        """J̇ = dJ/dt of the geometric Jacobian in ``reference`` along q̇, (6, dof). See
        :mod:`kinengine.kinematics.derivatives`."""
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        ref, fid = (
            resolve_reference(reference),
            robot.engine.frame_id(robot.end_effector if frame is None else frame),
        )
        qc: FloatArray = robot.engine.coordinates.check(q, allow_batch=False)
        vc: FloatArray = robot.engine.coordinates.check(qdot, name="qdot", allow_batch=False)
        return _derivatives.jacobian_time_variation(robot.engine, qc, vc, fid, ref)

    def kinematic_hessian(
        self, q: ArrayLike, frame: str | None = None, reference: Reference = "local_world_aligned"
    ) -> FloatArray:
        """∂J/∂q, (6, dof, dof) with H[:, :, k] = ∂J/∂q_k, in ``reference``. See
        :mod:`kinengine.kinematics.derivatives`."""
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        ref, fid = (
            resolve_reference(reference),
            robot.engine.frame_id(robot.end_effector if frame is None else frame),
        )
        return _derivatives.kinematic_hessian(
            robot.engine, robot.engine.coordinates.check(q, allow_batch=False), fid, ref
        )

    def analytic_hessian(
        self,
        q: ArrayLike,
        frame: str | None = None,
        position: str | None = "cartesian",
        rotation: str | None = "euler_zyx",
        *,
        rows: Sequence[str | int] | None = None,
        singularity_threshold: float = DEFAULT_SINGULARITY_THRESHOLD,
    ) -> FloatArray:
        """∂J_A/∂q, (m, dof, dof) with [:, :, k] = ∂J_A/∂q_k. See :mod:`kinengine.analytic.hessian`."""
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        pmap, fid = (
            pose_map(*checked_parameterization(position, rotation, rows)),
            robot.engine.frame_id(robot.end_effector if frame is None else frame),
        )
        singularity_threshold = checked_threshold(singularity_threshold)
        return _analytic_hessian(
            robot.engine,
            robot.engine.coordinates.check(q, allow_batch=False),
            fid,
            pmap,
            singularity_threshold,
        )

    def singularity_report(
        self,
        q: ArrayLike,
        frame: str | None = None,
        rows: Rows = "all",
        *,
        tolerance: float = DEFAULT_TOLERANCE,
    ) -> SingularityReport:
        """Singular values, manipulability, condition number and lost directions of J_e0 (kinematic
        singularities)."""
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        return _manipulability.singularity_report(robot, q, frame, rows, tolerance=tolerance)

    def manipulability(
        self, q: ArrayLike, frame: str | None = None, rows: Rows = "all"
    ) -> float | FloatArray:
        """Yoshikawa's sqrt(det(J Jᵀ)) of the chosen rows of J_e0; (N,) for q (N, dof)."""
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        return _manipulability.manipulability(robot, q, frame, rows)

    def velocity_ellipsoid(self, q: ArrayLike, frame: str | None = None) -> VelocityEllipsoid:
        """Axes and semi-axes [m/s per unit joint speed] of {J_v u : |u| <= 1} in the root frame."""
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        return _manipulability.velocity_ellipsoid(robot, q, frame)

    def require_regular(
        self,
        q: ArrayLike,
        frame: str | None = None,
        rows: Rows = "all",
        *,
        tolerance: float = DEFAULT_TOLERANCE,
    ) -> SingularityReport:
        """The singularity report, or KinematicSingularityError if J_e0 (rows) loses rank."""
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        return _manipulability.require_regular(robot, q, frame, rows, tolerance=tolerance)

    def inverse_kinematics(
        self,
        target: ArrayLike | Mapping[str, ArrayLike],
        frame: str | None = None,
        q0: ArrayLike | None = None,
        *,
        position: str | None = None,
        rotation: str | None = None,
        rows: Sequence[str | int] | Mapping[str, Sequence[str | int]] | None = None,
        weights: Sequence[float] | Mapping[str, Sequence[float]] | None = None,
        tol_position: float = 1e-6,
        tol_rotation: float = 1e-6,
        max_iterations: int = 100,
        restarts: int = 3,
        rng: np.random.Generator | int | None = None,
        nullspace_target: ArrayLike | None = None,
        nullspace_gain: float = 0.1,
        min_damping: float = 1e-6,
        avoid_collisions: bool = False,
    ) -> IKResult | IKBatchResult:
        """Differential IK (damped least squares) to a 4x4 pose, a batch of poses (N, 4, 4) (an IKBatchResult
        of N results, solved vectorized), a parameter target χ, or a mapping {frame: T_IF (4, 4)} solved for
        every frame at once (``frame`` None; ``rows``/``weights`` one spec or {frame: spec}; a MultiIKResult
        whose errors are the maxima over the frames, ``frame_errors`` per frame). See
        :func:`kinengine.control.ik.inverse_kinematics` for the options. ``avoid_collisions``: a solution in
        collision (:meth:`in_collision`) is solved again from random collision-free starts, ``restarts``
        times, else returned with success False; a batch's colliding rows get success False."""
        from ..control import ik as _ik  # here: inverse kinematics is imported by its first call

        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        solve = functools.partial(
            _ik.inverse_kinematics,
            robot,
            target,
            frame,
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
        result = solve(q0)
        if avoid_collisions:  # the collision hook (kinengine.facade.collisions)
            from .collisions import collision_free

            result = collision_free(robot, result, solve, restarts, rng)
        return result
