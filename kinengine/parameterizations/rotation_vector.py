"""Rotation vector χ_R = φ = θ n (3 coordinates, θ = |φ| [rad]): C_IE = exp([φ]x); from_rotation: θ ∈ [0, π].

exp([φ + dφ]x) ≈ exp([J_l(φ) dφ]x)·exp([φ]x), so ω (in I) = J_l(φ)·φ̇ with the LEFT Jacobian of SO(3):

    E_inverse = J_l(φ)    = I + (1 − cos θ)/θ² [φ]x + (θ − sin θ)/θ³ [φ]x²,
    E         = J_l(φ)⁻¹  = I − ½ [φ]x + b(θ) [φ]x²,   b(θ) = (1 − (θ/2) cot(θ/2))/θ²,
    Ė = −½ [φ̇]x + (b'(θ)/θ)(φ·φ̇) [φ]x² + b(θ) (φ φ̇^T + φ̇ φ^T − 2 (φ·φ̇) I),   φ̇ = E ω.

(With ω in the body frame it would be the right Jacobian, J_r(φ) = J_l(−φ).) Every coefficient has a Taylor
branch for θ² < SMALL_ANGLE_SQ, so E is regular at φ = 0 (E = I there). E is singular only where
cot(θ/2) blows up with θ ≠ 0, θ = 2π, 4π, ... (distance: |θ − 2πk| to the nearest, k >= 1). Branch cut at
θ = π: from_rotation keeps θ <= π (scipy's ``as_rotvec``), so rotating through π, φ jumps to about −φ.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ._so3 import cross_matrix, quaternion_from_matrix, rotation_entries, series_or_closed
from .base import (
    Component,
    Entries,
    FloatArray,
    Namespace,
    RotationParameterization,
    Values,
    is_single,
)

PIN_LOG3_MAX_SQ = 4.0
"""θ² below which one sample takes φ from pin.log3 (as accurate as the quaternion route there: ~5e-16 in C(φ);
measured to degrade to 4e-13 at θ = 3.1). Above, the canonical quaternion (scipy's sign rule at θ = π)."""
_TWO_PI = 2.0 * math.pi
JLOG3_MAX_ANGLE = 2.9
"""θ [rad] below which :meth:`RotationVector.pose_rate` takes E_R from Pinocchio's Jlog3: against a 40-digit
mpmath evaluation of E_R at random axes, Jlog3 is within 2.8e-15 (relative) up to θ = 2.9, 1.4e-14 at 3.0 and
1.7e-13 at 3.1, where the scalar formulas below stay within 3.2e-15."""
_JLOG3_MIN_COS = math.cos(JLOG3_MAX_ANGLE)
_TINY_SIN2 = 1e-12
"""sin²(θ/2) below which θ/sin(θ/2) uses its Taylor series in from_rotation (truncation O(1e-24))."""


# Coefficients as functions of t = θ²: the Taylor series (Horner, through θ⁸) used for t < SMALL_ANGLE_SQ
# and the closed form used elsewhere.
def _sinc_series(t: Component) -> Component:  # sin θ / θ
    return 1.0 - t / 6.0 * (1.0 - t / 20.0 * (1.0 - t / 42.0 * (1.0 - t / 72.0)))


def _sinc_closed(xp: Namespace, t: Component) -> Component:
    return xp.sin(xp.sqrt(t)) / xp.sqrt(t)


def _versine_series(t: Component) -> Component:  # (1 − cos θ)/θ²
    return 0.5 * (1.0 - t / 12.0 * (1.0 - t / 30.0 * (1.0 - t / 56.0 * (1.0 - t / 90.0))))


def _versine_closed(xp: Namespace, t: Component) -> Component:  # 2 sin²(θ/2)/θ², no cancellation
    half = xp.sin(0.5 * xp.sqrt(t))
    return 2.0 * half * half / t


def _theta_minus_sin_series(t: Component) -> Component:  # (θ − sin θ)/θ³
    return (1.0 - t / 20.0 * (1.0 - t / 42.0 * (1.0 - t / 72.0 * (1.0 - t / 110.0)))) / 6.0


def _theta_minus_sin_closed(xp: Namespace, t: Component) -> Component:
    theta = xp.sqrt(t)
    return (theta - xp.sin(theta)) / (t * theta)


def _b_series(t: Component) -> Component:  # b(θ) = (1 − (θ/2) cot(θ/2))/θ²
    return 1.0 / 12.0 + t * (1.0 / 720.0 + t * (1.0 / 30240.0 + t * (1.0 / 1209600.0 + t / 47900160.0)))


def _b_closed(xp: Namespace, t: Component) -> Component:
    half = 0.5 * xp.sqrt(t)
    return (1.0 - half / xp.tan(half)) / t


def _b_prime_over_theta_series(t: Component) -> Component:  # b'(θ)/θ
    return 1.0 / 360.0 + t * (1.0 / 7560.0 + t * (1.0 / 201600.0 + t / 5987520.0))


def _b_prime_over_theta_closed(
    xp: Namespace, t: Component
) -> Component:  # −2/θ⁴ + 1/(4θ² sin²(θ/2)) + cot(θ/2)/(2θ³)
    theta = xp.sqrt(t)
    half = xp.sin(0.5 * theta)
    return -2.0 / (t * t) + 0.25 / (t * half * half) + 0.5 / (xp.tan(0.5 * theta) * t * theta)


NEAR_PI_COS = -0.988
"""cos θ below which (θ > 171°) the closed form's axis, from 2 sin θ n, loses digits: the quaternion route."""


def _log_by_quaternion(xp: Namespace, *C: Component) -> Entries:
    """φ from the canonical quaternion of C (scipy's ``as_rotvec``, θ <= π, its sign rule at θ = π)."""
    w, x, y, z = quaternion_from_matrix(xp, *C)
    s2 = x * x + y * y + z * z  # sin²(θ/2)
    if xp is math:
        scale = (
            2.0 / w * (1.0 - s2 / (3.0 * w * w))
            if s2 < _TINY_SIN2
            else 2.0 * math.atan2(math.sqrt(s2), w) / math.sqrt(s2)
        )
    else:
        small = s2 < _TINY_SIN2
        s = np.sqrt(np.where(small, 1.0, s2))
        scale = np.where(small, 2.0 / w * (1.0 - s2 / (3.0 * w * w)), 2.0 * np.arctan2(s, w) / s)
    return scale * x, scale * y, scale * z


def _log_closed_form(*C: Component) -> Entries:
    """φ of arrays of C's 9 entries: with w = vee(C − Cᵀ) = 2 sin θ n and cos θ = (tr C − 1)/2,
    θ = atan2(|w|/2, cos θ) and φ = (θ/|w|) w (→ w/2 as θ → 0); where cos θ < NEAR_PI_COS, the quaternion
    route (a third of the numpy passes: the batched IK's log, where C is mostly near I)."""
    c00, c01, c02, c10, c11, c12, c20, c21, c22 = C
    w0, w1, w2 = c21 - c12, c02 - c20, c10 - c01
    norm = np.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    cos = 0.5 * (c00 + c11 + c22 - 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(norm > 1e-300, np.arctan2(0.5 * norm, cos) / norm, 0.5)
    phi = (scale * w0, scale * w1, scale * w2)
    near = cos < NEAR_PI_COS
    if near.any():
        for out, value in zip(phi, _log_by_quaternion(np, *(c[near] for c in C)), strict=True):
            out[near] = value
    return phi


class RotationVector(RotationParameterization):
    """χ_R = φ = θ n [rad]; E = J_l(φ)⁻¹ (left Jacobian: ω in I); singular only at θ = 2π k, k >= 1."""

    name = "rotation_vector"
    labels = ("rotvec_x", "rotvec_y", "rotvec_z")
    singular_set = "θ = |φ| = 2π k, k >= 1 (never reached by from_rotation, which keeps θ <= π)"
    alternatives: tuple[str, ...] = ("quaternion", "rotation_matrix")

    def from_rotation(self, C: npt.ArrayLike, *, warn: bool = True) -> FloatArray:
        # One sample with θ < 2: Pinocchio's log3 (measured ~3x faster); otherwise the generic path.
        if is_single(C, (3, 3)):
            phi = pin.log3(C)
            x, y, z = phi.tolist()
            if x * x + y * y + z * z < PIN_LOG3_MAX_SQ:
                return phi
        return super().from_rotation(C, warn=warn)

    def _from_rotation(self, xp: Namespace, warn: bool, *C: Component) -> Entries:
        if xp is not math:  # arrays: the closed form, the quaternion route only near θ = π
            return _log_closed_form(*C)
        return _log_by_quaternion(xp, *C)

    def pose_rate(self, C: FloatArray) -> tuple[float, FloatArray | Entries] | None:
        # θ < JLOG3_MAX_ANGLE: E_R = Jlog3(C)·Cᵀ (Jlog3 maps the angular velocity in the frame's own axes to
        # φ̇; Cᵀ takes ω from I's axes to them), θ from cos θ = (tr C − 1)/2, distance 2π − θ. Towards π the
        # scalar formulas (see JLOG3_MAX_ANGLE).
        (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = C.tolist()
        cos_theta = 0.5 * (c00 + c11 + c22 - 1.0)
        if cos_theta > _JLOG3_MIN_COS:
            return _TWO_PI - math.acos(min(cos_theta, 1.0)), pin.Jlog3(C).dot(C.T)
        found = self.chart(c00, c01, c02, c10, c11, c12, c20, c21, c22)
        return None if found is None else (found[1], found[2])

    def chart(self, *C: float) -> tuple[list[float], float, Entries] | None:
        # _from_rotation keeps θ <= π (+ rounding): _distance's nearest 2πk is 2π, so the distance is 2π − θ
        x, y, z = self._from_rotation(math, False, *C)
        return [x, y, z], _TWO_PI - math.sqrt(x * x + y * y + z * z), self._E(math, x, y, z)

    def _to_rotation(self, xp: Namespace, x: Component, y: Component, z: Component) -> Entries:
        t = x * x + y * y + z * z
        return rotation_entries(
            series_or_closed(xp, t, _sinc_series, _sinc_closed),
            series_or_closed(xp, t, _versine_series, _versine_closed),
            x,
            y,
            z,
        )

    def _E(self, xp: Namespace, x: Component, y: Component, z: Component) -> Entries:
        b = series_or_closed(xp, x * x + y * y + z * z, _b_series, _b_closed)
        return rotation_entries(-0.5, b, x, y, z)

    def _E_inverse(self, xp: Namespace, x: Component, y: Component, z: Component) -> Entries:
        t = x * x + y * y + z * z
        a1 = series_or_closed(xp, t, _versine_series, _versine_closed)
        a2 = series_or_closed(xp, t, _theta_minus_sin_series, _theta_minus_sin_closed)
        return rotation_entries(a1, a2, x, y, z)

    def _E_dot(self, xp: Namespace, chi: Values, u: Values) -> Entries:
        x, y, z = chi
        t = x * x + y * y + z * z
        b = series_or_closed(xp, t, _b_series, _b_closed)
        E = rotation_entries(-0.5, b, x, y, z)
        phi_dot = tuple(E[3 * i] * u[0] + E[3 * i + 1] * u[1] + E[3 * i + 2] * u[2] for i in range(3))
        p_pd = x * phi_dot[0] + y * phi_dot[1] + z * phi_dot[2]
        b_dot = series_or_closed(xp, t, _b_prime_over_theta_series, _b_prime_over_theta_closed) * p_pd
        skew = cross_matrix(*phi_dot)
        return tuple(
            -0.5 * skew[3 * i + j]
            + b_dot * (chi[i] * chi[j] - t * (i == j))
            + b * (chi[i] * phi_dot[j] + phi_dot[i] * chi[j] - 2.0 * p_pd * (i == j))
            for i in range(3)
            for j in range(3)
        )

    def _distance(self, xp: Namespace, x: Component, y: Component, z: Component) -> Component:
        theta = xp.sqrt(x * x + y * y + z * z)
        if xp is math:  # the nearest 2πk with k >= 1 (θ >= 0: a round to 0 means k = 1)
            return abs(theta - _TWO_PI * (round(theta / _TWO_PI) or 1))
        return abs(theta - _TWO_PI * np.maximum(1.0, np.round(theta / _TWO_PI)))
