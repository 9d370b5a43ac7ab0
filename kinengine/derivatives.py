"""Jacobian time derivatives J̇(q, q̇) and kinematic Hessians ∂J/∂q, geometric and analytic.

Frames: I is the root link frame, F the frame asked for, p = p_IF its origin and C = C_IF.
Rows are [linear; angular], columns follow ``robot.joint_names``; ``reference`` means what it
means for :meth:`Robot.jacobian`, and every result here is the derivative of *that* matrix:

* ``jacobian_time_variation``: J̇ = dJ/dt along q̇, (6, dof); entries in [m/(rad·s)], [1/s].
* ``kinematic_hessian``: H (6, dof, dof) with H[:, :, k] = ∂J/∂q_k, so J̇ = H @ q̇.
* ``analytic_hessian``: ∂J_A/∂q_k = Ė(χ, t_k)·J_e0 + E(χ)·∂J_e0/∂q_k, t_k = J_e0[:, k] (m, dof, dof).

How: everything starts from the WORLD Jacobian J_w (the spatial velocity of the body point at I's
origin). Pinocchio 4.1's ``getFrameJacobianTimeVariation`` is d/dt of the Jacobian in each of the
three references (checked against finite differences), except below a revolute mimic joint, where
only WORLD is right (tests/test_derivatives.py shows both). The Hessian
uses the Lie bracket of the joint axes: moving joint b turns every joint a below it, so
∂S_a/∂θ_b = ad(S_b)·S_a = (ω_b × v_a + v_b × ω_a, ω_b × ω_a) for b above a, 0 otherwise; a mimic
joint (θ = m·q_leader + offset) moves with its leader's coordinate. Pinocchio's own
``getFrameKinematicHessian`` gives the same numbers for robots without mimic joints, but only
after ``np.reshape(H.ravel(), (6, nv, nv), order="F")`` (it refuses mimic joints outright).
From J_w, with v = ∂p, ω = the frame's angular velocity along the differentiation direction:
J_lwa = [[I, −[p]×], [0, I]]·J_w, ∂J_lwa = ∂J_w + [∂J_w,ang × p + J_w,ang × v; 0] and
J_local = blockdiag(Cᵀ, Cᵀ)·J_lwa, ∂J_local = blockdiag(Cᵀ, Cᵀ)·(∂J_lwa − ω × J_lwa).
"""

from __future__ import annotations


import numpy as np
import pinocchio as pin

from .analytic import DEFAULT_SINGULARITY_THRESHOLD, as_rows, pose_map
from .robot import resolve_reference


def jacobian_time_variation(robot, q: object, qdot: object, frame: str | None = None,
                            reference: object = "local_world_aligned") -> np.ndarray:
    """J̇ = d/dt J(q(t), frame, reference) at q [rad | m] moving with q̇ [rad/s | m/s], (6, dof).

    In "local_world_aligned" this is the seed's d/dt(I J_e0): a_F = J_e0·q̈ + J̇_e0·q̇ is the
    acceleration of F's origin and the angular acceleration, both in I.
    """
    ref = resolve_reference(reference)
    fid = robot.frame_id(robot.end_effector if frame is None else frame)
    q = robot._joints.check(q, allow_batch=False)
    qdot = robot._joints.check(qdot, name="qdot", allow_batch=False)
    model, data = robot._model, robot._data()
    pin.computeJointJacobiansTimeVariation(model, data, robot._joints.to_pinocchio(q), qdot)
    Jw = pin.getFrameJacobian(model, data, fid, pin.WORLD).reshape(6, robot.dof)  # eigenpy: (6, 1) -> (6,)
    dJw = pin.getFrameJacobianTimeVariation(model, data, fid, pin.WORLD).reshape(6, robot.dof)
    M = pin.updateFramePlacement(model, data, fid)
    return _change_reference(Jw, dJw[:, :, None], qdot[:, None], M.rotation, M.translation, ref)[:, :, 0]


def kinematic_hessian(robot, q: object, frame: str | None = None,
                      reference: object = "local_world_aligned") -> np.ndarray:
    """H[:, j, k] = ∂J[:, j]/∂q_k of the geometric Jacobian J(q, frame, reference), (6, dof, dof).

    Not symmetric in (j, k) in general (the angular rows are no gradient). Units: [m/rad], [1/rad]
    and [1/m] for the linear, angular and prismatic entries.
    """
    ref = resolve_reference(reference)
    fid = robot.frame_id(robot.end_effector if frame is None else frame)
    q = robot._joints.check(q, allow_batch=False)
    model, data = robot._model, robot._data()
    pin.computeJointJacobians(model, data, robot._joints.to_pinocchio(q))
    chain = _chain(robot, fid)
    S = data.J[:, chain.columns]                       # (6, p) world axes of the supporting joints
    v, w = S[:3].T, S[3:].T                            # (p, 3)
    bracket = np.empty((6, len(chain.columns), len(chain.columns)))  # [:, b, a] = ad(S_b)·S_a
    bracket[:3] = np.moveaxis(np.cross(w[:, None], v[None]) + np.cross(v[:, None], w[None]), -1, 0)
    bracket[3:] = np.moveaxis(np.cross(w[:, None], w[None]), -1, 0)
    bracket *= chain.above                             # only joints b above a turn a
    Hw = chain.A.T @ np.swapaxes(bracket, 1, 2) @ chain.A  # Σ_ab A[a,j]·bracket[:,b,a]·A[b,k]: O(6·p²·dof)
    Jw = S @ chain.A
    M = pin.updateFramePlacement(model, data, fid)
    return _change_reference(Jw, Hw, np.eye(robot.dof), M.rotation, M.translation, ref)


