"""Batched IK (``robot.inverse_kinematics(T)`` for T (N, 4, 4)): every result checked independently of the
solver (forward kinematics and scipy's rotation angle), the same start giving the single solver's
solution, attempts run at once resolved as if run one after another, and the column-wise numerics
(Cholesky, log(C_d Cᵀ)) against numpy and Pinocchio."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from scipy.spatial.transform import Rotation

import kinengine
from kinengine.control import ik, ik_batch


def _errors(robot, q, T):
    """(|Δp| (N,) [m], angle of C_d Cᵀ (N,) [rad]) of the end effector at q against T."""
    F = robot.frame_pose(q)
    angle = Rotation.from_matrix(T[:, :3, :3] @ F[:, :3, :3].transpose(0, 2, 1)).magnitude()
    return np.linalg.norm(T[:, :3, 3] - F[:, :3, 3], axis=1), angle


def _within_limits(robot, q):
    return np.all((q >= robot.lower_limits) & (q <= robot.upper_limits), axis=1)


@pytest.mark.parametrize("name", ["abb_irb120", "ur5", "panda_arm"])
def test_batched_results_are_within_tolerance_and_limits(name):
    robot = kinengine.load(name)
    targets = robot.frame_pose(robot.random_configuration(np.random.default_rng(31), 1000))
    result = robot.inverse_kinematics(targets, rng=0)
    assert result.q.shape == (1000, robot.dof) and _within_limits(robot, result.q).all()
    assert result.success.sum() >= 995  # >= 99.5 %
    ep, er = _errors(robot, result.q, targets)
    np.testing.assert_allclose(result.position_error, ep, rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(result.rotation_error, er, rtol=1e-5, atol=1e-9)
    ok = result.success
    assert (ep[ok] <= 1e-6).all() and (er[ok] <= 1e-6 + 2e-8).all()
    assert (ep[~ok] + 0.2 * er[~ok] > 0).all()  # a failure reports a real, nonzero error
    assert (result.iterations >= 0).all() and (result.restarts <= ik.NEAREST_SEEDS + 3).all()


@pytest.mark.parametrize("name", ["abb_irb120", "ur5", "panda_arm"])
def test_same_start_gives_the_single_solution(name):
    """From the same start (q0 per target) the batched and the single solver converge to the same q."""
    robot = kinengine.load(name)
    rng = np.random.default_rng(32)
    solutions = robot.random_configuration(rng, 40)
    targets = robot.frame_pose(solutions)
    starts = np.clip(
        solutions + rng.normal(0.0, 0.15, solutions.shape), robot.lower_limits, robot.upper_limits
    )
    batch = robot.inverse_kinematics(targets, q0=starts, restarts=0)
    singles = [robot.inverse_kinematics(T, q0=s, restarts=0) for T, s in zip(targets, starts, strict=True)]
    np.testing.assert_array_equal(batch.success, [s.success for s in singles])
    assert batch.success.mean() >= 0.9
    for i, single in enumerate(singles):
        if single.success:
            np.testing.assert_allclose(batch.q[i], single.q, atol=1e-5)
            assert abs(int(batch.iterations[i]) - single.iterations) <= 1


@pytest.mark.parametrize("name", ["abb_irb120", "panda_arm"])
def test_attempts_run_at_once_resolve_as_one_after_another(name, monkeypatch):
    """With no random restarts every attempt is deterministic: running the next attempts of a target at
    once (SPECULATE) must give what running them in turn gives."""
    robot = kinengine.load(name)
    targets = robot.frame_pose(robot.random_configuration(np.random.default_rng(33), 300))
    targets[:20, 0, 3] += 2.0  # unreachable: every attempt runs and fails, the best one is reported
    outcomes = []
    for speculate in (0, 100_000):
        monkeypatch.setattr(ik_batch, "SPECULATE", speculate)
        outcomes.append(robot.inverse_kinematics(targets, restarts=0))
    in_turn, at_once = outcomes
    for field in ("success", "iterations", "restarts"):
        np.testing.assert_array_equal(getattr(in_turn, field), getattr(at_once, field), err_msg=field)
    # the same iterates up to rounding (the batch chain's numpy path or Pinocchio's loop, by batch size)
    np.testing.assert_allclose(in_turn.q, at_once.q, atol=1e-9)
    np.testing.assert_allclose(in_turn.position_error, at_once.position_error, rtol=1e-6, atol=1e-12)
    assert not in_turn.success[:20].any() and in_turn.success[20:].mean() >= 0.99
    assert (in_turn.restarts[:20] <= 10).all()  # the best of the 11 seeded attempts


def test_single_targets_in_a_batch_of_one_and_q0_batches():
    robot = kinengine.load("abb_irb120")
    q = robot.random_configuration(np.random.default_rng(34), 5)
    targets = robot.frame_pose(q)
    one = robot.inverse_kinematics(targets[:1], rng=0)
    assert len(one) == 1 and one.success[0] and one[0].success
    exact = robot.inverse_kinematics(targets, q0=q)  # already there: no iteration
    assert exact.success.all() and (exact.iterations == 0).all() and (exact.restarts == 0).all()
    np.testing.assert_allclose(exact.q, q, atol=1e-12)


def test_column_wise_cholesky_equals_numpy_solve():
    rng = np.random.default_rng(35)
    for m in (1, 3, 5, 6):
        J = rng.normal(size=(50, m, 7))
        A = J @ J.transpose(0, 2, 1) + 1e-3 * np.eye(m)
        b = rng.normal(size=(50, m))
        x = ik_batch._cholesky_solve(np.ascontiguousarray(A.transpose(1, 2, 0)), np.ascontiguousarray(b.T))
        np.testing.assert_allclose(x.T, np.linalg.solve(A, b[..., None])[..., 0], rtol=1e-8, atol=1e-10)


def test_column_wise_log3_equals_pinocchio_including_near_pi():
    rng = np.random.default_rng(36)
    C_d = Rotation.random(200, random_state=rng).as_matrix()
    C = Rotation.random(200, random_state=rng).as_matrix()
    axes = Rotation.random(40, random_state=rng).as_rotvec()
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    angles = np.concatenate((np.pi - np.geomspace(1e-9, 0.3, 20), np.geomspace(1e-12, 1e-3, 20)))
    C[:40] = Rotation.from_rotvec(-axes * angles[:, None]).as_matrix() @ C_d[:40]  # C_d Cᵀ: angle θ
    out = np.empty((3, 200))
    ik_batch._log3_columns(
        np.ascontiguousarray(C_d.transpose(1, 2, 0)), np.ascontiguousarray(C.transpose(1, 2, 0)), out
    )
    expected = np.array([pin.log3(a @ b.T) for a, b in zip(C_d, C, strict=True)])
    np.testing.assert_allclose(out.T, expected, atol=1e-9)


def test_large_batches_are_solved_in_chunks_with_the_same_results(monkeypatch):
    robot = kinengine.load("ur5")
    q = robot.random_configuration(np.random.default_rng(37), 130)
    targets = robot.frame_pose(q)
    starts = np.clip(q + 0.2, robot.lower_limits, robot.upper_limits)
    whole = robot.inverse_kinematics(targets, q0=starts, restarts=0)
    shared_whole = robot.inverse_kinematics(targets, q0=starts[0], restarts=0)  # one q0 for all
    monkeypatch.setattr(ik_batch, "CHUNK_TARGETS", 50)  # chunks of 50, 50, 30
    chunked = robot.inverse_kinematics(targets, q0=starts, restarts=0)
    shared = robot.inverse_kinematics(targets, q0=starts[0], restarts=0)
    assert len(chunked) == 130 and len(shared) == 130
    np.testing.assert_array_equal(shared.success, shared_whole.success)
    for field in ("success", "iterations", "restarts"):
        np.testing.assert_array_equal(getattr(whole, field), getattr(chunked, field), err_msg=field)
    np.testing.assert_allclose(whole.q, chunked.q, atol=1e-9)
    assert whole.success.all()
