"""The Robot's collision methods: its ``<collision>`` geometry, checked pairs, distances, collision tests and
obstacles (see :mod:`kinengine.collision`). coal's shapes and the geometry are built by the first call."""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Mapping, Sequence
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, cast

import numpy as np
import numpy.typing as npt

from ..arrays import ArrayLike
from ..errors import OptionError

if TYPE_CHECKING:
    import pinocchio as pin

    from ..collision import CollisionChecker, Distances, Obstacle
    from ..robot import Robot


class CollisionMethods:
    """Collision geometry, pairs, distances and obstacles; the obstacles and the SRDF's disabled pairs travel
    with the Robot when it is pickled (:meth:`_collision_state`)."""

    _obstacles: tuple[Obstacle, ...] = ()
    _disabled_pairs: frozenset[frozenset[str]] = frozenset()

    # -- collisions --------------------------------------------------------------------------------
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
        from ..collision import collision_checker  # coal's shapes and the lxml edit only when asked for

        robot = cast("Robot", self)  # a method group of Robot, mixed into it alone
        if packages is not None and not (
            isinstance(packages, Mapping)
            and all(isinstance(k, str) and isinstance(v, (str, os.PathLike)) for k, v in packages.items())
        ):
            raise OptionError(
                f"packages maps ROS package names to folders, e.g. {{'my_pkg': '/path/to/my_pkg'}}, got "
                f"{type(packages).__name__}"
            )
        chosen = robot.packages if packages is None else MappingProxyType(dict(packages))
        cached = self.__dict__.get("_collision")
        if cached is None or (packages is not None and cached[0] != chosen):
            checker = collision_checker(
                robot.engine, robot.urdf_text, robot.source, chosen, self._obstacles, self._disabled_pairs
            )
            cached = self.__dict__["_collision"] = (chosen, checker)
        return cached[1].geometry

    def collision_checker(self) -> CollisionChecker:
        """The collision model the queries below use (:class:`kinengine.collision.CollisionChecker`)."""
        if "_collision" not in self.__dict__:
            self.collision_geometry()
        return cast("CollisionChecker", self.__dict__["_collision"][1])

    def collision_pairs(self, srdf: str | os.PathLike[str] | None = None) -> list[tuple[str, str]]:
        """The link pairs checked for collision: adjacent links and rigidly joined ones left out, an SRDF's
        ``<disable_collisions>`` (a file or its text; default: the one given to :meth:`with_srdf`) too, then
        the moving links against each obstacle. See :mod:`kinengine.collision.pairs`."""
        from ..collision import collision_checker, read_disabled_pairs

        robot = cast("Robot", self)
        if srdf is None:
            links = self.collision_checker().links
        else:
            disabled = read_disabled_pairs(srdf)
            links = collision_checker(
                robot.engine, robot.urdf_text, robot.source, robot.packages, self._obstacles, disabled
            ).links
        return list(dict.fromkeys(links))

    def distances(self, q: ArrayLike) -> Distances:
        """Signed distances [m] and witness points (root link frame) of every checked shape pair at q (dof,):
        a :class:`kinengine.Distances` (``pairs``, ``links``, ``distance``, ``p1``, ``p2``)."""
        checked = cast("Robot", self).engine.coordinates.check(q, allow_batch=False)
        return self.collision_checker().distances(checked)

    def min_distance(self, q: ArrayLike) -> float:
        """The smallest signed distance [m] over the checked pairs at q (dof,); negative: penetration."""
        checked = cast("Robot", self).engine.coordinates.check(q, allow_batch=False)
        return self.collision_checker().min_distance(checked)

    def in_collision(self, q: ArrayLike) -> bool | npt.NDArray[np.bool_]:
        """q (dof,): True if a checked pair touches or overlaps; Q (N, dof): (N,) bool."""
        checked = cast("Robot", self).engine.coordinates.check(q)
        checker = self.collision_checker()
        return checker.in_collision_batch(checked) if checked.ndim == 2 else checker.in_collision(checked)

    def with_obstacles(self, obstacles: Sequence[Obstacle]) -> Robot:
        """A new Robot with these obstacles (:class:`kinengine.Box`, ``Sphere``, ``Capsule``, ``Mesh``; poses
        in the root link frame) added to this one's, checked against every moving link."""
        from ..collision import Obstacle

        try:
            items = tuple(obstacles)
        except TypeError:
            raise OptionError(
                f"obstacles is a list of Box, Sphere, Capsule or Mesh, got {obstacles!r}"
            ) from None
        for item in items:
            if not isinstance(item, Obstacle):
                raise OptionError(f"obstacles are Box, Sphere, Capsule or Mesh objects, got {item!r}")
        return self._with_collision_state(self._obstacles + items, self._disabled_pairs)

    def with_srdf(self, srdf: str | os.PathLike[str]) -> Robot:
        """A new Robot whose self-collision pairs leave out an SRDF's ``<disable_collisions>`` (a file or its
        text), e.g. one written by ``kinengine collision-pairs``."""
        from ..collision import read_disabled_pairs

        return self._with_collision_state(self._obstacles, frozenset(read_disabled_pairs(srdf)))

    def _with_collision_state(
        self, obstacles: tuple[Obstacle, ...], disabled: frozenset[frozenset[str]]
    ) -> Robot:
        robot = cast("Robot", self)
        new = type(robot)(
            robot.description,
            robot.urdf_text,
            name=robot.name,
            end_effector=robot.end_effector,
            packages=robot.packages,
        )
        new.__dict__.update(_obstacles=obstacles, _disabled_pairs=disabled)
        return new

    def _collision_state(self) -> dict[str, object] | None:
        """What pickling keeps of the collision setup (None: the defaults)."""
        if not self._obstacles and not self._disabled_pairs:
            return None
        return {"_obstacles": self._obstacles, "_disabled_pairs": self._disabled_pairs}


def collision_free(
    robot: Robot, result: Any, solve: Callable[[np.ndarray], Any], attempts: int, rng: object
) -> Any:
    """``inverse_kinematics(..., avoid_collisions=True)``: a solution in collision is repaired by solving
    again from random collision-free starts (up to ``attempts`` times) and rejected (success False) if every
    one collides. A batch's colliding rows are rejected (success False), not re-solved."""
    if isinstance(result.success, np.ndarray):  # IKBatchResult
        hit = robot.in_collision(result.q)
        return dataclasses.replace(result, success=result.success & ~hit)
    if not robot.in_collision(result.q):
        return result
    generator = np.random.default_rng(rng if isinstance(rng, (int, np.random.Generator)) else None)
    for _ in range(max(attempts, 1)):
        q0 = robot.random_configuration(rng=generator)
        if robot.in_collision(q0):
            continue
        again = solve(q0)
        if again.success and not robot.in_collision(again.q):
            return again
    return dataclasses.replace(result, success=False)
