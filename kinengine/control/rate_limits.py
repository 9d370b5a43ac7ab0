"""The URDF's rate limits per coordinate: ``<limit velocity>`` [rad/s | m/s] and ``<limit effort>``
[N·m | N] of each coordinate's joint (``robot.joint_names`` order; a mimic leader's own joint), inf where
the URDF gives none (or 0, which URDF parsers read as "not given")."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from ..errors import OptionError

if TYPE_CHECKING:
    from .robot_like import RobotLike


def urdf_velocity_limits(robot: RobotLike) -> npt.NDArray[np.float64]:
    """(dof,) the URDF's ``<limit velocity>`` of each coordinate's joint [rad/s | m/s]; inf where absent."""
    return _urdf_limits(robot, "velocity")


def urdf_effort_limits(robot: RobotLike) -> npt.NDArray[np.float64]:
    """(dof,) the URDF's ``<limit effort>`` of each coordinate's joint [N·m | N]; inf where absent."""
    return _urdf_limits(robot, "effort")


def _urdf_limits(robot: RobotLike, attribute: str) -> npt.NDArray[np.float64]:
    urdf = {j.name: getattr(j, attribute) for j in robot.description.joints}
    out = np.array([urdf.get(name) or np.inf for name in robot.joint_names], dtype=float).reshape(-1)
    out.flags.writeable = False
    return out


def checked_rate_limits(
    robot: RobotLike,
    limits: npt.ArrayLike | Mapping[str, float] | None,
    urdf: npt.NDArray[np.float64],
    what: str,
) -> npt.NDArray[np.float64]:
    """(dof,) rate limits: ``urdf`` (e.g. :func:`urdf_velocity_limits`) overridden by an array (dof,) or a
    mapping joint name -> limit; OptionError for unknown names, wrong shapes, NaN or negative values (inf:
    none)."""
    out = urdf.astype(float, copy=True)
    if limits is None:
        return out
    if isinstance(limits, Mapping):
        for name, value in limits.items():
            if name not in robot.joint_names:
                raise OptionError(
                    f"{what} names unknown joint {name!r}; known: {', '.join(robot.joint_names)}"
                )
            out[list(robot.joint_names).index(name)] = _rate(f"{what}[{name!r}]", value)
    else:
        try:
            out = np.array(limits, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise OptionError(f"{what} must be numbers of shape ({robot.dof},), got {limits!r:.60}") from None
        if out.shape != (robot.dof,):
            raise OptionError(f"{what} must have shape ({robot.dof},), got {out.shape}")
    if not (out >= 0).all():
        raise OptionError(f"{what} must be >= 0 (inf for none), got {out.tolist()}")
    return out


def _rate(what: str, value: object) -> float:
    """A limit >= 0 (inf allowed), else OptionError."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise OptionError(f"{what} must be a number, got {value!r:.60}")
    if not float(value) >= 0.0:
        raise OptionError(f"{what} must be >= 0 (inf for none), got {value!r:.60}")
    return float(value)


__all__ = ["RobotLike", "checked_rate_limits", "urdf_effort_limits", "urdf_velocity_limits"]
