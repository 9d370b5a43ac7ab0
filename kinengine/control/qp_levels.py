"""The per-step numerics of :class:`kinengine.control.qp.DifferentialIK`: the step's bounds from the position,
velocity and acceleration limits, the priority levels solved in turn (each a QP in the null space of the
levels above), the box QP (one linear solve when no bound is active) and the uniform scale of
``limits="scale"``. Steps Δq = q̇·dt in [rad | m]; a level's cost is ½ΔqᵀHΔq + cᵀΔq (H with its damping)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

_BIG = 1e20  # stands for an infinite bound
_max = np.maximum.reduce
NULL_TOLERANCE = 1e-9
"""Singular values of the levels above at or below this times max(1, σ_max) span the lower levels' space."""

LevelTerms = tuple[np.ndarray, np.ndarray, np.ndarray | None]
"""(H (n, n), c (n,), A (r, n) or None): a level's cost and its task rows (None for the last level)."""


@dataclass
class Limits:
    """The joint limits a step respects: positions [rad | m] (±inf: none), velocities [1/s] and
    accelerations [1/s²] (inf: none)."""

    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray

    def __post_init__(self) -> None:
        self.has_acceleration = bool(np.isfinite(self.acceleration).any())
        self._dt, self._step_velocity = math.nan, (self.velocity, -self.velocity)

    def step_velocity(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """(q̇_max·dt, −q̇_max·dt) [rad | m], kept while dt stays the same."""
        if dt != self._dt:
            self._dt, self._step_velocity = dt, (self.velocity * dt, self.velocity * -dt)
        return self._step_velocity


def step_bounds(
    limits: Limits, q: np.ndarray, dt: float, qdot: np.ndarray, lo: np.ndarray, hi: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """lb <= Δq <= ub [rad | m], written into (lo, hi): position limits over the step, |q̇| <= q̇_max, and with
    acceleration limits a: |q̇ − q̇_prev| <= a·dt (hard: the box is clipped into it) and braking in time,
    v²/(2a) + v·dt <= d to each position limit d away (an upper bound of the distance that steps of dt
    braking at a cover). q outside its limits moves back as fast as allowed."""
    vdt, minus_vdt = limits.step_velocity(dt)
    np.subtract(limits.upper, q, out=hi)
    np.minimum(hi, vdt, out=hi)
    np.subtract(limits.lower, q, out=lo)
    np.maximum(lo, minus_vdt, out=lo)
    if limits.has_acceleration:
        a = limits.acceleration
        u = a * dt
        with np.errstate(invalid="ignore"):  # inf·0, inf − inf: NaN, ignored by fmin/fmax
            np.fmin(hi, (np.sqrt(u * u + 2 * a * np.maximum(limits.upper - q, 0.0)) - u) * dt, out=hi)
            np.fmax(lo, (u - np.sqrt(u * u + 2 * a * np.maximum(q - limits.lower, 0.0))) * dt, out=lo)
    np.maximum(hi, np.minimum(lo, 0.0), out=hi)
    np.minimum(lo, hi, out=lo)
    if limits.has_acceleration:
        a_lo, a_hi = (qdot - limits.acceleration * dt) * dt, (qdot + limits.acceleration * dt) * dt
        np.clip(lo, a_lo, a_hi, out=lo)
        np.clip(hi, a_lo, a_hi, out=hi)
    return lo, hi


class Hierarchy:
    """Solves the levels of one step; ``qp_calls`` counts the calls of the QP solver."""

    def __init__(self, solver: str) -> None:
        self.solver = solver
        self.qp_calls = 0

    def solve(
        self,
        terms: Sequence[LevelTerms],
        lb: np.ndarray,
        ub: np.ndarray,
        G: np.ndarray,
        h: np.ndarray,
        scale: bool,
    ) -> tuple[np.ndarray, str, float]:
        """(Δq, status, s): the levels in turn under the bounds; with ``scale`` the levels without bounds,
        then times the largest s <= 1 within them (the bounded solve when no such s exists)."""
        if len(terms) == 1 and not scale:  # one level: its box QP, no null space to take
            H, c, _ = terms[0]
            step, status = self.box_qp(H, c, lb, ub, G, h, None, None)
            return step, status, 1.0
        if scale:
            free = np.full(len(lb), np.inf)
            step, _ = self.levels(terms, -free, free, G[:0], h[:0])
            s = largest_scale(step, lb, ub, G, h)
            if s is not None:
                return step * s, ("unconstrained" if s == 1.0 else "scaled"), s
        step, status = self.levels(terms, lb, ub, G, h)
        return step, status, 1.0

    def levels(
        self, terms: Sequence[LevelTerms], lb: np.ndarray, ub: np.ndarray, G: np.ndarray, h: np.ndarray
    ) -> tuple[np.ndarray, str]:
        """Level 1 as a QP over Δq; each next level over z in Δq = Δq_above + Z z, Z an orthonormal basis of
        the null space of every task row above (SVD), so the rows above keep their value."""
        step = np.zeros(len(lb))
        Z: np.ndarray | None = None  # basis of the free directions (None: all of Rⁿ)
        above: list[np.ndarray] = []
        worst = "unconstrained"
        last = len(terms) - 1
        for i, (H, c, A) in enumerate(terms):
            if Z is None:
                step, status = self.box_qp(H, c, lb, ub, G, h, None, step)
            else:  # H holds the damping: ZᵀHZ has it on z (Z orthonormal); ‖Δq‖² regularized as a whole
                z, status = self.box_qp(Z.T @ H @ Z, Z.T @ (H @ step + c), lb, ub, G, h, Z, step)
                step = step + Z @ z
            if status != "unconstrained" and worst != "infeasible":
                worst = status
            if A is not None and i < last:  # the last level's null space is not needed
                above.append(A)
                stacked = np.vstack(above)
                if stacked.shape[0]:
                    _, s, Vt = np.linalg.svd(stacked)
                    rank = int((s > NULL_TOLERANCE * max(1.0, float(s[0]))).sum())
                    Z = Vt[rank:].T
                    if Z.shape[1] == 0:
                        break
        return step, worst

    def box_qp(
        self,
        H: np.ndarray,
        c: np.ndarray,
        lb: np.ndarray,
        ub: np.ndarray,
        G: np.ndarray,
        h: np.ndarray,
        Z: np.ndarray | None,
        base: np.ndarray | None,
    ) -> tuple[np.ndarray, str]:
        """argmin ½zᵀHz + cᵀz with lb <= base + Z z <= ub and G (base + Z z) <= h (Z None: z = Δq, base
        unused; base None: zero)."""
        # H is positive definite: when the unconstrained minimizer −H⁻¹c satisfies the bounds it is the
        # QP's solution (no bound active), found by one linear solve; otherwise the QP solver decides.
        try:
            z = np.linalg.solve(H, -c)
        except np.linalg.LinAlgError:
            z = None
        if z is not None and math.isfinite(z @ z):  # finite (an overflow of z·z goes to the QP solver)
            x = z if Z is None else (Z @ z if base is None else base + Z @ z)
            # lb <= x <= ub (one reduction; NaN fails it), and G x <= h
            if _max(np.maximum(lb - x, x - ub)) <= 0.0 and (not len(h) or (G @ x <= h).all()):
                return z, "unconstrained"
        self.qp_calls += 1
        import qpsolvers  # only when a bound is active: keeps `import kinengine` light

        if Z is None:  # base None: z = Δq
            hz = _finite(h) if len(h) else h
            z = qpsolvers.solve_qp(
                H,
                c,
                G=G if len(h) else None,
                h=hz if len(h) else None,
                lb=_finite(lb),
                ub=_finite(ub),
                solver=self.solver,
            )
        else:  # the bounds as rows of G: lb − base <= Z z <= ub − base
            base = np.zeros(len(lb)) if base is None else base
            lbc, ubc = _finite(lb - base), _finite(ub - base)
            finite = np.isfinite(lb - base) | np.isfinite(ub - base)
            Gb = np.vstack([Z[finite], -Z[finite], G @ Z])
            hb = np.concatenate([ubc[finite], -lbc[finite], _finite(h - G @ base)])
            z = qpsolvers.solve_qp(
                H, c, G=Gb if len(hb) else None, h=hb if len(hb) else None, solver=self.solver
            )
        if z is None or not math.isfinite(z @ z):  # no feasible step: the bounds' point nearest zero
            z = np.zeros(H.shape[0])
            if Z is None:
                np.clip(z, lb, ub, out=z)
            return z, "infeasible"
        if Z is None:  # the solver's tolerance (~1e-14) off a bound: onto it
            np.minimum(np.maximum(z, lb, out=z), ub, out=z)
        return z, "optimal"


def _finite(x: np.ndarray) -> np.ndarray:
    """x with ±inf (and beyond ±1e20) as ±1e20, a new array (what the QP solvers take for "no bound")."""
    return np.minimum(np.maximum(x, -_BIG), _BIG)


def largest_scale(
    step: np.ndarray, lb: np.ndarray, ub: np.ndarray, G: np.ndarray, h: np.ndarray
) -> float | None:
    """The largest s in [0, 1] with lb <= s·step <= ub and s·G step <= h, or None if there is none."""
    lo, hi = 0.0, 1.0
    with np.errstate(divide="ignore", invalid="ignore"):
        for d, low, high in ((step, lb, ub), (G @ step if len(h) else h[:0], np.full(len(h), -np.inf), h)):
            pos, neg, zero = d > 0, d < 0, d == 0
            if ((low[zero] > 0) | (high[zero] < 0)).any():
                return None
            if pos.any():
                hi = min(hi, float(np.min(high[pos] / d[pos])))
                lo = max(lo, float(np.max(low[pos] / d[pos])))
            if neg.any():
                hi = min(hi, float(np.min(low[neg] / d[neg])))
                lo = max(lo, float(np.max(high[neg] / d[neg])))
    return hi if hi >= lo and hi >= 0.0 else None


__all__ = ["NULL_TOLERANCE", "Hierarchy", "LevelTerms", "Limits", "largest_scale", "step_bounds"]
