"""Batched IK (``robot.inverse_kinematics(T)`` for T (N, 4, 4)): every result checked independently of the
solver (forward kinematics and scipy's rotation angle), the same start giving the single solver's
solution, attempts run at once resolved as if run one after another, and the column-wise numerics
(Cholesky, log(C_d Cᵀ)) against numpy and Pinocchio."""

from __future__ import annotations

import numpy as np
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


def _explicit_step(q, J, e, inverse_w, diagonal, z):
    """Δq = W⁻¹Jᵀ (J W⁻¹Jᵀ + diag(d))⁺ (e − J z) + z for one column, written out (pseudo-inverse)."""
    A = (J * inverse_w) @ J.T + np.diag(diagonal)
    return q + (J * inverse_w).T @ np.linalg.pinv(A) @ (e - J @ z) + z


@pytest.mark.parametrize("r", [40, 300])  # numpy's solve, the column-wise Cholesky factorization
def test_the_batched_step_is_the_damped_least_squares_formula_also_for_singular_systems(r):
    """take_steps over columns equals the written-out step of each column, including columns whose system
    is not positive definite (J = 0 with no damping, a frame no joint moves at λ_min = 0: exactly singular,
    the step is the least-squares one; a negative diagonal: indefinite, which a Cholesky factorization
    refuses: those columns are solved again by numpy), every result finite."""
    from kinengine.control.ik_step import take_steps

    rng = np.random.default_rng(35)
    for m in (3, 6):
        dof = 7
        J, e = rng.normal(size=(m, dof, r)), rng.normal(size=(m, r))
        J[:, :, 0] = 0.0  # no joint moves the frame ...
        diagonal = np.abs(rng.normal(size=(m, r)))
        diagonal[:, 0] = 0.0  # ... and no damping: A = 0
        diagonal[:, 1] = -0.5  # indefinite (not positive definite)
        q, inverse_w = rng.normal(size=(dof, r)), rng.uniform(0.2, 1.0, size=(dof, r))
        q_ns = rng.normal(size=dof)
        buffers = (np.empty((6, dof, r)), np.empty(36 * r))
        for pull in (None, q_ns):
            z = (
                np.zeros((dof, r))
                if pull is None
                else 0.1 * np.minimum(1.0, 0.02 / 5e-2) * (q_ns[:, None] - q)
            )
            out = take_steps(q, J, e, inverse_w, diagonal, (pull, 0.1, np.full(r, 0.02)), buffers)
            assert np.isfinite(out).all()
            for n in range(r):
                expected = _explicit_step(
                    q[:, n], J[..., n], e[:, n], inverse_w[:, n], diagonal[:, n], z[:, n]
                )
                np.testing.assert_allclose(out[:, n], expected, rtol=1e-7, atol=1e-9)


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
