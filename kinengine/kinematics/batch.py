"""Frame poses and geometric Jacobians for a batch of configurations Q (N, dof), vectorized over N.

>>> T, J = evaluate(kin, Q, fid, pin.LOCAL_WORLD_ALIGNED)       # (N, 4, 4), (N, 6, dof); Q checked

Same conventions as :mod:`kinengine.kinematics.engine`: T_IF in the root link frame I [m], J rows
[linear; angular] in "local_world_aligned", "local" or "world", columns in ``joint_names`` order.

How: the chain from the root to the frame is compiled once (:func:`compiled_chain`) and evaluated by
the C chain or :mod:`kinengine.kinematics.chain` over chunks of configurations (:func:`chunk_rows`) on a
persistent pool of one thread per core this process may use (WORKERS; ``workers=`` caps it; a forked
child makes its own pool). Small batches loop over Pinocchio instead, which is faster there. Outputs not
given by ``out=`` come from :func:`kinengine.kinematics.outputs.empty` (large ones reuse dropped memory).
"""

from __future__ import annotations

import itertools
import math
import os
import threading
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from ..errors import OptionError
from . import compiler, outputs
from .chain import CHUNK, Chain, Outputs, evaluate_chain, scratch_rows
from .compiler import REFERENCE_CODES, compiled_chain
from .engine import Kinematics

if TYPE_CHECKING:  # imported when the first pool starts: concurrent.futures (and logging) cost ~5 ms
    from concurrent.futures import ThreadPoolExecutor

MIN_CHUNK = 4096
"""Fewest rows per chunk (unless CHUNK is smaller): numpy's cost per call dominates shorter ones."""
MEMORY_SHARE = 0.1
"""Chunks shrink (down to MIN_CHUNK) until the threads' scratch is within this share of the outputs."""
MIN_PER_WORKER = 4096
"""Batches are split over several threads only when each gets at least this many rows."""
KERNEL_FROM = 2
"""Batches of this many rows or more run on the C chain when it is built (one row: as fast as Pinocchio)."""
KERNEL_MIN_PER_WORKER = 600
"""The same for the C chain, whose share costs ~60 µs to hand to a pool thread."""
WORKERS = max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1)
"""Threads per batch (this one included): the cores this process may use."""
CALLS_PER_CONFIGURATION = 3
"""One configuration in Pinocchio's loop costs about as much as this many numpy calls over a chunk: a
chain that takes c numpy calls per chunk loops over Pinocchio for batches smaller than c / this."""
MIN_CALLS = 12
"""The fewest numpy calls of any chain (a pose of a frame fixed to the root)."""
_LOCK = threading.Lock()
_POOL: ThreadPoolExecutor | None = None
_POOL_SIZE = 0
POOL_PREFIX = "kinengine-batch"


