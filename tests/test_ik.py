"""Differential IK: the acceptance run (1,000 random reachable targets per arm), parameter targets,
partial targets, continuous and mimic joints, the nullspace task, failures and input checks.

Every check of a solution is independent of the solver: the pose of the returned q by forward
kinematics, compared with scipy's rotation angle."""

from __future__ import annotations

import time

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import kinengine
from kinengine.control.ik import inverse_kinematics


def _pose_errors(robot, q, frame, T):
    """(|Δp| [m], angle of C_d Cᵀ [rad]) of frame's pose at q against T, by forward kinematics."""
    F = robot.frame_pose(q, frame)
    angle = Rotation.from_matrix(T[:3, :3] @ F[:3, :3].T).magnitude()
    return float(np.linalg.norm(T[:3, 3] - F[:3, 3])), float(angle)


def _within_limits(robot, q):
    return bool(np.all(q >= robot.lower_limits) and np.all(q <= robot.upper_limits))


@pytest.mark.parametrize("name", ["abb_irb120", "ur5", "panda"])
def test_acceptance_1000_random_reachable_targets(name):
    robot = kinengine.load(name)
    frame = robot.end_effector
    rng = np.random.default_rng(2024)
    targets = robot.frame_pose(robot.random_configuration(rng, size=1000), frame)
    start = time.perf_counter()
    results = [inverse_kinematics(robot, T, frame, rng=i) for i, T in enumerate(targets)]
    elapsed = time.perf_counter() - start
    successes = sum(r.success for r in results)
    print(f"\n{name}: {successes}/1000 solved, {1000 / elapsed:.0f} solves/s, "
          f"restarts used {np.bincount([r.restarts for r in results], minlength=4).tolist()}")
    assert successes >= 990
    for T, result in zip(targets, results):
        assert result.restarts <= 3
        assert _within_limits(robot, result.q)
        ep, er = _pose_errors(robot, result.q, frame, T)
        assert ep == pytest.approx(result.position_error, rel=1e-6, abs=1e-12)
        assert er == pytest.approx(result.rotation_error, rel=1e-5, abs=2e-8)
        if result.success:
            assert ep <= 1e-6 and er <= 1e-6 + 2e-8


@pytest.mark.parametrize("position,rotation", [("cartesian", "quaternion"), ("spherical", "euler_zyz"),
                                               ("cylindrical", "rotation_vector")])
def test_parameter_targets_reach_the_pose_they_describe(position, rotation):
    robot = kinengine.load("abb_irb120")
    rng = np.random.default_rng(6)
    for _ in range(5):
        q_true = robot.random_configuration(rng)
        chi = robot.pose_parameters(q_true, "tool0", position, rotation)
        result = inverse_kinematics(robot, chi, "tool0", position=position, rotation=rotation, rng=rng)
        assert result.success
        ep, er = _pose_errors(robot, result.q, "tool0", robot.frame_pose(q_true, "tool0"))
        assert ep <= 1e-6 and er <= 1e-6 + 2e-8


def test_position_only_and_rotation_only_targets_leave_the_other_part_free():
    robot = kinengine.load("abb_irb120")
    rng = np.random.default_rng(7)
    T = robot.frame_pose(robot.random_configuration(rng), "tool0")
    only_p = inverse_kinematics(robot, T[:3, 3], "tool0", position="cartesian", rng=1)
    assert only_p.success and only_p.rotation_error == 0.0
    assert np.linalg.norm(robot.frame_pose(only_p.q, "tool0")[:3, 3] - T[:3, 3]) <= 1e-6
    angles = Rotation.from_matrix(T[:3, :3]).as_euler("ZYX")
    only_r = inverse_kinematics(robot, angles, "tool0", rotation="euler_zyx", rng=1)
    assert only_r.success and only_r.position_error == 0.0
    assert _pose_errors(robot, only_r.q, "tool0", T)[1] <= 1e-6 + 2e-8


def test_continuous_joints_are_returned_in_minus_pi_pi():
    robot = kinengine.load("kinova")
    continuous = ~np.isfinite(robot.lower_limits)
    assert continuous.any()
    rng = np.random.default_rng(8)
    for i in range(20):
        T = robot.frame_pose(robot.random_configuration(rng))
        result = inverse_kinematics(robot, T, rng=i)
        assert result.success and _within_limits(robot, result.q)
        assert np.all(np.abs(result.q[continuous]) <= np.pi)
        assert max(_pose_errors(robot, result.q, robot.end_effector, T)) <= 1e-6 + 2e-8