def analytic_hessian(robot, q: object, frame: str | None = None, position: str | None = "cartesian",
                     rotation: str | None = "euler_zyx", *, rows=None,
                     singularity_threshold: float = DEFAULT_SINGULARITY_THRESHOLD) -> np.ndarray:
    """∂J_A/∂q_k for J_A = E(χ)·J_e0 of :meth:`Robot.analytic_jacobian`, (m, dof, dof).

    ∂J_A/∂q_k = Ė(χ, t_k)·J_e0 + E(χ)·∂J_e0/∂q_k with t_k = J_e0[:, k] (the twist of a unit q̇_k)
    and Ė(χ, u) = dE/dt along the velocity u. Raises RepresentationSingularityError like
    :meth:`Robot.analytic_jacobian`.
    """
    pmap = pose_map(position, rotation, as_rows(rows))
    frame = robot.end_effector if frame is None else frame
    q = robot._joints.check(q, allow_batch=False)
    T, J = robot.frame_pose(q, frame), robot.jacobian(q, frame)
    pmap.jacobian(T, J, singularity_threshold)        # raises at a representation singularity
    H = kinematic_hessian(robot, q, frame)
    blocks = []
    parts = ((pmap.position, slice(0, 3), T[:3, 3]), (pmap.rotation, slice(3, 6), T[:3, :3]))
    for param, block, value in parts:
        if param is None:
            continue
        if param.name == "cartesian":
            blocks.append(H[block])
            continue
        if param.kind == "position":
            chi = param.from_position(value)
        else:
            chi = param.from_rotation(value, warn=False)
        Edot = param.E_dot(np.broadcast_to(chi, (robot.dof, chi.size)), J[block].T)  # (dof, m, 3): one per k
        blocks.append(np.einsum("kmi,ij->mjk", Edot, J[block])
                      + np.einsum("mi,ijk->mjk", param.E(chi), H[block]))
    HA = np.concatenate(blocks, axis=0)
    return HA if pmap.rows is None else HA[list(pmap.rows)]


# -- internals ----------------------------------------------------------------------------------
class _Chain:
    """The joints that move a frame, as columns of Pinocchio's (extended) joint Jacobian data.J.

    Column a of data.J is S_a·∂θ_a/∂q: a mimic joint's column already carries its multiplier.
    ``A`` (p, dof): A[a, k] = 1 if column a moves with q_k (a mimic joint with its leader's
    coordinate); ``above`` (p, p): above[b, a] = 1 if joint b is a strict ancestor of joint a.
    """

    def __init__(self, model: pin.Model, fid: int, dof: int) -> None:
        joints = [j for j in model.supports[model.frames[fid].parentJoint] if j > 0]
        self.columns = [model.joints[j].idx_vExtended for j in joints]
        self.A = np.zeros((len(joints), dof))
        for a, j in enumerate(joints):
            self.A[a, model.joints[j].idx_v] = 1.0   # a mimic joint's idx_v is its leader's
        self.above = np.array([[float(b != a and b in model.supports[a]) for a in joints] for b in joints],
                              dtype=float).reshape(len(joints), len(joints))


def _chain(robot, fid: int) -> _Chain:
    return robot._memoized(("hessian chain", fid), lambda: _Chain(robot._model, fid, robot.dof))


def _change_reference(Jw: np.ndarray, dJw: np.ndarray, directions: np.ndarray, C: np.ndarray, p: np.ndarray,
                      ref: pin.ReferenceFrame) -> np.ndarray:
    """Derivatives dJw (6, dof, K) of the WORLD Jacobian Jw (6, dof) along K directions of q (dof, K)
    turned into derivatives of the Jacobian in ``ref`` (see the module doc), (6, dof, K)."""
    if ref == pin.WORLD:
        return dJw
    J = Jw.copy()
    J[:3] += np.cross(Jw[3:].T, p).T                     # J_lwa: v_F = v_O + ω × p
    twist = J @ directions                               # (6, K): (∂p, ω) of F along each direction
    out = dJw.copy()
    out[:3] += np.moveaxis(np.cross(np.moveaxis(dJw[3:], 0, -1), p), -1, 0)
    out[:3] += np.moveaxis(np.cross(Jw[3:].T[:, None, :], twist[:3].T[None, :, :]), -1, 0)
    if ref == pin.LOCAL_WORLD_ALIGNED:
        return out
    for block in (slice(0, 3), slice(3, 6)):            # d(Cᵀ X) = Cᵀ (dX − ω × X)
        out[block] -= np.moveaxis(np.cross(twist[3:].T[None, :, :], J[block].T[:, None, :]), -1, 0)
        out[block] = np.einsum("ji,jnk->ink", C, out[block])
    return out
