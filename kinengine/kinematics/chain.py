"""The compiled kinematic chain behind :mod:`kinengine.kinematics.batch`: frame poses T_IF (4, 4) [m] and
Jacobians (6, dof) evaluated column-wise over a chunk of n configurations at once (arrays (3, n)).

The chain from the root to the frame is compiled once from the Pinocchio model
(:func:`kinengine.kinematics.batch.compiled_chain`). Joint i is carried as S_i = C_Ii · Q_i, where
Q_i is a constant rotation with Q_i e_z = a_i (its axis):

    S_i = S_parent · K_i · Rz(θ_i),   K_i = Q_parentᵀ · C_i⁰ · Q_i     (C_i⁰, p_i⁰: joint placement)
    p_i = p_parent + S_parent · t_i,  t_i = Q_parentᵀ · p_i⁰             (+ S_i e_z · d if prismatic)

so the world axis of joint i is the third column of S_i, and for axis-aligned joints K_i is a signed
permutation: composing with it costs nothing. Columns of S are (3, n) arrays over a chunk of n
configurations (chunks run in parallel: see :mod:`kinengine.kinematics.batch`). A mimic joint uses
θ = multiplier · q_leader + offset and adds multiplier × its column to the leader's column.
"""

from __future__ import annotations

import itertools
import threading

import numpy as np
import numpy.typing as npt
import pinocchio as pin

CHUNK = 8192
"""Most configurations per numpy pass: each call costs ~1 µs and hands the GIL to the other threads, so
long passes win (ABB IRB 120 on 2 threads: 1.3 M configs/s in chunks of 1024, 2.2 in 4096, 3.0 in 8192),
up to where two threads' scratch (8 · scratch_rows bytes per row each) crowds the shared L3 cache."""
Terms = tuple[tuple[tuple[int, float], ...], ...]


class Step:
    """One movable joint on the path to the frame (plain slots: no dataclass machinery at import)."""

    __slots__ = ("accumulate", "coordinate", "offset", "prismatic", "rotation", "scaling", "translation")
    FIELDS = ("prismatic", "coordinate", "scaling", "offset", "rotation", "translation", "accumulate")
    prismatic: bool
    coordinate: int  # column of Q that drives it (the leader's, for a mimic joint)
    scaling: float  # θ = scaling · q + offset
    offset: float
    rotation: Terms  # K_i (see _terms)
    translation: tuple[tuple[int, float], ...]  # nonzero entries of t_i: (row, value)
    accumulate: bool  # an earlier step already wrote this Jacobian column

    def __init__(self, *values: object) -> None:
        for name, value in zip(self.FIELDS, values, strict=True):
            setattr(self, name, value)


class Chain:
    """The compiled chain: its steps, the frame placement after the last one (C_IF = S_last · rotation),
    the zero Jacobian columns, and the numpy calls per chunk for the pose and for the Jacobian."""

    __slots__ = (
        "columns",
        "dof",
        "jacobian_calls",
        "pose_calls",
        "rotation",
        "steps",
        "translation",
        "unused",
    )

    def __init__(
        self, steps: tuple[Step, ...], rotation: Terms, translation: tuple, dof: int, pose: int, jac: int
    ) -> None:
        self.steps, self.rotation, self.translation, self.dof = steps, rotation, translation, dof
        self.pose_calls, self.jacobian_calls = pose, jac
        driven = {s.coordinate for s in steps}
        self.unused = tuple(k for k in range(dof) if k not in driven)
        first = steps[0].coordinate if steps else 0  # revolute steps filling a slice of columns, one each:
        plain = all(  # their Jacobian columns are computed at once
            not s.prismatic and s.scaling == 1.0 and s.offset == 0.0 and s.coordinate == first + i
            for i, s in enumerate(steps)
        )
        self.columns = slice(first, first + len(steps)) if plain and steps else None

    @property
    def full(self) -> bool:
        """Every coordinate drives a joint of the chain (no zero Jacobian column)."""
        return not self.unused


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


