"""The controller Task: one update equals the Robot's single calls, rates equal finite differences,
nothing is allocated per update, and χ stays continuous along trajectories."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest
from custom_robots import mixed_chain_urdf
from finite_differences import assert_close_relative
from scipy.spatial.transform import Rotation

import kinengine

CASES = [
    ("abb_irb120", "tool0", "cartesian", "euler_zyz"),
    ("abb_irb120", "tool0", "spherical", "quaternion"),
    ("ur5", "tool0", "cylindrical", "rotation_vector"),
    ("panda", "panda_hand", "cartesian", "angle_axis"),
    ("kinova", None, "cartesian", "rotation_matrix"),  # continuous joints
    ("baxter", "l_gripper_r_finger", "cartesian", "euler_xyz"),  # below a mimic joint
    ("mixed", "side", "spherical", "euler_zyx"),  # a branch: only some joints move it
    ("mixed", "finger_b", "cartesian", "quaternion"),  # mimic with multiplier and offset
]


def _load(name):
    return kinengine.load_urdf_string(mixed_chain_urdf()) if name == "mixed" else kinengine.load(name)


def _regular_q(robot, frame, position, rotation, rng):
    while True:
        q = robot.random_configuration(rng)
        try:
            robot.analytic_jacobian(q, frame, position, rotation, singularity_threshold=0.1)
        except kinengine.RepresentationSingularityError:
            continue
        T = robot.frame_pose(q, frame)
        if np.linalg.norm(Rotation.from_matrix(T[:3, :3]).as_rotvec()) < np.pi - 0.1:
            return q


@pytest.mark.parametrize("name,frame,position,rotation", CASES)
def test_update_equals_single_calls_and_rates_equal_finite_differences(name, frame, position, rotation):
    robot = _load(name)
    frame = frame or robot.end_effector
    rng = np.random.default_rng(5)
    task = robot.task(frame, position=position, rotation=rotation, continuous=False)
    for _ in range(3):
        q = _regular_q(robot, frame, position, rotation, rng)
        qdot = rng.normal(size=robot.dof)
        task.update(q, qdot)
        J = robot.jacobian(q, frame)
        np.testing.assert_allclose(task.pose, robot.frame_pose(q, frame), rtol=0, atol=1e-14)
        np.testing.assert_allclose(task.jacobian, J, rtol=0, atol=1e-13)
        np.testing.assert_allclose(
            task.chi, robot.pose_parameters(q, frame, position, rotation), rtol=0, atol=1e-13
        )
        JA = robot.analytic_jacobian(q, frame, position, rotation)
        np.testing.assert_allclose(task.analytic_jacobian, JA, rtol=0, atol=1e-12)
        np.testing.assert_allclose(task.twist, J @ qdot, rtol=0, atol=1e-13)
        np.testing.assert_allclose(task.chi_dot, JA @ qdot, rtol=0, atol=1e-12)
        h = 1e-6
        Jdot_fd = (robot.jacobian(q + h * qdot, frame) - robot.jacobian(q - h * qdot, frame)) / (2 * h)
        assert_close_relative(task.jacobian_dot, Jdot_fd, 1e-6, "J_e0 dot")
        JAdot_fd = (
            robot.analytic_jacobian(q + h * qdot, frame, position, rotation)
            - robot.analytic_jacobian(q - h * qdot, frame, position, rotation)
        ) / (2 * h)
        assert_close_relative(task.analytic_jacobian_dot, JAdot_fd, 1e-6, "J_A dot")


def test_several_frames_are_stacked():
    robot = kinengine.load("baxter")
    frames = ["left_gripper", "right_gripper"]
    task = robot.task(frames, position="cartesian", rotation="quaternion")
    q = robot.random_configuration(3)
    task.update(q)
    assert task.pose.shape == (2, 4, 4)
    assert task.chi.shape == (14,) and task.analytic_jacobian.shape == (14, robot.dof)
    assert task.jacobian.shape == (12, robot.dof)
    for i, frame in enumerate(frames):
        np.testing.assert_allclose(
            task.jacobian[6 * i : 6 * i + 6], robot.jacobian(q, frame), rtol=0, atol=1e-13
        )
        np.testing.assert_allclose(
            task.analytic_jacobian[7 * i : 7 * i + 7],
            robot.analytic_jacobian(q, frame, "cartesian", "quaternion"),
            rtol=0,
            atol=1e-12,
        )


def test_rows_select_operational_space_coordinates():
    robot = kinengine.load("scara")
    task = robot.task("ee", rotation="euler_zyx", rows=("x", "y", "z", "chi1_z"))
    q = robot.random_configuration(1)
    task.update(q, np.ones(4))
    np.testing.assert_allclose(
        task.analytic_jacobian,
        robot.analytic_jacobian(q, "ee", rotation="euler_zyx", rows=("x", "y", "z", "chi1_z")),
        rtol=0,
        atol=1e-13,
    )
    assert task.chi.shape == (4,) and task.labels == ("x", "y", "z", "chi1_z")


def test_attributes_are_read_only_and_preallocated():
    robot = kinengine.load("abb_irb120")
    task = robot.task("tool0", rotation="euler_zyz")
    buffers = {
        name: getattr(task, name).__array_interface__["data"][0]
        for name in ("pose", "chi", "jacobian", "analytic_jacobian", "jacobian_dot", "twist")
    }
    task.update(robot.random_configuration(0), np.ones(6))
    task.update(robot.random_configuration(1), np.ones(6))
    for name, address in buffers.items():
        assert getattr(task, name).__array_interface__["data"][0] == address
        with pytest.raises(ValueError):
            getattr(task, name)[...] = 0.0


@pytest.mark.parametrize("name,frame,position,rotation", [CASES[0], CASES[4], CASES[6]])
def test_update_allocates_no_numpy_memory(name, frame, position, rotation):
    robot = _load(name)
    frame = frame or robot.end_effector
    task = robot.task(frame, position=position, rotation=rotation)
    rng = np.random.default_rng(0)
    qs = [_regular_q(robot, frame, position, rotation, rng) for _ in range(4)]
    qdot = np.ones(robot.dof)
    numpy_domain = tracemalloc.DomainFilter(True, np.lib.tracemalloc_domain)
    tracemalloc.start()
    try:
        # warm up, ending as the loop ends (each frame holds its last Pinocchio Jacobian until the next update)
        for q in qs:
            task.update(q, qdot)
            task.update(q)
        before = tracemalloc.take_snapshot().filter_traces([numpy_domain])
        for _ in range(50):
            for q in qs:
                task.update(q, qdot)
                task.update(q)
        after = tracemalloc.take_snapshot().filter_traces([numpy_domain])
    finally:
        tracemalloc.stop()
    grown = [s for s in after.compare_to(before, "lineno") if s.size_diff > 0 or s.count_diff > 0]
    assert grown == []


def test_input_checks_are_on_by_default_and_can_be_switched_off():
    robot = kinengine.load("abb_irb120")
    task = robot.task("tool0", rotation="quaternion")
    with pytest.raises(kinengine.ConfigurationError, match=r"shape \(6,\)"):
        task.update(np.zeros(5))
    with pytest.raises(kinengine.ConfigurationError, match="qdot"):
        task.update(np.zeros(6), np.array([np.nan] * 6))
    fast = robot.task("tool0", rotation="quaternion", check_inputs=False)
    q = robot.random_configuration(2)
    fast.update(q)
    task.update(q)
    np.testing.assert_array_equal(fast.analytic_jacobian, task.analytic_jacobian)


def test_task_raises_at_representation_singularity():
    robot = kinengine.load("abb_irb120")
    task = robot.task("tool0", rotation="euler_zyx")
    with pytest.raises(kinengine.RepresentationSingularityError, match="euler_zyx"):
        task.update(robot.neutral())


@pytest.mark.parametrize(
    "rotation", ["euler_zyx", "euler_zyz", "quaternion", "rotation_vector", "angle_axis"]
)
def test_chi_stays_continuous_along_a_trajectory_and_reset_returns_to_canonical(rotation):
    """Spin joint 6 through several turns: canonical χ jumps (2π, sign, branch cut), the task's does not."""
    robot = kinengine.load("abb_irb120")
    task = robot.task("tool0", position=None, rotation=rotation)
    q = np.array([0.3, 0.2, -0.4, 0.5, 0.7, -6.5])
    previous = None
    for t in np.linspace(0.0, 13.0, 1301):  # joint 6 sweeps about two turns in steps of 0.01 rad
        q[5] = -6.5 + t
        task.update(q)
        if previous is not None:
            assert np.max(np.abs(task.chi - previous)) < 0.1
        previous = task.chi.copy()
        # always the same pose as the canonical parameters
        C = robot.pose_parameters(q, "tool0", None, rotation)
        R = kinengine.parameterizations.get_rotation(rotation)
        np.testing.assert_allclose(R.to_rotation(task.chi), R.to_rotation(C), rtol=0, atol=1e-9)
    task.reset()
    task.update(q)
    np.testing.assert_allclose(
        task.chi, robot.pose_parameters(q, "tool0", None, rotation), rtol=0, atol=1e-12
    )


