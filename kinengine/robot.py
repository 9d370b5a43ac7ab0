"""The :class:`Robot`: the public facade over one robot's kinematics.

Frames and conventions
----------------------
* "world" in Pinocchio is the URDF's root link frame: the inertial frame I of the Robot Dynamics
  lecture notes, ETH Zurich, section 2.8.
* ``frame_pose(q, f)`` is T_IF: the pose of frame f in the root link frame, (4, 4), [m].
* ``jacobian(q, f, reference)``: rows [linear; angular], columns in ``joint_names`` order.
  - "local_world_aligned": I J_e0 of the lecture notes (eq. 2.155) — velocity of f's origin and
    angular velocity, both in I.
  - "local": the same twist expressed in f: blockdiag(C_IF^T, C_IF^T) · J_lwa.
  - "world": the spatial velocity in I: linear rows are the velocity of the body point
    that currently coincides with I's origin: v_O = v_f − ω × p_f  (p_f = origin of f in I).

The Robot checks its inputs once and hands them to ``robot.engine`` (Pinocchio model, per-thread
Data, coordinate map) and to the analytic, control and presentation layers' functions.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Callable, Mapping, Sequence
from types import MappingProxyType
from typing import TYPE_CHECKING, overload

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from .analytic import analytic_batch, analytic_function, analytic_single
from .analytic.evaluate import analytic_relative
from .analytic.hessian import analytic_hessian as _analytic_hessian
from .analytic.options import DEFAULTS, AnalyticOptions
from .arrays import ArrayLike, FloatArray, Matrix, Reference, Stack, Vector
from .control import manipulability as _manipulability
from .control import rate_limits as _rate_limits
from .control.manipulability import DEFAULT_TOLERANCE, Rows, SingularityReport, VelocityEllipsoid
from .errors import OptionError
from .kinematics import Kinematics, resolve_reference
from .kinematics import batch as _batch
from .kinematics import derivatives as _derivatives
from .kinematics import relative as _relative
from .kinematics.handle import FrameHandle
from .kinematics.options import checked_flag, checked_frames, checked_rng
from .urdf import RobotDescription

if TYPE_CHECKING:  # imported by the first call that needs them
    import matplotlib.axes

    from .collision import CollisionChecker, Distances, Obstacle
    from .control.frame_task import FrameTask
    from .control.ik import IKResult
    from .control.ik_batch import IKBatchResult
    from .control.ik_solutions import IKSolutions
    from .control.task import Task
    from .presentation.viewer import Viewer

_jjtv, _fjtv = pin.computeJointJacobiansTimeVariation, pin.getFrameJacobianTimeVariation

FastPath = tuple[Callable[[object], bool], Callable[[FloatArray], FloatArray]]
"""(ready, J_A): the input test CoordinateMap.ready and J_A(q) for a q that passed it."""


class Robot:
    """A fixed-base robot: one coordinate per independent movable joint.

    Build it with :func:`kinengine.load` or :func:`kinengine.load_urdf_string`. The
    Pinocchio Model is private and immutable; each thread gets its own Data, so one
    Robot may be used from several threads at once. Every returned array is a fresh copy.
    """

    def __init__(
        self,
        description: RobotDescription,
        urdf_text: str,
        *,
        name: str | None = None,
        end_effector: str | None = None,
        packages: Mapping[str, str] | None = None,
    ) -> None:
        self._kin = kin = Kinematics(description)
        self._packages = MappingProxyType(dict(packages or {}))
        self._coords = kin.coordinates
        self._description = description
        self._urdf_text = urdf_text
        self._name = name or description.name
        if end_effector is not None:
            kin.frame_id(end_effector)  # FrameNotFoundError with suggestions for an unknown name
        self._end_effector = end_effector if end_effector is not None else _default_end_effector(description)
        self._handles: dict[object, FrameHandle] = {}  # frame name (None: end effector) -> checked handle
        self._analytic_paths: dict[tuple, FastPath | None] = {}  # analytic_jacobian's options -> J_A(q)
        self._jdot_paths: dict[tuple[object, object], tuple] = {}  # (frame, reference) -> J̇'s inline path
        self._obstacles: tuple[Obstacle, ...] = ()  # with_obstacles(); travel with pickles and edits
        self._disabled_pairs: frozenset[frozenset[str]] = frozenset()  # with_srdf()
        self._collision: tuple[Mapping[str, str], CollisionChecker] | None = None  # (packages, checker)

    # -- description ------------------------------------------------------------------------
    name = property(lambda self: self._name, doc="Robot name (catalog short name or the URDF's name).")
    dof = property(lambda self: self._coords.dof, doc="Number of coordinates in q.")
    joint_names = property(lambda self: self._coords.names, doc="Names of q's coordinates, in order.")
    frame_names = property(
        lambda self: self._kin.frame_names, doc="Every link and joint frame, in model order."
    )
    end_effector = property(lambda self: self._end_effector, doc="Default end-effector frame name.")
    description = property(lambda self: self._description, doc="The validated RobotDescription.")
    urdf_text = property(lambda self: self._urdf_text, doc="The URDF text the robot was loaded from.")
    source = property(lambda self: self._description.source, doc="File the robot came from, or '<string>'.")
    packages = property(
        lambda self: self._packages,
        doc="ROS package name -> folder given to load() (read-only "
        "mapping) for $(find pkg) and package:// URIs (meshes).",
    )
    engine = property(
        lambda self: self._kin,
        doc="The Kinematics object (Pinocchio model, per-thread Data, "
        "coordinate map) that the methods below delegate to.",
    )

    @property
    def lower_limits(self) -> FloatArray:
        """(dof,) lower limits [rad or m]; -inf if none (a fresh copy)."""
        return self._coords.lower.copy()

    @property
    def upper_limits(self) -> FloatArray:
        """(dof,) upper limits [rad or m]; +inf if none (a fresh copy)."""
        return self._coords.upper.copy()

    def __repr__(self) -> str:
        return f"<Robot {self._name!r}: {self.dof} dof, {len(self.frame_names)} frames>"

    def __reduce__(self) -> tuple:
        """Pickle and deepcopy: rebuilt from its validated description, URDF text, name and end effector
        (a fresh Pinocchio model and Data in the receiving process; nothing per-thread is sent)."""
        state = (self._description, self._urdf_text, self._name, self._end_effector, dict(self._packages))
        return _rebuild_robot, state, self._collision_state()

    # -- configurations ---------------------------------------------------------------------
    def neutral(self) -> FloatArray:
        """The zero configuration clipped into the joint limits, (dof,): q = 0 unless a joint's limits exclude
        0 (e.g. the Panda's joint 4), which then sits at its nearest limit (as MoveIt's default state)."""
        return np.clip(np.zeros(self.dof), self._coords.lower, self._coords.upper)

    def random_configuration(
        self, rng: np.random.Generator | int | None = None, size: int | None = None
    ) -> FloatArray:
        """Uniform within limits, (dof,) or (size, dof); continuous joints in [-π, π)."""
        return self._coords.sample(checked_rng(rng), size)

    def configuration(
        self, values: Mapping[str, float], *, base: ArrayLike | None = None, strict: bool = True
    ) -> FloatArray:
        """q from joint name -> value (e.g. a ROS JointState); unnamed joints at ``base`` (default neutral).

        Unknown names raise FrameNotFoundError (``strict=False`` ignores them).
        """
        coords = self._coords
        start = (
            self.neutral() if base is None else np.array(coords.check(base, name="base", allow_batch=False))
        )
        return coords.from_mapping(values, start, strict=checked_flag(strict, "strict"))

    def check_configuration(
        self, q: ArrayLike, *, check_limits: bool = True, batch: bool = True
    ) -> FloatArray:
        """A fresh float64 copy of q, (dof,) or (with ``batch``) (N, dof); ConfigurationError on bad shape,
        values or (optionally) limits."""
        allow_batch = checked_flag(batch, "batch")
        return np.array(self._coords.check(q, check_limits=check_limits, allow_batch=allow_batch))

    def pinocchio_model(self) -> pin.Model:
        """A copy of Pinocchio's Model: one plain joint (nq = nv = 1) per movable URDF joint, mimic joints
        included as ordinary joints; its configuration is :meth:`pinocchio_configuration`."""
        return pin.Model(self._kin.model)

    def pinocchio_configuration(self, q: ArrayLike) -> FloatArray:
        """Pinocchio's configuration (nq,) for q: q_pin = M q + b (every movable joint's value, mimic
        joints at multiplier·leader + offset); equal to q for robots without mimic joints."""
        q = self._coords.check(q, allow_batch=False)
        return np.array(self._coords.to_pinocchio(q), dtype=float)

    # -- analytic Jacobians (options: kinengine.analytic.options) ------------------------------
    def pose_parameters(
        self,
        q: ArrayLike,
        frame: str | None = None,
        position: str | None = DEFAULTS.position,
        rotation: str | None = DEFAULTS.rotation,
        *,
        rows: Sequence[str | int] | None = DEFAULTS.rows,
        check_limits: bool = False,
        relative_to: str | None = None,
        on_singularity: str | None = DEFAULTS.on_singularity,
        singularity_threshold: float = DEFAULTS.singularity_threshold,
    ) -> FloatArray:
        """χ_e(q) = (χ_P, χ_R) of ``frame`` in the root frame, (m,) or (N, m) for q (N, dof).

        ``position``/``rotation`` name a parameterization (None leaves its rows out);
        ``rows`` keeps only the named rows (labels or indices), e.g. ("x", "z", "ry").
        ``relative_to``: χ of T_BA, the pose of ``frame`` in that frame B, instead of T_IA.
        ``on_singularity`` "raise" (default): RepresentationSingularityError within ``singularity_threshold``
        of the singular set (where χ is not unique, e.g. ZYX angles at gimbal lock); "nan": NaN in that
        parameterization's rows there; None: χ everywhere (a warning is issued at gimbal lock).
        """
        mode = "raise" if on_singularity is None else on_singularity  # None: χ alone, unchecked
        options = AnalyticOptions(position, rotation, rows, singularity_threshold, mode).checked()
        fa, fb, qc = self._checked(q, frame, relative_to, check_limits=check_limits)
        kin, pmap = self._kin, options.pose_map()
        T = self.frame_pose(qc, frame) if fb is None else _relative.relative_pose(kin, qc, fa, fb)
        if on_singularity is None:
            return pmap.parameters(T)

        def J(row: int | None) -> FloatArray:
            qr = qc if row is None else qc[row]
            if fb is None:
                return kin.jacobian(qr, fa, pin.LOCAL_WORLD_ALIGNED)
            return _relative.relative_jacobian(kin, qr, fa, fb)

        return pmap.parameters(T, options.singularity_threshold, options.nan, J)

    def analytic_jacobian(
        self,
        q: ArrayLike,
        frame: str | None = None,
        position: str | None = DEFAULTS.position,
        rotation: str | None = DEFAULTS.rotation,
        *,
        rows: Sequence[str | int] | None = DEFAULTS.rows,
        singularity_threshold: float = DEFAULTS.singularity_threshold,
        check_limits: bool = False,
        relative_to: str | None = None,
        on_singularity: str = DEFAULTS.on_singularity,
    ) -> FloatArray:
        """J_eA = ∂χ_e/∂q = E_e(χ_e) · J_e0(q), (m, dof) or (N, m, dof) for q (N, dof).

        Raises RepresentationSingularityError when χ_e is closer than ``singularity_threshold``
        to its parameterization's singular set (the message names regular alternatives and says whether
        the robot itself is singular); ``on_singularity="nan"`` gives NaN in that parameterization's rows
        instead (in a batch, only in the rows of those configurations). ``relative_to``: the analytic
        Jacobian of χ(T_BA), E(χ)·J_rel with J_rel = :meth:`relative_jacobian` expressed in B.
        """
        if relative_to is None and check_limits is False:
            key = (frame, position, rotation, rows, singularity_threshold, on_singularity)
            path, found = None, True
            try:  # options seen before (checked then): J_A(q) for them, looked up once
                path = self._analytic_paths[key]
            except KeyError:
                found = False
            except TypeError:  # unhashable options (e.g. rows as a list): the general path checks them
                pass
            if not found:  # checked here (outside the handlers, so that an error reads plainly)
                options = AnalyticOptions(position, rotation, rows, singularity_threshold, on_singularity)
                options, fid = options.checked(), self._frame_id(frame)  # an error is raised, not kept
                if not options.nan:  # "nan" takes the general path
                    J_A = analytic_function(self._kin, fid, options.pose_map(), options.singularity_threshold)
                    path = self._coords.ready, J_A
                if len(self._analytic_paths) < 256:
                    self._analytic_paths[key] = path
            if path is not None:
                ready, evaluate = path
                if ready(q):  # a float64 (dof,) array within the bounds: checked
                    return evaluate(q)  # type: ignore[arg-type]
        options = AnalyticOptions(position, rotation, rows, singularity_threshold, on_singularity).checked()
        fid, fb, qc = self._checked(q, frame, relative_to, check_limits=check_limits)
        kin, pmap, threshold, nan = self._kin, options.pose_map(), options.singularity_threshold, options.nan
        if fb is not None:
            return analytic_relative(kin, qc, fid, fb, pmap, threshold, nan)
        if qc.ndim == 2:
            return analytic_batch(kin, qc, fid, pmap, threshold, nan)
        return analytic_single(kin, qc, fid, pmap, threshold, nan)

    def analytic_hessian(
        self,
        q: ArrayLike,
        frame: str | None = None,
        position: str | None = DEFAULTS.position,
        rotation: str | None = DEFAULTS.rotation,
        *,
        rows: Sequence[str | int] | None = DEFAULTS.rows,
        singularity_threshold: float = DEFAULTS.singularity_threshold,
    ) -> FloatArray:
        """∂J_A/∂q, (m, dof, dof) with [:, :, k] = ∂J_A/∂q_k. See :mod:`kinengine.analytic.hessian`."""
        options = AnalyticOptions(position, rotation, rows, singularity_threshold).checked()
        fid, _, qc = self._checked(q, frame, allow_batch=False)
        return _analytic_hessian(self._kin, qc, fid, options.pose_map(), options.singularity_threshold)

    def task(
        self,
        frames: str | FrameTask | Sequence[str | FrameTask] | None = None,
        position: str | None = DEFAULTS.position,
        rotation: str | None = DEFAULTS.rotation,
        *,
        rows: Sequence[str | int] | None = DEFAULTS.rows,
        check_inputs: bool = True,
        continuous: bool = True,
        singularity_threshold: float = DEFAULTS.singularity_threshold,
        relative_to: str | None = None,
        on_singularity: str = DEFAULTS.on_singularity,
    ) -> Task:
        """A :class:`~kinengine.control.task.Task` for a control loop: ``task.update(q, qdot)`` fills pose, χ,
        J_e0, J_A (and with q̇ the twist, J̇_e0, J̇_A) into preallocated read-only arrays.

        ``frames``: one name (default: end_effector), several (blocks stacked), or
        :class:`~kinengine.FrameTask` entries, each with its own parameterizations, rows and relative_to
        (names given as strings take ``position``, ``rotation``, ``rows`` and ``relative_to`` of this call).
        ``on_singularity``: "raise" (default) or "nan"; ``task.singularity_distances`` tells how far each
        parameterization is from its singular set. See :mod:`kinengine.control.task`.
        """
        options = AnalyticOptions(position, rotation, rows, singularity_threshold, on_singularity).checked()
        continuous, check_inputs = (
            checked_flag(continuous, "continuous"),
            checked_flag(check_inputs, "check_inputs"),
        )
        from .control.frame_task import FrameTask
        from .control.task import Task

        checked_frames(frames, (str, FrameTask))
        return Task(
            self,
            self._end_effector if frames is None else frames,
            options,
            check_inputs=check_inputs,
            continuous=continuous,
            relative_to=relative_to,
        )

    # -- relative kinematics --------------------------------------------------------------------
    def relative_pose(
        self, q: ArrayLike, frame: str | None = None, *, relative_to: str, check_limits: bool = False
    ) -> FloatArray:
        """T_BA = T_IB⁻¹ T_IA: the pose of ``frame`` A (default: end_effector) in frame B = ``relative_to``,
        (4, 4) [m], or (N, 4, 4) for q (N, dof). See :mod:`kinengine.kinematics.relative`."""
        fa, fb = self._frame_id(frame), self._kin.frame_id(relative_to)
        return _relative.relative_pose(self._kin, self._coords.check(q, check_limits=check_limits), fa, fb)

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
        fa, fb = self._frame_id(frame), self._kin.frame_id(relative_to)
        fe = None if expressed_in is None else self._kin.frame_id(expressed_in)
        qc = self._coords.check(q, check_limits=check_limits)
        return _relative.relative_jacobian(self._kin, qc, fa, fb, fe)

    # -- derivatives ------------------------------------------------------------------------------
    def jacobian_time_variation(
        self,
        q: ArrayLike,
        qdot: ArrayLike,
        frame: str | None = None,
        reference: Reference = "local_world_aligned",
    ) -> FloatArray:
        """J̇ = dJ/dt of the geometric Jacobian in ``reference`` along q̇, (6, dof). See
        :mod:`kinengine.kinematics.derivatives`."""
        try:  # the inline path: (frame, reference) seen before, no mimic map, q and q̇ ready
            ready, model, data_of, fid, ref = self._jdot_paths[frame, reference]
            if ready(q) and ready(qdot):
                data = data_of()
                _jjtv(model, data, q, qdot)
                return _fjtv(model, data, fid, ref)
        except (KeyError, TypeError):
            pass
        kin, coords = self._kin, self._coords
        ref = resolve_reference(reference)
        fid, _, qc = self._checked(q, frame, allow_batch=False)
        vc: FloatArray = coords.check(qdot, name="qdot", allow_batch=False)
        # not at dof 1: eigenpy gives a (6, 1) result the shape (6,)
        if (
            coords.identity
            and kin.dof > 1
            and (frame is None or type(frame) is str)
            and type(reference) is str
            and len(self._jdot_paths) < 256
        ):
            self._jdot_paths[frame, reference] = (coords.ready, kin.model, kin.data, fid, ref)
        return _derivatives.jacobian_time_variation(kin, qc, vc, fid, ref)

    def kinematic_hessian(
        self, q: ArrayLike, frame: str | None = None, reference: Reference = "local_world_aligned"
    ) -> FloatArray:
        """∂J/∂q, (6, dof, dof) with H[:, :, k] = ∂J/∂q_k, in ``reference``. See
        :mod:`kinengine.kinematics.derivatives`."""
        ref = resolve_reference(reference)
        fid, _, qc = self._checked(q, frame, allow_batch=False)
        return _derivatives.kinematic_hessian(self._kin, qc, fid, ref)

    # -- singularities ------------------------------------------------------------------------------
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
        return _manipulability.singularity_report(self, q, frame, rows, tolerance=tolerance)

    def manipulability(
        self, q: ArrayLike, frame: str | None = None, rows: Rows = "all"
    ) -> float | FloatArray:
        """Yoshikawa's sqrt(det(J Jᵀ)) of the chosen rows of J_e0; (N,) for q (N, dof)."""
        return _manipulability.manipulability(self, q, frame, rows)

    def velocity_ellipsoid(self, q: ArrayLike, frame: str | None = None) -> VelocityEllipsoid:
        """Axes and semi-axes [m/s per unit joint speed] of {J_v u : |u| <= 1} in the root frame."""
        return _manipulability.velocity_ellipsoid(self, q, frame)

    def require_regular(
        self,
        q: ArrayLike,
        frame: str | None = None,
        rows: Rows = "all",
        *,
        tolerance: float = DEFAULT_TOLERANCE,
    ) -> SingularityReport:
        """The singularity report, or KinematicSingularityError if J_e0 (rows) loses rank."""
        return _manipulability.require_regular(self, q, frame, rows, tolerance=tolerance)

    # -- inverse kinematics -------------------------------------------------------------------------
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
        method: str = "auto",
        avoid_collisions: bool = False,
    ) -> IKResult | IKBatchResult:
        """Differential IK (damped least squares) to a 4x4 pose, a batch of poses (N, 4, 4) (an IKBatchResult
        of N results, solved vectorized), a parameter target χ, or a mapping {frame: T_IF (4, 4)} solved for
        every frame at once (``frame`` None; ``rows``/``weights`` one spec or {frame: spec}; a MultiIKResult
        whose errors are the maxima over the frames, ``frame_errors`` per frame). See
        :func:`kinengine.control.ik.inverse_kinematics` for the options. ``method``: "auto" (the closed form
        when the chain has one, see :meth:`ik_solutions`), "closed_form" or "numeric". ``avoid_collisions``:
        a solution in collision (:meth:`in_collision`) is solved again from random collision-free starts,
        ``restarts`` times, else returned with success False; a batch's colliding rows get success False."""
        from .control import ik as _ik  # here: inverse kinematics is imported by its first call

        solve = functools.partial(
            _ik.inverse_kinematics,
            self,
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
            method=method,
        )
        result = solve(q0)
        if avoid_collisions:
            from .control.ik_repair import collision_free

            result = collision_free(self, result, solve, restarts, rng)
        return result

    # -- model editing (kinengine.model.editing, imported by the first edit) ----------------------
    def with_frame(self, name: str, parent: str, placement: ArrayLike) -> Robot:
        """A new Robot with frame ``name`` fixed to frame ``parent`` (a link or joint) at ``placement``:
        T_parent,name as a (4, 4) homogeneous transform [m], or a pair (xyz [m], rpy [rad]). The frame is a
        new link on a fixed joint ``<name>_joint``; it is in ``frame_names``, ``urdf_text`` (edited alike)
        and everything else. See :func:`kinengine.model.editing.add_frame`."""
        from .model.editing import add_frame

        return self._edited(add_frame(self._description, name, parent, placement))

    def locked(self, values: Mapping[str, float]) -> Robot:
        """A new Robot with the named joints fixed at their values [rad or m] (mimic followers too, at
        multiplier·value + offset); the other coordinates keep their order. Its poses and Jacobians equal
        this robot's at those values with the locked columns removed. ConfigurationError for a value
        outside the limits. See :func:`kinengine.model.editing.lock_joints`."""
        from .model.editing import lock_joints

        return self._edited(lock_joints(self._description, values))

    def _edited(self, description: RobotDescription) -> Robot:
        """The Robot of an edited description: same name, end effector, packages, obstacles and an SRDF's
        disabled pairs; its URDF text edited alike."""
        from .model.editing import edited_urdf_text

        text = edited_urdf_text(self._urdf_text, description)
        return self._rebuilt(description, text, self._obstacles, self._disabled_pairs)

    def _rebuilt(
        self,
        description: RobotDescription,
        text: str,
        obstacles: tuple[Obstacle, ...],
        disabled: frozenset[frozenset[str]],
    ) -> Robot:
        robot = type(self)(
            description, text, name=self._name, end_effector=self._end_effector, packages=self._packages
        )
        robot._obstacles, robot._disabled_pairs = obstacles, disabled
        return robot

    # -- presentation (matplotlib and viser imported only when asked for) ------------------------
    def plot(
        self,
        q: ArrayLike | None = None,
        ax: matplotlib.axes.Axes | None = None,
        *,
        frames: Sequence[str] = (),
        ellipsoid: str | None = None,
        axis_length: float | None = None,
        title: bool | str = True,
    ) -> matplotlib.axes.Axes:
        """A matplotlib 3D picture of the robot at q (None: neutral); returns the axes. See
        :func:`kinengine.presentation.plotting.plot_robot`."""
        from .presentation.plotting import plot_robot

        return plot_robot(
            self, q, ax, frames=frames, ellipsoid=ellipsoid, axis_length=axis_length, title=title
        )

    def view(
        self,
        q: ArrayLike | None = None,
        *,
        port: int | None = None,
        frames: Sequence[str] = (),
        ellipsoid: str | None = None,
        parameterization: str = "euler_zyx",
        meshes: bool = True,
        host: str = "127.0.0.1",
    ) -> Viewer:
        """Serve the robot at q (None: neutral) in the browser (Viser); returns the running viewer:
        ``.url``, ``.update(q)`` (moves the robot live), ``.close()``. Needs
        ``pip install 'kinengine[view]'``. See :func:`kinengine.presentation.viewer.view`."""
        from .presentation.viewer import view

        return view(
            self,
            q,
            port=port,
            host=host,
            frames=frames,
            ellipsoid=ellipsoid,
            parameterization=parameterization,
            meshes=meshes,
        )

    # -- kinematics -------------------------------------------------------------------------
    def frame_id(self, frame: str) -> int:
        """Pinocchio's frame index of a frame name (FrameNotFoundError with suggestions otherwise)."""
        return self._kin.frame_id(frame)

    def _frame_id(self, frame: str | None) -> int:
        """:meth:`frame_id` of ``frame``, None: the end effector."""
        return self._kin.frame_id(self._end_effector if frame is None else frame)

    def _checked(
        self,
        q: ArrayLike,
        frame: str | None,
        relative_to: str | None = None,
        *,
        check_limits: bool = False,
        allow_batch: bool = True,
    ) -> tuple[int, int | None, FloatArray]:
        """A method's inputs checked, names before values: (the frame id of ``frame`` (None: the end
        effector), that of ``relative_to`` (None if not given), q as float64 (dof,) or (N, dof))."""
        fa = self._frame_id(frame)
        fb = None if relative_to is None else self._kin.frame_id(relative_to)
        return fa, fb, self._coords.check(q, check_limits=check_limits, allow_batch=allow_batch)

    def frame(self, name: str | None = None, *, check_inputs: bool = True) -> FrameHandle:
        """A handle on one frame (default: end_effector) for hot loops: ``fk.pose(q)``,
        ``fk.jacobian(q, reference=...)``, ``fk.kinematics(q, reference=...)`` at single q (dof,), with
        the frame and Pinocchio's functions looked up once. ``check_inputs=False`` skips the input check:
        the caller promises a C-contiguous float64 array of shape (dof,) with finite entries. See
        :mod:`kinengine.kinematics.handle`."""
        return FrameHandle(self._kin, self._end_effector if name is None else name, check_inputs=check_inputs)

    def _handle(self, frame: str | None) -> FrameHandle:
        """The Robot's own handle of ``frame`` (None: the end effector): inputs checked, batches taken to
        the vectorized path; kept for up to 256 frame names (frame_pose, jacobian, kinematics use it)."""
        try:
            return self._handles[frame]
        except (KeyError, TypeError):
            pass
        handle = FrameHandle(self._kin, self._end_effector if frame is None else frame, batches=True)
        if len(self._handles) < 256:
            self._handles[frame] = handle
        return handle

    @overload
    def frame_pose(
        self, q: Vector | Sequence[float], frame: str | None = ..., *, check_limits: bool = ...
    ) -> Matrix: ...
    @overload
    def frame_pose(
        self, q: Matrix | Sequence[Sequence[float]], frame: str | None = ..., *, check_limits: bool = ...
    ) -> Stack: ...
    @overload
    def frame_pose(
        self, q: ArrayLike, frame: str | None = ..., *, check_limits: bool = ...
    ) -> FloatArray: ...

    def frame_pose(self, q: ArrayLike, frame: str | None = None, *, check_limits: bool = False) -> FloatArray:
        """T_IF: pose of ``frame`` (default: end_effector) in the root link frame.

        q (dof,) -> (4, 4); q (N, dof) -> (N, 4, 4). Translation in [m].
        """
        try:
            handle = self._handles[frame]
        except (KeyError, TypeError):
            handle = self._handle(frame)
        if check_limits is False:
            return handle.pose(q)
        return handle.pose(self._coords.check(q, check_limits=check_limits))

    @overload
    def jacobian(
        self,
        q: Vector | Sequence[float],
        frame: str | None = ...,
        reference: Reference = ...,
        *,
        check_limits: bool = ...,
    ) -> Matrix: ...
    @overload
    def jacobian(
        self,
        q: Matrix | Sequence[Sequence[float]],
        frame: str | None = ...,
        reference: Reference = ...,
        *,
        check_limits: bool = ...,
    ) -> Stack: ...
    @overload
    def jacobian(
        self, q: ArrayLike, frame: str | None = ..., reference: Reference = ..., *, check_limits: bool = ...
    ) -> FloatArray: ...

    def jacobian(
        self,
        q: ArrayLike,
        frame: str | None = None,
        reference: Reference = "local_world_aligned",
        *,
        check_limits: bool = False,
    ) -> FloatArray:
        """Geometric Jacobian of ``frame`` in ``reference``, rows [linear; angular].

        q (dof,) -> (6, dof); q (N, dof) -> (N, 6, dof). See the module doc for the references.
        """
        try:
            handle = self._handles[frame]
        except (KeyError, TypeError):
            handle = self._handle(frame)
        if check_limits is False:
            return handle.jacobian(q, reference)
        resolve_reference(reference)  # an unknown reference is reported before q
        return handle.jacobian(self._coords.check(q, check_limits=check_limits), reference)

    @overload
    def kinematics(
        self,
        q: Vector | Sequence[float],
        frame: str | None = ...,
        reference: Reference = ...,
        *,
        check_limits: bool = ...,
        out: None = ...,
        workers: int | None = ...,
    ) -> tuple[Matrix, Matrix]: ...
    @overload
    def kinematics(
        self,
        q: Matrix | Sequence[Sequence[float]],
        frame: str | None = ...,
        reference: Reference = ...,
        *,
        check_limits: bool = ...,
        out: tuple[FloatArray, FloatArray] | None = ...,
        workers: int | None = ...,
    ) -> tuple[Stack, Stack]: ...
    @overload
    def kinematics(
        self,
        q: ArrayLike,
        frame: str | None = ...,
        reference: Reference = ...,
        *,
        check_limits: bool = ...,
        out: tuple[FloatArray, FloatArray] | None = ...,
        workers: int | None = ...,
    ) -> tuple[FloatArray, FloatArray]: ...

    def kinematics(
        self,
        q: ArrayLike,
        frame: str | None = None,
        reference: Reference = "local_world_aligned",
        *,
        check_limits: bool = False,
        out: tuple[FloatArray, FloatArray] | None = None,
        workers: int | None = None,
    ) -> tuple[FloatArray, FloatArray]:
        """(T_IF, J) in one pass: (4, 4) and (6, dof) for q (dof,); (N, 4, 4) and (N, 6, dof) for q (N, dof),
        equal bit for bit to :meth:`frame_pose` and :meth:`jacobian` called separately. Batches only:
        ``out=(T, J)`` preallocated C-contiguous float64 arrays of those shapes, filled and returned (q may
        lie in their memory: it is then read from a copy); without it, outputs of 4 to 512 MiB view memory
        kept for reuse (:mod:`kinengine.kinematics.outputs`); ``workers``: threads to use (default: the
        cores this process may use)."""
        try:
            handle = self._handles[frame]
        except (KeyError, TypeError):
            handle = self._handle(frame)
        if check_limits is False and out is None and workers is None:
            return handle.kinematics(q, reference)
        ref = resolve_reference(reference)
        q = self._coords.check(q, check_limits=check_limits)
        if q.ndim == 2:
            out, workers = _batch.checked_out(out, len(q), self.dof), _batch.checked_workers(workers)
            T, J = _batch.evaluate(self._kin, q, handle.frame_id, ref, out=out, workers=workers)
            return T, J  # type: ignore[return-value]
        if out is not None:
            raise OptionError("`out=` is for batches q (N, dof); a single q returns fresh arrays")
        _batch.checked_workers(workers)
        return handle.kinematics(q, reference)

    # -- closed-form inverse kinematics ---------------------------------------------------------
    def ik_solutions(
        self,
        T: ArrayLike,
        frame: str | None = None,
        *,
        q_near: ArrayLike | None = None,
        within_limits: bool = True,
        all_turns: bool = False,
        avoid_collisions: bool = False,
    ) -> IKSolutions:
        """Every joint solution of the pose T_IF (4, 4) of ``frame`` (default: end effector) in the root link
        frame [m], or of each pose of (N, 4, 4), in closed form (the ``ik`` extra: EAIK's subproblem
        decomposition of the 6 revolute joints that move ``frame``). Each angle within its joint's range
        (continuous joints in (−π, π]); ``all_turns``: every 2π shift within the limits too;
        ``within_limits=False``: solutions outside the limits too, flagged. Sorted by distance to
        ``q_near`` (dof,) or (N, dof) when given; ``avoid_collisions``: the solutions in collision
        (:meth:`in_collision`, obstacles included) dropped. See :mod:`kinengine.control.closed_form`."""
        import kinengine.control.closed_form as _closed_form  # absolute: a third of the relative form's cost

        found = _closed_form.ik_solutions(
            self, T, frame, q_near=q_near, within_limits=within_limits, all_turns=all_turns
        )
        if checked_flag(avoid_collisions, "avoid_collisions"):
            from .control.ik_repair import without_collisions

            found = without_collisions(self, found)
        return found

    # -- controller: URDF rate limits, manipulability gradient ---
    @property
    def velocity_limits(self) -> FloatArray:
        """(dof,) each coordinate's URDF ``<limit velocity>`` [rad/s | m/s]; inf where absent (read-only)."""
        return _rate_limits.urdf_velocity_limits(self)

    @property
    def effort_limits(self) -> FloatArray:
        """(dof,) each coordinate's URDF ``<limit effort>`` [N·m | N]; inf where absent (read-only)."""
        return _rate_limits.urdf_effort_limits(self)

    def manipulability_gradient(
        self, q: ArrayLike, frame: str | None = None, rows: Rows = "all"
    ) -> FloatArray:
        """∂w/∂q (dof,) of the manipulability w = sqrt(det(J Jᵀ)) of J_e0[rows] at q (dof,), from the
        kinematic Hessian. See :func:`kinengine.control.manipulability.manipulability_gradient`."""
        return _manipulability.manipulability_gradient(
            self, self._coords.check(q, allow_batch=False), frame, rows
        )

    # -- collisions (kinengine.collision: coal's shapes and the geometry built by the first call) --------
    @property
    def obstacles(self) -> tuple[Obstacle, ...]:
        """The obstacles given to :meth:`with_obstacles` (poses in the root link frame)."""
        return self._obstacles

    @property
    def disabled_collision_pairs(self) -> frozenset[frozenset[str]]:
        """The link pairs an SRDF given to :meth:`with_srdf` disables."""
        return self._disabled_pairs

    def collision_geometry(self, packages: Mapping[str, str] | None = None) -> pin.GeometryModel:
        """Pinocchio's GeometryModel of the URDF's ``<collision>`` elements (meshes as convex hulls) and the
        obstacles, with the checked pairs set; built once per Robot (again if other ``packages`` are given:
        ROS package name -> folder for ``package://`` meshes, default :attr:`packages`), and then used by
        the queries below. URDFError naming the missing mesh files (:mod:`kinengine.collision.geometry`)."""
        from .collision import checked_packages

        chosen = self._packages if packages is None else checked_packages(packages)
        cached = self._collision
        if cached is None or (packages is not None and cached[0] != chosen):
            cached = self._collision = (chosen, self._new_checker(chosen, self._disabled_pairs))
        return cached[1].geometry

    def _new_checker(
        self, packages: Mapping[str, str], disabled: set[frozenset[str]] | frozenset[frozenset[str]]
    ) -> CollisionChecker:
        """A collision model of this robot and its obstacles with these packages and disabled pairs."""
        from .collision import collision_checker

        urdf, obstacles = self._urdf_text, self._obstacles
        return collision_checker(self._kin, urdf, self.source, packages, obstacles, disabled, self.name)

    def collision_checker(self) -> CollisionChecker:
        """The collision model the queries below use (:class:`kinengine.collision.CollisionChecker`)."""
        if self._collision is None:
            self.collision_geometry()
        assert self._collision is not None
        return self._collision[1]

    def collision_pairs(self, srdf: str | os.PathLike[str] | None = None) -> list[tuple[str, str]]:
        """The link pairs checked for collision: adjacent links and rigidly joined ones left out, an SRDF's
        ``<disable_collisions>`` (a file or its text; default: the one given to :meth:`with_srdf`) too, then
        the moving links against each obstacle. See :mod:`kinengine.collision.pairs`."""
        from .collision import read_disabled_pairs

        if srdf is None:
            links = self.collision_checker().links
        else:
            disabled = read_disabled_pairs(srdf)
            self._warn_unknown_links(disabled)
            links = self._new_checker(self._packages, disabled).links
        return list(dict.fromkeys(links))

    def distances(self, q: ArrayLike) -> Distances:
        """Signed distances [m] and witness points (root link frame) of every checked shape pair at q (dof,):
        a :class:`kinengine.Distances` (``pairs``, ``links``, ``distance``, ``p1``, ``p2``)."""
        return self.collision_checker().distances(self._coords.check(q, allow_batch=False))

    def min_distance(self, q: ArrayLike) -> float:
        """The smallest signed distance [m] over the checked pairs at q (dof,); negative: penetration."""
        return self.collision_checker().min_distance(self._coords.check(q, allow_batch=False))

    def in_collision(self, q: ArrayLike) -> bool | npt.NDArray[np.bool_]:
        """q (dof,): True if a checked pair touches or overlaps; Q (N, dof): (N,) bool."""
        checked = self._coords.check(q)
        checker = self.collision_checker()
        return checker.in_collision_batch(checked) if checked.ndim == 2 else checker.in_collision(checked)

    def with_obstacles(self, obstacles: Sequence[Obstacle]) -> Robot:
        """A new Robot with these obstacles (:class:`kinengine.Box`, ``Sphere``, ``Capsule``, ``Mesh``; poses
        in the root link frame) added to this one's, checked against every moving link."""
        from .collision import checked_obstacles

        added = checked_obstacles(obstacles)
        return self._rebuilt(
            self._description, self._urdf_text, self._obstacles + added, self._disabled_pairs
        )

    def with_srdf(self, srdf: str | os.PathLike[str]) -> Robot:
        """A new Robot whose self-collision pairs leave out an SRDF's ``<disable_collisions>`` (a file or its
        text), e.g. one written by ``kinengine collision-pairs``."""
        from .collision import read_disabled_pairs

        disabled = frozenset(read_disabled_pairs(srdf))
        self._warn_unknown_links(disabled)
        return self._rebuilt(self._description, self._urdf_text, self._obstacles, disabled)

    def _warn_unknown_links(self, disabled: set[frozenset[str]] | frozenset[frozenset[str]]) -> None:
        """A UserWarning naming an SRDF's links this robot (links and obstacles) does not have."""
        from .collision import warn_unknown_links

        known = [link.name for link in self._description.links] + [
            o.name or f"obstacle_{k}" for k, o in enumerate(self._obstacles)
        ]
        warn_unknown_links(disabled, known)

    def _collision_state(self) -> dict[str, object] | None:
        """What pickling keeps of the collision setup (None: the defaults)."""
        if not self._obstacles and not self._disabled_pairs:
            return None
        return {"_obstacles": self._obstacles, "_disabled_pairs": self._disabled_pairs}


def _rebuild_robot(
    description: RobotDescription,
    urdf_text: str,
    name: str,
    end_effector: str,
    packages: Mapping[str, str] | None = None,
) -> Robot:
    """The Robot of :meth:`Robot.__reduce__` (the unpickling path)."""
    return Robot(description, urdf_text, name=name, end_effector=end_effector, packages=packages)


def _default_end_effector(description: RobotDescription) -> str:
    """'tool0' if present, else the leaf link with the most movable joints above it (first in file order)."""
    if any(link.name == "tool0" for link in description.links):
        return "tool0"
    depth = {description.root: 0}
    parents = set()
    for j in description.joints:  # depth-first order: a parent is seen before its children
        depth[j.child] = depth[j.parent] + (1 if j.movable else 0)
        parents.add(j.parent)
    leaves = [link.name for link in description.links if link.name not in parents]
    return max(leaves, key=lambda n: depth.get(n, 0)) if leaves else description.root


__all__ = ["Robot"]
