"""The compiled kinematic chain behind :mod:`kinengine.kinematics.batch`: frame poses T_IF (4, 4) [m] and
Jacobians (6, dof) evaluated column-wise over a chunk of n configurations at once (arrays (3, n)).

The chain from the root to the frame is compiled once (:func:`kinengine.kinematics.compiler.compiled_chain`).
Joint i is carried as S_i = C_Ii · Q_i, where Q_i is a constant rotation with Q_i e_z = a_i (its axis):

    S_i = S_parent · K_i · Rz(θ_i),   K_i = Q_parentᵀ · C_i⁰ · Q_i     (C_i⁰, p_i⁰: joint placement)
    p_i = p_parent + S_parent · t_i,  t_i = Q_parentᵀ · p_i⁰             (+ S_i e_z · d if prismatic)

so the world axis of joint i is the third column of S_i. S and p live in a (4, 3, n) buffer M, slot j
one column up to sign (slot and sign fixed at compile time: :class:`Plan`), slot 3 p. A signed
permutation K_i with t_i = 0 only renames slots; any other joint is one 4x4 product; Rz(θ_i) is one
product and one sum on the pair of slots of columns 0 and 1. A mimic joint uses
θ = multiplier · q_leader + offset and adds multiplier × its column to the leader's column.
"""

from __future__ import annotations

import itertools
import threading
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
import pinocchio as pin

if TYPE_CHECKING:
    from .chainkernel import Kernel

CHUNK = 8192
"""Most configurations per numpy pass: each numpy call costs ~1 µs and hands the GIL over, so long passes
win, up to where the threads' scratch (8 · scratch_rows bytes per row each) crowds the shared cache."""
Terms = tuple[tuple[tuple[int, float], ...], ...]
_PAIRS = {(0, 1): slice(0, 2), (1, 0): slice(1, None, -1), (0, 2): slice(0, 3, 2)}
_PAIRS |= {(2, 0): slice(2, None, -2), (1, 2): slice(1, 3), (2, 1): slice(2, 0, -1)}


class Step(NamedTuple):
    """One movable joint on the path to the frame."""

    prismatic: bool
    coordinate: int  # column of Q that drives it (the leader's, for a mimic joint)
    scaling: float  # θ = scaling · q + offset
    offset: float
    rotation: Terms  # K_i (see _terms)
    translation: tuple[tuple[int, float], ...]  # nonzero entries of t_i: (row, value)
    accumulate: bool  # an earlier step already wrote this Jacobian column


class Plan:
    """The chain's work on M (4, 3, n): slots 0-2 the columns of S up to sign, slot 3 p. M starts as
    ``start`` (the first step's K and t folded in); ``moves``, one per step: (matrix (4, 4): M' = matrix ·
    M into the other buffer, K_i and t_i in one product, or None when K_i is a signed permutation and
    t_i = 0: slots renamed; pair: M[pair] = the slots of columns 0 and 1, ordered so that Rz is
    (a c + b s, b c − a s); axis: slot and sign of column 2). Last, M' = ``matrix`` · M holds C_IF's
    columns and p_f in order (or, None: the columns are ``slots`` × ``signs``)."""

    def __init__(self, steps: tuple[Step, ...], rotation: Terms, translation: tuple) -> None:
        slots: tuple[int, ...] = (0, 1, 2)
        signs: tuple[float, ...] = (1.0, 1.0, 1.0)

        def rename(terms: Terms, moved: tuple, move: bool = False) -> np.ndarray | None:
            nonlocal slots, signs
            if not move and all(len(c) == 1 and abs(c[0][1]) == 1.0 for c in terms):
                slots = tuple(slots[c[0][0]] for c in terms)
                signs = tuple(signs[c[0][0]] * c[0][1] for c in terms)
                return None
            A = np.eye(4)  # row 3: p' = p + Σ value · M[slot]
            A[:3, :3] = 0.0
            for (k, column), row in itertools.product(enumerate(terms), range(3)):
                A[k, slots[row]] += sum(v * signs[row] for m, v in column if m == row)
            for slot, value in moved:
                A[3, slot] += value
            slots, signs = (0, 1, 2), (1.0, 1.0, 1.0)
            return A

        def shift(terms: tuple) -> tuple:
            return tuple((slots[m], v * signs[m]) for m, v in terms)

        self.moves: list[tuple] = []
        for i, step in enumerate(steps):
            if i == 0:  # S = I and p = 0 until the first joint moves: K_1 and t_1 are constants
                self.origin, start = constant_terms(step.rotation, step.translation)
                matrix = None
            else:
                matrix = rename(step.rotation, shift(step.translation), bool(step.translation))
            a, b = (slots[0], slots[1]) if signs[0] == signs[1] else (slots[1], slots[0])
            self.moves.append((matrix, _PAIRS[a, b], (slots[2], signs[2])))
        if steps:  # no product for a signed permutation and no shift (C_IF's columns: slots × signs)
            self.matrix = rename(rotation, shift(translation), bool(translation))
        else:
            (self.origin, start), self.matrix = constant_terms(rotation, translation), None
        self.slots, self.signs = slots, signs
        self.start = np.vstack([start.T, self.origin.T])[:, :, None]  # slot k: column k; slot 3: p
        self.calls = 21 + sum(4 + (m[0] is not None) for m in self.moves)  # cos/sin, Rz, z_i, p_i, T


