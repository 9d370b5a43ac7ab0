"""Continuous pose parameters along a trajectory.

χ from a rotation matrix is canonical (angles in [−π, π), quaternion w >= 0, rotation
vector |φ| <= π), so it jumps by 2π, flips sign or crosses the branch cut θ = π while
the pose moves smoothly. :func:`continuity_rule` returns, per parameterization, the
function that picks among the coordinates *equivalent* to a canonical χ (same pose)
the one closest to the previous χ. E(χ) is evaluated at that representative, so
J_A and χ̇ stay exact. Rules work on lists of Python floats (no numpy allocation).
"""

from __future__ import annotations

import math
from collections.abc import Callable

TWO_PI = 2.0 * math.pi

Rule = Callable[[list[float], list[float]], list[float]]


def _unwrap(angle: float, previous: float) -> float:
    """angle + 2πk closest to previous."""
    return angle + TWO_PI * round((previous - angle) / TWO_PI)


def _azimuth(chi: list[float], previous: list[float]) -> list[float]:
    """Cylindrical and spherical coordinates: the azimuth θ (χ2) unwrapped next to the previous one."""
    chi[1] = _unwrap(chi[1], previous[1])
    return chi


def _euler(proper: bool) -> Rule:
    """Euler angles: every χ equivalent to a canonical one is one of the two solutions
    (χ1, χ2, χ3) and (χ1 + π, s − χ2, χ3 + π) — s = 0 for proper sequences (a = c), π for Tait–Bryan — with
    2π shifts of each angle. Picks the candidate nearest (Euclidean) the previous χ, so χ2 may leave its
    canonical range ([−π/2, π/2] or [0, π]) and χ1, χ3 do not jump by π where the canonical χ2 turns back.
    χ within 1 rad of the previous χ in every angle is kept as it is: its squared distance is below 3, the
    other solution's (χ1 and χ3 shifted by π) above (π − 1)² > 4.5 — the common case of a control loop."""
    shift = 0.0 if proper else math.pi

    def rule(chi: list[float], previous: list[float]) -> list[float]:
        p1, p2, p3 = previous
        if abs(chi[0] - p1) < 1.0 and abs(chi[1] - p2) < 1.0 and abs(chi[2] - p3) < 1.0:
            return chi
        same = [_unwrap(chi[0], p1), _unwrap(chi[1], p2), _unwrap(chi[2], p3)]
        other = [_unwrap(chi[0] + math.pi, p1), _unwrap(shift - chi[1], p2), _unwrap(chi[2] + math.pi, p3)]
        return other if math.dist(other, previous) < math.dist(same, previous) else same

    return rule


def _quaternion(chi: list[float], previous: list[float]) -> list[float]:
    """q and −q are the same rotation: keep the sign of the previous quaternion."""
    if sum(a * b for a, b in zip(chi, previous, strict=True)) < 0.0:
        return [-c for c in chi]
    return chi


def _rotation_vector(chi: list[float], previous: list[float]) -> list[float]:
    """φ = θn equals (θ + 2πk)n for every integer k: pick the k closest to the previous φ."""
    theta = math.hypot(*chi)
    if theta < 1e-9:  # at the identity the axis is undefined: candidates are 2πk·n for any n
        p = math.hypot(*previous)
        k = round(p / TWO_PI)
        return [c * (k * TWO_PI / p) for c in previous] if k and p > 0 else chi
    n = [c / theta for c in chi]
    k = round((sum(a * b for a, b in zip(n, previous, strict=True)) - theta) / TWO_PI)
    candidates = [[x * (theta + TWO_PI * j) for x in n] for j in (k - 1, k, k + 1)]
    return min(candidates, key=lambda c: math.dist(c, previous))


def _angle_axis(chi: list[float], previous: list[float]) -> list[float]:
    """(θ, n) equals (θ + 2πk, n) and (−θ + 2πk, −n): pick the candidate closest to the previous one."""
    candidates = [[_unwrap(s * chi[0], previous[0]), *(s * x for x in chi[1:])] for s in (1.0, -1.0)]
    return min(candidates, key=lambda c: math.dist(c, previous))


def _identity(chi: list[float], previous: list[float]) -> list[float]:
    return chi


def continuity_rule(name: str) -> Rule:
    """The rule for a parameterization name (identity where χ is unique: cartesian, rotation_matrix)."""
    if name.startswith("euler_"):
        return _euler(name[6] == name[8])
    return {
        "cylindrical": _azimuth,
        "spherical": _azimuth,
        "quaternion": _quaternion,
        "rotation_vector": _rotation_vector,
        "angle_axis": _angle_axis,
    }.get(name, _identity)
