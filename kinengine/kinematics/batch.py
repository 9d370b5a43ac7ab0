"""Frame poses and geometric Jacobians for a batch of configurations Q (N, dof), vectorized over N.

>>> T, J = evaluate(kin, Q, fid, pin.LOCAL_WORLD_ALIGNED)       # (N, 4, 4), (N, 6, dof); Q checked

Same conventions as :mod:`kinengine.kinematics.engine`: T_IF in the root link frame I [m], J rows
[linear; angular] in "local_world_aligned", "local" or "world", columns in ``joint_names`` order.

How: the chain from the root to the frame is compiled once (:func:`compiled_chain`) and evaluated by
:mod:`kinengine.kinematics.chain` over chunks of configurations (:func:`chunk_rows`: long numpy passes,
each thread's scratch reused from chunk to chunk and call to call) on a persistent pool of one thread
per core this process may use (WORKERS, from ``os.sched_getaffinity``; ``workers=`` caps it; numpy
releases the GIL in its loops; a forked child makes its own pool). Small batches loop over Pinocchio
instead, which is faster there (see ``CALLS_PER_CONFIGURATION``). ``benchmarks/batch_throughput.py``
measures configs/s, page faults and memory against the inline Pinocchio loop.
"""

from __future__ import annotations

import itertools
import math
import os
import threading
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from ..errors import OptionError
from .chain import CHUNK, Chain, Step, Terms, evaluate_chain, scratch_rows
from .engine import Kinematics

if TYPE_CHECKING:  # imported when the first pool starts: concurrent.futures (and logging) cost ~5 ms
    from concurrent.futures import ThreadPoolExecutor

MIN_CHUNK = 4096
"""Fewest rows per chunk (unless CHUNK is smaller): numpy's ~1 µs per call, and the GIL hand-over at
every call, dominate shorter ones (ABB IRB 120, 10k rows on 2 threads: chunks of 1024 1.3, 2048 1.7,
4096 2.2 M configs/s)."""
MEMORY_SHARE = 0.1
"""Chunks shrink (down to MIN_CHUNK) until the threads' scratch is within this share of the outputs, so a
call's memory stays within its outputs + 10 %. (Longer chunks are faster: 100k rows on 2 threads, median
M configs/s at 0.1, 0.2, 0.3 measured interleaved: Kinova 6.48, 6.90, 7.17; ABB IRB 120 5.83, 6.19, 6.50.)"""
ROUNDING = 1e-15
"""Compiled constants within this (relative) of 0 or ±1 are taken as exactly that (see _snap)."""
MIN_PER_WORKER = 4096
"""Batches are split over several threads only when each gets at least this many rows."""
WORKERS = max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1)
"""Threads per batch (this one included): the cores this process may use."""
CALLS_PER_CONFIGURATION = 3
"""One configuration in Pinocchio's loop costs about as much as this many numpy calls over a chunk
(measured on the ABB IRB 120, UR5 and Panda: 1.75 µs against 0.55 µs): a chain that takes c numpy
calls per chunk loops over Pinocchio for batches smaller than c / this."""
MIN_CALLS = 12
"""The fewest numpy calls of any chain (a pose of a frame fixed to the root)."""
_LOCK = threading.Lock()
_POOL: ThreadPoolExecutor | None = None
_POOL_SIZE = 0


def _pool(threads: int) -> ThreadPoolExecutor:
    """The shared pool, with at least ``threads`` threads (WORKERS − 1 unless asked for more)."""
    global _POOL, _POOL_SIZE
    from concurrent.futures import ThreadPoolExecutor

    with _LOCK:
        if _POOL is None or threads > _POOL_SIZE:
            old, _POOL_SIZE = _POOL, max(threads, WORKERS - 1, 1)
            _POOL = ThreadPoolExecutor(_POOL_SIZE, thread_name_prefix="kinengine-batch")
            if old is not None:
                old.shutdown(wait=False)
        return _POOL


def _forget_pool() -> None:
    """In a forked child: the parent's pool threads do not exist here, so start a new pool on demand."""
    global _POOL, _LOCK, _POOL_SIZE
    _POOL, _LOCK, _POOL_SIZE = None, threading.Lock(), 0


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_pool)


