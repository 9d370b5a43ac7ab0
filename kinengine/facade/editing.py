"""The Robot's model-editing methods: each returns a new Robot built once from an edited description
(see :mod:`kinengine.model.editing`); nothing is paid per call afterwards. :mod:`kinengine.model.editing`
(lxml tree edits, XML quoting) is imported by the first edit, not by ``import kinengine``."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, cast

from ..arrays import ArrayLike
from ..urdf import RobotDescription

if TYPE_CHECKING:
    from ..robot import Robot


class EditingMethods:
    """Tool frames (:meth:`with_frame`) and locked joints (:meth:`locked`)."""

    # -- model editing ---------------------------------------------------------------------------
    def with_frame(self, name: str, parent: str, placement: ArrayLike) -> Robot:
        """A new Robot with frame ``name`` fixed to frame ``parent`` (a link or joint) at ``placement``:
        T_parent,name as a (4, 4) homogeneous transform [m], or a pair (xyz [m], rpy [rad]). The frame is a
        new link on a fixed joint ``<name>_joint``; it is in ``frame_names``, ``urdf_text`` (edited alike)
        and everything else. See :func:`kinengine.model.editing.add_frame`."""
        from ..model.editing import add_frame

        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        return _edited(robot, add_frame(robot.description, name, parent, placement))

    def locked(self, values: Mapping[str, float]) -> Robot:
        """A new Robot with the named joints fixed at their values [rad or m] (mimic followers too, at
        multiplier·value + offset); the other coordinates keep their order. Its poses and Jacobians equal
        this robot's at those values with the locked columns removed. ConfigurationError for a value
        outside the limits. See :func:`kinengine.model.editing.lock_joints`."""
        from ..model.editing import lock_joints

        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        return _edited(robot, lock_joints(robot.description, values))


def _edited(robot: Robot, description: RobotDescription) -> Robot:
    """The Robot of an edited description: same name, end effector, packages, obstacles and disabled collision
    pairs; URDF text edited alike."""
    from ..model.editing import edited_urdf_text

    edited = type(robot)(
        description,
        edited_urdf_text(robot.urdf_text, description),
        name=robot.name,
        end_effector=robot.end_effector,
        packages=robot.packages,
    )
    if robot.obstacles:  # obstacles and an SRDF's disabled pairs stay with the robot
        edited = edited.with_obstacles(robot.obstacles)
    if robot.disabled_collision_pairs:
        from ..collision import write_srdf

        pairs = [(tuple(sorted(pair)), "Disabled") for pair in robot.disabled_collision_pairs]
        edited = edited.with_srdf(write_srdf(robot.name, pairs))  # type: ignore[arg-type]
    return edited