def constant_terms(rotation: Terms, translation: tuple) -> tuple[np.ndarray, np.ndarray]:
    """(t (3, 1), K (3, 3)) from their nonzero entries."""
    p, K = np.zeros((3, 1)), np.zeros((3, 3))
    for k, column in enumerate(rotation):
        K[[m for m, _ in column], k] = [value for _, value in column]
    p[[m for m, _ in translation], 0] = [value for _, value in translation]
    return p, K


class Chain:
    """The compiled chain: its steps, the frame placement after the last one (C_IF = S_last · rotation),
    the zero Jacobian columns, its :class:`Plan` and its numpy calls per chunk (pose; Jacobian)."""

    __slots__ = ("columns", "dof", "jacobian_calls", "kernel", "plan", "pose_calls",
                 "rotation", "steps", "translation", "unused")  # fmt: skip

    def __init__(self, steps: tuple[Step, ...], rotation: Terms, translation: tuple, dof: int) -> None:
        self.steps, self.rotation, self.translation, self.dof = steps, rotation, translation, dof
        self.plan = Plan(steps, rotation, translation)
        self.pose_calls = self.plan.calls + sum(4 for s in steps if s.scaling != 1.0 or s.offset != 0.0)
        self.jacobian_calls = 4 + sum(3 if s.prismatic else 12 for s in steps)
        self.unused = tuple(k for k in range(dof) if k not in {s.coordinate for s in steps})
        first = steps[0].coordinate if steps else 0  # revolute steps filling a slice of columns, one each:
        plain = all(  # their Jacobian columns are computed at once
            not s.prismatic and s.scaling == 1.0 and s.offset == 0.0 and s.coordinate == first + i
            for i, s in enumerate(steps)
        )
        self.columns = slice(first, first + len(steps)) if plain and steps else None
        self.kernel: Kernel | None = None  # the C chain, set by kinengine.kinematics.compiler when built


def _column(M: np.ndarray, slot: int, sign: float, out: np.ndarray | None = None) -> np.ndarray:
    """sign · M[slot] as an array of its own (into ``out`` if given)."""
    out = np.empty_like(M[slot]) if out is None else out
    np.negative(M[slot], out=out) if sign < 0 else np.copyto(out, M[slot])
    return out


def _cross(a: np.ndarray, b: np.ndarray, out: np.ndarray, temp: np.ndarray | None = None) -> None:
    """out[0:3] = a × b for (3, ...) arrays (out rows may be strided views; temp: two scratch rows)."""
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        t = (None, None) if temp is None else temp
        np.subtract(np.multiply(a[j], b[k], out=t[0]), np.multiply(a[k], b[j], out=t[1]), out=out[i])


