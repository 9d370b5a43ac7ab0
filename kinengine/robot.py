"""The :class:`Robot`: a fixed-base kinematic model built from a validated URDF.

Frames and conventions
----------------------
* "world" in Pinocchio is the URDF's root link frame; it is the seed's inertial frame I.
* ``frame_pose(q, f)`` is T_IF: the pose of frame f in the root link frame, (4, 4).
* ``jacobian(q, f, reference)``: rows [linear; angular], columns in ``joint_names`` order.
  - "local_world_aligned": I J_e0 of the seed (eq. 2.155) — velocity of f's origin and
    angular velocity, both in I.
  - "local": the same twist expressed in f: blockdiag(C_IF^T, C_IF^T) · J_lwa.
  - "world": the spatial velocity in I: linear rows are the velocity of the body point
    that currently coincides with I's origin: v_O = v_f − ω × p_f  (p_f = origin of f in I).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from math import isfinite
import threading
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from . import batch
from .analytic import DEFAULT_SINGULARITY_THRESHOLD, analytic_at, as_rows, frame_views, pose_map
from .errors import FrameNotFoundError, OptionError
from .joint_space import JointSpace
from .urdf import RobotDescription, build_pinocchio_model

if TYPE_CHECKING:  # imported lazily at run time: these modules import this one
    from .ik import IKResult
    from .manipulability import SingularityReport, VelocityEllipsoid
    from .task import Task

_NDARRAY = np.ndarray
_F64 = np.dtype(np.float64)

REFERENCES: dict[object, pin.ReferenceFrame] = {
    "world": pin.WORLD,
    "local": pin.LOCAL,
    "local_world_aligned": pin.LOCAL_WORLD_ALIGNED,
    pin.WORLD: pin.WORLD,
    pin.LOCAL: pin.LOCAL,
    pin.LOCAL_WORLD_ALIGNED: pin.LOCAL_WORLD_ALIGNED,
}


def resolve_reference(reference: object) -> pin.ReferenceFrame:
    """Pinocchio's ReferenceFrame for "world", "local", "local_world_aligned" (or the enum itself)."""
    try:
        return REFERENCES[reference]
    except (KeyError, TypeError):
        raise OptionError(f"unknown reference {reference!r}; use 'world', 'local' or "
                              "'local_world_aligned' (or a pinocchio.ReferenceFrame)") from None