def test_robot_with_mimic_joints():
    robot = kinengine.load("baxter")
    rng = np.random.default_rng(9)
    for i in range(5):
        T = robot.frame_pose(robot.random_configuration(rng), "left_gripper")
        result = inverse_kinematics(robot, T, "left_gripper", rng=i)
        assert result.success and _within_limits(robot, result.q)


def test_nullspace_target_pulls_a_redundant_arm_towards_it():
    robot = kinengine.load("panda")
    rng = np.random.default_rng(10)
    q_true, preferred = robot.random_configuration(rng), robot.random_configuration(rng)
    T = robot.frame_pose(q_true)
    q0 = np.clip(q_true + 0.05, robot.lower_limits, robot.upper_limits)
    plain = inverse_kinematics(robot, T, q0=q0, rng=0)
    pulled = inverse_kinematics(robot, T, q0=q0, rng=0, nullspace_target=preferred, nullspace_gain=0.2)
    assert plain.success and pulled.success
    assert np.linalg.norm(pulled.q - preferred) < np.linalg.norm(plain.q - preferred) - 0.1


def test_a_close_first_guess_stays_on_its_branch():
    robot = kinengine.load("ur5")
    q_true = np.array([0.4, -1.2, 1.5, -0.8, 1.1, 0.3])
    result = inverse_kinematics(robot, robot.frame_pose(q_true), q0=q_true + 0.02)
    assert result.success and result.restarts == 0 and result.iterations < 10
    np.testing.assert_allclose(result.q, q_true, rtol=0, atol=1e-4)  # same branch (others are > 0.1 away)


def test_unreachable_target_reports_failure_with_the_best_attempt():
    robot = kinengine.load("abb_irb120")
    T = np.eye(4)
    T[:3, 3] = [2.0, 0.0, 0.5]   # the IRB 120 reaches 0.58 m
    result = inverse_kinematics(robot, T, rng=3)
    assert not result.success and result.restarts == 3
    assert _within_limits(robot, result.q)
    ep, er = _pose_errors(robot, result.q, "tool0", T)
    assert ep == pytest.approx(result.position_error, rel=1e-9) and ep > 1.0
    assert "did not converge" in str(result)


def test_same_rng_same_answer():
    robot = kinengine.load("panda")
    T = robot.frame_pose(robot.random_configuration(11))
    a = inverse_kinematics(robot, T, rng=5, restarts=2)
    b = inverse_kinematics(robot, T, rng=5, restarts=2)
    np.testing.assert_array_equal(a.q, b.q)


def test_inputs_are_checked():
    robot = kinengine.load("abb_irb120")
    with pytest.raises(kinengine.ParameterizationError, match=r"shape \(4, 4\)"):
        inverse_kinematics(robot, np.eye(3))
    with pytest.raises(kinengine.ParameterizationError, match="not a rotation matrix"):
        inverse_kinematics(robot, np.diag([1.0, 1.0, -1.0, 1.0]))
    with pytest.raises(kinengine.ParameterizationError, match=r"shape \(7,\)"):
        inverse_kinematics(robot, np.zeros(6), position="cartesian", rotation="quaternion")
    with pytest.raises(kinengine.ParameterizationError, match="unknown rotation parameterization"):
        inverse_kinematics(robot, np.zeros(6), position="cartesian", rotation="euler")
    with pytest.raises(kinengine.ConfigurationError, match="q0"):
        inverse_kinematics(robot, np.eye(4), q0=np.zeros(5))
    with pytest.raises(kinengine.ConfigurationError, match="nullspace_target"):
        inverse_kinematics(robot, np.eye(4), nullspace_target=[np.nan] * 6)
    with pytest.raises(kinengine.FrameNotFoundError):
        inverse_kinematics(robot, np.eye(4), "tool9")
    with pytest.raises(kinengine.OptionError, match="restarts"):
        inverse_kinematics(robot, np.eye(4), restarts=-1)
