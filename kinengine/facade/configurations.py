"""The Robot's configurations: the neutral and random ones, q from joint names, the checked copy of q, and
Pinocchio's own model and configuration (q_pin = M q + b, see :mod:`kinengine.model.coordinates`)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, cast

import numpy as np
import pinocchio as pin

from ..arrays import ArrayLike, FloatArray
from ..kinematics.options import checked_flag, checked_rng

if TYPE_CHECKING:
    from ..robot import Robot


class ConfigurationMethods:
    """Configurations q (dof,) [rad | m] in ``joint_names`` order, and Pinocchio's view of them."""

    def pinocchio_model(self) -> pin.Model:
        """A copy of Pinocchio's Model: one plain joint (nq = nv = 1) per movable URDF joint, mimic joints
        included as ordinary joints; its configuration is :meth:`pinocchio_configuration`."""
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        return pin.Model(robot.engine.model)

    def pinocchio_configuration(self, q: ArrayLike) -> FloatArray:
        """Pinocchio's configuration (nq,) for q: q_pin = M q + b (every movable joint's value, mimic
        joints at multiplier·leader + offset); equal to q for robots without mimic joints."""
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        q = robot.engine.coordinates.check(q, allow_batch=False)
        return np.array(robot.engine.coordinates.to_pinocchio(q), dtype=float)

    # -- configurations ---------------------------------------------------------------------
    def neutral(self) -> FloatArray:
        """The zero configuration clipped into the joint limits, (dof,): q = 0 unless a joint's limits exclude
        0 (e.g. the Panda's joint 4), which then sits at its nearest limit (as MoveIt's default state)."""
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        return np.clip(np.zeros(robot.dof), robot.engine.coordinates.lower, robot.engine.coordinates.upper)

    def random_configuration(
        self, rng: np.random.Generator | int | None = None, size: int | None = None
    ) -> FloatArray:
        """Uniform within limits, (dof,) or (size, dof); continuous joints in [-π, π)."""
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        return robot.engine.coordinates.sample(checked_rng(rng), size)

    def configuration(
        self, values: Mapping[str, float], *, base: ArrayLike | None = None, strict: bool = True
    ) -> FloatArray:
        """q from joint name -> value (e.g. a ROS JointState); unnamed joints at ``base`` (default neutral).

        Unknown names raise FrameNotFoundError (``strict=False`` ignores them).
        """
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        start = (
            robot.neutral()
            if base is None
            else np.array(robot.engine.coordinates.check(base, name="base", allow_batch=False))
        )
        return robot.engine.coordinates.from_mapping(values, start, strict=checked_flag(strict, "strict"))

    def check_configuration(
        self, q: ArrayLike, *, check_limits: bool = True, batch: bool = True
    ) -> FloatArray:
        """A fresh float64 copy of q, (dof,) or (with ``batch``) (N, dof); ConfigurationError on bad shape,
        values or (optionally) limits."""
        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        return np.array(
            robot.engine.coordinates.check(
                q, check_limits=check_limits, allow_batch=checked_flag(batch, "batch")
            )
        )
