"""Memory for large batch outputs, reused once the caller has let go of every array viewing it.

>>> T, J = empty((n, 4, 4), (n, 6, dof))    # float64, uninitialized; each its own block

A new array of many MiB gets new pages from the operating system, zeroed on first touch (glibc maps every
block above 32 MiB anew): for ``robot.kinematics(Q)`` of a large batch that costs a good part of the
kinematics itself. :func:`empty` hands out an array whose memory is a kept block instead, when one of the
same size is free. At most :data:`SLOTS` blocks are kept, the most recently handed out (two calls' T and
J), each of :data:`RECYCLE_FROM` bytes to :data:`KEEP_UP_TO`: that much memory stays with the process
after its arrays are dropped, until :func:`release` or blocks of other sizes take the slots.

How "free" is known: the array handed out is a view of the block, and numpy gives every view of it, of any
depth, the block itself as its ``base`` (the array that owns the data). So whatever still reaches the
memory (a view, a memoryview or ctypes object made from one, the block taken from ``.base``) holds a
reference to the block, and the block is free when the references to it are only the ones kept here:
the test numpy's own ``ndarray.resize`` makes before it moves an array's memory.
"""

from __future__ import annotations

import math
import os
import sys
import threading

import numpy as np

RECYCLE_FROM = 4 << 20
"""[bytes] Arrays this large (up to KEEP_UP_TO) come from a kept block; others are new arrays."""
KEEP_UP_TO = 512 << 20
"""[bytes] The largest block kept."""
SLOTS = 4
"""Blocks kept: a loop that holds one result (T, J) while it asks for the next reuses both calls' blocks."""

_LOCK = threading.Lock()
_KEPT: list[np.ndarray] = []  # the blocks (1-D float64 arrays that own their data), newest first


def _references(blocks: list[np.ndarray], k: int) -> int:
    """sys.getrefcount of blocks[k], read the same way for every block (so interpreter details, such as
    borrowed references, shift every reading alike)."""
    return sys.getrefcount(blocks[k])


_UNHELD = _references([np.empty(0)], 0)
"""What :func:`_references` reads for a block that only the list holds."""


def _forget_lock() -> None:
    """In a forked child: a new lock (a thread of the parent may have held it at the fork)."""
    global _LOCK
    _LOCK = threading.Lock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_lock)


def empty(*shapes: tuple[int, ...]) -> tuple[np.ndarray, ...]:
    """Uninitialized C-contiguous float64 arrays of ``shapes``: each of RECYCLE_FROM to KEEP_UP_TO bytes
    views a kept block of its size nobody else holds (a new kept block if none is free); others are new."""
    return tuple(_one(shape) for shape in shapes)


def _one(shape: tuple[int, ...]) -> np.ndarray:
    size = math.prod(shape)
    if not RECYCLE_FROM <= 8 * size <= KEEP_UP_TO:
        return np.empty(shape)
    with _LOCK:
        free = (k for k in range(len(_KEPT)) if _KEPT[k].size == size and _references(_KEPT, k) == _UNHELD)
        k = next(free, None)  # (no name holds a block while its references are read)
        block = _KEPT.pop(k) if k is not None else np.empty(size)
        _KEPT.insert(0, block)
        del _KEPT[SLOTS:]  # an evicted block still in use is freed when its last view is
    return block.reshape(shape)


def release() -> None:
    """Drop the kept blocks (one still viewed by some array is freed when that array is)."""
    with _LOCK:
        _KEPT.clear()


__all__ = ["KEEP_UP_TO", "RECYCLE_FROM", "SLOTS", "empty", "release"]
