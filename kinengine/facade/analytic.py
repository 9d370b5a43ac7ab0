"""The Robot's analytic and relative kinematics: pose parameters χ, analytic Jacobians J_A = E(χ)·J_e0 (Robot
Dynamics lecture notes, ETH Zurich, section 2.8), the Task of a control loop, and poses and Jacobians of one
frame relative to another. Inputs are checked once, then handed to the analytic, control and kinematics
layers."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, cast

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..analytic import (
    DEFAULT_SINGULARITY_THRESHOLD,
    analytic_batch,
    analytic_function,
    analytic_single,
    pose_map,
)
from ..analytic.evaluate import analytic_relative
from ..analytic.pose_map import check_on_singularity
from ..arrays import ArrayLike, FloatArray
from ..kinematics import relative as _relative
from ..kinematics.options import checked_flag, checked_frames, checked_parameterization, checked_threshold

if TYPE_CHECKING:  # the Task's modules are imported by the first robot.task(...) call
    from ..control.frame_task import FrameTask
    from ..control.task import Task
    from ..robot import Robot


FastPath = tuple[Callable[[object], bool], Callable[[np.ndarray], FloatArray]]
"""(ready, J_A): the input test CoordinateMap.ready and J_A(q) for a q that passed it."""


def _fast_path(
    robot: Robot,
    frame: object,
    position: object,
    rotation: object,
    rows: object,
    threshold: object,
    on_singularity: object,
) -> FastPath | None:
    """For these options (each checked here: an error is raised, not kept), (ready, J_A): J_A(q) answers a
    float64 (dof,) array q that ``ready`` passed (any other q takes the general path, which checks it);
    None where the general path is needed (on_singularity other than "raise")."""
    pmap = pose_map(*checked_parameterization(position, rotation, rows))
    threshold = checked_threshold(threshold)
    fid = robot.engine.frame_id(robot.end_effector if frame is None else frame)
    if on_singularity != "raise":
        check_on_singularity(on_singularity)
        return None
    return robot.engine.coordinates.ready, analytic_function(robot.engine, fid, pmap, threshold)


class AnalyticMethods:
    """χ, J_A, the Task, and relative poses and Jacobians."""

    # -- analytic Jacobians --------------------------------------------------------------------
    def pose_parameters(
        self,
        q: ArrayLike,
        frame: str | None = None,
        position: str | None = "cartesian",
        rotation: str | None = "euler_zyx",
        *,
        rows: Sequence[str | int] | None = None,
        check_limits: bool = False,
        relative_to: str | None = None,
        on_singularity: str | None = None,
        singularity_threshold: float = DEFAULT_SINGULARITY_THRESHOLD,
    ) -> FloatArray:
        """χ_e(q) = (χ_P, χ_R) of ``frame`` in the root frame, (m,) or (N, m) for q (N, dof).

        ``position``/``rotation`` name a parameterization (None leaves its rows out);
        ``rows`` keeps only the named rows (labels or indices), e.g. ("x", "z", "ry").
        ``relative_to``: χ of T_BA, the pose of ``frame`` in that frame B, instead of T_IA.
        ``on_singularity`` None (default): near a representation singularity the angles stay valid (a
        warning is issued at gimbal lock); "raise": RepresentationSingularityError within
        ``singularity_threshold`` of the singular set; "nan": NaN in that parameterization's rows there.
        """
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        pmap = pose_map(*checked_parameterization(position, rotation, rows))
        singularity_threshold = checked_threshold(singularity_threshold)
        if relative_to is None:
            T = robot.frame_pose(q, frame, check_limits=check_limits)
        else:
            T = robot.relative_pose(q, frame, relative_to=relative_to, check_limits=check_limits)
        if on_singularity is None:
            return pmap.parameters(T)
        nan = check_on_singularity(on_singularity)
        qc = robot.engine.coordinates.check(q)
        fa = robot.engine.frame_id(robot.end_effector if frame is None else frame)
        kin = robot.engine
        fb = None if relative_to is None else kin.frame_id(relative_to)

        def J(row: int | None) -> npt.NDArray[np.float64]:
            qr = qc if row is None else qc[row]
            if fb is None:
                return kin.jacobian(qr, fa, pin.LOCAL_WORLD_ALIGNED)
            return _relative.relative_jacobian(kin, qr, fa, fb)

        return pmap.parameters(T, singularity_threshold, nan, J)

    def analytic_jacobian(
        self,
        q: ArrayLike,
        frame: str | None = None,
        position: str | None = "cartesian",
        rotation: str | None = "euler_zyx",
        *,
        rows: Sequence[str | int] | None = None,
        singularity_threshold: float = DEFAULT_SINGULARITY_THRESHOLD,
        check_limits: bool = False,
        relative_to: str | None = None,
        on_singularity: str = "raise",
    ) -> FloatArray:
        """J_eA = ∂χ_e/∂q = E_e(χ_e) · J_e0(q), (m, dof) or (N, m, dof) for q (N, dof).

        Raises RepresentationSingularityError when χ_e is closer than ``singularity_threshold``
        to its parameterization's singular set (the message names regular alternatives and says whether
        the robot itself is singular); ``on_singularity="nan"`` gives NaN in that parameterization's rows
        instead (in a batch, only in the rows of those configurations). ``relative_to``: the analytic
        Jacobian of χ(T_BA), E(χ)·J_rel with J_rel = :meth:`relative_jacobian` expressed in B.
        """
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        if relative_to is None and check_limits is False:
            key = (frame, position, rotation, rows, singularity_threshold, on_singularity)
            path, found = None, True
            try:  # options seen before (checked then): J_A(q) for them, looked up once
                path = self._analytic_paths[key]
            except AttributeError:  # the first call on this Robot
                self._analytic_paths: dict[tuple, FastPath | None] = {}
                found = False
            except KeyError:
                found = False
            except TypeError:  # unhashable options (e.g. rows as a list): the general path checks them
                pass
            if not found:  # checked here (outside the handlers above, so that an error reads plainly)
                path = _fast_path(robot, *key)
                if len(self._analytic_paths) < 256:
                    self._analytic_paths[key] = path
            if path is not None:
                ready, evaluate = path
                if ready(q):  # a float64 (dof,) array within the bounds: checked
                    return evaluate(q)  # type: ignore[arg-type]
        kin = robot.engine
        pmap = pose_map(*checked_parameterization(position, rotation, rows))
        singularity_threshold = checked_threshold(singularity_threshold)
        fid = kin.frame_id(robot.end_effector if frame is None else frame)
        nan = on_singularity != "raise" and check_on_singularity(on_singularity)
        qc: FloatArray = kin.coordinates.check(q, check_limits=check_limits)
        if relative_to is not None:
            fb = kin.frame_id(relative_to)
            return analytic_relative(kin, qc, fid, fb, pmap, singularity_threshold, nan)
        if qc.ndim == 2:
            return analytic_batch(kin, qc, fid, pmap, singularity_threshold, nan)
        return analytic_single(kin, qc, fid, pmap, singularity_threshold, nan)

    def task(
        self,
        frames: str | FrameTask | Sequence[str | FrameTask] | None = None,
        position: str | None = "cartesian",
        rotation: str | None = "euler_zyx",
        *,
        rows: Sequence[str | int] | None = None,
        check_inputs: bool = True,
        continuous: bool = True,
        singularity_threshold: float = DEFAULT_SINGULARITY_THRESHOLD,
        relative_to: str | None = None,
        on_singularity: str = "raise",
    ) -> Task:
        """A :class:`~kinengine.control.task.Task` for a control loop: ``task.update(q, qdot)`` fills pose, χ,
        J_e0, J_A (and with q̇ the twist, J̇_e0, J̇_A) into preallocated read-only arrays.

        ``frames``: one name (default: end_effector), several (blocks stacked), or
        :class:`~kinengine.FrameTask` entries, each with its own parameterizations, rows and relative_to
        (names given as strings take ``position``, ``rotation``, ``rows`` and ``relative_to`` of this call).
        ``on_singularity``: "raise" (default) or "nan"; ``task.singularity_distances`` tells how far each
        parameterization is from its singular set. See :mod:`kinengine.control.task`.
        """
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        position, rotation, rows = checked_parameterization(position, rotation, rows)
        singularity_threshold = checked_threshold(singularity_threshold)
        continuous, check_inputs = (
            checked_flag(continuous, "continuous"),
            checked_flag(check_inputs, "check_inputs"),
        )
        from ..control.frame_task import FrameTask
        from ..control.task import Task

        checked_frames(frames, (str, FrameTask))
        return Task(
            robot,
            robot.end_effector if frames is None else frames,
            position,
            rotation,
            rows=rows,
            check_inputs=check_inputs,
            continuous=continuous,
            singularity_threshold=singularity_threshold,
            relative_to=relative_to,
            on_singularity=on_singularity,
        )

    # -- relative kinematics --------------------------------------------------------------------
    def relative_pose(
        self, q: ArrayLike, frame: str | None = None, *, relative_to: str, check_limits: bool = False
    ) -> FloatArray:
        """T_BA = T_IB⁻¹ T_IA: the pose of ``frame`` A (default: end_effector) in frame B = ``relative_to``,
        (4, 4) [m], or (N, 4, 4) for q (N, dof). See :mod:`kinengine.kinematics.relative`."""
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        fa, fb = (
            robot.engine.frame_id(robot.end_effector if frame is None else frame),
            robot.engine.frame_id(relative_to),
        )
        return _relative.relative_pose(
            robot.engine, robot.engine.coordinates.check(q, check_limits=check_limits), fa, fb
        )

    def relative_jacobian(
        self,
        q: ArrayLike,
        frame: str | None = None,
        *,
        relative_to: str,
        expressed_in: str | None = None,
        check_limits: bool = False,
    ) -> FloatArray:
        """(6, dof), or (N, 6, dof) for q (N, dof); rows [v; ω]: the velocity of A's origin and the angular
        velocity of A (A = ``frame``, default end_effector), both relative to B = ``relative_to`` (as seen by
        an observer fixed in B), in the axes of ``expressed_in`` (any frame name; default B).

        In B: d/dt(B_p_BA) = J[:3]·q̇ and Ċ_BA = [J[3:]·q̇]× C_BA. See :mod:`kinengine.kinematics.relative`.
        """
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        fa, fb = (
            robot.engine.frame_id(robot.end_effector if frame is None else frame),
            robot.engine.frame_id(relative_to),
        )
        fe = None if expressed_in is None else robot.engine.frame_id(expressed_in)
        return _relative.relative_jacobian(
            robot.engine, robot.engine.coordinates.check(q, check_limits=check_limits), fa, fb, fe
        )
