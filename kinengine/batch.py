"""Frame poses and geometric Jacobians for a batch of configurations Q (N, dof), vectorized over N.

>>> T, J = batch_pose_and_jacobian(robot, Q, "tool0", "local_world_aligned")   # (N, 4, 4), (N, 6, dof)

Same conventions as :class:`~kinengine.robot.Robot`: T_IF in the root link frame I [m], J rows
[linear; angular] in "local_world_aligned", "local" or "world", columns in ``joint_names`` order.

How: the chain from the root to the frame is compiled once from the Pinocchio model. Joint i is
carried as S_i = C_Ii · Q_i, where Q_i is a constant rotation with Q_i e_z = a_i (its axis):

    S_i = S_parent · K_i · Rz(θ_i),   K_i = Q_parentᵀ · C_i⁰ · Q_i     (C_i⁰, p_i⁰: joint placement)
    p_i = p_parent + S_parent · t_i,  t_i = Q_parentᵀ · p_i⁰             (+ S_i e_z · d if prismatic)

so the world axis of joint i is the third column of S_i, and for axis-aligned joints K_i is a signed
permutation: composing with it costs nothing. Columns of S are (3, n) arrays over a chunk of n
configurations; chunks run on a thread pool (numpy releases the GIL). A mimic joint uses
θ = multiplier · q_leader + offset and adds multiplier × its column to the leader's column. Small
batches loop over Pinocchio instead, which is faster there (see ``CALLS_PER_CONFIGURATION``).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
import itertools
import os
import threading

import numpy as np
import pinocchio as pin

from .analytic import analytic_at, frame_views

CHUNK = 8192
"""Most configurations per numpy pass (the temporaries stay in the core's cache)."""
MIN_PER_WORKER = 4096
"""Batches are split over several threads only when each gets at least this many rows."""
WORKERS = max(1, min(4, os.cpu_count() or 1))
CALLS_PER_CONFIGURATION = 3
"""One configuration in Pinocchio's loop costs about as much as this many numpy calls over a chunk
(measured on the ABB IRB 120, UR5 and Panda: 1.75 µs against 0.55 µs): a chain that takes c numpy
calls per chunk loops over Pinocchio for batches smaller than c / this."""
MIN_CALLS = 12
"""The fewest numpy calls of any chain (a pose of a frame fixed to the root)."""
ANALYTIC_CALLS = 100
"""numpy calls for χ, E and E·J_e0 over a chunk (about; they vary with the parameterization). A row
of the analytic single-call loop costs about twice a row of Pinocchio's pose and Jacobian loop."""

Terms = tuple[tuple[tuple[int, float], ...], ...]


@dataclass(frozen=True)
class _Step:
    """One movable joint on the path to the frame."""

    prismatic: bool
    coordinate: int             # column of Q that drives it (the leader's, for a mimic joint)
    scaling: float              # θ = scaling · q + offset
    offset: float
    rotation: Terms             # K_i (see _terms)
    translation: tuple[tuple[int, float], ...]   # nonzero entries of t_i: (row, value)
    accumulate: bool            # an earlier step already wrote this Jacobian column


@dataclass(frozen=True)
class _Chain:
    steps: tuple[_Step, ...]
    rotation: Terms             # Q_lastᵀ · C_f (frame placement): C_IF = S_last · this
    translation: tuple[tuple[int, float], ...]
    dof: int
    pose_calls: int             # numpy calls per chunk for the pose, and more for the Jacobian
    jacobian_calls: int


def _axis_basis(axis: np.ndarray) -> np.ndarray:
    """A rotation Q with Q e_z = axis (exact signed permutation when the axis is a coordinate axis)."""
    e = np.zeros(3)
    e[int(np.argmin(np.abs(axis)))] = 1.0
    x = e - (e @ axis) * axis
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(axis, x), axis])


def _terms(matrix: np.ndarray) -> Terms:
    """Nonzero entries of a 3x3 matrix, column by column: ((row, value), ...) per column."""
    return tuple(tuple((m, float(matrix[m, k])) for m in range(3) if matrix[m, k] != 0.0) for k in range(3))


def _vector_terms(vector: np.ndarray) -> tuple[tuple[int, float], ...]:
    return tuple((m, float(vector[m])) for m in range(3) if vector[m] != 0.0)


def _compose_calls(terms: Terms) -> int:
    """numpy calls that _compose makes (a column that is a plain copy costs none)."""
    return sum(0 if len(t) == 1 and t[0][1] == 1.0 else 2 * len(t) - 1 for t in terms)


