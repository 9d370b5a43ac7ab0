"""Spherical coordinates χ_P = (r, θ, φ) of the origin: p = (r cos θ sin φ, r sin θ sin φ, r cos φ) in I.

θ is the azimuth, φ the polar angle from +z. ∂p/∂χ has the orthogonal columns e_r, r sin φ·e_θ, r·e_φ
(e_r = p/r, e_θ = (−sin θ, cos θ, 0), e_φ = (cos θ cos φ, sin θ cos φ, −sin φ)), so

    E_P = [e_r^T; e_θ^T/(r sin φ); e_φ^T/r],   E_P⁻¹ = ∂p/∂χ = [e_r, r sin φ·e_θ, r·e_φ].

Singular on the z axis (r sin φ = 0, which includes r = 0): there θ (and at r = 0 also φ) is undefined;
from_position returns atan2(0, 0) = 0 for it.
"""

from __future__ import annotations

from .base import Component, Entries, Namespace, PositionParameterization, Values


class Spherical(PositionParameterization):
    """χ_P = (r [m], θ [rad], φ [rad]), r >= 0, θ ∈ [−π, π], φ ∈ [0, π]; distance: r·|sin φ| [m]."""

    name = "spherical"
    labels = ("r", "theta", "phi")
    singular_set = "the z axis, r·sin φ = 0 (azimuth θ undefined; at r = 0 also φ)"

    def _from_position(self, xp: Namespace, x: Component, y: Component, z: Component) -> Entries:
        rho, theta = self._azimuth(xp, x, y)
        return xp.sqrt(x * x + y * y + z * z), theta, xp.atan2(rho, z)

    def _to_position(self, xp: Namespace, r: Component, theta: Component, phi: Component) -> Entries:
        r_sin = r * xp.sin(phi)
        return r_sin * xp.cos(theta), r_sin * xp.sin(theta), r * xp.cos(phi)

    def _E(self, xp: Namespace, r: Component, theta: Component, phi: Component) -> Entries:
        ct, st, cp, sp = xp.cos(theta), xp.sin(theta), xp.cos(phi), xp.sin(phi)
        rs = r * sp
        return (ct * sp, st * sp, cp, -st / rs, ct / rs, 0.0, ct * cp / r, st * cp / r, -sp / r)

    def _E_inverse(self, xp: Namespace, r: Component, theta: Component, phi: Component) -> Entries:
        ct, st, cp, sp = xp.cos(theta), xp.sin(theta), xp.cos(phi), xp.sin(phi)
        return (ct * sp, -r * st * sp, r * ct * cp, st * sp, r * ct * sp, r * st * cp, cp, 0.0, -r * sp)

    def _E_dot(self, xp: Namespace, chi: Values, u: Values) -> Entries:
        # rows' rates: ė_r = θ̇ sin φ e_θ + φ̇ e_φ, ė_θ = −θ̇ (sin φ e_r + cos φ e_φ), ė_φ = θ̇ cos φ e_θ − φ̇ e_r
        r, theta, phi = chi
        vx, vy, vz = u
        ct, st, cp, sp = xp.cos(theta), xp.sin(theta), xp.cos(phi), xp.sin(phi)
        e_r = (ct * sp, st * sp, cp)
        e_t = (-st, ct, 0.0)
        e_p = (ct * cp, st * cp, -sp)
        rs = r * sp
        r_dot = e_r[0] * vx + e_r[1] * vy + e_r[2] * vz
        t_dot = (e_t[0] * vx + e_t[1] * vy) / rs
        p_dot = (e_p[0] * vx + e_p[1] * vy + e_p[2] * vz) / r
        row_r = [t_dot * sp * a + p_dot * b for a, b in zip(e_t, e_p, strict=True)]
        scale = (r_dot * sp + r * cp * p_dot) / (rs * rs)
        row_t = [-t_dot * (sp * a + cp * b) / rs - scale * c for a, b, c in zip(e_r, e_p, e_t, strict=True)]
        row_p = [
            (t_dot * cp * a - p_dot * b) / r - r_dot * c / (r * r)
            for a, b, c in zip(e_t, e_r, e_p, strict=True)
        ]
        return (*row_r, *row_t, *row_p)

    def _distance(self, xp: Namespace, r: Component, theta: Component, phi: Component) -> Component:
        return abs(r * xp.sin(phi))