def test_a_task_without_frames_is_an_option_error():
    robot = kinengine.load("abb_irb120")
    with pytest.raises(kinengine.OptionError, match="at least one frame"):
        robot.task([])


@pytest.mark.parametrize("rows", [None, ("x", "z", "chi2_y")])
def test_rates_are_nan_after_an_update_without_qdot_never_stale(rows):
    robot = kinengine.load("abb_irb120")
    rng = np.random.default_rng(5)
    q1, q2, q3 = robot.random_configuration(rng, size=3)
    qdot = rng.uniform(-1, 1, robot.dof)
    # continuous=False: across these random jumps a continuous task may pick the other Euler solution,
    # whose rates differ from the canonical one's
    task = robot.task("tool0", rotation="euler_zyx", rows=rows, continuous=False)
    rates = ("twist", "chi_dot", "jacobian_dot", "analytic_jacobian_dot")
    task.update(q1)
    assert all(np.isnan(getattr(task, name)).all() for name in rates)  # never filled yet
    task.update(q1, qdot)
    assert all(np.isfinite(getattr(task, name)).all() for name in rates)
    task.update(q2)
    assert all(np.isnan(getattr(task, name)).all() for name in rates)
    task.update(q3, qdot)
    fresh = robot.task("tool0", rotation="euler_zyx", rows=rows, continuous=False)
    fresh.update(q3, qdot)
    for name in rates:
        np.testing.assert_array_equal(getattr(task, name), getattr(fresh, name))