def _compile(robot, fid: int) -> _Chain:
    """The chain of movable joints from the root to frame ``fid``, with its constants."""
    model = robot._model
    joints = {j.name: j for j in robot.description.joints}
    frame = model.frames[fid]
    steps, seen = [], set()
    Q_parent = np.eye(3)
    for jid in list(model.supports[frame.parentJoint])[1:]:
        jmodel = model.joints[jid]
        joint = joints[model.names[jid]]
        scaling, offset = 1.0, 0.0
        if jmodel.shortname() == "JointModelMimic":
            mimic = jmodel.extract()
            scaling, offset = float(mimic.scaling), float(mimic.offset)
        axis = np.asarray(joint.axis, dtype=float)
        Q = _axis_basis(axis / np.linalg.norm(axis))
        placement = model.jointPlacements[jid]
        steps.append(_Step(joint.type == "prismatic", jmodel.idx_v, scaling, offset,
                           _terms(Q_parent.T @ placement.rotation @ Q),
                           _vector_terms(Q_parent.T @ placement.translation), jmodel.idx_v in seen))
        seen.add(jmodel.idx_v)
        Q_parent = Q
    rotation = _terms(Q_parent.T @ frame.placement.rotation)
    translation = _vector_terms(Q_parent.T @ frame.placement.translation)
    pose_calls = 12 + _compose_calls(rotation) + 2 * len(translation) + sum(
        _compose_calls(s.rotation) + 2 * len(s.translation) + (2 if s.prismatic else 8) for s in steps)
    jacobian_calls = 4 + sum(3 if s.prismatic else 12 for s in steps)
    return _Chain(tuple(steps), rotation, translation, robot.dof, pose_calls, jacobian_calls)


def _compose(columns: list, terms: Terms) -> list:
    """Columns of S · K, for S given by its columns and K by its nonzero entries."""
    out = []
    for column_terms in terms:
        (m, value), rest = column_terms[0], column_terms[1:]
        if not rest and value == 1.0:
            out.append(columns[m])
            continue
        acc = -columns[m] if value == -1.0 else columns[m] * value
        for m, value in rest:
            acc = acc + columns[m] * value
        out.append(acc)
    return out


def _shift(p, columns: list, terms: tuple[tuple[int, float], ...]):
    for m, value in terms:
        p = p + columns[m] * value
    return p


def _cross(a, b, out: np.ndarray) -> None:
    """out[0:3] = a × b for (3, n) arrays (out rows may be strided views)."""
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        np.subtract(a[j] * b[k], a[k] * b[j], out=out[i])


def _evaluate(chain: _Chain, qT: np.ndarray, pose: np.ndarray | None, jac: np.ndarray | None,
              reference: pin.ReferenceFrame | None, analytic: tuple | None = None) -> None:
    """Fill pose (n, 4, 4), jac (n, 6, dof) and/or the analytic Jacobian for the chunk qT (dof, n).

    analytic: (pmap, out (n, m, dof), distances (n, parts)), with reference "local_world_aligned".
    """
    n = qT.shape[1]
    eye = np.eye(3)
    S = [eye[:, k:k + 1] for k in range(3)]  # (3, 1) columns broadcast against (3, n)
    p = np.zeros((3, 1))
    joints = []
    for step in chain.steps:
        p = _shift(p, S, step.translation)
        S = _compose(S, step.rotation)
        theta = qT[step.coordinate]
        if step.scaling != 1.0 or step.offset != 0.0:
            theta = theta * step.scaling + step.offset
        if step.prismatic:
            p = p + S[2] * theta
        else:
            c, s = np.cos(theta), np.sin(theta)
            S = [S[0] * c + S[1] * s, S[1] * c - S[0] * s, S[2]]
        joints.append((step, S[2], p))
    p_f = _shift(p, S, chain.translation)
    R_f = _compose(S, chain.rotation)
    if pose is not None:
        for k in range(3):
            pose[:, :3, k] = R_f[k].T
        pose[:, :3, 3] = p_f.T
        pose[:, 3, :] = (0.0, 0.0, 0.0, 1.0)
    if jac is None and analytic is None:
        return
    buf = np.zeros((6, chain.dof, n))
    col = np.empty((6, n))
    for step, z, p_i in joints:
        if step.prismatic:
            col[:3] = z
            col[3:] = 0.0
        else:
            if reference == pin.WORLD:
                _cross(p_i, z, col)
            else:
                _cross(z, p_f - p_i, col)
            col[3:] = z
        if step.scaling != 1.0:
            col *= step.scaling
        if step.accumulate:
            buf[:, step.coordinate] += col
        else:
            buf[:, step.coordinate] = col
    if reference == pin.LOCAL:  # [v; ω] in F: C_IFᵀ applied to both halves
        world = buf.copy()
        for r in range(3):
            for half in (0, 3):
                block = world[half:half + 3]
                buf[half + r] = R_f[r][0] * block[0] + R_f[r][1] * block[1] + R_f[r][2] * block[2]
    if jac is not None:
        jac[...] = buf.transpose(2, 0, 1)
    if analytic is not None:
        pmap, out, distances = analytic
        JA = np.empty((pmap.size, chain.dof, n))
        # row-major entries of C_IF and p, as (n,) views (a column the chain never turns is (3, 1))
        C = [np.broadcast_to(R_f[j][i], (n,)) for i in range(3) for j in range(3)]
        p = [np.broadcast_to(p_f[i], (n,)) for i in range(3)]
        for k, distance in enumerate(pmap.fill_columns(p, C, buf, JA)):
            distances[:, k] = distance
        out[...] = JA.transpose(2, 0, 1)


