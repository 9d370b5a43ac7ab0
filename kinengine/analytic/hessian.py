"""The analytic Hessian ∂J_A/∂q of J_A = E(χ)·J_e0 (rows of the pose map, columns and pages over q).

∂J_A/∂q_k = Ė(χ, t_k)·J_e0 + E(χ)·∂J_e0/∂q_k with t_k = J_e0[:, k] (the twist of a unit q̇_k) and
Ė(χ, u) = dE/dt along the velocity u; ∂J_e0/∂q_k is the kinematic Hessian in LOCAL_WORLD_ALIGNED.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..kinematics.derivatives import kinematic_hessian
from ..kinematics.engine import Kinematics
from .pose_map import PoseMap


def analytic_hessian(
    kin: Kinematics, q: np.ndarray, fid: int, pmap: PoseMap, threshold: float
) -> npt.NDArray[np.float64]:
    """∂J_A/∂q, (m, dof, dof) with [:, :, k] = ∂J_A/∂q_k, at a checked q. Raises
    RepresentationSingularityError where J_A itself would."""
    T, J = kin.pose(q, fid), kin.jacobian(q, fid, pin.LOCAL_WORLD_ALIGNED)
    pmap.jacobian(T, J, threshold)  # raises at a representation singularity
    H = kinematic_hessian(kin, q, fid, pin.LOCAL_WORLD_ALIGNED)
    blocks = []
    p, C = T[:3, 3].tolist(), T[:3, :3].ravel().tolist()
    for param, block in ((pmap.position, slice(0, 3)), (pmap.rotation, slice(3, 6))):
        if param is None:
            continue
        chi = np.array(param._coordinates(math, p, C))
        Edot = param.E_dot(np.broadcast_to(chi, (kin.dof, chi.size)), J[block].T)  # (dof, m, 3): one per k
        blocks.append(
            np.einsum("kmi,ij->mjk", Edot, J[block]) + np.einsum("mi,ijk->mjk", param.E(chi), H[block])
        )
    HA = np.concatenate(blocks, axis=0)
    return HA if pmap.rows is None else HA[list(pmap.rows)]


__all__ = ["analytic_hessian"]
