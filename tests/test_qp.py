"""DifferentialIK (one QP per control step) and pose_error (log6): closed forms, convergence, bounds."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
import qpsolvers
from scipy.spatial.transform import Rotation

import kinengine
from kinengine import DifferentialIK, PoseTarget, PostureTarget, pose_error

REGULAR = np.array([0.3, 0.2, -0.4, 0.5, 0.7, 1.0])


@pytest.fixture(scope="module")
def abb_robot():
    return kinengine.load("abb_irb120")


def _pose(rotvec, p):
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = Rotation.from_rotvec(rotvec).as_matrix(), p
    return T


def test_pose_error_frames():
    rng = np.random.default_rng(1)
    for _ in range(10):
        T, T_target = (
            _pose(rng.normal(size=3), rng.normal(size=3)),
            _pose(rng.normal(size=3), rng.normal(size=3)),
        )
        xi = pose_error(T, T_target, "local")
        np.testing.assert_allclose(T @ pin.exp6(xi).homogeneous, T_target, atol=1e-12)
        C = T[:3, :3]
        np.testing.assert_allclose(pose_error(T, T_target), np.r_[C @ xi[:3], C @ xi[3:]], atol=1e-14)
        world = pose_error(T, T_target, "world")
        np.testing.assert_allclose(pin.exp6(world).homogeneous @ T, T_target, atol=1e-12)
        assert np.linalg.norm(xi[3:]) == pytest.approx(
            Rotation.from_matrix(C.T @ T_target[:3, :3]).magnitude(), abs=1e-12
        )
    # pure translation: the world-aligned error is the displacement itself
    T = _pose([0.3, -0.2, 0.1], [1.0, 2.0, 3.0])
    T_target = T.copy()
    T_target[:3, 3] += [0.1, -0.2, 0.05]
    np.testing.assert_allclose(pose_error(T, T_target), [0.1, -0.2, 0.05, 0, 0, 0], atol=1e-14)
    assert pose_error(np.array([T, T]), T_target).shape == (2, 6)
    with pytest.raises(kinengine.OptionError, match="frame"):
        pose_error(T, T_target, "body")
    with pytest.raises(kinengine.OptionError, match="T_target"):
        pose_error(T, np.eye(3))


def _iterate(robot, ik, q, dt=0.1, steps=60):
    for _ in range(steps):
        qdot = ik.solve(q, dt)
        assert np.all(np.abs(qdot) <= ik.velocity_limits + 1e-9)
        q = q + qdot * dt
        assert np.all(q >= robot.lower_limits - 1e-9) and np.all(q <= robot.upper_limits + 1e-9)
    return q


def test_converges_to_a_full_pose_within_limits(abb_robot):
    robot = abb_robot
    T_target = robot.frame_pose(REGULAR, "tool0")
    ik = DifferentialIK(robot, [PoseTarget("tool0", T_target)])
    q = _iterate(robot, ik, REGULAR + np.array([0.3, -0.2, 0.25, -0.3, 0.2, 0.4]))
    np.testing.assert_allclose(robot.frame_pose(q, "tool0"), T_target, atol=1e-9)
    np.testing.assert_allclose(ik.last_error, 0.0, atol=1e-9)


def test_unconstrained_step_is_the_damped_least_squares_solution_and_bounded_steps_match_a_qp(abb_robot):
    robot = abb_robot
    T_target = robot.frame_pose(REGULAR + 0.01, "tool0")
    ik = DifferentialIK(robot, [PoseTarget("tool0", T_target, gain=0.5)], lm_damping=1e-2, damping=1e-6)
    q = REGULAR
    qdot = ik.solve(q, 0.1)
    assert ik.qp_calls == 0
    # closed form: position rows J_v, rotation rows Jlog3(C*ᵀC) Cᵀ J_ω (d log3(CᵀC*) = −that · dq)
    T, J = robot.kinematics(q, "tool0")
    C, Cs = T[:3, :3], T_target[:3, :3]
    A = np.vstack([J[:3], pin.Jlog3(Cs.T @ C) @ C.T @ J[3:]])
    e = 0.5 * np.r_[T_target[:3, 3] - T[:3, 3], pin.log3(C.T @ Cs)]
    H = A.T @ A + (1e-6 + 1e-2 * e @ e) * np.eye(6)
    np.testing.assert_allclose(qdot * 0.1, np.linalg.solve(H, A.T @ e), rtol=1e-9, atol=1e-13)
    # a far target: velocity bounds are active; DAQP's answer equals ProxQP's on the same QP
    far = DifferentialIK(robot, [PoseTarget("tool0", robot.frame_pose(-REGULAR, "tool0"))])
    slow = DifferentialIK(robot, [PoseTarget("tool0", robot.frame_pose(-REGULAR, "tool0"))], solver="proxqp")
    a, b = far.solve(REGULAR, 0.01), slow.solve(REGULAR, 0.01)
    assert far.qp_calls == 1 and np.any(np.isclose(np.abs(a), far.velocity_limits, rtol=1e-6))
    np.testing.assert_allclose(a, b, atol=1e-3)  # ProxQP stops at its default tolerance (~1e-4 here)


def test_velocity_limits_come_from_the_urdf_and_can_be_overridden(abb_robot):
    robot = abb_robot
    urdf = {j.name: j.velocity for j in robot.description.joints}
    ik = DifferentialIK(robot, [PostureTarget(np.zeros(6), 1.0)])
    np.testing.assert_array_equal(ik.velocity_limits, [urdf[n] for n in robot.joint_names])
    locked = DifferentialIK(
        robot, [PoseTarget("tool0", robot.frame_pose(-REGULAR, "tool0"))], velocity_limits={"joint_6": 0.0}
    )
    assert locked.solve(REGULAR, 0.01)[5] == 0.0
    with pytest.raises(kinengine.OptionError, match="unknown joint"):
        DifferentialIK(robot, [PostureTarget(np.zeros(6))], velocity_limits={"joint_9": 1.0})
    with pytest.raises(kinengine.OptionError, match="shape"):
        DifferentialIK(robot, [PostureTarget(np.zeros(6))], velocity_limits=[1.0, 2.0])


def test_five_dimensional_target_leaves_rotation_about_the_tool_axis_free(abb_robot):
    robot = abb_robot
    T_target = robot.frame_pose(REGULAR, "tool0")
    ik = DifferentialIK(
        robot,
        [
            PoseTarget("tool0", T_target, rows=("x", "y", "z", "rx", "ry")),
            PostureTarget(REGULAR + [0, 0, 0, 0, 0, 1.0], weight=1e-4, joints=["joint_6"]),
        ],
    )
    q = _iterate(robot, ik, REGULAR + np.array([0.2, -0.1, 0.15, -0.2, 0.1, 0.0]), steps=150)
    T = robot.frame_pose(q, "tool0")
    np.testing.assert_allclose(T[:3, 3], T_target[:3, 3], atol=1e-7)
    np.testing.assert_allclose(T[:3, 2], T_target[:3, 2], atol=1e-7)  # tool axis aligned
    assert abs(q[5] - REGULAR[5]) > 0.1  # ... and the posture task turned the free rotation


def test_relative_target_and_posture_lock_on_the_panda():
    robot = kinengine.load("panda")
    q_star = np.clip(
        np.array([0.3, -0.4, 0.2, -2.0, 0.3, 1.8, 0.5, 0.02]), robot.lower_limits, robot.upper_limits
    )
    # relative to link 1: joints 2-7 move the hand in it (6 coordinates for 6 rows)
    T_rel = robot.relative_pose(q_star, "panda_hand_tcp", relative_to="panda_link1")
    ik = DifferentialIK(
        robot,
        [
            PoseTarget("panda_hand_tcp", T_rel, relative_to="panda_link1"),
            PostureTarget(robot.neutral(), weight=1.0, joints=["panda_finger_joint1"]),
        ],
        velocity_limits={"panda_finger_joint1": 0.0},
    )
    q0 = robot.neutral()
    q0[:7] = q_star[:7] + 0.15
    q = _iterate(robot, ik, q0, steps=120)
    np.testing.assert_allclose(
        robot.relative_pose(q, "panda_hand_tcp", relative_to="panda_link1"), T_rel, atol=1e-6
    )
    assert q[7] == q0[7]  # the finger never moved


def test_at_a_kinematic_singularity_the_step_is_finite(abb_robot):
    robot = abb_robot
    ik = DifferentialIK(robot, [PoseTarget("tool0", robot.frame_pose(REGULAR, "tool0"))])
    qdot = ik.solve(np.zeros(6), 0.01)  # q5 = 0: the wrist is singular
    assert np.isfinite(qdot).all()


def test_bad_options_are_option_errors(abb_robot):
    robot = abb_robot
    with pytest.raises(kinengine.OptionError, match="rows"):
        DifferentialIK(robot, [PoseTarget("tool0", np.eye(4), rows=("x", "w"))])
    with pytest.raises(kinengine.OptionError, match="gain"):
        DifferentialIK(robot, [PoseTarget("tool0", np.eye(4), gain=2.0)])
    with pytest.raises(kinengine.OptionError, match="solver"):
        DifferentialIK(robot, [PoseTarget("tool0", np.eye(4))], solver="quadprog")
    with pytest.raises(kinengine.OptionError, match="at least one task"):
        DifferentialIK(robot, [])
    with pytest.raises(kinengine.OptionError, match="dt"):
        DifferentialIK(robot, [PoseTarget("tool0", np.eye(4))]).solve(REGULAR, 0.0)
    with pytest.raises(kinengine.FrameNotFoundError):
        DifferentialIK(robot, [PoseTarget("tool9", np.eye(4))])
    assert "daqp" in qpsolvers.available_solvers
