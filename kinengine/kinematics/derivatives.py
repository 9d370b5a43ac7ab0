"""Jacobian time derivatives J̇(q, q̇) and kinematic Hessians ∂J/∂q of the geometric Jacobian.

Frames: I is the root link frame, F the frame asked for, p = p_IF its origin and C = C_IF.
Rows are [linear; angular], columns follow the coordinate map (``robot.joint_names``); ``ref``
means what it means for the Jacobian (see :mod:`.engine`), and every result here is the derivative
of *that* matrix. q (and q̇) are checked by the caller.

* ``jacobian_time_variation``: J̇ = dJ/dt along q̇, (6, dof); entries in [m/(rad·s)], [1/s].
* ``kinematic_hessian``: H (6, dof, dof) with H[:, :, k] = ∂J/∂q_k, so J̇ = H @ q̇.

How: everything starts from the WORLD Jacobian J_w (the spatial velocity of the body point at I's origin)
of Pinocchio's plain-joint model, folded by the coordinate map (J = J_pin·M, and J̇ = J̇_pin·M with
q̇_pin = M q̇), so mimic joints take no special path. The Hessian uses the Lie bracket of the joint axes:
moving joint b turns every joint a below it, so ∂S_a/∂θ_b = ad(S_b)·S_a = (ω_b × v_a + v_b × ω_a, ω_b × ω_a)
for b above a, 0 otherwise, and θ = M q gives H = Σ_ab M[a, j]·ad(S_b)S_a·M[b, k]. Pinocchio's own
``getFrameKinematicHessian`` gives the same numbers (after ``np.reshape(H.ravel(), (6, nv, nv), order="F")``).
From J_w, with v = ∂p, ω = the frame's angular velocity along the differentiation direction:
J_lwa = [[I, −[p]×], [0, I]]·J_w, ∂J_lwa = ∂J_w + [∂J_w,ang × p + J_w,ang × v; 0] and
J_local = blockdiag(Cᵀ, Cᵀ)·J_lwa, ∂J_local = blockdiag(Cᵀ, Cᵀ)·(∂J_lwa − ω × J_lwa).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from .engine import Kinematics


def jacobian_time_variation(
    kin: Kinematics, q: np.ndarray, qdot: np.ndarray, fid: int, ref: pin.ReferenceFrame
) -> npt.NDArray[np.float64]:
    """J̇ = d/dt J(q(t), frame, reference) at checked q [rad | m] moving with q̇ [rad/s | m/s], (6, dof).

    In LOCAL_WORLD_ALIGNED this is d/dt(I J_e0) of the lecture notes: a_F = J_e0·q̈ + J̇_e0·q̇ is the
    acceleration of F's origin and the angular acceleration, both in I.
    """
    if kin.dof == 0:  # Pinocchio 4.1 crashes on a frame Jacobian with nv = 0
        return np.zeros((6, 0))
    model, data, coords = kin.model, kin.data(), kin.coordinates
    pin.computeJointJacobiansTimeVariation(
        model, data, coords.to_pinocchio(q), coords.velocity_to_pinocchio(qdot)
    )
    if coords.identity or ref == pin.WORLD:
        # without mimic joints Pinocchio's J̇ in ``ref`` is the time derivative of the Jacobian in ``ref``
        # (tests compare it with finite differences of J); J̇ = J̇_pin·M since M is constant
        return coords.fold(pin.getFrameJacobianTimeVariation(model, data, fid, ref).reshape(6, -1))
    # below revolute mimic joints Pinocchio 4.1's LOCAL / LOCAL_WORLD_ALIGNED J̇ is wrong (WORLD is right):
    # change the reference of WORLD's J̇ here (module doc)
    Jw = coords.fold(pin.getFrameJacobian(model, data, fid, pin.WORLD).reshape(6, -1))
    dJw = coords.fold(pin.getFrameJacobianTimeVariation(model, data, fid, pin.WORLD).reshape(6, -1))
    M = pin.updateFramePlacement(model, data, fid)
    return _change_reference(Jw, dJw[:, :, None], qdot[:, None], M, ref)[:, :, 0]


def kinematic_hessian(
    kin: Kinematics, q: np.ndarray, fid: int, ref: pin.ReferenceFrame
) -> npt.NDArray[np.float64]:
    """H[:, j, k] = ∂J[:, j]/∂q_k of the geometric Jacobian J(q, frame, reference), (6, dof, dof).

    Not symmetric in (j, k) in general (the angular rows are no gradient). Units: [m/rad], [1/rad]
    and [1/m] for the linear, angular and prismatic entries.
    """
    if kin.dof == 0:
        return np.zeros((6, 0, 0))
    model, data = kin.model, kin.data()
    pin.computeJointJacobians(model, data, kin.coordinates.to_pinocchio(q))
    chain = kin.memoized(("hessian chain", fid), lambda: _Chain(kin, fid))
    S = data.J.reshape(6, model.nv)[:, chain.columns]  # (6, p) world axes of the supporting joints
    v, w = S[:3].T, S[3:].T  # (p, 3)
    bracket = np.empty((6, len(chain.columns), len(chain.columns)))  # [:, b, a] = ad(S_b)·S_a
    bracket[:3] = np.moveaxis(np.cross(w[:, None], v[None]) + np.cross(v[:, None], w[None]), -1, 0)
    bracket[3:] = np.moveaxis(np.cross(w[:, None], w[None]), -1, 0)
    bracket *= chain.above  # only joints b above a turn a
    Hw = chain.A.T @ np.swapaxes(bracket, 1, 2) @ chain.A  # Σ_ab A[a,j]·bracket[:,b,a]·A[b,k]: O(6·p²·dof)
    return _change_reference(
        S @ chain.A, Hw, np.eye(kin.dof), pin.updateFramePlacement(model, data, fid), ref
    )


# -- internals ----------------------------------------------------------------------------------
class _Chain:
    """The joints that move a frame, as columns of Pinocchio's joint Jacobian data.J (unit joint axes).

    ``A`` (p, dof): A[a, k] = ∂θ_a/∂q_k — the coordinate map's rows of the chain's joints (1 for an
    independent joint, the multiplier for a mimic joint under its root leader's coordinate);
    ``above`` (p, p): above[b, a] = 1 if joint b is a strict ancestor of joint a.
    """

    def __init__(self, kin: Kinematics, fid: int) -> None:
        model, joints = kin.model, kin.supports(fid)
        self.columns = [model.joints[j].idx_v for j in joints]
        self.A = kin.coordinates.matrix[self.columns].reshape(len(joints), kin.dof)
        self.above = np.array(
            [[float(b != a and b in model.supports[a]) for a in joints] for b in joints], dtype=float
        ).reshape(len(joints), len(joints))


def _change_reference(
    Jw: np.ndarray, dJw: np.ndarray, directions: np.ndarray, M: pin.SE3, ref: pin.ReferenceFrame
) -> npt.NDArray[np.float64]:
    """Derivatives dJw (6, dof, K) of the WORLD Jacobian Jw (6, dof) along K directions of q (dof, K)
    turned into derivatives of the Jacobian in ``ref`` (see the module doc), (6, dof, K); M: T_IF."""
    if ref == pin.WORLD:
        return dJw
    C, p = M.rotation, M.translation
    J = Jw.copy()
    J[:3] += np.cross(Jw[3:].T, p).T  # J_lwa: v_F = v_O + ω × p
    twist = J @ directions  # (6, K): (∂p, ω) of F along each direction
    out = dJw.copy()
    out[:3] += np.moveaxis(np.cross(np.moveaxis(dJw[3:], 0, -1), p), -1, 0)
    out[:3] += np.moveaxis(np.cross(Jw[3:].T[:, None, :], twist[:3].T[None, :, :]), -1, 0)
    if ref == pin.LOCAL_WORLD_ALIGNED:
        return out
    for block in (slice(0, 3), slice(3, 6)):  # d(Cᵀ X) = Cᵀ (dX − ω × X)
        out[block] -= np.moveaxis(np.cross(twist[3:].T[None, :, :], J[block].T[:, None, :]), -1, 0)
        out[block] = np.einsum("ji,jnk->ink", C, out[block])
    return out
