"""Large batch outputs reuse the memory of dropped ones (kinengine/kinematics/outputs.py), never of held ones.

A block is reused only when nothing reaches it any more: views of views, transposes, slices, memoryviews,
the block itself taken from ``.base``, and results held across calls all keep it; the values written into a
reused block are the new call's (checked against Pinocchio's single calls); two threads never share a
block; at most SLOTS blocks are kept; a forked child gets a lock of its own.
"""

from __future__ import annotations

import gc
import os
import threading
import time

import numpy as np
import pytest

import kinengine
from kinengine.kinematics import outputs


class Subclass(np.ndarray):
    """A caller's own array type."""


def _address(a: np.ndarray) -> int:
    return a.__array_interface__["data"][0]


@pytest.fixture
def kept(monkeypatch):
    """Every output recycled (RECYCLE_FROM 0), starting with no kept block."""
    monkeypatch.setattr(outputs, "RECYCLE_FROM", 0)
    outputs.release()
    yield
    outputs.release()


def test_small_and_huge_outputs_are_new_arrays(monkeypatch):
    T, J = outputs.empty((10, 4, 4), (10, 6, 6))
    assert T.flags.owndata and J.flags.owndata and T.shape == (10, 4, 4) and J.shape == (10, 6, 6)
    monkeypatch.setattr(outputs, "KEEP_UP_TO", outputs.RECYCLE_FROM)
    (T,) = outputs.empty((outputs.RECYCLE_FROM // 128 + 1, 4, 4))
    assert T.flags.owndata


def test_kinematics_of_a_large_batch_reuses_the_dropped_results_blocks_with_the_new_values():
    """At real sizes (no threshold changed): UR5, N = 40,000 (T 5.1 MB, J 11.5 MB)."""
    outputs.release()
    robot = kinengine.load("ur5")
    Q1, Q2 = (robot.random_configuration(seed, size=40_000) for seed in (1, 2))
    T, J = robot.kinematics(Q1)
    assert not T.flags.owndata and T.flags.c_contiguous and J.flags.c_contiguous
    addresses = _address(T), _address(J)
    del T, J
    T, J = robot.kinematics(Q2)
    assert (_address(T), _address(J)) == addresses
    rows = np.arange(0, 40_000, 3_999)
    np.testing.assert_allclose(T[rows], [robot.frame_pose(q) for q in Q2[rows]], rtol=0, atol=1e-14)
    np.testing.assert_allclose(J[rows], [robot.jacobian(q) for q in Q2[rows]], rtol=0, atol=1e-14)
    outputs.release()


@pytest.mark.parametrize(
    "keep",
    [
        lambda T, J: T,
        lambda T, J: J[3:, 1],
        lambda T, J: J.T,
        lambda T, J: T.reshape(-1)[::4].reshape(-1, 2)[1:],
        lambda T, J: memoryview(J),
        lambda T, J: np.asarray(T[0]),
        lambda T, J: T.base,  # the block itself
        lambda T, J: J.base[5:],
        lambda T, J: J.view(Subclass),
        lambda T, J: np.frombuffer(memoryview(T), dtype=np.float64),
    ],
)
def test_a_block_reached_by_anything_is_not_reused(kept, keep):
    T, J = outputs.empty((20, 4, 4), (20, 6, 7))
    T[...], J[...] = 1.0, 2.0
    held = keep(T, J)
    del T, J
    gc.collect()
    T2, J2 = outputs.empty((20, 4, 4), (20, 6, 7))
    T2[...], J2[...] = -1.0, -2.0
    assert (np.asarray(held) > 0).all()  # not overwritten
    del held
    T3, _ = outputs.empty((20, 4, 4), (20, 6, 7))
    assert not np.shares_memory(T3, T2)


def test_holding_t_keeps_only_t(kept):
    T, J = outputs.empty((20, 4, 4), (20, 6, 7))
    j_address = _address(J)
    del J
    _, J2 = outputs.empty((20, 4, 4), (20, 6, 7))
    assert _address(J2) == j_address and not np.shares_memory(J2, T)


def test_a_loop_that_holds_the_last_result_alternates_two_blocks_with_right_values(kept):
    robot = kinengine.load("ur5")
    frame, addresses = robot.end_effector, set()
    rng = np.random.default_rng(4)
    T, J = robot.kinematics(robot.random_configuration(rng, size=50), frame)
    for _ in range(6):
        Q = robot.random_configuration(rng, size=50)
        previous = T
        T, J = robot.kinematics(Q, frame)
        assert not np.shares_memory(T, previous)
        addresses.add(_address(T))
        np.testing.assert_allclose(T, [robot.frame_pose(q, frame) for q in Q], rtol=0, atol=1e-14)
        np.testing.assert_allclose(J, [robot.jacobian(q, frame) for q in Q], rtol=0, atol=1e-14)
        del previous
    assert len(addresses) == 2


def test_threads_never_share_a_block(kept):
    """Four threads take, mark, yield, check and drop blocks of one size: a block handed to two threads at
    once would show another thread's mark."""
    blocks, errors, barrier = [], [], threading.Barrier(4)

    def take(mark: float) -> None:
        barrier.wait()
        for _ in range(300):
            poses, jacobians = outputs.empty((8, 4, 4), (8, 6, 6))
            poses[...], jacobians[...] = mark, mark
            time.sleep(0)
            if not ((poses == mark).all() and (jacobians == mark).all()):
                errors.append(mark)
            del poses, jacobians
        blocks.append(outputs.empty((8, 4, 4), (8, 6, 6)))

    threads = [threading.Thread(target=take, args=(float(k),)) for k in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert not errors and len(blocks) == 4
    for a, b in ((a, b) for i, a in enumerate(blocks) for b in blocks[i + 1 :]):
        assert not np.shares_memory(a[0], b[0])


def test_at_most_slots_blocks_are_kept_and_release_drops_them(kept):
    live = [outputs.empty((30 + k, 4, 4)) for k in range(outputs.SLOTS + 2)]
    assert len(outputs._KEPT) == outputs.SLOTS
    live[0][0][...] = 5.0  # an evicted block still in use stays valid
    assert (live[0][0] == 5.0).all()
    outputs.release()
    assert not outputs._KEPT


@pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork here")
@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # fork() in a process with threads
def test_a_child_forked_while_another_thread_holds_the_lock_makes_outputs(kept):
    with outputs._LOCK:  # as if another thread were inside empty() at the fork
        pid = os.fork()
        if pid == 0:  # the child: a new lock, so this returns (with the parent's lock it would hang)
            code = 0 if outputs.empty((8, 4, 4))[0].shape == (8, 4, 4) else 1
            os._exit(code)
    deadline = time.monotonic() + 20.0
    while (ended := os.waitpid(pid, os.WNOHANG))[0] == 0 and time.monotonic() < deadline:
        time.sleep(0.01)
    if ended[0] == 0:
        os.kill(pid, 9)
        os.waitpid(pid, 0)
        pytest.fail("the forked child hung on the parent's lock")
    assert os.waitstatus_to_exitcode(ended[1]) == 0


def test_the_free_reading_matches_this_interpreter():
    """_UNHELD is what a block only the list holds reads (interpreters differ in how they count)."""
    blocks = [np.empty(3)]
    assert outputs._references(blocks, 0) == outputs._UNHELD
    extra = blocks[0]
    assert outputs._references(blocks, 0) == outputs._UNHELD + 1
    del extra
    assert outputs._references(blocks, 0) == outputs._UNHELD
