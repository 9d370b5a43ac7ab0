"""Damped least squares: x = argmin ‖J x − e‖² + λ‖x‖², for the Task path (J q̇ = e solved each cycle).

x = (JᵀJ + λI)⁻¹ Jᵀ e = V diag(σ_i / (σ_i² + λ)) Uᵀ e from the SVD J = U Σ Vᵀ, so it never raises: at an
exactly singular J (σ_i = 0) the lost directions get 0 (with λ = 0 it is the pseudo-inverse solution
J⁺ e). λ is the same Tikhonov weight as ``DifferentialIK(damping=...)``; the often written
(JᵀJ + λ²I)⁻¹Jᵀe has damping = λ².
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from ..errors import OptionError


def damped_solve(J: npt.ArrayLike, e: npt.ArrayLike, damping: float = 1e-6) -> npt.NDArray[np.float64]:
    """x (n,) minimizing ‖J x − e‖² + damping·‖x‖² for J (m, n) and e (m,) (or x (n, k) for e (m, k)).

    damping >= 0 (units of J²: [m²/rad²] for linear rows). Never raises at a singular J; OptionError for
    non-finite or wrongly shaped input.
    """
    if isinstance(damping, (bool, np.bool_)) or not isinstance(
        damping, (int, float, np.integer, np.floating)
    ):
        raise OptionError(f"damping must be a number >= 0, got {damping!r:.60}")
    lam = float(damping)
    if not (math.isfinite(lam) and lam >= 0.0):
        raise OptionError(f"damping must be a finite number >= 0, got {damping!r:.60}")
    try:
        A = np.asarray(J, dtype=float)
        b = np.asarray(e, dtype=float)
    except (TypeError, ValueError):
        raise OptionError("damped_solve takes real arrays J (m, n) and e (m,) or (m, k)") from None
    if A.ndim != 2 or b.ndim not in (1, 2) or b.shape[0] != A.shape[0]:
        raise OptionError(f"damped_solve needs J (m, n) and e (m,) or (m, k), got {A.shape} and {b.shape}")
    if not (np.isfinite(A).all() and np.isfinite(b).all()):
        raise OptionError("damped_solve: J and e must be finite (no NaN or inf)")
    if A.size == 0:
        return np.zeros((A.shape[1],) + b.shape[1:])
    U, s, Vt = np.linalg.svd(A, full_matrices=False)
    denominator = s * s + lam
    cutoff = np.finfo(float).eps * max(A.shape) * (float(s[0]) if len(s) else 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        gain = np.where(s > cutoff, s / np.where(denominator > 0, denominator, 1.0), 0.0)
    projected = U.T @ b  # (r,) or (r, k)
    x: npt.NDArray[np.float64] = Vt.T @ (gain[:, None] * projected if b.ndim == 2 else gain * projected)
    return x


__all__ = ["damped_solve"]
