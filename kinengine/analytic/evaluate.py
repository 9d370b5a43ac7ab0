"""Analytic Jacobians J_A = E(χ)·J_e0 on a robot's kinematics: one configuration (J_e0 and T_IF from
Pinocchio, χ and E by scalar math) or a batch (numpy next to the chain; small batches row by row). q is
checked by the caller."""

from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..kinematics import batch, relative
from ..kinematics.engine import Kinematics
from ..kinematics.handle import FrameHandle
from .pose_map import PoseMap

LWA = pin.LOCAL_WORLD_ALIGNED
ANALYTIC_CALLS = 100
"""How many numpy calls χ, E and E·J_e0 take over a chunk, about (a row of the single-call loop costs about
twice one of Pinocchio's pose and Jacobian loop)."""


def analytic_single(
    kin: Kinematics,
    q: np.ndarray,
    fid: int,
    pmap: PoseMap,
    threshold: float,
    nan: bool = False,
    row: int | None = None,
) -> npt.NDArray[np.float64]:
    """J_A (m, dof) at one checked q, with this thread's views of the frame's placement and its unchecked
    handle (which writes and folds only the mimic joints that move the frame). ``nan``: NaN rows for a
    parameterization within ``threshold`` of its singular set instead of the error; ``row`` (a batch row)
    only goes into the error message."""
    (C, p), jacobian, pose = kin.per_thread(("analytic", fid), lambda: _single_path(kin, fid))
    J = jacobian(q, "local_world_aligned")  # places the frame too (but a 0-dof Jacobian is zeros)
    if kin.dof == 0:
        pose(q)
    return pmap.jacobian_single(C.tolist(), p.tolist(), J, threshold, row, nan)


def analytic_function(
    kin: Kinematics, fid: int, pmap: PoseMap, threshold: float
) -> Callable[[np.ndarray], npt.NDArray[np.float64]]:
    """``J_A(q)`` for one frame and fixed options at a checked q (RepresentationSingularityError at singular
    poses): for E = blockdiag(I or none, E_R), the rotation's :meth:`chart` written into this thread's E
    (each thread binds its own Data views, unchecked frame handle and E on its first call); otherwise, and
    where the chart has no answer, the general single path."""
    rotation = pmap.rotation
    if kin.dof == 0 or rotation is None or pmap.rows is not None or pmap.formula_parts != (rotation,):
        return lambda q: analytic_single(kin, q, fid, pmap, threshold)
    local = threading.local()
    jacobian_single, chart, layout = pmap.jacobian_single, rotation.chart, pmap.layout
    pack_into, offset = layout.pack_into, layout.offset

    def evaluate(q: np.ndarray) -> npt.NDArray[np.float64]:
        try:
            C, p, jacobian, E = local.path
        except AttributeError:  # this thread's first call
            (C, p), jacobian, _ = _single_path(kin, fid)
            E = np.frombuffer(bytearray(layout.template)).reshape(layout.shape)
            local.path = C, p, jacobian, E
        J = jacobian(q, "local_world_aligned")  # also places the frame: C and p show T_IF at q
        rows = C.tolist()
        (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = rows
        found = chart(c00, c01, c02, c10, c11, c12, c20, c21, c22)
        if found is None or not found[1] >= threshold:  # (chart gives None at distance 0)
            return jacobian_single(rows, p.tolist(), J, threshold)
        pack_into(E, offset, *found[2])
        return E.dot(J)

    return evaluate


def _single_path(kin: Kinematics, fid: int) -> tuple[tuple[np.ndarray, np.ndarray], Callable, Callable]:
    """((C_IF, p) views, J_e0(q, reference), T_IF(q)) of the frame's unchecked handle in this thread."""
    name = next(n for n, i in kin.frame_ids.items() if i == fid)
    handle = FrameHandle(kin, name, check_inputs=False)
    return handle.placement(), handle.jacobian, handle.pose  # views of the Data the handle's calls place


def analytic_batch(
    kin: Kinematics, Q: np.ndarray, fid: int, pmap: PoseMap, threshold: float, nan: bool = False
) -> npt.NDArray[np.float64]:
    """J_A = E(χ)·J_e0 for every row of a checked Q (N, dof) -> (N, m, dof).

    Small batches take the single-call path row by row; larger ones evaluate χ, E and E·J_e0 with numpy
    over each chunk, next to the chain. RepresentationSingularityError names the first row within
    ``threshold`` of a singular set; with ``nan`` that row's rows of the singular parameterization are
    NaN instead (every other row exact).
    """
    n = len(Q)
    out = np.empty((n, pmap.size, kin.dof))
    chain = (
        batch.numpy_chain(kin, fid, n, True, ANALYTIC_CALLS, row_cost=2, native=False)
        if kin.dof
        else batch.compiled_chain(kin, fid)
    )
    if chain is None:
        for i, qi in enumerate(Q):
            out[i] = analytic_single(kin, qi, fid, pmap, threshold, nan, i)
        return out
    distances = np.empty((n, len(pmap.parts)))
    batch.run_chain(chain, Q, None, None, pin.LOCAL_WORLD_ALIGNED, (pmap, out, distances))
    pose, jacobian = (lambda row: kin.pose(Q[row], fid)), (lambda row: kin.jacobian(Q[row], fid, LWA))
    pmap.singular_rows(distances, threshold, out, nan, pose, jacobian)
    return out


def analytic_relative(
    kin: Kinematics, q: np.ndarray, fa: int, fb: int, pmap: PoseMap, threshold: float, nan: bool = False
) -> npt.NDArray[np.float64]:
    """J_A of frame A relative to frame B: E(χ(T_BA))·J_rel with J_rel the relative Jacobian expressed in B
    (see :mod:`kinengine.kinematics.relative`); q (dof,) -> (m, dof), q (N, dof) -> (N, m, dof)."""
    T = relative.relative_pose(kin, q, fa, fb)
    J = relative.relative_jacobian(kin, q, fa, fb, fb)
    if q.ndim == 1:
        return pmap.jacobian(T, J, threshold, nan)
    n = len(q)
    out = np.empty((pmap.size, kin.dof, n))
    C = [np.ascontiguousarray(T[:, i, j]) for i in range(3) for j in range(3)]
    p = [np.ascontiguousarray(T[:, i, 3]) for i in range(3)]
    distances = np.empty((n, len(pmap.parts)))
    for k, distance in enumerate(pmap.fill_columns(p, C, np.ascontiguousarray(J.transpose(1, 2, 0)), out)):
        distances[:, k] = distance
    out = np.ascontiguousarray(out.transpose(2, 0, 1))
    pmap.singular_rows(distances, threshold, out, nan, lambda row: T[row], lambda row: J[row])
    return out


__all__ = ["ANALYTIC_CALLS", "analytic_batch", "analytic_function", "analytic_relative", "analytic_single"]
