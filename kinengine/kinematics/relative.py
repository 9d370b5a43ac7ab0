"""Relative kinematics of a frame A with respect to a frame B of the same robot (both moving).

Pose: T_BA = T_IB⁻¹ · T_IA (4, 4) [m]: A's origin and axes seen from B.

Velocity of A relative to B, as seen by an observer fixed in B (Robot Dynamics lecture notes, ETH Zurich,
section 2.8, with the relative-motion rules of rigid bodies). With p_A, p_B the origins in I, C_IB the
rotation of B in I, and J_A, J_B the geometric Jacobians in "local_world_aligned" (rows [v; ω] in I):

    ω_rel = ω_A − ω_B                                    (in I)
    v_rel = d/dt(p_A − p_B) − ω_B × (p_A − p_B)          (in I; = C_IB · d/dt(B_p_BA))
          = (J_A,v − J_B,v + [p_A − p_B]× J_B,ω) q̇

and expressed in a frame E's axes ("expressed_in", default B): blockdiag(C_IEᵀ, C_IEᵀ) · [v_rel; ω_rel].
So J_rel (6, dof) with E = B satisfies d/dt(B_p_BA) = J_rel[:3] q̇ and Ċ_BA = [J_rel[3:] q̇]× C_BA.

Every function takes the Kinematics engine, a checked q (dof,) or Q (N, dof) and Pinocchio frame ids.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from . import batch
from .engine import Kinematics

_LWA = pin.LOCAL_WORLD_ALIGNED


def _inverse_times(TB: np.ndarray, TA: np.ndarray) -> npt.NDArray[np.float64]:
    """T_IB⁻¹ · T_IA for (4, 4) or (N, 4, 4) rigid transforms."""
    CBt = np.swapaxes(TB[..., :3, :3], -1, -2)
    out = np.zeros(np.broadcast_shapes(TA.shape, TB.shape))
    out[..., :3, :3] = CBt @ TA[..., :3, :3]
    out[..., :3, 3] = (CBt @ (TA[..., :3, 3] - TB[..., :3, 3])[..., None])[..., 0]
    out[..., 3, 3] = 1.0
    return out


def _pose(kin: Kinematics, q: np.ndarray, fid: int) -> npt.NDArray[np.float64]:
    """T_IF (4, 4) or (N, 4, 4), an array of its own, for q (dof,) or Q (N, dof)."""
    if q.ndim == 2:
        return batch.evaluate(kin, q, fid, None, jacobian=False)[0]  # type: ignore[return-value]
    return kin.pose(q, fid).copy()


def _pose_jacobian(kin: Kinematics, q: np.ndarray, fid: int) -> tuple[np.ndarray, np.ndarray]:
    """(T_IF, J_e0 in "local_world_aligned") for q (dof,) or Q (N, dof)."""
    if q.ndim == 2:
        return batch.evaluate(kin, q, fid, _LWA)  # type: ignore[return-value]
    return kin.pose(q, fid).copy(), kin.jacobian(q, fid, _LWA).copy()


def relative_pose(kin: Kinematics, q: np.ndarray, fa: int, fb: int) -> npt.NDArray[np.float64]:
    """T_BA = T_IB⁻¹ T_IA: q (dof,) -> (4, 4), q (N, dof) -> (N, 4, 4); translation [m]."""
    return _inverse_times(_pose(kin, q, fb), _pose(kin, q, fa))


def relative_terms(TA: np.ndarray, JA: np.ndarray, TB: np.ndarray, JB: np.ndarray) -> npt.NDArray[np.float64]:
    """[v_rel; ω_rel] Jacobian (6, dof) or (N, 6, dof) in I's axes from the frames' poses and
    "local_world_aligned" Jacobians (see the module doc)."""
    d = TA[..., :3, 3] - TB[..., :3, 3]
    out = JA - JB  # and [d]× J_B,ω on the linear rows, column by column: d × (J_B,ω e_k)
    out[..., :3, :] += np.swapaxes(np.cross(d[..., None, :], np.swapaxes(JB[..., 3:, :], -1, -2)), -1, -2)
    return out


def relative_jacobian(
    kin: Kinematics, q: np.ndarray, fa: int, fb: int, fe: int | None = None
) -> npt.NDArray[np.float64]:
    """J_rel (6, dof) or (N, 6, dof): rows [v; ω] of A relative to B (module doc), in the axes of frame
    ``fe`` (default ``fb``). Units: [m/s] and [rad/s] per unit joint speed."""
    TA, JA = _pose_jacobian(kin, q, fa)
    TB, JB = _pose_jacobian(kin, q, fb)
    inner = relative_terms(TA, JA, TB, JB)
    C = TB[..., :3, :3] if fe is None or fe == fb else _pose(kin, q, fe)[..., :3, :3]
    Ct = np.swapaxes(C, -1, -2)
    inner[..., :3, :] = Ct @ inner[..., :3, :]
    inner[..., 3:, :] = Ct @ inner[..., 3:, :]
    return inner


__all__ = ["relative_jacobian", "relative_pose", "relative_terms"]
