"""Intrinsic Euler angles χ_R = (χ1, χ2, χ3), C_IE = R_a(χ1)·R_b(χ2)·R_c(χ3), for the 12 sequences "abc".

Angular velocity in I: ω = e_a χ̇1 + R_a(χ1) e_b χ̇2 + R_a(χ1) R_b(χ2) e_c χ̇3 = B(χ)·χ̇, and E_R = B⁻¹.
Written in the coordinates (a, b, t), t the third axis, ε = ε_abt = ±1, c_k = cos χk, s_k = sin χk:

Tait–Bryan (c = t):  B = [[1, 0, ε s2], [0, c1, −ε s1 c2], [0, ε s1, c1 c2]],        det B = c2,
                     E = [[1, s1 s2/c2, −ε c1 s2/c2], [0, c1, ε s1], [0, −ε s1/c2, c1/c2]].
Proper (c = a):      B = [[1, 0, c2], [0, c1, s1 s2], [0, ε s1, −ε c1 s2]],        det B = −ε s2,
                     E = [[1, −s1 c2/s2, ε c1 c2/s2], [0, c1, ε s1], [0, s1/s2, −ε c1/s2]].

E_dot = ∂E/∂χ1·χ̇1 + ∂E/∂χ2·χ̇2 with χ̇ = E·ω (E does not depend on χ3).
from_rotation reads χ1 and χ2 off matrix entries with atan2 (no asin/acos) and χ3 off R_a(χ1)^T·C (as
Eigen's eulerAngles), so C(χ) reproduces C to rounding even near gimbal lock, where χ1 and χ3 alone are
ill-conditioned.
Ranges are scipy's ``Rotation.as_euler(seq.upper())``: χ1, χ3 ∈ [−π, π], χ2 ∈ [−π/2, π/2] (Tait–Bryan) or
[0, π] (proper). At gimbal lock (χ2 within 1e-7 rad of the singular value, scipy's tolerance) only χ1 ± χ3 is
defined: like scipy, χ3 is set to 0 (χ1 from R_a(χ1)·R_b(χ2) = C) and a UserWarning is issued.
"""

from __future__ import annotations

import math
from operator import itemgetter

from ..errors import ParameterizationError
from ._so3 import rotation_entries
from .base import Component, Entries, Namespace, RotationParameterization, Values, warn_where, where

EULER_SEQUENCES = ("xyz", "xzy", "yxz", "yzx", "zxy", "zyx", "xyx", "xzx", "yxy", "yzy", "zxz", "zyz")
GIMBAL_LOCK_TOLERANCE = 1e-7
"""[rad]; scipy's tolerance on χ2 for declaring gimbal lock in ``as_euler``."""


_UNIT = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def _matmul(A: Entries, B: Entries) -> Entries:
    """Row-major entries of A·B for 3x3 matrices given by row-major entries."""
    return tuple(
        A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j]
        for i in range(3)
        for j in range(3)
    )