def _cross(
    a: npt.NDArray[np.float64], b: npt.NDArray[np.float64], out: np.ndarray, temp: np.ndarray | None = None
) -> None:
    """out[0:3] = a × b for (3, ...) arrays (out rows may be strided views; temp: two scratch rows)."""
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        if temp is None:
            np.subtract(a[j] * b[k], a[k] * b[j], out=out[i])
        else:
            np.subtract(
                np.multiply(a[j], b[k], out=temp[0]), np.multiply(a[k], b[j], out=temp[1]), out=out[i]
            )


def _cos_sin(q: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """cos q and sin q (the first two thirds of ``rows``) from t = tan(q/2): cos = (1 − t²)/(1 + t²),
    sin = 2t/(1 + t²). One tan and six cheap passes cost ~30 ns per angle where numpy's cos and sin
    take ~40; within 2.3e-16 of them (q/2 is exact; measured on 3e6 angles, ±π and ±π/2 included)."""
    k = len(q)
    cos, sin, d = rows[:k], rows[k : 2 * k], rows[2 * k :]
    t = np.tan(np.multiply(q, 0.5, out=sin), out=sin)
    tt = np.multiply(t, t, out=cos)
    np.reciprocal(np.add(tt, 1.0, out=d), out=d)
    np.multiply(np.subtract(1.0, tt, out=cos), d, out=cos)
    np.multiply(np.add(t, t, out=sin), d, out=sin)
    return cos, sin


def evaluate_chain(
    chain: Chain,
    qT: np.ndarray,
    pose: np.ndarray | None,
    jac: np.ndarray | None,
    reference: pin.ReferenceFrame | None,
    analytic: tuple | None = None,
) -> None:
    """Fill pose (n, 4, 4), jac (n, 6, dof) and/or the analytic Jacobian for the chunk qT (dof, n).

    qT may be a strided view (``Q[a:b].T``): only its rows are read. Results go straight into the
    outputs' strided views (no transposing copy); analytic: (pmap, out (n, m, dof), distances (n, parts)),
    with reference "local_world_aligned". Few numpy calls per chunk, each over many entries: threads
    hand the GIL over at every call.
    """
    dof, n, m = chain.dof, qT.shape[1], len(chain.steps)
    jacobian = jac is not None or analytic is not None
    direct = analytic is None and reference != pin.LOCAL  # Jacobian columns straight into jac's view
    # this thread's scratch rows (see scratch_rows): cos, sin, 1/(1 + t²), later the Jacobian's products |
    # z_i, p_i stacked (3, m, n) | the Jacobian (6, dof, n) when it is not written straight into jac
    head = 3 * max(dof, 2)
    memory = _rows(n, scratch_rows(chain, jacobian, direct))
    cos, sin = _cos_sin(qT, memory[: 3 * dof])  # of every coordinate
    stacked = jacobian and chain.columns is not None  # z_i, p_i stacked (3, m, n) for the Jacobian
    if stacked:
        Z = memory[head : head + 3 * m].reshape(3, m, n)
        P = memory[head + 3 * m : head + 6 * m].reshape(3, m, n)
    eye = np.eye(3)
    S = [eye[:, k : k + 1] for k in range(3)]  # (3, 1) columns broadcast against (3, n)
    p = np.zeros((3, 1))
    joints = []
    for i, step in enumerate(chain.steps):
        p = _shift(p, S, step.translation)
        S = _compose(S, step.rotation)
        if step.scaling != 1.0 or step.offset != 0.0:
            theta = qT[step.coordinate] * step.scaling + step.offset
            c, s = np.cos(theta), np.sin(theta)
        else:
            theta, c, s = qT[step.coordinate], cos[step.coordinate], sin[step.coordinate]
        if step.prismatic:
            p = p + S[2] * theta
        else:
            S = [S[0] * c + S[1] * s, S[1] * c - S[0] * s, S[2]]
        if stacked:
            Z[:, i], P[:, i] = S[2], p
        elif jacobian:
            joints.append((step, S[2], p))
    p_f = _shift(p, S, chain.translation)
    R_f = _compose(S, chain.rotation)
    if pose is not None:
        for k in range(3):  # one strided copy per entry: faster than a transposing copy of (3, n) blocks
            for r in range(3):
                pose[:, r, k] = R_f[k][r]
            pose[:, k, 3] = p_f[k]
        pose[:, 3] = (0.0, 0.0, 0.0, 1.0)
    if not jacobian:
        return
    target = jac.transpose(1, 2, 0) if direct else memory[head + 6 * m :].reshape(6, dof, n)  # type: ignore[union-attr]
    for k in chain.unused:
        target[:, k] = 0.0
    if stacked:
        cols = target[:, chain.columns]  # (6, m, n)
        temp = memory[: 2 * m].reshape(2, m, n)  # m <= dof: within cos and sin, done with
        if reference == pin.WORLD:
            _cross(P, Z, cols, temp)
        else:  # p_f − p_i in place of p_i
            _cross(Z, np.subtract(p_f[:, None], P, out=P), cols, temp)
        for r in range(3):
            cols[3 + r] = Z[r]
    else:
        _columns(joints, p_f, reference, target, memory[:6])
    if direct:
        return
    if jac is not None:
        if reference == pin.LOCAL:  # [v; ω] in F: C_IFᵀ applied to both halves
            t = memory[: 2 * dof].reshape(2, dof, n)  # within the cos and sin rows, done with
            for r, half in itertools.product(range(3), (0, 3)):
                block = target[half : half + 3]
                np.add(
                    np.multiply(R_f[r][0], block[0], out=t[0]),
                    np.multiply(R_f[r][1], block[1], out=t[1]),
                    out=t[0],
                )
                np.add(t[0], np.multiply(R_f[r][2], block[2], out=t[1]), out=jac[:, half + r, :].T)
        else:
            jac.transpose(1, 2, 0)[...] = target
    if analytic is not None:
        pmap, out, distances = analytic
        JA = np.empty((pmap.size, chain.dof, n))
        # row-major entries of C_IF and p, as (n,) views (a column the chain never turns is (3, 1))
        C = [np.broadcast_to(R_f[j][i], (n,)) for i in range(3) for j in range(3)]
        p_rows = [np.broadcast_to(p_f[i], (n,)) for i in range(3)]
        for k, distance in enumerate(pmap.fill_columns(p_rows, C, target, JA)):
            distances[:, k] = distance
        out[...] = JA.transpose(2, 0, 1)


def _columns(
    joints: list, p_f: np.ndarray, reference: pin.ReferenceFrame | None, target: np.ndarray, col: np.ndarray
) -> None:
    """The Jacobian column of each step in turn (prismatic joints; mimic joints scaled and accumulated
    through the scratch ``col`` (6, n))."""
    for step, z, p_i in joints:
        rows = target[:, step.coordinate]  # (6, n)
        dst = col if step.accumulate or step.scaling != 1.0 else rows
        if step.prismatic:
            dst[:3] = z
            dst[3:] = 0.0
        else:
            if reference == pin.WORLD:
                _cross(p_i, z, dst)
            else:
                _cross(z, p_f - p_i, dst)
            dst[3:] = z
        if step.scaling != 1.0:
            dst *= step.scaling
        if step.accumulate:
            rows += dst
        elif dst is not rows:
            rows[...] = dst


_LOCAL = threading.local()


def scratch_rows(chain: Chain, jacobian: bool, direct: bool) -> int:
    """Scratch float64 per configuration of a chunk (``direct``: J written in place, no LOCAL frame)."""
    return 3 * max(chain.dof, 2) + (
        6 * len(chain.steps) + (0 if direct else 6 * chain.dof) if jacobian else 0
    )


def _rows(n: int, rows: int) -> np.ndarray:
    """This thread's reusable scratch as (rows, n): one allocation per thread (grown when needed), not
    one per chunk (which page-faults through large batches)."""
    memory = getattr(_LOCAL, "memory", None)
    if memory is None or memory.size < rows * n:
        memory = _LOCAL.memory = np.empty(rows * n)
    return memory[: rows * n].reshape(rows, n)


__all__ = ["CHUNK", "Chain", "Step", "Terms", "evaluate_chain", "scratch_rows"]
