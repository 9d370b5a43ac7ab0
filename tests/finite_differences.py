"""Central finite differences of frame poses: the numerical Jacobians every analytic one is checked against."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.spatial.transform import Rotation


def pose_jacobian_fd(
    pose: Callable[[np.ndarray], np.ndarray], q: np.ndarray, reference: str, h: float = 1e-6
) -> np.ndarray:
    """(6, dof) geometric Jacobian of T_IF(q) by central differences, rows [linear; angular].

    Linear: (p(q + h e_k) − p(q − h e_k)) / 2h; angular: log(C(q + h e_k) C(q − h e_k)^T) / 2h,
    both in I ("local_world_aligned"); then rotated into F ("local") or shifted to the point at
    I's origin ("world": v_O = v_F − ω × p_F).
    """
    q = np.asarray(q, dtype=float)
    T0 = pose(q)
    C, p = T0[:3, :3], T0[:3, 3]
    J = np.empty((6, q.size))
    for k in range(q.size):
        dq = np.zeros_like(q)
        dq[k] = h
        Tp, Tm = pose(q + dq), pose(q - dq)
        v = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        w = Rotation.from_matrix(Tp[:3, :3] @ Tm[:3, :3].T).as_rotvec() / (2 * h)
        if reference == "local_world_aligned":
            J[:, k] = np.concatenate([v, w])
        elif reference == "local":
            J[:, k] = np.concatenate([C.T @ v, C.T @ w])
        elif reference == "world":
            J[:, k] = np.concatenate([v - np.cross(w, p), w])
        else:
            raise ValueError(reference)
    return J


def assert_close_relative(actual: np.ndarray, expected: np.ndarray, rtol: float, what: str = "") -> None:
    """max |actual − expected| <= rtol · max(1, max |expected|)."""
    scale = max(1.0, float(np.max(np.abs(expected))))
    err = float(np.max(np.abs(actual - expected))) / scale
    assert err <= rtol, f"{what}: relative error {err:.3e} > {rtol:.1e}"
