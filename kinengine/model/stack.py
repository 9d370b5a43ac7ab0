"""Running Pinocchio's recursive C++ on a thread whose stack is known to be big enough.

Pinocchio's URDF model builder recurses once per level of the kinematic tree (~2 KiB of stack per
level, measured on pin 4.1), and Python cannot tell how much stack the calling thread has left: a
thread made with ``threading.stack_size(128 * 1024)`` crashes (SIGSEGV) on a 120-level chain that the
default :class:`~kinengine.urdf.Limits` admit. So a Pinocchio model build runs on a fresh,
short-lived thread made with :data:`BUILD_STACK` bytes of stack (more for deeper trees, see
:func:`stack_for_depth`), and the calling thread waits for it — unless the caller is the main thread
and its stack limit (``RLIMIT_STACK``, the main thread's stack on Linux) is at least twice what the
tree needs: then the build runs in place and costs no thread (~1 ms). ``threading.stack_size`` is
process-wide, so it is set and restored under a lock, only around ``Thread.start``. When no thread
can be started (interpreter shutdown) the work runs on the calling thread, as it would without this
module.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import TypeVar

try:
    import resource
except ImportError:  # not on Windows: always use the build thread
    resource = None  # type: ignore[assignment]

from ..errors import ResourceLimitError

T = TypeVar("T")

PER_LEVEL = 4096
"""[bytes] stack reserved per tree level (measured on pin 4.1: ~2.2 KiB)."""
BUILD_STACK = 16 * 1024 * 1024
"""[bytes] stack of the build thread: 4x what the deepest admitted tree (Limits.max_tree_depth = 128,
~300 KiB) needs, and 2x a Linux main thread's default; only the pages it touches are ever resident."""

IN_PLACE_MAX = 4 * 1024 * 1024
"""[bytes] the most stack a build may need to run in place on the main thread (~750 levels): the space
below the main stack is reserved from the limit at program start, so a limit raised later is not
trusted for more."""

_START_LOCK = threading.Lock()


def stack_for_depth(depth: int) -> int:
    """[bytes] the build stack for a tree ``depth`` levels deep: :data:`BUILD_STACK`, or ~4 KiB per level
    (twice the measured ~2 KiB) plus 1 MiB when that is more."""
    return max(BUILD_STACK, stack_needed(depth))


def main_thread_has(stack: int) -> bool:
    """Whether the calling thread is the main thread and its stack limit is at least twice ``stack``."""
    if resource is None or threading.current_thread() is not threading.main_thread():
        return False
    soft, _ = resource.getrlimit(resource.RLIMIT_STACK)
    return soft == resource.RLIM_INFINITY or soft >= 2 * stack


def call_with_big_stack(function: Callable[[], T], stack: int = BUILD_STACK, need: int | None = None) -> T:
    """``function()`` run on a thread with ``stack`` bytes of stack; its result, or its exception
    re-raised in the calling thread. ``need`` [bytes]: what the job needs; when given and the main thread
    has twice that (:func:`main_thread_has`), the job runs in place. When the thread cannot be started,
    a small job (``stack`` at most :data:`BUILD_STACK`) runs on the calling thread; a larger one is a
    ResourceLimitError."""
    if need is not None and need <= IN_PLACE_MAX and main_thread_has(need):
        return function()
    box: list[tuple[bool, object]] = []

    def run() -> None:
        try:
            box.append((True, function()))
        except BaseException as exc:  # handed to the caller, re-raised there
            box.append((False, exc))

    thread = threading.Thread(target=run, name="kinengine-model-build", daemon=True)
    with _START_LOCK:
        previous = threading.stack_size()
        try:
            threading.stack_size(stack)
            thread.start()
            started = True
        except (RuntimeError, ValueError, MemoryError):  # shutdown, no threads, or no memory for the stack
            started = False
        finally:
            threading.stack_size(previous)
    if not started:
        if stack > BUILD_STACK:
            raise ResourceLimitError(
                f"cannot start a thread with the {stack // 1024**2} MiB of stack that "
                "Pinocchio needs to build this tree: raise the memory limit or load a "
                "shallower tree"
            )
        return function()
    thread.join()
    returned, value = box[0]
    if not returned:
        raise value  # type: ignore[misc]
    return value  # type: ignore[return-value]


def stack_needed(depth: int) -> int:
    """[bytes] what building a tree ``depth`` levels deep needs: ~4 KiB per level plus 1 MiB for the rest."""
    return depth * PER_LEVEL + 1024 * 1024


__all__ = [
    "BUILD_STACK",
    "IN_PLACE_MAX",
    "PER_LEVEL",
    "call_with_big_stack",
    "main_thread_has",
    "stack_for_depth",
    "stack_needed",
]