class EulerAngles(RotationParameterization):
    """Intrinsic Euler angles of one sequence, e.g. ``EulerAngles("zyx")`` (yaw, pitch, roll) [rad]."""

    def __init__(self, seq: str) -> None:
        if seq not in EULER_SEQUENCES:
            raise ParameterizationError(
                f"Expected `seq` to be one of {', '.join(EULER_SEQUENCES)}, got {seq!r}"
            )
        a, b, c = ("xyz".index(axis) for axis in seq)
        t = 3 - a - b
        self.seq = seq
        self.name = f"euler_{seq}"
        self.labels = (f"chi1_{seq[0]}", f"chi2_{seq[1]}", f"chi3_{seq[2]}")
        self._proper = a == c
        self._eps = float((a - b) * (b - t) * (t - a) // 2)
        self._axes = (a, b, c)
        self._perm = (a, b, t)
        # flat indices of C[a][b], C[a][t], C[a][a], C[b][a], C[t][a], C[b][t], C[t][t], C[t][b], C[b][b]
        pairs = ((a, b), (a, t), (a, a), (b, a), (t, a), (b, t), (t, t), (t, b), (b, b))
        self._index = tuple(3 * r + c for r, c in pairs)
        # E' (columns in (a, b, t) order) -> E: E[:, perm[k]] = E'[:, k]; B' (rows) -> B: B[perm[k]] = B'[k]
        self._to_columns = itemgetter(*(3 * r + self._perm.index(col) for r in range(3) for col in range(3)))
        self._to_rows = itemgetter(*(3 * self._perm.index(row) + col for row in range(3) for col in range(3)))
        if self._proper:
            self.singular_set = f"χ2 = 0 or π, sin χ2 = 0 (gimbal lock: first and third axis {seq[0]} align)"
            self.alternatives = ("quaternion", f"euler_{seq[0]}{seq[1]}{'xyz'[t]}", "rotation_matrix")
        else:
            self.singular_set = f"χ2 = ±π/2, cos χ2 = 0 (gimbal lock: axes {seq[0]} and {seq[2]} aligned)"
            self.alternatives = ("quaternion", f"euler_{seq[0]}{seq[1]}{seq[0]}", "rotation_matrix")

    def _angles(self, xp: Namespace, C: Values) -> tuple[Component, ...]:
        """(χ1, χ2, χ3, locked, cos χ1, sin χ1) off C's row-major entries by atan2. ``locked``: χ2 within
        GIMBAL_LOCK_TOLERANCE of gimbal lock, where χ1 alone is not defined: χ1 then from C = R_a(χ1) R_b(χ2),
        whose column b is R_a(χ1) e_b = c1 e_b + ε s1 e_t (the caller sets χ3 = 0). χ3 from row b of
        R_a(χ1)^T C = R_b(χ2) R_c(χ3) (as Eigen's eulerAngles): near gimbal lock χ1 is ill-conditioned, but
        then χ3 compensates and χ -> C stays accurate."""
        ab, at, aa, ba, ta, bt, tt, tb, bb = self._index
        e, proper = self._eps, self._proper
        if proper:  # C[a][a] = c2, C[a][b] = s2 s3, C[a][t] = ε s2 c3, C[b][a] = s1 s2, C[t][a] = −ε c1 s2
            chi2 = xp.atan2(xp.hypot(C[ab], C[at]), C[aa])
            locked = (abs(chi2) <= GIMBAL_LOCK_TOLERANCE) | (abs(chi2 - math.pi) <= GIMBAL_LOCK_TOLERANCE)
            chi1 = xp.atan2(C[ba], -e * C[ta])
        else:  # C[a][t] = ε s2, C[b][t] = −ε s1 c2, C[t][t] = c1 c2
            chi2 = xp.atan2(e * C[at], xp.hypot(C[bt], C[tt]))
            locked = abs(abs(chi2) - 0.5 * math.pi) <= GIMBAL_LOCK_TOLERANCE
            chi1 = xp.atan2(-e * C[bt], C[tt])
        if xp is not math or locked:
            chi1 = where(xp, locked, xp.atan2(e * C[tb], C[bb]), chi1)
        c1, s1 = xp.cos(chi1), xp.sin(chi1)
        # row b of R_b(χ2) R_a(χ3) = (−ε s3 on t, c3 on b) (proper), of R_b(χ2) R_t(χ3) = (ε s3 on a, c3 on b)
        y3 = -e * c1 * C[bt] - s1 * C[tt] if proper else e * c1 * C[ba] + s1 * C[ta]
        return chi1, chi2, xp.atan2(y3, c1 * C[bb] + e * s1 * C[tb]), locked, c1, s1

    def _from_rotation(self, xp: Namespace, warn: bool, *C: Component) -> Entries:
        chi1, chi2, chi3, locked, _, _ = self._angles(xp, C)
        if warn:
            warn_where(
                xp,
                locked,
                f"{self.name}: gimbal lock detected. Setting third angle to zero "
                "since it is not possible to uniquely determine all angles.",
            )
        return chi1, chi2, where(xp, locked, 0.0, chi3)

    def chart(self, *C: float) -> tuple[list[float], float, Entries] | None:
        # _from_rotation, _distance and _E with cos and sin of χ1 and χ2 computed once
        chi1, chi2, chi3, locked, c1, s1 = self._angles(math, C)
        c2, s2 = math.cos(chi2), math.sin(chi2)
        distance = abs(s2) if self._proper else abs(c2)
        if locked or distance == 0.0:
            return None
        return [chi1, chi2, chi3], distance, self._rate_entries(c1, s1, c2, s2)

    def _to_rotation(self, xp: Namespace, chi1: Component, chi2: Component, chi3: Component) -> Entries:
        R1, R2, R3 = (  # the rotation by χk about the basis axis k: I + sin χk [e]x + (1 − cos χk) [e]x²
            rotation_entries(xp.sin(x), 1.0 - xp.cos(x), *_UNIT[axis])
            for axis, x in zip(self._axes, (chi1, chi2, chi3), strict=True)
        )
        return _matmul(_matmul(R1, R2), R3)

    def _E(self, xp: Namespace, chi1: Component, chi2: Component, chi3: Component) -> Entries:
        return self._rate_entries(xp.cos(chi1), xp.sin(chi1), xp.cos(chi2), xp.sin(chi2))

    def _rate_entries(self, c1: Component, s1: Component, c2: Component, s2: Component) -> Entries:
        """E's row-major entries from c_k = cos χk, s_k = sin χk (the module doc's E, columns on a, b, t)."""
        e = self._eps
        if self._proper:
            u = 1.0 / s2
            k = c2 * u
            return self._to_columns((1.0, -s1 * k, e * c1 * k, 0.0, c1, e * s1, 0.0, s1 * u, -e * c1 * u))
        u = 1.0 / c2
        t = s2 * u
        return self._to_columns((1.0, s1 * t, -e * c1 * t, 0.0, c1, e * s1, 0.0, -e * s1 * u, c1 * u))

    def _E_inverse(self, xp: Namespace, chi1: Component, chi2: Component, chi3: Component) -> Entries:
        c1, s1, c2, s2, e = xp.cos(chi1), xp.sin(chi1), xp.cos(chi2), xp.sin(chi2), self._eps
        if self._proper:
            return self._to_rows((1.0, 0.0, c2, 0.0, c1, s1 * s2, 0.0, e * s1, -e * c1 * s2))
        return self._to_rows((1.0, 0.0, e * s2, 0.0, c1, -e * s1 * c2, 0.0, e * s1, c1 * c2))

    def _E_dot(self, xp: Namespace, chi: Values, u: Values) -> Entries:
        chi1, chi2, _ = chi
        c1, s1, c2, s2, e = xp.cos(chi1), xp.sin(chi1), xp.cos(chi2), xp.sin(chi2), self._eps
        wa, wb, wt = (u[axis] for axis in self._perm)
        d2 = c1 * wb + e * s1 * wt  # χ̇2 (row 2 of E is the same for both kinds)
        if self._proper:
            r = 1.0 / s2
            k = c2 * r
            d1 = wa - s1 * k * wb + e * c1 * k * wt  # χ̇1
            return self._to_columns((
                0.0, -c1 * k * d1 + s1 * r * r * d2, -e * (s1 * k * d1 + c1 * r * r * d2),
                0.0, -s1 * d1, e * c1 * d1,
                0.0, c1 * r * d1 - s1 * k * r * d2, e * (s1 * r * d1 + c1 * k * r * d2),
            ))  # fmt: skip
        r = 1.0 / c2
        t = s2 * r
        d1 = wa + s1 * t * wb - e * c1 * t * wt
        return self._to_columns((
            0.0, c1 * t * d1 + s1 * r * r * d2, e * (s1 * t * d1 - c1 * r * r * d2),
            0.0, -s1 * d1, e * c1 * d1,
            0.0, -e * (c1 * r * d1 + s1 * t * r * d2), -s1 * r * d1 + c1 * t * r * d2,
        ))  # fmt: skip

    def _distance(self, xp: Namespace, chi1: Component, chi2: Component, chi3: Component) -> Component:
        return abs(xp.sin(chi2)) if self._proper else abs(xp.cos(chi2))


class EulerZYX(EulerAngles):
    """euler_zyx = (yaw, pitch, roll) [rad], the reverse of Pinocchio's ``rpy`` (roll, pitch, yaw)."""

    def __init__(self) -> None:
        super().__init__("zyx")
