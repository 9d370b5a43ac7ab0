"""Cylindrical coordinates χ_P = (ρ, θ, z) of the frame origin: p = (ρ cos θ, ρ sin θ, z) in I.

With v = ṗ in I: ρ̇ = cos θ·v_x + sin θ·v_y, θ̇ = (−sin θ·v_x + cos θ·v_y)/ρ, ż = v_z, so

    E_P = [[c, s, 0], [−s/ρ, c/ρ, 0], [0, 0, 1]],   E_P⁻¹ = ∂p/∂χ = [[c, −ρ s, 0], [s, ρ c, 0], [0, 0, 1]].

Singular on the z axis (ρ = 0), where θ is undefined (from_position returns θ = atan2(0, 0) = 0).
"""

from __future__ import annotations

from .base import Component, Entries, Namespace, PositionParameterization, Values


class Cylindrical(PositionParameterization):
    """χ_P = (ρ [m], θ [rad], z [m]), ρ >= 0, θ ∈ [−π, π]; singular at ρ = 0 (distance: |ρ| [m])."""

    name = "cylindrical"
    labels = ("rho", "theta", "z")
    singular_set = "the z axis, ρ = 0 (azimuth θ undefined)"

    def _from_position(self, xp: Namespace, x: Component, y: Component, z: Component) -> Entries:
        return (*self._azimuth(xp, x, y), z)

    def _to_position(self, xp: Namespace, rho: Component, theta: Component, z: Component) -> Entries:
        return rho * xp.cos(theta), rho * xp.sin(theta), z

    def _E(self, xp: Namespace, rho: Component, theta: Component, z: Component) -> Entries:
        c, s = xp.cos(theta), xp.sin(theta)
        return (c, s, 0.0, -s / rho, c / rho, 0.0, 0.0, 0.0, 1.0)

    def _E_inverse(self, xp: Namespace, rho: Component, theta: Component, z: Component) -> Entries:
        c, s = xp.cos(theta), xp.sin(theta)
        return (c, -rho * s, 0.0, s, rho * c, 0.0, 0.0, 0.0, 1.0)

    def _E_dot(self, xp: Namespace, chi: Values, u: Values) -> Entries:
        rho, theta, _ = chi
        vx, vy, _ = u
        c, s = xp.cos(theta), xp.sin(theta)
        rho_dot = c * vx + s * vy
        theta_dot = (c * vy - s * vx) / rho
        return (
            -s * theta_dot, c * theta_dot, 0.0,
            (s * rho_dot / rho - c * theta_dot) / rho, (-s * theta_dot - c * rho_dot / rho) / rho, 0.0,
            0.0, 0.0, 0.0,
        )  # fmt: skip

    def _distance(self, xp: Namespace, rho: Component, theta: Component, z: Component) -> Component:
        return abs(rho)
