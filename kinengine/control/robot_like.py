"""What the layers below the facade read of a robot: :class:`RobotLike`, the public members of
:class:`kinengine.Robot` that the Task, inverse kinematics, the QP step, the singularity measures, the
pictures and ``kinengine verify`` use, typing their argument against it, never against the facade."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Protocol

import numpy as np
import numpy.typing as npt

from ..arrays import FloatArray, Reference
from ..kinematics.engine import Kinematics
from ..urdf import RobotDescription

if TYPE_CHECKING:  # manipulability types its own argument against RobotLike
    from ..collision import CollisionChecker
    from .ik import IKResult
    from .ik_batch import IKBatchResult
    from .manipulability import VelocityEllipsoid


class RobotLike(Protocol):
    """A robot's description, limits and the kinematics the lower layers call (see :class:`kinengine.Robot`
    for each member's frames and units)."""

    @property
    def name(self) -> str: ...

    @property
    def dof(self) -> int: ...

    @property
    def joint_names(self) -> Sequence[str]: ...

    @property
    def frame_names(self) -> Sequence[str]: ...

    @property
    def end_effector(self) -> str: ...

    @property
    def description(self) -> RobotDescription: ...

    @property
    def source(self) -> str: ...

    @property
    def urdf_text(self) -> str: ...

    @property
    def packages(self) -> Mapping[str, str]: ...

    @property
    def engine(self) -> Kinematics: ...

    @property
    def lower_limits(self) -> FloatArray: ...

    @property
    def upper_limits(self) -> FloatArray: ...

    def frame_id(self, frame: str) -> int: ...

    def neutral(self) -> FloatArray: ...

    def random_configuration(
        self, rng: np.random.Generator | int | None = None, size: int | None = None
    ) -> FloatArray: ...

    def check_configuration(
        self, q: npt.ArrayLike, *, check_limits: bool = True, batch: bool = True
    ) -> FloatArray: ...

    def frame_pose(
        self, q: npt.ArrayLike, frame: str | None = None, *, check_limits: bool = False
    ) -> FloatArray: ...

    def jacobian(
        self, q: npt.ArrayLike, frame: str | None = None, reference: Reference = "local_world_aligned"
    ) -> FloatArray: ...

    def pose_parameters(
        self,
        q: npt.ArrayLike,
        frame: str | None = None,
        position: str | None = "cartesian",
        rotation: str | None = "euler_zyx",
        *,
        on_singularity: str | None = "raise",
    ) -> FloatArray: ...

    def analytic_jacobian(
        self,
        q: npt.ArrayLike,
        frame: str | None = None,
        position: str | None = "cartesian",
        rotation: str | None = "euler_zyx",
        *,
        singularity_threshold: float = 1e-6,
    ) -> FloatArray: ...

    def velocity_ellipsoid(self, q: npt.ArrayLike, frame: str | None = None) -> VelocityEllipsoid: ...

    def kinematic_hessian(
        self, q: npt.ArrayLike, frame: str | None = None, reference: Reference = "local_world_aligned"
    ) -> FloatArray: ...

    def in_collision(self, q: npt.ArrayLike) -> bool | npt.NDArray[np.bool_]: ...

    def collision_checker(self) -> CollisionChecker: ...

    def inverse_kinematics(
        self,
        target: npt.ArrayLike,
        frame: str | None = None,
        q0: npt.ArrayLike | None = None,
        *,
        tol_position: float = 1e-6,
        tol_rotation: float = 1e-6,
        restarts: int = 3,
        method: str = "auto",
    ) -> IKResult | IKBatchResult: ...


__all__ = ["RobotLike"]
