"""Memory for large batch outputs, reused once the caller has dropped every array viewing it.

>>> T, J = empty((n, 4, 4), (n, 6, dof))    # float64 views of one block; fresh memory when it is small

A new array of many MiB gets new pages from the operating system, zeroed on first touch (glibc maps every
block above 32 MiB anew): for ``robot.kinematics(Q)`` of a large batch that costs a good part of the
kinematics itself. :func:`empty` hands out views of a kept block instead, when one of the same size is free.
At most :data:`SLOTS` blocks are kept, the most recently handed out, each of :data:`RECYCLE_FROM` bytes to
:data:`KEEP_UP_TO`: the memory of up to two large outputs stays with the process after their arrays are
dropped, until :func:`release` or a block of another size takes the slot.

How "free" is known: a block is owned by an array of a private ndarray subclass (kept here), and the arrays
handed out view a plain-ndarray view of it, the lease. numpy sets a view's ``base`` to the first array up
the chain that owns its data or whose type differs from the view's, so every view a caller makes, of any
of them, holds the lease, never the owner: the lease lives exactly as long as some array viewing the block,
and a weak reference to it says when the last one is gone. A numpy that collapsed bases otherwise would
make this unsafe: :func:`_collapse_stops_at_the_lease` checks it on first use, and blocks are then never
reused.
"""

from __future__ import annotations

import functools
import itertools
import math
import threading
import weakref

import numpy as np

RECYCLE_FROM = 4 << 20
"""[bytes] Outputs this large (up to KEEP_UP_TO) come from a kept block; others are new arrays."""
KEEP_UP_TO = 512 << 20
"""[bytes] The largest block kept: at most SLOTS x this stays with the process."""
SLOTS = 2
"""Blocks kept: two, so that a loop that holds one result while it asks for the next reuses both."""


class _Owner(np.ndarray):
    """A kept block's owner: its own type stops numpy's collapse of view bases at the lease."""


_LOCK = threading.Lock()
_KEPT: list[tuple[_Owner, weakref.ref]] = []  # (owner, weak reference to its current lease), newest first


@functools.cache
def _collapse_stops_at_the_lease() -> bool:
    """numpy gives a view of a view of the lease the lease as its base (so the lease outlives every view)."""
    lease = np.ndarray.__new__(_Owner, (8,)).view(np.ndarray)
    view = lease[2:].reshape(2, 3)[1:]
    return view.base is lease and view.T.base is lease


def empty(*shapes: tuple[int, ...]) -> tuple[np.ndarray, ...]:
    """Uninitialized C-contiguous float64 arrays of ``shapes``: views of one kept block when together they
    take RECYCLE_FROM bytes or more (a free block of that size, else a new one), else new arrays."""
    sizes = [math.prod(shape) for shape in shapes]
    total = sum(sizes)
    if not RECYCLE_FROM <= 8 * total <= KEEP_UP_TO or not _collapse_stops_at_the_lease():
        return tuple(np.empty(shape) for shape in shapes)
    with _LOCK:
        free = next(
            (k for k, (owner, lease) in enumerate(_KEPT) if owner.size == total and lease() is None), None
        )
        owner = _KEPT.pop(free)[0] if free is not None else np.ndarray.__new__(_Owner, (total,))
        block = owner.view(np.ndarray)
        _KEPT.insert(0, (owner, weakref.ref(block)))
        del _KEPT[SLOTS:]  # an evicted block in use lives on through its lease, then is freed
    starts = list(itertools.accumulate(sizes, initial=0))[:-1]
    return tuple(
        block[a : a + size].reshape(shape) for a, size, shape in zip(starts, sizes, shapes, strict=True)
    )


def release() -> None:
    """Drop the kept blocks (those still viewed by some array are freed when it is)."""
    with _LOCK:
        _KEPT.clear()


__all__ = ["KEEP_UP_TO", "RECYCLE_FROM", "SLOTS", "empty", "release"]
