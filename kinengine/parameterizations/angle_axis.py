"""Angle-axis χ_R = (θ, n_x, n_y, n_z), |n| = 1, θ ∈ [0, π]: C_IE = I + sin θ [n]x + (1 − cos θ)[n]x².

With φ = θ n, ω = J_l(φ) φ̇ (left Jacobian, ω in I). n^T J_l⁻¹ = n^T gives θ̇ = n·ω, and the part of φ̇
normal to n gives ṅ = −½ ([n]x + cot(θ/2) [n]x²) ω, so

    E = [n^T; −½ ([n]x + cot(θ/2) [n]x²)]                       (4x3),
    E_inverse = [n, sin θ (I − n n^T) + (1 − cos θ) [n]x]       (3x4),

E_inverse·E = I_3 and E_inverse·(0, n) = 0: it is the Moore–Penrose pseudo-inverse, which discards the
part of ṅ along n that a unit axis cannot have. Singular at θ = 0 (axis undefined; cot(θ/2) → ∞;
distance: |sin(θ/2)|). Branch cut at θ = π: rotating through π, χ jumps from (π, n) to (π, −n) and θ turns
back (E itself is finite there). from_rotation returns θ n = scipy's ``as_rotvec()`` (canonical quaternion
w >= 0: at θ = π the first nonzero component of n is positive) and n = (1, 0, 0) at θ = 0, with a
UserWarning when θ <= 1e-7 (axis ill-defined).
"""

from __future__ import annotations

import math

import numpy as np

from ._so3 import cross_matrix, quaternion_from_matrix, rotation_entries
from .base import Component, Entries, Namespace, RotationParameterization, Values, warn_where
from .euler import GIMBAL_LOCK_TOLERANCE


class AngleAxis(RotationParameterization):
    """χ_R = (θ [rad], n_x, n_y, n_z), θ ∈ [0, π], |n| = 1; singular at θ = 0, branch cut at θ = π."""

    name = "angle_axis"
    labels = ("angle", "axis_x", "axis_y", "axis_z")
    singular_set = "θ = 0, the identity rotation (axis undefined)"
    alternatives: tuple[str, ...] = ("quaternion", "rotation_vector", "rotation_matrix")

    def _from_rotation(self, xp: Namespace, warn: bool, *C: Component) -> Entries:
        w, x, y, z = quaternion_from_matrix(xp, *C)
        s = xp.sqrt(x * x + y * y + z * z)  # sin(θ/2)
        theta = 2.0 * xp.atan2(s, w)
        if warn:
            warn_where(
                xp,
                theta <= GIMBAL_LOCK_TOLERANCE,
                f"{self.name}: rotation angle θ <= "
                f"{GIMBAL_LOCK_TOLERANCE:g} rad, the axis is ill-defined (n = (1, 0, 0) at θ = 0)",
            )
        if xp is math:
            return (theta, x / s, y / s, z / s) if s > 0.0 else (theta, 1.0, 0.0, 0.0)
        zero = s == 0.0
        s = np.where(zero, 1.0, s)
        return theta, np.where(zero, 1.0, x / s), y / s, z / s

    def _to_rotation(
        self, xp: Namespace, theta: Component, nx: Component, ny: Component, nz: Component
    ) -> Entries:
        n2 = nx * nx + ny * ny + nz * nz
        half = xp.sin(0.5 * theta)
        return rotation_entries(xp.sin(theta) / xp.sqrt(n2), 2.0 * half * half / n2, nx, ny, nz)

    def _E(self, xp: Namespace, theta: Component, nx: Component, ny: Component, nz: Component) -> Entries:
        M = rotation_entries(-0.5, -0.5 / xp.tan(0.5 * theta), nx, ny, nz)  # I − ½ [n]x − ½ cot(θ/2) [n]x²
        return (nx, ny, nz, M[0] - 1.0, M[1], M[2], M[3], M[4] - 1.0, M[5], M[6], M[7], M[8] - 1.0)

    def _E_inverse(
        self, xp: Namespace, theta: Component, nx: Component, ny: Component, nz: Component
    ) -> Entries:
        half = xp.sin(0.5 * theta)  # M − I = sin θ (I − n n^T) + (1 − cos θ)[n]x, |n| = 1
        M = rotation_entries(2.0 * half * half, -xp.sin(theta), nx, ny, nz)
        return (nx, M[0] - 1.0, M[1], M[2], ny, M[3], M[4] - 1.0, M[5], nz, M[6], M[7], M[8] - 1.0)

    def _E_dot(self, xp: Namespace, chi: Values, u: Values) -> Entries:
        theta, nx, ny, nz = chi
        a, b, c = u
        half = xp.sin(0.5 * theta)
        k = xp.cos(0.5 * theta) / half  # cot(θ/2)
        n_dot_w = nx * a + ny * b + nz * c  # θ̇
        k_dot = -n_dot_w / (2.0 * half * half)
        n = (nx, ny, nz)
        cross = (ny * c - nz * b, nz * a - nx * c, nx * b - ny * a)
        nd = tuple(-0.5 * (cross[i] + k * (n[i] * n_dot_w - u[i])) for i in range(3))  # ṅ
        skew = cross_matrix(*nd)
        rows = tuple(
            -0.5 * (skew[3 * i + j] + k_dot * (n[i] * n[j] - (i == j)) + k * (nd[i] * n[j] + n[i] * nd[j]))
            for i in range(3)
            for j in range(3)
        )
        return (*nd, *rows)

    def _distance(
        self, xp: Namespace, theta: Component, nx: Component, ny: Component, nz: Component
    ) -> Component:
        return abs(xp.sin(0.5 * theta))
