"""Damped least squares: x = argmin ‖J x − e‖² + λ‖x‖², for the Task path (J q̇ = e solved each cycle).

x = (JᵀJ + λI)⁻¹ Jᵀ e = V diag(σ_i / (σ_i² + λ)) Uᵀ e from the SVD J = U Σ Vᵀ, so it never raises: at an
exactly singular J (σ_i = 0) the lost directions get 0 (with λ = 0 it is the pseudo-inverse solution
J⁺ e). λ is the same Tikhonov weight as ``DifferentialIK(damping=...)``; the often written
(JᵀJ + λ²I)⁻¹Jᵀe has damping = λ².
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from ..errors import OptionError
from ..kinematics.options import checked_nonnegative


def damped_solve(J: npt.ArrayLike, e: npt.ArrayLike, damping: float = 1e-6) -> npt.NDArray[np.float64]:
    """x (n,) minimizing ‖J x − e‖² + damping·‖x‖² for J (m, n) and e (m,) (or x (n, k) for e (m, k)).

    damping >= 0 (units of J²: [m²/rad²] for linear rows). Never raises at a singular J; OptionError for
    non-finite or wrongly shaped input.
    """
    lam = checked_nonnegative(damping, "damping")
    try:
        A, b = np.asarray(J, dtype=float), np.asarray(e, dtype=float)
    except (TypeError, ValueError):
        raise OptionError("damped_solve takes real arrays J (m, n) and e (m,) or (m, k)") from None
    if A.ndim != 2 or b.ndim not in (1, 2) or b.shape[0] != A.shape[0]:
        raise OptionError(f"damped_solve needs J (m, n) and e (m,) or (m, k), got {A.shape} and {b.shape}")
    if not (np.isfinite(A).all() and np.isfinite(b).all()):
        raise OptionError("damped_solve: J and e must be finite (no NaN or inf)")
    U, s, Vt = np.linalg.svd(A, full_matrices=False)  # numpy's SVD takes empty matrices too
    kept = s > np.finfo(float).eps * max(A.shape) * s.max(initial=0.0)  # numerically nonzero σ_i
    gain = np.divide(s, s * s + lam, out=np.zeros_like(s), where=kept)
    x: npt.NDArray[np.float64] = Vt.T @ (gain.reshape((-1,) + (1,) * (b.ndim - 1)) * (U.T @ b))
    return x


__all__ = ["damped_solve"]
