"""The compiled kinematic chain behind :mod:`kinengine.kinematics.batch`: frame poses T_IF (4, 4) [m] and
Jacobians (6, dof) evaluated column-wise over a chunk of n configurations at once (arrays (3, n)).

The chain from the root to the frame is compiled once from the Pinocchio model. Joint i is
carried as S_i = C_Ii · Q_i, where Q_i is a constant rotation with Q_i e_z = a_i (its axis):

    S_i = S_parent · K_i · Rz(θ_i),   K_i = Q_parentᵀ · C_i⁰ · Q_i     (C_i⁰, p_i⁰: joint placement)
    p_i = p_parent + S_parent · t_i,  t_i = Q_parentᵀ · p_i⁰             (+ S_i e_z · d if prismatic)

so the world axis of joint i is the third column of S_i, and for axis-aligned joints K_i is a signed
permutation: composing with it costs nothing. Columns of S are (3, n) arrays over a chunk of n
configurations (chunks run in parallel: see :mod:`kinengine.kinematics.batch`). A mimic joint uses
θ = multiplier · q_leader + offset and adds multiplier × its column to the leader's column.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from .engine import Kinematics

CHUNK = 8192
"""Most configurations per numpy pass (the temporaries stay in the core's cache)."""
Terms = tuple[tuple[tuple[int, float], ...], ...]


@dataclass(frozen=True)
class Step:
    """One movable joint on the path to the frame."""

    prismatic: bool
    coordinate: int  # column of Q that drives it (the leader's, for a mimic joint)
    scaling: float  # θ = scaling · q + offset
    offset: float
    rotation: Terms  # K_i (see _terms)
    translation: tuple[tuple[int, float], ...]  # nonzero entries of t_i: (row, value)
    accumulate: bool  # an earlier step already wrote this Jacobian column


@dataclass(frozen=True)
class Chain:
    steps: tuple[Step, ...]
    rotation: Terms  # Q_lastᵀ · C_f (frame placement): C_IF = S_last · this
    translation: tuple[tuple[int, float], ...]
    dof: int
    full: bool  # every coordinate drives a joint of the chain (no zero Jacobian column)
    pose_calls: int  # numpy calls per chunk for the pose, and more for the Jacobian
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


def _compile(kin: Kinematics, fid: int) -> Chain:
    """The chain of movable joints from the root to frame ``fid``, with its constants."""
    model, coords = kin.model, kin.coordinates
    joints = {j.name: j for j in kin.description.joints}
    frame = model.frames[fid]
    steps, seen = [], set()
    Q_parent = np.eye(3)
    for jid in list(model.supports[frame.parentJoint])[1:]:
        k = model.joints[jid].idx_v  # Pinocchio's coordinate: row k of the coordinate map
        joint = joints[model.names[jid]]
        coordinate = int(coords.leader[k])
        axis = np.asarray(joint.axis, dtype=float)
        Q = _axis_basis(axis / np.linalg.norm(axis))
        placement = model.jointPlacements[jid]
        steps.append(
            Step(
                joint.type == "prismatic",
                coordinate,
                float(coords.multiplier[k]),
                float(coords.offset[k]),
                _terms(Q_parent.T @ placement.rotation @ Q),
                _vector_terms(Q_parent.T @ placement.translation),
                coordinate in seen,
            )
        )
        seen.add(coordinate)
        Q_parent = Q
    rotation = _terms(Q_parent.T @ frame.placement.rotation)
    translation = _vector_terms(Q_parent.T @ frame.placement.translation)
    pose_calls = (
        12
        + _compose_calls(rotation)
        + 2 * len(translation)
        + sum(_compose_calls(s.rotation) + 2 * len(s.translation) + (2 if s.prismatic else 8) for s in steps)
    )
    jacobian_calls = 4 + sum(3 if s.prismatic else 12 for s in steps)
    full = len({s.coordinate for s in steps}) == kin.dof
    return Chain(tuple(steps), rotation, translation, kin.dof, full, pose_calls, jacobian_calls)


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


def _shift(
    p: npt.NDArray[np.float64], columns: list, terms: tuple[tuple[int, float], ...]
) -> npt.NDArray[np.float64]:
    for m, value in terms:
        p = p + columns[m] * value
    return p


def _cross(a: npt.NDArray[np.float64], b: npt.NDArray[np.float64], out: np.ndarray) -> None:
    """out[0:3] = a × b for (3, n) arrays (out rows may be strided views)."""
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        np.subtract(a[j] * b[k], a[k] * b[j], out=out[i])


def evaluate_chain(
    chain: Chain,
    qT: np.ndarray,
    pose: np.ndarray | None,
    jac: np.ndarray | None,
    reference: pin.ReferenceFrame | None,
    analytic: tuple | None = None,
) -> None:
    """Fill pose (n, 4, 4), jac (n, 6, dof) and/or the analytic Jacobian for the chunk qT (dof, n).

    analytic: (pmap, out (n, m, dof), distances (n, parts)), with reference "local_world_aligned".
    """
    n = qT.shape[1]
    eye = np.eye(3)
    S = [eye[:, k : k + 1] for k in range(3)]  # (3, 1) columns broadcast against (3, n)
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
    buf, col = _scratch(chain.dof, n)
    if not chain.full:
        buf.fill(0.0)
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
                block = world[half : half + 3]
                buf[half + r] = R_f[r][0] * block[0] + R_f[r][1] * block[1] + R_f[r][2] * block[2]
    if jac is not None:
        jac[...] = buf.transpose(2, 0, 1)
    if analytic is not None:
        pmap, out, distances = analytic
        JA = np.empty((pmap.size, chain.dof, n))
        # row-major entries of C_IF and p, as (n,) views (a column the chain never turns is (3, 1))
        C = [np.broadcast_to(R_f[j][i], (n,)) for i in range(3) for j in range(3)]
        p_rows = [np.broadcast_to(p_f[i], (n,)) for i in range(3)]
        for k, distance in enumerate(pmap.fill_columns(p_rows, C, buf, JA)):
            distances[:, k] = distance
        out[...] = JA.transpose(2, 0, 1)


_LOCAL = threading.local()


def _scratch(dof: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """This thread's reusable (6, dof, n) Jacobian buffer and (6, n) column: one allocation per thread
    (grown when needed), not one per chunk (which page-faults through large batches)."""
    size = 6 * dof * n + 6 * n
    try:
        memory = _LOCAL.memory
        if memory.size < size:
            raise AttributeError
    except AttributeError:
        memory = _LOCAL.memory = np.empty(max(size, 6 * 8 * CHUNK))
    return memory[: 6 * dof * n].reshape(6, dof, n), memory[6 * dof * n : size].reshape(6, n)


def compiled_chain(kin: Kinematics, fid: int) -> Chain:
    """The chain to frame ``fid``, compiled once per robot and frame."""
    return kin.memoized(("batch chain", fid), lambda: _compile(kin, fid))


__all__ = ["CHUNK", "Chain", "Step", "Terms", "compiled_chain", "evaluate_chain"]