class Robot:
    """A fixed-base robot: one coordinate per independent movable joint.

    Build it with :func:`kinengine.load` or :func:`kinengine.load_urdf_string`. The
    Pinocchio Model is private and immutable; each thread gets its own Data, so one
    Robot may be used from several threads at once. Every returned array is a fresh copy.
    """

    def __init__(self, description: RobotDescription, urdf_text: str, *, name: str | None = None,
                 end_effector: str | None = None) -> None:
        model = build_pinocchio_model(description)  # from the canonical XML, checked joint for joint
        self._model = model
        self._description = description
        self._urdf_text = urdf_text
        self._name = name or description.name
        self._joints = JointSpace(model, description)
        self._identity_q = self._joints.identity
        self._shape = (self._joints.dof,)
        self._frame_ids = _frame_ids(model)
        self._frame_names = tuple(self._frame_ids)
        self._end_effector = end_effector if end_effector in self._frame_ids else _default_end_effector(
            description)
        self._tls = threading.local()
        self._memo: dict[object, object] = {}

    # -- description ------------------------------------------------------------------------
    name = property(lambda self: self._name, doc="Robot name (catalog short name or the URDF's name).")
    dof = property(lambda self: self._joints.dof, doc="Number of coordinates in q.")
    joint_names = property(lambda self: self._joints.names, doc="Names of q's coordinates, in order.")
    lower_limits = property(lambda self: self._joints.lower, doc="(dof,) lower limits [rad or m]; -inf if none.")
    upper_limits = property(lambda self: self._joints.upper, doc="(dof,) upper limits [rad or m]; +inf if none.")
    frame_names = property(lambda self: self._frame_names, doc="Every link and joint frame, in model order.")
    end_effector = property(lambda self: self._end_effector, doc="Default end-effector frame name.")
    description = property(lambda self: self._description, doc="The validated RobotDescription.")
    urdf_text = property(lambda self: self._urdf_text, doc="The URDF text the robot was loaded from.")
    source = property(lambda self: self._description.source, doc="File the robot came from, or '<string>'.")

    def __repr__(self) -> str:
        return f"<Robot {self._name!r}: {self.dof} dof, {len(self._frame_names)} frames>"

    def pinocchio_model(self) -> pin.Model:
        """A copy of the Pinocchio Model (continuous joints have nq = 2; mimic joints nq = 0)."""
        return pin.Model(self._model)

    def pinocchio_configuration(self, q: object) -> np.ndarray:
        """Pinocchio's configuration vector (nq,) for q (continuous joints as cos, sin)."""
        q = self._joints.check(q, allow_batch=False)
        return np.array(self._joints.to_pinocchio(q), dtype=float)

    # -- configurations ---------------------------------------------------------------------
    def neutral(self) -> np.ndarray:
        """The zero configuration clipped into the joint limits, (dof,): q = 0 unless a joint's limits exclude
        0 (e.g. the Panda's joint 4), which then sits at its nearest limit (as MoveIt's default state)."""
        return np.clip(np.zeros(self.dof), self.lower_limits, self.upper_limits)

    def random_configuration(self, rng: np.random.Generator | int | None = None,
                             size: int | None = None) -> np.ndarray:
        """Uniform within limits, (dof,) or (size, dof); continuous joints in [-π, π)."""
        return self._joints.sample(np.random.default_rng(rng), size)

    def configuration(self, values: Mapping[str, float], *, base: object = None,
                      strict: bool = True) -> np.ndarray:
        """q from joint name -> value (e.g. a ROS JointState); unnamed joints at ``base`` (default neutral).

        Unknown names raise FrameNotFoundError (``strict=False`` ignores them).
        """
        start = self.neutral() if base is None else np.array(self._joints.check(base, name="base",
                                                                              allow_batch=False))
        return self._joints.from_mapping(values, start, strict=strict)

    def check_configuration(self, q: object, *, check_limits: bool = True, batch: bool = True) -> np.ndarray:
        """A fresh float64 copy of q, (dof,) or (with ``batch``) (N, dof); ConfigurationError on bad shape,
        values or (optionally) limits."""
        return np.array(self._joints.check(q, check_limits=check_limits, allow_batch=batch))

    # -- kinematics -------------------------------------------------------------------------
    def frame_id(self, frame: str) -> int:
        """Pinocchio's frame index of a frame name (FrameNotFoundError with suggestions otherwise)."""
        try:
            return self._frame_ids[frame]
        except (KeyError, TypeError):
            raise FrameNotFoundError(frame, self._frame_names) from None

    def _memoized(self, key: object, make: Callable[[], object]) -> object:
        """A constant derived from the model (a compiled chain, an IK seed table), made once per key.
        Two threads may both make it the first time; their results are equal and one is kept."""
        try:
            return self._memo[key]
        except KeyError:
            return self._memo.setdefault(key, make())

    def _data(self) -> pin.Data:
        try:
            return self._tls.data
        except AttributeError:
            data = self._tls.data = self._model.createData()
            return data

    def frame_pose(self, q: object, frame: str | None = None, *, check_limits: bool = False) -> np.ndarray:
        """T_IF: pose of ``frame`` (default: end_effector) in the root link frame.

        q (dof,) -> (4, 4); q (N, dof) -> (N, 4, 4). Translation in [m].
        """
        try:
            fid = self._frame_ids[frame if frame is not None else self._end_effector]
        except (KeyError, TypeError):
            raise FrameNotFoundError(frame, self._frame_names) from None
        # JointSpace.check's fast path, inlined here, in jacobian and in analytic_jacobian: a call costs
        # ~0.17 µs, 16 % of the call (measured). A float64 (dof,) array with a finite sum goes straight to
        # Pinocchio (which reads strided vectors element by element); anything else gets the full check.
        if not (type(q) is _NDARRAY and q.dtype is _F64 and q.shape == self._shape and not check_limits
                and isfinite(sum(q.tolist()))):
            q = self._joints.check(q, check_limits=check_limits)
            if q.ndim == 2:
                return batch.evaluate(self, q, fid, None, jacobian=False)[0]
        try:
            data = self._tls.data
        except AttributeError:
            data = self._data()
        model = self._model
        pin.forwardKinematics(model, data, q if self._identity_q else self._joints.to_pinocchio(q))
        return pin.updateFramePlacement(model, data, fid).homogeneous

    def jacobian(self, q: object, frame: str | None = None, reference: object = "local_world_aligned", *,
                 check_limits: bool = False) -> np.ndarray:
        """Geometric Jacobian of ``frame`` in ``reference``, rows [linear; angular].

        q (dof,) -> (6, dof); q (N, dof) -> (N, 6, dof). See the module doc for the references.
        """
        try:
            fid = self._frame_ids[frame if frame is not None else self._end_effector]
        except (KeyError, TypeError):
            raise FrameNotFoundError(frame, self._frame_names) from None
        try:
            ref = REFERENCES[reference]
        except (KeyError, TypeError):
            ref = resolve_reference(reference)  # raises with the valid names
        if not (type(q) is _NDARRAY and q.dtype is _F64 and q.shape == self._shape and not check_limits
                and isfinite(sum(q.tolist()))):
            q = self._joints.check(q, check_limits=check_limits)
            if q.ndim == 2:
                return batch.evaluate(self, q, fid, ref, pose=False)[1]
        try:
            data = self._tls.data
        except AttributeError:
            data = self._data()
        J = pin.computeFrameJacobian(self._model, data, q if self._identity_q else self._joints.to_pinocchio(q),
                                     fid, ref)
        return J if J.ndim == 2 else J.reshape(6, 1)  # eigenpy returns a (6, 1) matrix as (6,)

    # -- analytic Jacobians --------------------------------------------------------------------
    def pose_parameters(self, q: object, frame: str | None = None, position: str | None = "cartesian",
                        rotation: str | None = "euler_zyx", *, rows: Sequence[str | int] | None = None,
                        check_limits: bool = False) -> np.ndarray:
        """χ_e(q) = (χ_P, χ_R) of ``frame`` in the root frame, (m,) or (N, m) for q (N, dof).

        ``position``/``rotation`` name a parameterization (None leaves its rows out);
        ``rows`` keeps only the named rows (labels or indices), e.g. ("x", "z", "ry").
        Near a representation singularity the angles stay valid (a warning is issued).
        """
        return pose_map(position, rotation, as_rows(rows)).parameters(
            self.frame_pose(q, frame, check_limits=check_limits))

    def analytic_jacobian(self, q: object, frame: str | None = None, position: str | None = "cartesian",
                          rotation: str | None = "euler_zyx", *, rows: Sequence[str | int] | None = None,
                          singularity_threshold: float = DEFAULT_SINGULARITY_THRESHOLD,
                          check_limits: bool = False) -> np.ndarray:
        """J_eA = ∂χ_e/∂q = E_e(χ_e) · J_e0(q), (m, dof) or (N, m, dof) for q (N, dof).

        Raises RepresentationSingularityError when χ_e is closer than ``singularity_threshold``
        to its parameterization's singular set (the message names regular alternatives).
        """
        pmap = pose_map(position, rotation, rows if rows is None else as_rows(rows))
        try:
            fid = self._frame_ids[frame if frame is not None else self._end_effector]
        except (KeyError, TypeError):
            raise FrameNotFoundError(frame, self._frame_names) from None
        if not (type(q) is _NDARRAY and q.dtype is _F64 and q.shape == self._shape and not check_limits
                and isfinite(sum(q.tolist()))):
            q = self._joints.check(q, check_limits=check_limits)
            if q.ndim == 2:
                return batch.analytic_jacobian(self, q, fid, pmap, singularity_threshold)
        tls = self._tls
        try:
            views = tls.placements[fid]
        except (AttributeError, KeyError):  # this thread's first call for the frame
            if not hasattr(tls, "placements"):
                tls.placements = {}
            views = tls.placements[fid] = frame_views(self._data(), fid)
        qp = q if self._identity_q else self._joints.to_pinocchio(q)
        return analytic_at(self._model, tls.data, qp, fid, views, pmap, singularity_threshold)

    def task(self, frames: str | Sequence[str] | None = None, position: str | None = "cartesian",
             rotation: str | None = "euler_zyx", **options: object) -> "Task":
        """A :class:`~kinengine.task.Task` for a control loop: ``task.update(q, qdot)`` fills pose, χ,
        J_e0, J_A (and with q̇ the twist, J̇_e0, J̇_A) into preallocated read-only arrays.

        ``frames``: one name (default: end_effector) or several (blocks stacked). Options:
        rows, check_inputs, continuous, singularity_threshold.
        """
        from .task import Task
        return Task(self, self._end_effector if frames is None else frames, position, rotation, **options)

    # -- derivatives, singularities, inverse kinematics (thin wrappers; see their modules) ----------
    def jacobian_time_variation(self, q: object, qdot: object, frame: str | None = None,
                                reference: object = "local_world_aligned") -> np.ndarray:
        """J̇ = dJ/dt of the geometric Jacobian in ``reference`` along q̇, (6, dof). See kinengine.derivatives."""
        from .derivatives import jacobian_time_variation
        return jacobian_time_variation(self, q, qdot, frame, reference)

    def kinematic_hessian(self, q: object, frame: str | None = None,
                          reference: object = "local_world_aligned") -> np.ndarray:
        """∂J/∂q, (6, dof, dof) with H[:, :, k] = ∂J/∂q_k, in ``reference``. See kinengine.derivatives."""
        from .derivatives import kinematic_hessian
        return kinematic_hessian(self, q, frame, reference)

    def analytic_hessian(self, q: object, frame: str | None = None, position: str | None = "cartesian",
                         rotation: str | None = "euler_zyx", **options: object) -> np.ndarray:
        """∂J_A/∂q, (m, dof, dof). Options: rows, singularity_threshold. See kinengine.derivatives."""
        from .derivatives import analytic_hessian
        return analytic_hessian(self, q, frame, position, rotation, **options)

    def singularity_report(self, q: object, frame: str | None = None, rows: object = "all",
                           **options: object) -> "SingularityReport":
        """Singular values, manipulability, condition number and lost directions of J_e0 (kinematic singularities)."""
        from .manipulability import singularity_report
        return singularity_report(self, q, frame, rows, **options)

    def manipulability(self, q: object, frame: str | None = None, rows: object = "all") -> float | np.ndarray:
        """Yoshikawa's sqrt(det(J Jᵀ)) of the chosen rows of J_e0; (N,) for q (N, dof)."""
        from .manipulability import manipulability
        return manipulability(self, q, frame, rows)

    def velocity_ellipsoid(self, q: object, frame: str | None = None) -> "VelocityEllipsoid":
        """Axes and semi-axes [m/s per unit joint speed] of {J_v u : |u| <= 1} in the root frame."""
        from .manipulability import velocity_ellipsoid
        return velocity_ellipsoid(self, q, frame)

    def plot(self, q: object = None, ax: object = None, **options: object) -> object:
        """A matplotlib 3D picture of the robot at q (None: neutral); returns the axes. See kinengine.plotting."""
        from .plotting import plot_robot
        return plot_robot(self, q, ax, **options)

    def require_regular(self, q: object, frame: str | None = None, rows: object = "all",
                        **options: object) -> "SingularityReport":
        """The singularity report, or KinematicSingularityError if J_e0 (rows) loses rank."""
        from .manipulability import require_regular
        return require_regular(self, q, frame, rows, **options)

    def inverse_kinematics(self, target: object, frame: str | None = None, q0: object = None,
                           **options: object) -> "IKResult":
        """Differential IK (damped least squares) to a 4x4 pose or a parameter target χ. See kinengine.ik."""
        from .ik import inverse_kinematics
        return inverse_kinematics(self, target, frame, q0, **options)


def _frame_ids(model: pin.Model) -> dict[str, int]:
    """Frame name -> index for every frame but 'universe'; a link wins over a joint of the same name."""
    ids: dict[str, int] = {}
    for kind_first in (True, False):
        for fid in range(model.nframes):
            frame = model.frames[fid]
            if frame.name == "universe" or frame.name in ids:
                continue
            if (frame.type == pin.FrameType.BODY) == kind_first:
                ids[frame.name] = fid
    return dict(sorted(ids.items(), key=lambda kv: kv[1]))


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


__all__ = ["Robot", "REFERENCES", "resolve_reference"]
