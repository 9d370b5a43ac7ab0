"""Making Pinocchio Data only when it fits: a clear error instead of an out-of-memory abort.

One Pinocchio ``Data`` of a model with nv velocity coordinates holds four nv×nv×nv tensors of second
derivatives (measured on pin 4.1, resident memory added by ``createData()`` / peak while it is made:
nv = 64: 12 / 20 MiB, 128: 73 / 139 MiB, 256: 542 / 1062 MiB); a Robot makes one per thread that uses it.
Under a memory cap (``RLIMIT_AS``, a cgroup ``memory.max``) an allocation that fails deep inside C++ or
glibc aborts the whole process, so :func:`create_data` first checks that twice :func:`data_bytes` fits in
the memory left with :data:`RESERVE` to spare, and raises :class:`~kinengine.errors.ResourceLimitError`
otherwise (a ``MemoryError`` from Pinocchio becomes the same error). The check reads a few ``/proc`` and
cgroup files (Linux) once per thread and model, and is skipped below :data:`CHECK_FROM`.
"""

from __future__ import annotations

import os
import threading

try:
    import resource
except ImportError:  # not on Windows
    resource = None  # type: ignore[assignment]

import pinocchio as pin

from ..errors import ResourceLimitError

CHECK_FROM = 4 * 1024**2
"""[bytes] Data smaller than this (nv < ~40) is made without looking at the memory left."""
_CREATE_LOCK = threading.Lock()  # checks and makes one large Data at a time, so two threads cannot both fit
RESERVE = 128 * 1024**2
"""[bytes] memory that must stay free after a Data is made: a new thread's stack, TLS and malloc arena."""


def data_bytes(nv: int) -> int:
    """[bytes] an upper bound of the memory one Pinocchio Data of ``nv`` velocity coordinates holds
    (40 nv³ + 2 MiB, above the measurements in the module doc)."""
    return 40 * nv**3 + 2 * 1024**2


def memory_left() -> int | None:
    """[bytes] what this process may still allocate: the least of RLIMIT_AS minus the address space in
    use, the cgroup's memory.max minus memory.current, and MemAvailable; None if none is known."""
    bounds = []
    soft = resource.getrlimit(resource.RLIMIT_AS)[0] if resource else None
    used = _number("/proc/self/statm", 0)
    if soft is not None and soft != resource.RLIM_INFINITY and used is not None:
        bounds.append(soft - used * os.sysconf("SC_PAGE_SIZE"))
    limit, current = _number("/sys/fs/cgroup/memory.max"), _number("/sys/fs/cgroup/memory.current")
    if limit is not None and current is not None:
        bounds.append(limit - current)
    available = _number("/proc/meminfo", 1, b"MemAvailable:")  # [KiB]
    if available is not None:
        bounds.append(available * 1024)
    return min(bounds) if bounds else None


def create_data(model: pin.Model, what: str = "this robot") -> pin.Data:
    """``model.createData()``, or ResourceLimitError if it would not fit (see the module doc)."""
    need = data_bytes(model.nv)
    try:
        if need < CHECK_FROM:
            return model.createData()
        with _CREATE_LOCK:
            left = memory_left()
            if left is not None and 2 * need + RESERVE > left:
                raise _too_big(what, model.nv, need, left)
            return model.createData()
    except ResourceLimitError:
        raise
    except MemoryError:
        raise _too_big(what, model.nv, need, memory_left()) from None


def _too_big(what: str, nv: int, need: int, left: int | None) -> ResourceLimitError:
    mib = 1024**2
    room = "an unknown amount" if left is None else f"{max(left, 0) / mib:.0f} MiB"
    return ResourceLimitError(
        f"{what} ({nv} joint coordinates) needs ~{need / mib:.0f} MiB of Pinocchio Data per thread that "
        f"uses it (~{2 * need / mib:.0f} MiB while it is made, plus {RESERVE // mib} MiB kept free) but only "
        f"{room} of memory is left: use it from fewer threads (e.g. a pool of a few workers), a smaller "
        "model, or raise the memory limit"
    )


def _number(path: str, field: int = 0, line: bytes = b"") -> int | None:
    """Whitespace-separated ``field`` of the first line of file ``path`` that starts with ``line``, as an int;
    None if the file, the line or a number is missing (e.g. "max")."""
    try:
        with open(path, "rb") as f:
            return int(next(text for text in f if text.startswith(line)).split()[field])
    except (OSError, ValueError, IndexError, StopIteration):
        return None


__all__ = ["CHECK_FROM", "RESERVE", "create_data", "data_bytes", "memory_left"]