def _cos_sin(q: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """cos q and sin q from t = tan(q/2): cos = (1 − t²)/(1 + t²), sin = 2t/(1 + t²) (one tan and cheap
    passes, within 2.3e-16 of numpy's cos and sin). ``rows`` (4 k, n) end as cos, cos, −sin, sin."""
    k = len(q)
    cos, cos2, d, sin = rows[:k], rows[k : 2 * k], rows[2 * k : 3 * k], rows[3 * k :]
    t = np.tan(np.multiply(q, 0.5, out=sin), out=sin)
    tt = np.multiply(t, t, out=cos)
    np.reciprocal(np.add(tt, 1.0, out=d), out=d)
    np.multiply(np.subtract(1.0, tt, out=cos), d, out=cos)
    np.multiply(np.add(t, t, out=sin), d, out=sin)
    np.copyto(cos2, cos)
    np.negative(sin, out=d)
    return cos, sin


class Outputs(NamedTuple):
    """What a batch evaluation fills, for rows 0..n of Q: pose (n, 4, 4) and / or jac (n, 6, dof) in
    ``reference``, or the analytic Jacobian: (pmap, out (n, m, dof), distances (n, parts)) in
    "local_world_aligned". None: not asked."""

    pose: np.ndarray | None
    jac: np.ndarray | None
    reference: pin.ReferenceFrame | None
    analytic: tuple | None = None

    def rows(self, a: int, b: int) -> Outputs:
        """The outputs of rows a..b (views)."""
        pose, jac, reference, analytic = self
        cut = None if analytic is None else (analytic[0], analytic[1][a:b], analytic[2][a:b])
        return Outputs(None if pose is None else pose[a:b], None if jac is None else jac[a:b], reference, cut)


def evaluate_chain(chain: Chain, qT: np.ndarray, outputs: Outputs) -> None:
    """Fill ``outputs`` for the chunk qT (dof, n), which may be a strided view (``Q[a:b].T``)."""
    pose, jac, reference, analytic = outputs
    dof, n, m, plan = chain.dof, qT.shape[1], len(chain.steps), chain.plan
    jacobian = jac is not None or analytic is not None
    direct = analytic is None and reference != pin.LOCAL  # Jacobian columns straight into jac's view
    # this thread's scratch rows (see scratch_rows): cos, cos, −sin, sin (later the Jacobian's products) |
    # the buffers M, M' (Rz's product goes to the one not holding M) | z_i, p_i stacked (3, m, n) |
    # J (6, dof, n) unless direct
    head, body = 4 * max(dof, 2), 24
    memory = _rows(n, scratch_rows(chain, jacobian, direct))
    _cos_sin(qT, memory[: 4 * dof])  # of every coordinate
    turns = memory[: 4 * dof].reshape(2, 2, dof, n)  # [[cos, cos], [−sin, sin]]
    buffers = list(memory[head : head + 24].reshape(2, 4, 3 * n))  # M, M' (4, 3 n) for the products
    stacked = jacobian and chain.columns is not None  # z_i, p_i stacked for the Jacobian
    if stacked:
        Z, P = ZP = memory[head + body : head + body + 6 * m].reshape(2, 3, m, n)
    M = buffers[0].reshape(4, 3, n)
    M[...] = plan.start
    p, held = M[3], True  # held: p is M[3]
    joints = []
    for i, (step, move) in enumerate(zip(chain.steps, plan.moves, strict=True)):
        matrix, pair, (slot, sign) = move
        if matrix is not None:  # K_i and t_i in one product
            M = _product(matrix, M, p, held, buffers)
            p, held = M[3], True
        plain = step.scaling == 1.0 and step.offset == 0.0
        theta = qT[step.coordinate] if plain else qT[step.coordinate] * step.scaling + step.offset
        if step.prismatic:
            p, held = (np.add if sign > 0 else np.subtract)(p, M[slot] * theta), False
        else:  # Rz(θ) on M[pair] = (a, b) in place: (a c + b s, b c − a s)
            c, s = (0.0, 0.0) if plain else (np.cos(theta), np.sin(theta))
            turn = turns[:, :, step.coordinate] if plain else np.array([[c, c], [-s, s]])
            product = buffers[1].reshape(2, 2, 3, n)  # M' is free: M lives in buffers[0]
            np.multiply(M[pair][None], turn[:, :, None], out=product)
            np.add(product[0], product[1, ::-1], out=M[pair])
        if stacked and held and (slot, sign) == (2, 1.0):  # axis in slot 2, p in slot 3: one copy
            ZP[:, :, i] = M[2:]
        elif stacked:
            _column(M, slot, sign, Z[:, i])
            P[:, i] = p
        elif jacobian:
            joints.append((step, _column(M, slot, sign), p.copy() if held else p))
    if plan.matrix is not None:
        M = _product(plan.matrix, M, p, held, buffers)
        p = M[3]
    p_f = p.copy() if analytic is not None and stacked else p  # P is overwritten below
    if pose is not None and plan.matrix is not None:
        pose[:, :3] = M.transpose(2, 1, 0)  # M[k, r] = T[r, k]; one call: calls cost more than bytes
    elif pose is not None:
        for k, (slot, sign) in enumerate(zip(plan.slots, plan.signs, strict=True)):
            _column(M, slot, sign, pose[:, :3, k].T)
        pose[:, :3, 3] = p_f.T
    if pose is not None:
        pose[:, 3] = (0.0, 0.0, 0.0, 1.0)
    if not jacobian:
        return
    target = jac.transpose(1, 2, 0) if direct else memory[head + body + 6 * m :].reshape(6, dof, n)  # type: ignore[union-attr]
    for k in chain.unused:
        target[:, k] = 0.0
    if stacked:
        cols = target[:, chain.columns]  # (6, m, n)
        temp = memory[: 2 * m].reshape(2, m, n)  # m <= dof: within cos and sin, done with
        a, b = (P, Z) if reference == pin.WORLD else (Z, np.subtract(p_f[:, None], P, out=P))  # p_f − p_i
        _cross(a, b, cols, temp)
        cols[3:] = Z
    else:
        _columns(joints, p_f, reference, target)
    if direct:
        return
    R_f = [_column(M, slot, sign) for slot, sign in zip(plan.slots, plan.signs, strict=True)]
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
        # row-major entries of C_IF and p, as (n,) views (a position the chain never moves is (3, 1))
        C = [R_f[j][i] for i in range(3) for j in range(3)]
        p_rows = [np.broadcast_to(p_f[i], (n,)) for i in range(3)]
        for k, distance in enumerate(pmap.fill_columns(p_rows, C, target, JA)):
            distances[:, k] = distance
        out[...] = JA.transpose(2, 0, 1)


def _product(matrix: np.ndarray, M: np.ndarray, p: np.ndarray, held: bool, buffers: list) -> np.ndarray:
    """matrix (4, 4) · M (p into slot 3 first unless ``held``) into the buffer not holding M; they swap."""
    if not held:
        M[3] = p
    buffers.reverse()
    return np.matmul(matrix, buffers[1], out=buffers[0]).reshape(M.shape)


def _columns(joints: list, p_f: np.ndarray, reference: pin.ReferenceFrame | None, target: np.ndarray) -> None:
    """The Jacobian column of each step in turn (prismatic joints; mimic joints scaled and accumulated)."""
    for step, z, p_i in joints:
        rows = target[:, step.coordinate]  # (6, n)
        dst = np.empty_like(rows) if step.accumulate or step.scaling != 1.0 else rows
        if step.prismatic:
            dst[:3], dst[3:] = z, 0.0
        else:
            _cross(*((p_i, z) if reference == pin.WORLD else (z, p_f - p_i)), dst)
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
    head = 4 * max(chain.dof, 2) + 24  # cos/sin | M, M' (Rz's product in the one not holding M)
    return head + (6 * len(chain.steps) + (0 if direct else 6 * chain.dof) if jacobian else 0)


def _rows(n: int, rows: int) -> np.ndarray:
    """This thread's reusable scratch as (rows, n): one allocation per thread (grown when needed), not
    one per chunk (which page-faults through large batches)."""
    memory = getattr(_LOCAL, "memory", None)
    if memory is None or memory.size < rows * n:
        memory = _LOCAL.memory = np.empty(rows * n)
    return memory[: rows * n].reshape(rows, n)


__all__ = ["CHUNK", "Chain", "Outputs", "Step", "Terms", "constant_terms", "evaluate_chain", "scratch_rows"]
