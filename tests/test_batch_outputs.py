"""Large batch outputs reuse the memory of dropped ones (kinengine/kinematics/outputs.py), never of live ones.

A block is reused only when no array viewing it is left: views of views, transposes, slices, memoryviews and
results held across calls all keep it; the values written into a reused block are the new call's (checked
against Pinocchio); two threads never share a block; at most SLOTS blocks are kept.
"""

from __future__ import annotations

import gc
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


def test_this_numpy_collapses_view_bases_at_the_lease():
    assert outputs._collapse_stops_at_the_lease()


def test_small_and_huge_outputs_are_new_arrays(monkeypatch):
    T, J = outputs.empty((10, 4, 4), (10, 6, 6))
    assert T.flags.owndata and J.flags.owndata and T.shape == (10, 4, 4) and J.shape == (10, 6, 6)
    monkeypatch.setattr(outputs, "KEEP_UP_TO", outputs.RECYCLE_FROM)
    (T,) = outputs.empty((outputs.RECYCLE_FROM // 128 + 1, 4, 4))
    assert T.flags.owndata


def test_large_outputs_are_views_of_one_block_reused_once_dropped():
    n = outputs.RECYCLE_FROM // (8 * 16) + 1
    T, J = outputs.empty((n, 4, 4), (n, 6, 7))
    assert T.flags.c_contiguous and J.flags.c_contiguous and T.dtype == J.dtype == np.float64
    assert not np.shares_memory(T, J)
    address = _address(T)
    del T, J
    T2, _ = outputs.empty((n, 4, 4), (n, 6, 7))
    assert _address(T2) == address
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
        lambda T, J: T.base,  # the lease itself
        lambda T, J: J.view(Subclass),  # a view of another type holds J
    ],
)
def test_a_block_viewed_by_anything_is_not_reused(kept, keep):
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
    live = [outputs.empty((30 + k, 4, 4)) for k in range(4)]
    assert len(outputs._KEPT) == outputs.SLOTS
    live[0][0][...] = 5.0  # an evicted block still in use stays valid
    assert (live[0][0] == 5.0).all()
    outputs.release()
    assert not outputs._KEPT
