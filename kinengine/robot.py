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
Data, coordinate map); its other method groups live in :mod:`kinengine.facade`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import overload

from .arrays import ArrayLike, FloatArray, Matrix, Reference, Stack, Vector
from .errors import OptionError
from .facade.analysis import AnalysisMethods
from .facade.analytic import AnalyticMethods
from .facade.collisions import CollisionMethods
from .facade.configurations import ConfigurationMethods
from .facade.editing import EditingMethods
from .facade.presentation import PresentationMethods
from .kinematics import Kinematics, resolve_reference
from .kinematics import batch as _batch
from .kinematics.handle import FrameHandle
from .urdf import RobotDescription


class Robot(
    ConfigurationMethods,
    AnalyticMethods,
    AnalysisMethods,
    EditingMethods,
    PresentationMethods,
    CollisionMethods,
):
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

    # -- kinematics -------------------------------------------------------------------------
    def frame_id(self, frame: str) -> int:
        """Pinocchio's frame index of a frame name (FrameNotFoundError with suggestions otherwise)."""
        return self._kin.frame_id(frame)

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
        lie in their memory: it is then read from a copy); ``workers``: threads to use (default: the cores
        this process may use)."""
        try:
            handle = self._handles[frame]
        except (KeyError, TypeError):
            handle = self._handle(frame)
        if check_limits is False and out is None and workers is None:
            return handle.kinematics(q, reference)
        ref = resolve_reference(reference)
        q = self._coords.check(q, check_limits=check_limits)
        if q.ndim == 2:
            T, J = _batch.evaluate(
                self._kin,
                q,
                handle.frame_id,
                ref,
                out=_batch.checked_out(out, len(q), self.dof),
                workers=_batch.checked_workers(workers),
            )
            return T, J  # type: ignore[return-value]
        if out is not None:
            raise OptionError("`out=` is for batches q (N, dof); a single q returns fresh arrays")
        _batch.checked_workers(workers)
        return handle.kinematics(q, reference)


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
