"""The fast path of :meth:`Task.update(q[, qdot]) <kinengine.control.task.Task.update>` for the common
task: one absolute frame, all rows, Cartesian position and one rotation parameterization.

One closure does the whole update with few numpy calls: the input checks, one Pinocchio call (without q̇
computeFrameJacobian, which also places the frame; with q̇ the joint Jacobians and their rates of
:func:`~kinengine.control.task_frame.joint_jacobians`, then the frame placement), χ_R, its distance to the
singular set and E_R(χ) by the parameterization's :meth:`chart` (see :func:`rotation_function`), then
J_e0 and J_A = E·J_e0 by *one* product of the stacked (6 + 3 + m, 6) matrix [X; E·X] with J_e0 (X = I) or
with J_w (X = [[I, −[p]x], [0, I]], E·X = [[I, −[p]x], [0, E_R]]) into one buffer whose rows are the Task's
``jacobian`` and ``analytic_jacobian``. With q̇: [twist; χ̇] by one product and [J̇_e0; J̇_A] by two (see
:func:`fast_update`).

It computes what :class:`~kinengine.control.task_frame.FrameBlock` computes, with the same scalar
formulas and the same continuity rule: the same floats for χ, the distances and the pose; J_e0, J_A and
the rates agree to rounding (fewer, larger products). For a pose within the threshold of a singular set, or at
gimbal lock, it writes nothing and returns False: the general path then runs (NaN rows or the error,
exactly as before). [X; E·X], χ, the distances and the pose share one Task buffer, in this order, so
that one struct call (native byte order: the buffer is a float64 ndarray of this process) writes every
entry that changes (see :func:`fast_update`).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable
from operator import itemgetter
from typing import Any

import numpy as np
import pinocchio as pin

from ..parameterizations.base import RotationParameterization
from .continuity import Rule, continuity_rule
from .task_frame import FrameBlock, FrameKinematics, joint_jacobians

Write = Callable[[list[list[float]], list[float], float, "list[float] | None", bool], "list[float] | None"]
"""(C_IF's rows, p, threshold, previous χ or None, world) -> χ (3 + m), written with everything else into the
Task's buffer (see :func:`fast_update`), or None (not a regular pose: nothing written). ``world``: [X; E·X]
will multiply the joint Jacobians J_w at I's origin (X = [[I, −[p]x], [0, I]]); else J_e0 (X = I)."""
_INF = math.inf
_ORIGIN = (0.0, 0.0, 0.0)


def rotation_function(
    param: RotationParameterization, rule: Rule, pack: Callable[..., None], buffer: Any
) -> Write:
    """χ_R (continuous w.r.t. the previous χ through ``rule``), its distance and E_R for a regular pose,
    written by one ``pack(buffer, offset, ...)`` in the order of :func:`fast_update`'s buffer: columns
    3-5 of [X; E·X] (column-major), χ, the distances (inf for Cartesian), rows 0-2 of the pose."""
    chart, distance_of, E_of = param.chart, param._distance, param._E
    m = param.size
    by_columns = itemgetter(*(3 * r + c for c in range(3) for r in range(m)))  # E_R (m, 3) column-major

    def generic(
        C: list[list[float]], p: list[float], threshold: float, previous: list[float] | None, world: bool
    ) -> list[float] | None:
        (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = C
        found = chart(c00, c01, c02, c10, c11, c12, c20, c21, c22)
        if found is None:
            return None
        chi, distance, entries = found
        if previous is not None:
            nearest = rule(chi, previous[3 : 3 + m])
            if nearest != chi:  # another representative: its own distance and E
                chi, distance, entries = nearest, distance_of(math, *nearest), E_of(math, *nearest)
        if not distance >= threshold or distance == 0.0:
            return None
        E = by_columns(entries)
        px, py, pz = p
        ox, oy, oz = p if world else _ORIGIN  # X moves the twist from I's origin to p, or is the identity
        # fmt: off
        pack(buffer, 0, -oz, oy, 1.0, -oz, oy, *E[:m], oz, -ox, 1.0, oz, -ox, *E[m : 2 * m],
             -oy, ox, 1.0, -oy, ox, *E[2 * m :], px, py, pz, *chi, _INF, distance,
             c00, c01, c02, px, c10, c11, c12, py, c20, c21, c22, pz)
        # fmt: on
        return [px, py, pz, *chi]

    return generic


def fast_update(
    a: FrameKinematics,
    block: FrameBlock,
    stacked: np.ndarray,
    stacked_dot: np.ndarray,
    rates: np.ndarray,
    flat: np.ndarray,
) -> Callable[[np.ndarray, np.ndarray | None, bool, float, bool], bool]:
    """``update(q, qdot, check, threshold, continuous) -> bool``: True when it wrote every attribute (the
    rates only with q̇: without, the Task keeps them NaN); False, having written nothing, where the general
    path must run.

    ``stacked`` (6 + 3 + m, dof) C-contiguous: rows 0-5 are the block's J_e0, the rest its J_A;
    ``stacked_dot`` alike [J̇_e0; J̇_A] and ``rates`` (6 + 3 + m,) [twist; χ̇] = stacked·q̇. ``flat`` holds
    [X; E·X] (9 + m, 6) column-major, χ (3 + m), the two distances and the pose (4, 4): one struct call
    writes all but their constants (columns 0-2 of [X; E·X], the pose's last row).

    Rates: [J̇_e0; J̇_A] = [X; E·X]·J̇_w + T·J_w with T = [Ẋ; Ė·X + E·Ẋ] = [[0, −[v]x]; 0; [0, −[v]x];
    [0, Ė_R]] (Ė = blockdiag(0, Ė_R), Ẋ = [[0, −[v]x], [0, 0]], v the origin's velocity): the terms of
    the general path's J̇ = X·J̇_w + Ẋ·J_w and J̇_A = E·J̇ + Ė·J, added in the same order.
    """
    model, data, fid, coords = a.model, a.data, a.fid, a.coords
    R, p = a.R, a.p  # live views of the frame's placement in the Task's Data
    rotation = block.pmap.rotation
    assert rotation is not None
    m = rotation.size
    rows = 9 + m  # [X; E·X], X = [[I, −[p]x], [0, I]], E·X = [[I, −[p]x], [0, E_R]]
    S = flat[: 6 * rows].reshape(6, rows).T
    S[:6] = np.eye(6)
    S[6:9, :3] = np.eye(3)
    # column 3: −pz, py, 1, −pz, py in rows 1, 2, 3, 7, 8; column 4: pz, −px, 1, pz, −px in rows 0, 2, 4,
    # 6, 8; column 5: −py, px, 1, −py, px in rows 0, 1, 5, 6, 7; E_R's columns in rows 9-
    places = [rows * c + r for c, used in ((3, (1, 2, 3, 7, 8)), (4, (0, 2, 4, 6, 8)), (5, (0, 1, 5, 6, 7)))
              for r in (*used, *range(9, rows))]  # fmt: skip
    chi_at = 6 * rows
    places += list(range(chi_at, chi_at + 3 + m + 2 + 12))  # χ, the distances, the pose's rows 0-2
    assert places[-1] == flat.size - 5
    pack, start = _packer(places)
    buffer: Any = flat[start:]  # an ndarray is a buffer (numpy declares __buffer__ for Python >= 3.12)
    write = rotation_function(rotation, continuity_rule(rotation.name), pack, buffer)
    # T (rows, 6) column-major: −[v]x in rows 0-2 and 6-8 of columns 3-5 (as X's −[p]x), Ė_R in rows 9-
    T = np.zeros((6, rows)).T
    pack_T, start_T = _packer(
        [k for k in places if k < chi_at and k not in (3 * rows + 3, 4 * rows + 4, 5 * rows + 5)]
    )
    T_buffer: Any = T.T.reshape(6 * rows)[start_T:]
    E_dot, by_columns = rotation._E_dot, itemgetter(*(3 * r + c for c in range(3) for r in range(m)))
    Jw, dJw = data.J.reshape(6, model.nv), data.dJ.reshape(6, model.nv)
    zero = np.zeros(model.nv)
    qp, vp = np.empty(model.nq), np.empty(model.nv)
    identity, has_offset = coords.identity, coords.has_offset
    fold = None if identity else coords.matrix
    offset = coords.offset if has_offset else None
    if a.mask is not None and fold is not None:
        fold = a.mask[:, None] * fold  # J_w·diag(mask)·M in one product
    mask = a.mask if fold is None else None
    n = stacked.shape[1]
    G, dG, tmp = np.empty((6, n)), np.empty((6, n)), np.empty((rows, n))
    product, product_T, product_rates = S.dot, T.dot, stacked.dot
    twist = rates[:6]
    place, frame_jacobian, LWA, nv = (
        pin.updateFramePlacement,
        pin.computeFrameJacobian,
        pin.LOCAL_WORLD_ALIGNED,
        model.nv,
    )
    ready, check_q = coords.ready, coords.check
    fold_q = coords.matrix

    def update(
        q: np.ndarray, qdot: np.ndarray | None, check: bool, threshold: float, continuous: bool
    ) -> bool:
        if check and not ready(q):
            q = check_q(q, allow_batch=False)
        v = zero
        if qdot is not None:
            if check and not ready(qdot):
                qdot = check_q(qdot, name="qdot", allow_batch=False)
            v = qdot
        if not identity:
            np.dot(fold_q, q, out=qp)
            if offset is not None:
                np.add(qp, offset, out=qp)
            q = qp
            if qdot is not None:
                np.dot(fold_q, qdot, out=vp)
                v = vp
        if qdot is None and nv:  # J_e0 from Pinocchio (it places the frame too): S = [I; blockdiag(I, E_R)]
            J = frame_jacobian(model, data, q, fid, LWA).reshape(6, nv)  # eigenpy: (6,) for nv = 1
            chi = write(R.tolist(), p.tolist(), threshold, block.previous, False)
        else:  # J_w and J̇_w at I's origin: S = [X; E·X]
            joint_jacobians(model, data, q, v, zero)
            place(model, data, fid)
            J = Jw
            chi = write(R.tolist(), p.tolist(), threshold, block.previous, True)
        if chi is None:
            return False
        dJ = dJw
        if fold is not None:
            Jw_folded, J, dJ = J, G, dG
            Jw_folded.dot(fold, G)
        elif mask is not None:
            np.multiply(J, mask, out=G)
            J, dJ = G, dG
        product(J, stacked)
        if continuous:
            block.previous = chi
        if qdot is None:
            return True
        product_rates(qdot, rates)
        vx, vy, vz, wx, wy, wz = twist.tolist()
        Ed = by_columns(E_dot(math, chi[3:], (wx, wy, wz)))
        # fmt: off
        pack_T(T_buffer, 0, -vz, vy, -vz, vy, *Ed[:m], vz, -vx, vz, -vx, *Ed[m : 2 * m],
               -vy, vx, -vy, vx, *Ed[2 * m :])
        # fmt: on
        if fold is not None:
            dJw.dot(fold, dG)
        elif mask is not None:
            np.multiply(dJw, mask, out=dG)
        product(dJ, stacked_dot)
        product_T(J, tmp)
        np.add(stacked_dot, tmp, out=stacked_dot)
        return True

    return update


def _packer(places: list[int]) -> tuple[Callable[..., None], int]:
    """A struct ``pack_into`` writing doubles at these increasing indices of a float64 buffer (from the first
    one on, given as the second value: pack into ``buffer[first:]``); struct writes zeros into pad bytes, so
    every entry skipped in between must be a zero."""
    fmt, last = "=", places[0] - 1  # native byte order: numpy's float64
    for k in places:
        fmt += f"{8 * (k - last - 1)}xd"
        last = k
    return struct.Struct(fmt).pack_into, places[0]