# -- compilation cache, thread pool, Pinocchio loop -----------------------------------------------
_LOCK = threading.Lock()
_POOL: ThreadPoolExecutor | None = None


def _chain(robot, fid: int) -> _Chain:
    return robot._memoized(("batch chain", fid), lambda: _compile(robot, fid))


def _pool() -> ThreadPoolExecutor:
    global _POOL
    with _LOCK:
        if _POOL is None:
            _POOL = ThreadPoolExecutor(max(1, WORKERS - 1), thread_name_prefix="kinengine-batch")
        return _POOL


def _run(chain: _Chain, Q: np.ndarray, pose, jac, reference, analytic=None) -> None:
    """Evaluate Q in chunks of at most CHUNK rows, split evenly over up to WORKERS threads."""
    workers = max(1, min(WORKERS, len(Q) // MIN_PER_WORKER))
    pieces = workers * -(-len(Q) // (workers * CHUNK))
    chunks = list(itertools.pairwise(len(Q) * i // pieces for i in range(pieces + 1)))

    def work(part: list[tuple[int, int]]) -> None:
        for a, b in part:
            _evaluate(chain, np.ascontiguousarray(Q[a:b].T), None if pose is None else pose[a:b],
                      None if jac is None else jac[a:b], reference,
                      None if analytic is None else (analytic[0], analytic[1][a:b], analytic[2][a:b]))

    per = pieces // workers
    futures = [_pool().submit(work, chunks[i:i + per]) for i in range(per, pieces, per)]
    work(chunks[:per])  # the calling thread takes the first share
    for future in futures:
        future.result()


def _pinocchio_loop(robot, Q: np.ndarray, fid: int, pose, jac, reference) -> None:
    """The same outputs from a Python loop over Pinocchio (faster for small batches)."""
    model, data = robot._model, robot._data()
    if robot.dof == 0:
        jac = None  # nothing to fill (and Pinocchio 4.1's getFrameJacobian crashes when nv = 0)
    if pose is None and jac is None:
        return
    for i, qi in enumerate(robot._joints.to_pinocchio(Q)):
        if jac is None:
            pin.forwardKinematics(model, data, qi)
        elif pose is None:
            jac[i] = pin.computeFrameJacobian(model, data, qi, fid, reference).reshape(6, -1)  # dof 1: (6,)
            continue
        else:  # computeFrameJacobian leaves data.oMi stale in LOCAL: place every joint first
            pin.computeJointJacobians(model, data, qi)
            jac[i] = pin.getFrameJacobian(model, data, fid, reference).reshape(6, -1)
        pose[i] = pin.updateFramePlacement(model, data, fid).homogeneous


def evaluate(robot, Q: np.ndarray, fid: int, reference: pin.ReferenceFrame | None, *, pose: bool = True,
             jacobian: bool = True) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(T (N, 4, 4) or None, J (N, 6, dof) or None) for an already checked float64 Q (N, dof).

    The entry point for :class:`~kinengine.robot.Robot`, which has checked q and resolved the
    frame index and the reference (a pin.ReferenceFrame; unused when ``jacobian`` is False).
    """
    n = len(Q)
    T = np.empty((n, 4, 4)) if pose else None
    J = np.empty((n, 6, robot.dof)) if jacobian else None
    chain = _numpy_chain(robot, fid, n, jacobian)
    if chain is None:
        _pinocchio_loop(robot, Q, fid, T, J, reference)
    else:
        _run(chain, Q, T, J, reference)
    return T, J


def _numpy_chain(robot, fid: int, n: int, jacobian: bool, extra: int = 0, row_cost: int = 1) -> _Chain | None:
    """The compiled chain if numpy over the batch is the faster path, else None (loop row by row).

    A loop row costs ``row_cost`` × CALLS_PER_CONFIGURATION numpy calls; the numpy path costs the
    chain's calls plus ``extra``.
    """
    budget = row_cost * n * CALLS_PER_CONFIGURATION
    if budget < MIN_CALLS + extra:  # the chain is not even looked up
        return None
    chain = _chain(robot, fid)
    return chain if budget >= chain.pose_calls + (chain.jacobian_calls if jacobian else 0) + extra else None


def analytic_jacobian(robot, Q: np.ndarray, fid: int, pmap, threshold: float) -> np.ndarray:
    """J_A = E(χ)·J_e0 for every row of an already checked Q (N, dof) -> (N, m, dof).

    ``pmap`` is the :class:`~kinengine.analytic.PoseMap`. Small batches take the single-call path
    row by row; larger ones evaluate χ, E and E·J_e0 with numpy over each chunk, next to the chain.
    RepresentationSingularityError names the first row within ``threshold`` of a singular set.
    """
    n = len(Q)
    out = np.empty((n, pmap.size, robot.dof))
    # (Pinocchio 4.1 crashes on a Jacobian with nv = 0: such robots take the numpy chain)
    chain = _numpy_chain(robot, fid, n, True, ANALYTIC_CALLS, row_cost=2) if robot.dof else _chain(robot, fid)
    if chain is None:
        return _analytic_loop(robot, Q, fid, pmap, threshold, out)
    distances = np.empty((n, len(pmap.parts)))
    _run(chain, Q, None, None, pin.LOCAL_WORLD_ALIGNED, (pmap, out, distances))
    pmap.raise_if_singular(distances, threshold, lambda row: evaluate(robot, Q[row:row + 1], fid, None,
                                                                      jacobian=False)[0][0])
    return out


def _analytic_loop(robot, Q: np.ndarray, fid: int, pmap, threshold: float, out: np.ndarray) -> np.ndarray:
    model, data = robot._model, robot._data()
    views = frame_views(data, fid)
    for i, qi in enumerate(robot._joints.to_pinocchio(Q)):
        out[i] = analytic_at(model, data, qi, fid, views, pmap, threshold, i)
    return out


def _batch(robot, Q: object, frame: str | None, reference: object, pose: bool, jacobian: bool):
    from .robot import resolve_reference  # robot.py routes its batches here: import it late
    fid = robot.frame_id(frame if frame is not None else robot.end_effector)
    ref = resolve_reference(reference) if jacobian else None
    Q = robot._joints.check(Q, name="Q")
    single = Q.ndim == 1
    out = tuple(a[0] if single else a for a in evaluate(robot, Q[None] if single else Q, fid, ref,
                                                       pose=pose, jacobian=jacobian) if a is not None)
    return out if len(out) == 2 else out[0]


def batch_frame_pose(robot, Q: object, frame: str | None = None) -> np.ndarray:
    """T_IF for every row of Q: (N, dof) -> (N, 4, 4) (a single (dof,) q gives (4, 4)). [m]"""
    return _batch(robot, Q, frame, None, True, False)


def batch_jacobian(robot, Q: object, frame: str | None = None,
                   reference: object = "local_world_aligned") -> np.ndarray:
    """Geometric Jacobians for every row of Q: (N, dof) -> (N, 6, dof), rows [linear; angular]."""
    return _batch(robot, Q, frame, reference, False, True)


def batch_pose_and_jacobian(robot, Q: object, frame: str | None = None,
                            reference: object = "local_world_aligned") -> tuple[np.ndarray, np.ndarray]:
    """(T, J) in one pass over the chain: (N, 4, 4) and (N, 6, dof) for Q (N, dof)."""
    return _batch(robot, Q, frame, reference, True, True)


__all__ = ["CALLS_PER_CONFIGURATION", "CHUNK", "analytic_jacobian", "batch_frame_pose", "batch_jacobian",
           "batch_pose_and_jacobian", "evaluate"]