def run_chain(
    chain: Chain,
    Q: np.ndarray,
    pose: np.ndarray | None,
    jac: np.ndarray | None,
    reference: pin.ReferenceFrame | None,
    analytic: tuple | None = None,
    workers: int | None = None,
) -> None:
    """Evaluate Q in chunks of about chunk_rows rows, split evenly over up to ``workers`` (WORKERS)
    threads, each reusing its own scratch from chunk to chunk."""
    workers = max(1, min(WORKERS if workers is None else workers, len(Q) // MIN_PER_WORKER))
    chunk = chunk_rows(chain, len(Q), workers, pose is not None, jac is not None, analytic, reference)
    per = len(Q) / (workers * chunk)  # chunks per worker: rounded (2/3 to 3/2 × chunk rows), or up
    pieces = workers * max(1, math.ceil(per) if MIN_CHUNK < chunk < CHUNK else round(per))  # if memory binds
    chunks = list(itertools.pairwise(len(Q) * i // pieces for i in range(pieces + 1)))

    def work(part: list[tuple[int, int]]) -> None:
        for a, b in part:
            evaluate_chain(
                chain,
                Q[a:b].T,  # a strided view: the chain reads its rows
                None if pose is None else pose[a:b],
                None if jac is None else jac[a:b],
                reference,
                None if analytic is None else (analytic[0], analytic[1][a:b], analytic[2][a:b]),
            )

    per = pieces // workers
    futures = []
    for i in range(per, pieces, per):
        try:  # after interpreter shutdown (an atexit handler) no pool starts or takes work: do it here
            futures.append(_pool(workers - 1).submit(work, chunks[i : i + per]))
        except RuntimeError:
            work(chunks[i : i + per])
    work(chunks[:per])  # the calling thread takes the first share
    for future in futures:
        future.result()


def chunk_rows(
    chain: Chain, n: int, workers: int, pose: bool, jac: bool, analytic: tuple | None, reference: object
) -> int:
    """Rows per chunk: CHUNK, or fewer (not below MIN_CHUNK) so that ``workers`` threads' scratch stays
    within MEMORY_SHARE of the outputs of the n rows."""
    direct = analytic is None and reference != pin.LOCAL
    out = (16 if pose else 0) + (6 * chain.dof if jac else 0)
    if analytic is not None:
        out += analytic[1].shape[1] * chain.dof + analytic[2].shape[1]
    scratch = scratch_rows(chain, jac or analytic is not None, direct)
    return min(CHUNK, max(MIN_CHUNK, int(MEMORY_SHARE * out * n / (workers * scratch))))


def _pinocchio_loop(
    kin: Kinematics,
    Q: np.ndarray,
    fid: int,
    pose: np.ndarray | None,
    jac: np.ndarray | None,
    reference: pin.ReferenceFrame | None,
) -> None:
    """The same outputs from a Python loop over Pinocchio (faster for small batches)."""
    model, data, coords = kin.model, kin.data(), kin.coordinates
    if kin.dof == 0 and jac is not None:
        jac[...] = 0.0
        jac = None  # nothing to fill (and Pinocchio 4.1's getFrameJacobian crashes when nv = 0)
    if pose is None and jac is None:
        return
    place_first = jac is None or (pose is not None and reference == pin.LOCAL)
    for i, qi in enumerate(coords.to_pinocchio(Q)):  # the single-q calls' algorithms: equal bit for bit
        if place_first:  # computeFrameJacobian leaves data.oMi stale in LOCAL: place the joints first
            pin.forwardKinematics(model, data, qi)
        if jac is not None:
            jac[i] = coords.fold(pin.computeFrameJacobian(model, data, qi, fid, reference).reshape(6, -1))
        if pose is not None:
            pose[i] = pin.updateFramePlacement(model, data, fid).homogeneous


def evaluate(
    kin: Kinematics,
    Q: np.ndarray,
    fid: int,
    reference: pin.ReferenceFrame | None,
    *,
    pose: bool = True,
    jacobian: bool = True,
    out: tuple[np.ndarray | None, np.ndarray | None] | None = None,
    workers: int | None = None,
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(T (N, 4, 4) or None, J (N, 6, dof) or None) for an already checked float64 Q (N, dof).

    ``reference`` is a pin.ReferenceFrame (unused when ``jacobian`` is False); ``out`` optional
    preallocated (T, J) arrays of those shapes, filled in place; ``workers`` caps the threads.
    """
    n = len(Q)
    T, J = out if out is not None else (None, None)
    if pose and T is None:
        T = np.empty((n, 4, 4))
    if jacobian and J is None:
        J = np.empty((n, 6, kin.dof))
    chain = numpy_chain(kin, fid, n, True)  # one choice for poses, Jacobians or both: equal bit for bit
    if chain is None:
        _pinocchio_loop(kin, Q, fid, T if pose else None, J if jacobian else None, reference)
    else:
        run_chain(chain, Q, T if pose else None, J if jacobian else None, reference, workers=workers)
    return (T if pose else None), (J if jacobian else None)


def _axis_basis(axis: np.ndarray) -> np.ndarray:
    """A rotation Q with Q e_z = axis (exact signed permutation when the axis is a coordinate axis)."""
    e = np.zeros(3)
    e[int(np.argmin(np.abs(axis)))] = 1.0
    x = e - (e @ axis) * axis
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(axis, x), axis])


def _snap(values: np.ndarray) -> np.ndarray:
    """Rounding residue (|v| <= ROUNDING of the largest entry, e.g. cos(π/2) = 6e-17 from an rpy of π/2)
    set to 0, and ±(1 − residue) to ±1: each costs a numpy pass per chunk for a change below 1e-15."""
    residue = ROUNDING * float(np.abs(values).max(initial=0.0))
    values = np.where(np.abs(values) <= residue, 0.0, values)
    return np.where(np.abs(np.abs(values) - 1.0) <= ROUNDING, np.sign(values), values)


def _terms(matrix: np.ndarray) -> Terms:
    """Nonzero entries of a 3x3 rotation, column by column: ((row, value), ...) per column (snapped)."""
    matrix = _snap(matrix)
    return tuple(tuple((m, float(matrix[m, k])) for m in range(3) if matrix[m, k] != 0.0) for k in range(3))


def _vector_terms(vector: np.ndarray) -> tuple[tuple[int, float], ...]:
    vector = _snap(vector) if np.abs(vector).max(initial=0.0) > 0 else vector
    return tuple((m, float(vector[m])) for m in range(3) if vector[m] != 0.0)


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
        placement, scale = model.jointPlacements[jid], float(coords.multiplier[k])
        K, t = _terms(Q_parent.T @ placement.rotation @ Q), _vector_terms(Q_parent.T @ placement.translation)
        prismatic, offset = joint.type == "prismatic", float(coords.offset[k])
        steps.append(Step(prismatic, coordinate, scale, offset, K, t, coordinate in seen))
        seen.add(coordinate)
        Q_parent = Q
    rotation = _terms(Q_parent.T @ frame.placement.rotation)
    translation = _vector_terms(Q_parent.T @ frame.placement.translation)
    return Chain(tuple(steps), rotation, translation, kin.dof)


def compiled_chain(kin: Kinematics, fid: int) -> Chain:
    """The chain to frame ``fid``, compiled once per robot and frame."""
    return kin.memoized(("batch chain", fid), lambda: _compile(kin, fid))


def checked_workers(workers: object) -> int | None:
    """``workers`` as a thread count >= 1 (None: WORKERS); OptionError otherwise."""
    if workers is None:
        return None
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or not 1 <= workers <= 1024:
        raise OptionError(f"`workers` must be None or a number of threads from 1 to 1024, got {workers!r}")
    return int(workers)


def checked_out(out: object, n: int, dof: int) -> tuple[np.ndarray, np.ndarray] | None:
    """``out`` as (T (n, 4, 4), J (n, 6, dof)) writable C-contiguous float64 arrays; OptionError otherwise."""
    if out is None:
        return None
    shapes = ((n, 4, 4), (n, 6, dof))
    if (
        not isinstance(out, tuple)
        or len(out) != 2
        or not all(
            type(a) is np.ndarray
            and a.dtype == np.float64
            and a.shape == shape
            and a.flags.c_contiguous
            and a.flags.writeable
            for a, shape in zip(out, shapes, strict=True)
        )
    ):
        raise OptionError(
            f"`out` must be a tuple (T, J) of writable C-contiguous float64 arrays of shapes "
            f"{shapes[0]} and {shapes[1]}"
        )
    if np.shares_memory(out[0], out[1]):
        raise OptionError("`out`'s T and J must not share memory")
    return out


def numpy_chain(
    kin: Kinematics, fid: int, n: int, jacobian: bool, extra: int = 0, row_cost: int = 1
) -> Chain | None:
    """The compiled chain if numpy over the batch is the faster path, else None (loop row by row).

    A loop row costs ``row_cost`` × CALLS_PER_CONFIGURATION numpy calls; the numpy path costs the
    chain's calls plus ``extra``.
    """
    budget = row_cost * n * CALLS_PER_CONFIGURATION
    if budget < MIN_CALLS + extra:  # the chain is not even looked up
        return None
    chain = compiled_chain(kin, fid)
    return chain if budget >= chain.pose_calls + (chain.jacobian_calls if jacobian else 0) + extra else None


__all__ = [
    "CALLS_PER_CONFIGURATION",
    "CHUNK",
    "MEMORY_SHARE",
    "MIN_CHUNK",
    "WORKERS",
    "checked_out",
    "checked_workers",
    "chunk_rows",
    "compiled_chain",
    "evaluate",
    "numpy_chain",
    "run_chain",
]
