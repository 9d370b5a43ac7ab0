"""E_R(χ) of two rotation parameterizations from Pinocchio's C++ helpers, for one pose C_IF (3, 3) on the
single-configuration hot path (the rows act on J_e0's angular rows ω in the root frame I, so χ̇_R = E_R·ω):

* ``rotation_vector``: φ = log3(C) and E_R = Jlog3(C)·Cᵀ (Jlog3 maps the angular velocity in the frame's own
  axes to φ̇; Cᵀ takes ω from I's axes to them). Used for θ < 2.5 rad (NATIVE_MAX_SQ), where it is within
  1.2e-15 (relative) of the scalar formulas of :mod:`kinengine.parameterizations` (measured on random C:
  6e-15 at θ = 2.9, 2e-12 at 3.13 — Jlog3 loses accuracy towards π, so the scalar path takes over).
* ``euler_zyx``: (roll, pitch, yaw) = matrixToRpy(C) and E_R = computeRpyJacobianInverse(rpy,
  LOCAL_WORLD_ALIGNED) with its rows reversed (χ = (yaw, pitch, roll) = (χ1, χ2, χ3)); distance |cos χ2|.

Each returns (distance to the singular set, E_R (3, 3)) or None where the general (scalar) path must decide
(near θ = π for the rotation vector, within GIMBAL_LOCK_TOLERANCE of gimbal lock for ZYX)."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pinocchio as pin

from ..parameterizations.euler import GIMBAL_LOCK_TOLERANCE

NativeE = Callable[[np.ndarray], "tuple[float, np.ndarray] | None"]
_TWO_PI, _HALF_PI = 2.0 * math.pi, 0.5 * math.pi
NATIVE_MAX_SQ = 2.5**2
"""θ² [rad²] below which the rotation vector's E_R comes from Jlog3 (see the module doc)."""


def _rotation_vector() -> NativeE:
    log3, jlog3, sqrt = pin.log3, pin.Jlog3, math.sqrt

    def native(C: np.ndarray) -> tuple[float, np.ndarray] | None:
        x, y, z = log3(C).tolist()
        t = x * x + y * y + z * z
        if not t < NATIVE_MAX_SQ:
            return None
        return abs(sqrt(t) - _TWO_PI), jlog3(C).dot(C.T)

    return native


def _euler_zyx() -> NativeE:
    to_rpy, rpy_inverse, LWA, cos = (
        pin.rpy.matrixToRpy,
        pin.rpy.computeRpyJacobianInverse,
        pin.LOCAL_WORLD_ALIGNED,
        math.cos,
    )

    def native(C: np.ndarray) -> tuple[float, np.ndarray] | None:
        rpy = to_rpy(C)
        pitch = float(rpy[1])
        if abs(abs(pitch) - _HALF_PI) <= GIMBAL_LOCK_TOLERANCE:
            return None
        return abs(cos(pitch)), rpy_inverse(rpy, LWA)[::-1]

    return native


NATIVE_E: dict[str, Callable[[], NativeE]] = {"rotation_vector": _rotation_vector, "euler_zyx": _euler_zyx}
"""Rotation parameterization name -> a maker of its native E_R."""

__all__ = ["NATIVE_E", "NATIVE_MAX_SQ", "NativeE"]