def _pool(threads: int) -> ThreadPoolExecutor:
    """The shared pool, with at least ``threads`` threads (WORKERS − 1 unless asked for more)."""
    global _POOL, _POOL_SIZE
    from concurrent.futures import ThreadPoolExecutor

    with _LOCK:
        if _POOL is None or threads > _POOL_SIZE:
            old, _POOL_SIZE = _POOL, max(threads, WORKERS - 1, 1)
            _POOL = ThreadPoolExecutor(_POOL_SIZE, thread_name_prefix=POOL_PREFIX)
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
    threads, each reusing its own scratch from chunk to chunk; or, with the C chain (not for analytic
    Jacobians), in one share per thread, written straight into the outputs."""
    if chain.kernel is not None and analytic is None and compiler.KERNEL is not None:
        workers = max(1, min(WORKERS if workers is None else workers, len(Q) // KERNEL_MIN_PER_WORKER))
        code = REFERENCE_CODES.get(reference, 0)  # reference None: no Jacobian asked
        run = chain.kernel.run
        # the C chain reads and writes aligned float64: other layouts go through an aligned copy
        Q = Q if Q.flags.aligned else Q.copy()
        T, J = (a if a is None or a.flags.aligned else np.empty_like(a) for a in (pose, jac))

        def share(a: int, b: int) -> None:
            run(Q[a:b], None if T is None else T[a:b], None if J is None else J[a:b], code)

        in_shares(_split(len(Q), workers), share, workers)
        for target, result in ((pose, T), (jac, J)):
            if target is not None and result is not target:
                target[...] = result
        return
    workers = max(1, min(WORKERS if workers is None else workers, len(Q) // MIN_PER_WORKER))
    chunk = chunk_rows(chain, len(Q), workers, pose is not None, jac is not None, analytic, reference)
    per = len(Q) / (workers * chunk)  # chunks per worker: rounded (2/3 to 3/2 × chunk rows), or up
    pieces = workers * max(1, math.ceil(per) if MIN_CHUNK < chunk < CHUNK else round(per))  # if memory binds
    writer = Outputs(pose, jac, reference, analytic)

    def evaluate_rows(a: int, b: int) -> None:
        evaluate_chain(chain, Q[a:b].T, writer.rows(a, b))  # Q[a:b].T: a strided view, its rows read

    in_shares(_split(len(Q), pieces), evaluate_rows, workers)


def _split(n: int, pieces: int) -> list[tuple[int, int]]:
    """Rows 0..n as ``pieces`` consecutive (start, stop) ranges of near-equal length."""
    return list(itertools.pairwise(n * i // pieces for i in range(pieces + 1)))


def in_shares(chunks: list[tuple[int, int]], work: Callable[[int, int], None], workers: int) -> None:
    """work(a, b) for every chunk, in ``workers`` equal shares of consecutive chunks: the calling thread
    takes the first, the pool the others. Called from a pool thread (work that shares its own work), all
    in that thread: waiting there for the pool could wait for itself."""

    def part(shares: list[tuple[int, int]]) -> None:
        for a, b in shares:
            work(a, b)

    if workers > 1 and threading.current_thread().name.startswith(POOL_PREFIX):
        workers = 1
    per = len(chunks) // workers
    futures = []
    for i in range(per, len(chunks), per):
        try:  # after interpreter shutdown (an atexit handler) no pool starts or takes work: do it here
            futures.append(_pool(workers - 1).submit(part, chunks[i : i + per]))
        except RuntimeError:
            part(chunks[i : i + per])
    part(chunks[:per])
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
    """The same outputs from a loop over the single-configuration calls (faster for small batches)."""
    pose1, jacobian1, both = kin.frame_calls(fid)
    for i, q in enumerate(Q):
        if pose is not None and jac is not None:
            pose[i], jac[i] = both(q, reference)
        elif pose is not None:
            pose[i] = pose1(q)
        elif jac is not None:
            jac[i] = jacobian1(q, reference)


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
    """(T (N, 4, 4) or None, J (N, 6, dof) or None) for an already checked float64 Q (N, dof); ``reference``
    a pin.ReferenceFrame (unused without ``jacobian``); ``out``: (T, J) filled in place; ``workers``: cap."""
    n = len(Q)
    T, J = out if out is not None else (None, None)
    if out is not None and any(a is not None and np.may_share_memory(Q, a) for a in out):
        Q = Q.copy()  # the outputs are written while Q is still read: read a copy
    missing = (((n, 4, 4), pose and T is None), ((n, 6, kin.dof), jacobian and J is None))
    new = iter(outputs.empty(*(shape for shape, needed in missing if needed)))
    T = (next(new) if T is None else T) if pose else None
    J = (next(new) if J is None else J) if jacobian else None
    chain = numpy_chain(kin, fid, n, True)  # one choice for poses, Jacobians or both: equal bit for bit
    if chain is None:
        _pinocchio_loop(kin, Q, fid, T, J, reference)
    else:
        run_chain(chain, Q, T, J, reference, workers=workers)
    return T, J


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
    kin: Kinematics, fid: int, n: int, jacobian: bool, extra: int = 0, row_cost: int = 1, native: bool = True
) -> Chain | None:
    """The compiled chain if evaluating it over the batch is faster than a loop over rows, else None.
    ``native``: poses and Jacobians, on the C chain (when built) from KERNEL_FROM rows. Otherwise a loop row
    costs ``row_cost`` × CALLS_PER_CONFIGURATION numpy calls, the numpy path the chain's plus ``extra``."""
    if native and compiler.KERNEL is not None and n >= KERNEL_FROM:
        return compiled_chain(kin, fid)
    budget = row_cost * n * CALLS_PER_CONFIGURATION
    if budget < MIN_CALLS + extra:  # the chain is not even looked up
        return None
    chain = compiled_chain(kin, fid)
    return chain if budget >= chain.pose_calls + (chain.jacobian_calls if jacobian else 0) + extra else None


__all__ = [
    "CALLS_PER_CONFIGURATION",
    "CHUNK",
    "KERNEL_FROM",
    "KERNEL_MIN_PER_WORKER",
    "MEMORY_SHARE",
    "MIN_CHUNK",
    "WORKERS",
    "checked_out",
    "checked_workers",
    "chunk_rows",
    "compiled_chain",
    "evaluate",
    "in_shares",
    "numpy_chain",
    "run_chain",
]
