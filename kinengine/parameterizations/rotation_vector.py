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

from ._so3 import cross_matrix, quaternion_from_matrix, rotation_entries, series_or_closed
from .base import Component, Entries, Namespace, RotationParameterization, Values

_TWO_PI = 2.0 * math.pi


# Coefficients as functions of t = θ²: the Taylor series (Horner, through θ⁸) used for t < SMALL_ANGLE_SQ
# and the closed form used elsewhere.
def _sinc_series(t: Component) -> Component:  # sin θ / θ
    return 1.0 - t / 6.0 * (1.0 - t / 20.0 * (1.0 - t / 42.0 * (1.0 - t / 72.0)))


def _sinc_closed(xp: Namespace, t: Component) -> Component:
    return xp.sin(xp.sqrt(t)) / xp.sqrt(t)


def _half_sinc(xp: Namespace, t: Component) -> Component:
    """k = sin(θ/2)/θ = ½ sinc(θ/2) of t = θ² (the quaternion's vector part is k φ)."""
    return 0.5 * series_or_closed(xp, 0.25 * t, _sinc_series, _sinc_closed)


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


def _b_prime_over_theta_closed(xp: Namespace, t: Component) -> Component:
    # −2/θ⁴ + 1/(4θ² sin²(θ/2)) + cot(θ/2)/(2θ³)
    theta = xp.sqrt(t)
    half = xp.sin(0.5 * theta)
    return -2.0 / (t * t) + 0.25 / (t * half * half) + 0.5 / (xp.tan(0.5 * theta) * t * theta)


NEAR_PI_COS = -0.988
"""cos θ below which (θ > 171°) the closed form's axis, from 2 sin θ n, loses digits: the quaternion route."""


def _inverse_left_jacobian(xp: Namespace, t: Component, x: Component, y: Component, z: Component) -> Entries:
    """E(φ) = J_l(φ)⁻¹ = I − ½ [φ]x + b(θ) [φ]x² for φ = (x, y, z), t = θ² = |φ|²."""
    return rotation_entries(-0.5, series_or_closed(xp, t, _b_series, _b_closed), x, y, z)


def _log_by_quaternion(xp: Namespace, *C: Component) -> Entries:
    """φ from the canonical quaternion of C (scipy's ``as_rotvec``, θ <= π, its sign rule at θ = π); called
    for θ near π only, where sin(θ/2) ≈ 1."""
    w, x, y, z = quaternion_from_matrix(xp, *C)
    s = xp.sqrt(x * x + y * y + z * z)  # sin(θ/2)
    scale = 2.0 * xp.atan2(s, w) / s  # θ / sin(θ/2)
    return scale * x, scale * y, scale * z


def _log(xp: Namespace, C: Values) -> Entries:
    """φ of C's 9 entries: with w = vee(C − Cᵀ) = 2 sin θ n and cos θ = (tr C − 1)/2, θ = atan2(|w|/2, cos θ)
    and φ = (θ/|w|) w (→ w/2 as θ → 0); where cos θ < NEAR_PI_COS, the quaternion route (in a batch only for
    those samples: the batched IK's log, where C is mostly near I)."""
    c00, c01, c02, c10, c11, c12, c20, c21, c22 = C
    w0, w1, w2 = c21 - c12, c02 - c20, c10 - c01
    norm = xp.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    cos = 0.5 * (c00 + c11 + c22 - 1.0)
    if xp is math:
        if cos < NEAR_PI_COS:
            return _log_by_quaternion(math, *C)
        scale = math.atan2(0.5 * norm, cos) / norm if norm > 1e-300 else 0.5
        return scale * w0, scale * w1, scale * w2
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

    def _from_rotation(self, xp: Namespace, warn: bool, *C: Component) -> Entries:
        return _log(xp, C)

    def chart(self, *C: float) -> tuple[list[float], float, Entries] | None:
        # _from_rotation keeps θ <= π (+ rounding): _distance's nearest 2πk is 2π, so the distance is 2π − θ
        x, y, z = _log(math, C)
        t = x * x + y * y + z * z
        return [x, y, z], _TWO_PI - math.sqrt(t), _inverse_left_jacobian(math, t, x, y, z)

    def _to_rotation(self, xp: Namespace, x: Component, y: Component, z: Component) -> Entries:
        t = x * x + y * y + z * z
        k = _half_sinc(xp, t)  # with w = cos(θ/2): sin θ/θ = 2wk, (1 − cos θ)/θ² = 2k²
        return rotation_entries(2.0 * xp.cos(0.5 * xp.sqrt(t)) * k, 2.0 * k * k, x, y, z)

    def _E(self, xp: Namespace, x: Component, y: Component, z: Component) -> Entries:
        return _inverse_left_jacobian(xp, x * x + y * y + z * z, x, y, z)

    def _E_inverse(self, xp: Namespace, x: Component, y: Component, z: Component) -> Entries:
        t = x * x + y * y + z * z
        k = _half_sinc(xp, t)  # (1 − cos θ)/θ² = 2k²
        return rotation_entries(
            2.0 * k * k, series_or_closed(xp, t, _theta_minus_sin_series, _theta_minus_sin_closed), x, y, z
        )

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
        theta = xp.sqrt(x * x + y * y + z * z)  # to the nearest 2πk with k >= 1
        return abs(theta - _TWO_PI * np.maximum(1.0, np.round(theta / _TWO_PI)))
