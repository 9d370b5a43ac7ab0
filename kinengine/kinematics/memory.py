"""Making Pinocchio Data only when it fits: a clear error instead of an out-of-memory abort.

One Pinocchio ``Data`` of a model with nv velocity coordinates holds four nv×nv×nv tensors of second
derivatives; measured on pin 4.1 (resident memory added by ``createData()`` / peak while it is made):
nv = 64: 12 / 20 MiB, 128: 73 / 139 MiB, 192: 234 / 455 MiB, 256: 542 / 1062 MiB.
:func:`data_bytes` bounds the first number from above, the peak is taken as twice that.

A Robot makes one Data per thread that uses it (see :class:`~kinengine.kinematics.Kinematics`), so a
128-dof robot used from 32 threads holds ~2.3 GiB of Data. Under a memory cap (``RLIMIT_AS``, a
cgroup ``memory.max``) an allocation that fails deep inside C++ or in glibc ("cannot allocate memory
for thread-local data") aborts the whole process. :func:`create_data` therefore checks, before each
Data it makes, that the peak fits in the memory left with :data:`RESERVE` to spare, and raises
:class:`~kinengine.errors.ResourceLimitError` (one line: the size, the memory left, the fix)
otherwise; a ``MemoryError`` from Pinocchio becomes the same error. The check reads a few
``/proc`` and cgroup files (Linux; elsewhere only the MemoryError is translated) and is skipped for
models whose Data is smaller than :data:`CHECK_FROM` — the 6-dof arms never pay for it. It runs once per
thread and model, never on the hot path.
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
    if soft is not None and soft != resource.RLIM_INFINITY:
        used = _address_space()
        if used is not None:
            bounds.append(soft - used)
    limit, current = _read_int("/sys/fs/cgroup/memory.max"), _read_int("/sys/fs/cgroup/memory.current")
    if limit is not None and current is not None:
        bounds.append(limit - current)
    available = _mem_available()
    if available is not None:
        bounds.append(available)
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
        f"{what} ({nv} joint coordinates) needs ~{need / mib:.0f} MiB of Pinocchio Data per thread that uses "
        "it "
        f"(~{2 * need / mib:.0f} MiB while it is made, plus {RESERVE // mib} MiB kept free) but only {room} "
        "of memory is left: use it from fewer threads (e.g. a pool of a few workers), a smaller model, "
        "or raise the memory limit"
    )


def _address_space() -> int | None:
    try:
        with open("/proc/self/statm", "rb") as f:
            return int(f.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return None


def _read_int(path: str) -> int | None:
    try:
        with open(path, "rb") as f:
            return int(f.read().strip())
    except (OSError, ValueError):  # missing, or "max"
        return None


def _mem_available() -> int | None:
    try:
        with open("/proc/meminfo", "rb") as f:
            for line in f:
                if line.startswith(b"MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


__all__ = ["CHECK_FROM", "RESERVE", "create_data", "data_bytes", "memory_left"]
