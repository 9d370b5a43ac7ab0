"""E_R(χ) of two rotation parameterizations from Pinocchio's C++ helpers, for one pose C_IF (3, 3) on the
single-configuration hot path (the rows act on J_e0's angular rows ω in the root frame I, so χ̇_R = E_R·ω):

* ``rotation_vector``: E_R = Jlog3(C)·Cᵀ (Jlog3 maps the angular velocity in the frame's own axes to φ̇;
  Cᵀ takes ω from I's axes to them), with θ = |φ| from cos θ = (tr C − 1)/2. Used for θ < 2.9 rad
  (NATIVE_MAX_ANGLE): against a 40-digit mpmath evaluation of E_R at random axes, Jlog3 is within 2.8e-15
  (relative) up to θ = 2.9, 1.4e-14 at 3.0 and 1.7e-13 at 3.1, where the scalar formulas of
  :mod:`kinengine.parameterizations` stay within 3.2e-15 — so towards π E_R comes from those formulas
  (the rotation vector's one-pass ``_fast_E``).
* ``euler_zyx``: (roll, pitch, yaw) = matrixToRpy(C) and E_R = computeRpyJacobianInverse(rpy,
  LOCAL_WORLD_ALIGNED) with its rows reversed (χ = (yaw, pitch, roll) = (χ1, χ2, χ3)); distance |cos χ2|.

Each returns (distance to the singular set, E_R (3, 3)) or None where the general (scalar) path must decide
(near θ = π for the rotation vector, within GIMBAL_LOCK_TOLERANCE of gimbal lock for ZYX)."""

from __future__ import annotations

import math
import struct
from collections.abc import Callable

import numpy as np
import pinocchio as pin

from ..parameterizations import ROTATION_PARAMETERIZATIONS
from ..parameterizations.euler import GIMBAL_LOCK_TOLERANCE
from ..parameterizations.rotation_vector import RotationVector

NativeE = Callable[[np.ndarray], "tuple[float, np.ndarray] | None"]
_TWO_PI, _HALF_PI = 2.0 * math.pi, 0.5 * math.pi
NATIVE_MAX_ANGLE = 2.9
"""θ [rad] below which the rotation vector's E_R comes from Jlog3 (see the module doc)."""
_MIN_COS = math.cos(NATIVE_MAX_ANGLE)


def _rotation_vector() -> NativeE:
    jlog3, acos, ndarray, f64, pack = (
        pin.Jlog3,
        math.acos,
        np.ndarray,
        np.dtype(np.float64),
        struct.Struct("9d").pack,
    )
    rotation_vector = ROTATION_PARAMETERIZATIONS["rotation_vector"]
    assert isinstance(rotation_vector, RotationVector)
    scalar = rotation_vector._fast_E  # the general formulas in one pass

    def native(C: np.ndarray) -> tuple[float, np.ndarray] | None:
        (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = C.tolist()
        cos_theta = 0.5 * (c00 + c11 + c22 - 1.0)
        if cos_theta > _MIN_COS:  # θ < NATIVE_MAX_ANGLE: Jlog3; distance to |φ| = 2π
            return _TWO_PI - acos(min(cos_theta, 1.0)), jlog3(C).dot(C.T)
        found = scalar(c00, c01, c02, c10, c11, c12, c20, c21, c22)  # towards π: the scalar formulas
        return None if found is None else (found[0], ndarray((3, 3), f64, pack(*found[1])))  # read-only

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

__all__ = ["NATIVE_E", "NATIVE_MAX_ANGLE", "NativeE"]
