"""Task stacks (FrameTask entries with their own parameterizations, rows, relative_to and weight),
on_singularity="raise" | "nan" on analytic_jacobian / pose_parameters / task, singularity_distances, a
failed update that leaves every attribute new, and the RepresentationSingularityError message about the
robot's own rank."""

from __future__ import annotations

import pickle
import tracemalloc

import numpy as np
import pytest

import kinengine
from kinengine import FrameTask
from kinengine.parameterizations import get_position, get_rotation

REGULAR = np.array([0.3, 0.2, -0.4, 0.5, 0.7, 1.0])
ZYZ_LOCK = np.array([0.0, 0.0, 0.0, 0.0, np.pi / 2, 0.0])  # tool0 z axis straight down; J_e0 has rank 6


@pytest.fixture(scope="module")
def stack_robot():
    return kinengine.load("abb_irb120")


def _stack(robot, **kwargs):
    return robot.task(
        [
            FrameTask("tool0", rotation="euler_zyz", weight=2.0),
            FrameTask("link_4", rotation=None, rows=("x", "y"), weight=0.5),
            FrameTask("tool0", position="spherical", rotation="quaternion", relative_to="link_2"),
            FrameTask("link_6", position=None, rotation="euler_xyz", rows=("chi2_y",), relative_to="link_1"),
        ],
        **kwargs,
    )


def _expected(robot, q):
    """Stacked χ and J_A from the Robot's single calls."""
    parts = [
        (
            robot.pose_parameters(q, "tool0", "cartesian", "euler_zyz"),
            robot.analytic_jacobian(q, "tool0", "cartesian", "euler_zyz"),
        ),
        (
            robot.pose_parameters(q, "link_4", "cartesian", None)[:2],
            robot.analytic_jacobian(q, "link_4", "cartesian", None, rows=("x", "y")),
        ),
        (
            robot.pose_parameters(q, "tool0", "spherical", "quaternion", relative_to="link_2"),
            robot.analytic_jacobian(q, "tool0", "spherical", "quaternion", relative_to="link_2"),
        ),
        (
            robot.pose_parameters(q, "link_6", None, "euler_xyz", relative_to="link_1", rows=("chi2_y",)),
            robot.analytic_jacobian(q, "link_6", None, "euler_xyz", relative_to="link_1", rows=("chi2_y",)),
        ),
    ]
    return np.concatenate([c for c, _ in parts]), np.concatenate([J for _, J in parts])


def test_stack_equals_the_single_calls(stack_robot):
    robot = stack_robot
    task = _stack(robot, continuous=False)
    assert task.chi.shape == (6 + 2 + 7 + 1,) and task.analytic_jacobian.shape == (16, 6)
    assert task.pose.shape == (4, 4, 4) and task.jacobian.shape == (24, 6)
    assert task.row_labels[:8] == (
        "tool0:x",
        "tool0:y",
        "tool0:z",
        "tool0:chi1_z",
        "tool0:chi2_y",
        "tool0:chi3_z",
        "link_4:x",
        "link_4:y",
    )
    np.testing.assert_array_equal(task.weights, [2.0] * 6 + [0.5] * 2 + [1.0] * 8)
    rng = np.random.default_rng(7)
    for q in [REGULAR] + list(robot.random_configuration(rng, size=3)):
        task.update(q)
        chi, JA = _expected(robot, q)
        np.testing.assert_allclose(task.chi, chi, rtol=0, atol=1e-12)
        np.testing.assert_allclose(task.analytic_jacobian, JA, rtol=0, atol=1e-11)
        np.testing.assert_allclose(
            task.pose[2], robot.relative_pose(q, "tool0", relative_to="link_2"), atol=1e-14
        )
        np.testing.assert_allclose(
            task.jacobian[12:18],
            robot.relative_jacobian(q, "tool0", relative_to="link_2"),
            rtol=0,
            atol=1e-13,
        )
        np.testing.assert_allclose(task.jacobian[6:12], robot.jacobian(q, "link_4"), rtol=0, atol=1e-14)


def test_stack_rates_equal_finite_differences(stack_robot):
    robot = stack_robot
    task, probe = _stack(robot, continuous=False), _stack(robot, continuous=False)
    rng = np.random.default_rng(8)
    h = 1e-6
    for q in [REGULAR, np.array([-0.5, 0.4, 0.3, -1.0, 1.1, -0.3])]:
        qdot = rng.uniform(-1, 1, 6)
        task.update(q, qdot)
        JA, J = task.analytic_jacobian.copy(), task.jacobian.copy()
        probe.update(q + h * qdot)
        JAp, Jp, chip = probe.analytic_jacobian.copy(), probe.jacobian.copy(), probe.chi.copy()
        probe.update(q - h * qdot)
        JAm, Jm, chim = probe.analytic_jacobian.copy(), probe.jacobian.copy(), probe.chi.copy()
        np.testing.assert_allclose(task.jacobian_dot, (Jp - Jm) / (2 * h), rtol=0, atol=1e-7)
        np.testing.assert_allclose(task.analytic_jacobian_dot, (JAp - JAm) / (2 * h), rtol=0, atol=1e-6)
        np.testing.assert_allclose(task.chi_dot, (chip - chim) / (2 * h), rtol=0, atol=1e-7)
        np.testing.assert_allclose(task.twist, J @ qdot, rtol=0, atol=1e-13)
        np.testing.assert_allclose(task.chi_dot, JA @ qdot, rtol=0, atol=1e-13)


def test_string_entries_take_the_call_arguments_and_single_calls_keep_working(stack_robot):
    robot = stack_robot
    task = robot.task(
        ["tool0", FrameTask("link_4", rotation=None)], rotation="quaternion", relative_to="link_1"
    )
    task.update(REGULAR)
    np.testing.assert_allclose(
        task.chi[:7],
        robot.pose_parameters(REGULAR, "tool0", "cartesian", "quaternion", relative_to="link_1"),
        atol=1e-13,
    )
    np.testing.assert_allclose(task.chi[7:], robot.frame_pose(REGULAR, "link_4")[:3, 3], atol=1e-14)
    single = robot.task(FrameTask("tool0", rotation="euler_zyz"))
    single.update(REGULAR)
    assert single.pose.shape == (4, 4)
    with pytest.raises(kinengine.OptionError, match="FrameTask"):
        robot.task([3])
    for bad in (-1.0, True, np.nan, "1"):
        with pytest.raises(kinengine.OptionError, match="weight"):
            FrameTask("tool0", weight=bad)
    weighted = FrameTask("tool0", rows="x", weight=np.float32(2.5))  # numpy scalars, one label as a row
    assert type(weighted.weight) is float and weighted.weight == 2.5 and weighted.rows == ("x",)
    with pytest.raises(kinengine.OptionError, match="on_singularity"):
        robot.task("tool0", on_singularity="ignore")
    with pytest.raises(kinengine.FrameNotFoundError):
        robot.task(FrameTask("tool0", relative_to="nowhere"))


def test_stack_update_allocates_no_numpy_memory(stack_robot):
    robot = stack_robot
    task = _stack(robot)
    q, qdot = REGULAR.copy(), np.full(6, 0.1)
    task.update(q, qdot)
    numpy_domain = tracemalloc.DomainFilter(True, np.lib.tracemalloc_domain)
    tracemalloc.start()
    try:
        task.update(q, qdot)
        task.update(q)  # end as the loop ends: a frame holds its last Pinocchio Jacobian till the next update
        before = tracemalloc.take_snapshot().filter_traces([numpy_domain])
        for _ in range(50):
            task.update(q, qdot)
            task.update(q)
        after = tracemalloc.take_snapshot().filter_traces([numpy_domain])
    finally:
        tracemalloc.stop()
    grown = sum(stat.size_diff for stat in after.compare_to(before, "filename"))
    assert grown <= 0, grown


def test_singularity_distances_are_each_parameterizations_own(stack_robot):
    robot = stack_robot
    task = _stack(robot, continuous=False)
    assert task.singularity_labels == (
        "tool0:cartesian",
        "tool0:euler_zyz",
        "link_4:cartesian",
        "tool0:spherical",
        "tool0:quaternion",
        "link_6:euler_xyz",
    )
    task.update(REGULAR)
    T = robot.frame_pose(REGULAR, "tool0")
    T_rel = robot.relative_pose(REGULAR, "tool0", relative_to="link_2")
    C6 = robot.relative_pose(REGULAR, "link_6", relative_to="link_1")[:3, :3]
    zyz, sph, xyz = get_rotation("euler_zyz"), get_position("spherical"), get_rotation("euler_xyz")
    expected = [
        np.inf,
        zyz.singularity_distance(zyz.from_rotation(T[:3, :3])),
        np.inf,
        sph.singularity_distance(sph.from_position(T_rel[:3, 3])),
        np.inf,
        xyz.singularity_distance(xyz.from_rotation(C6)),
    ]
    np.testing.assert_allclose(task.singularity_distances, expected, rtol=1e-12)


def test_nan_rows_only_for_the_singular_parameterization(stack_robot):
    robot = stack_robot
    task = robot.task(
        [FrameTask("tool0", rotation="euler_zyz"), FrameTask("tool0", rotation="quaternion")],
        on_singularity="nan",
    )
    task.update(ZYZ_LOCK, np.full(6, 0.2))
    JA = task.analytic_jacobian
    assert np.isnan(JA[3:6]).all() and np.isnan(task.analytic_jacobian_dot[3:6]).all()
    assert np.isnan(task.chi_dot[3:6]).all()
    assert np.isfinite(JA[:3]).all() and np.isfinite(JA[6:]).all() and np.isfinite(task.chi).all()
    assert task.singularity_distances[1] < 1e-12
    np.testing.assert_allclose(
        JA[6:], robot.analytic_jacobian(ZYZ_LOCK, "tool0", rotation="quaternion"), atol=1e-13
    )


def test_a_failed_update_leaves_every_attribute_new(stack_robot):
    robot = stack_robot
    task = robot.task("tool0", rotation="euler_zyz")
    task.update(REGULAR)
    with pytest.raises(kinengine.RepresentationSingularityError, match="not singular here"):
        task.update(ZYZ_LOCK)
    np.testing.assert_allclose(task.pose, robot.frame_pose(ZYZ_LOCK, "tool0"), atol=1e-14)
    np.testing.assert_allclose(task.jacobian, robot.jacobian(ZYZ_LOCK, "tool0"), atol=1e-14)
    C = get_rotation("euler_zyz").to_rotation(task.chi[3:])
    np.testing.assert_allclose(C, robot.frame_pose(ZYZ_LOCK, "tool0")[:3, :3], atol=1e-12)
    np.testing.assert_allclose(task.chi[:3], robot.frame_pose(ZYZ_LOCK, "tool0")[:3, 3], atol=1e-14)
    assert np.isnan(task.analytic_jacobian[3:]).all() and np.isfinite(task.analytic_jacobian[:3]).all()


def test_message_says_whether_the_robot_itself_is_singular(stack_robot):
    robot = stack_robot
    with pytest.raises(kinengine.RepresentationSingularityError) as home:  # q5 = 0: the wrist is singular
        robot.analytic_jacobian(np.zeros(6), "tool0")
    assert "The robot itself is also kinematically singular here (rank 5 of 6)" in str(home.value)
    assert home.value.robot_rank == 5 and home.value.full_rank == 6
    with pytest.raises(kinengine.RepresentationSingularityError) as regular:
        robot.analytic_jacobian(ZYZ_LOCK, "tool0", rotation="euler_zyz")
    assert "The robot itself is not singular here (rank 6 of 6)" in str(regular.value)
    for error in (home.value, regular.value):
        copy = pickle.loads(pickle.dumps(error))
        assert str(copy) == str(error) and copy.robot_rank == error.robot_rank
    for call in (
        lambda: robot.task("tool0").update(np.zeros(6)),
        lambda: robot.analytic_jacobian(np.zeros((3, 6)), "tool0"),
        lambda: robot.analytic_jacobian(np.zeros((300, 6)), "tool0"),
        lambda: robot.pose_parameters(np.zeros(6), "tool0", on_singularity="raise"),
    ):
        with pytest.raises(
            kinengine.RepresentationSingularityError, match=r"also kinematically singular.*5 of 6"
        ):
            call()


@pytest.mark.parametrize("n", [3, 300])  # the row-by-row path and the vectorized chain
def test_batch_nan_only_in_the_rows_of_singular_configurations(stack_robot, n):
    robot = stack_robot
    Q = robot.random_configuration(np.random.default_rng(9), size=n)
    Q[1] = 0.0  # exactly at the ZYX gimbal lock
    Q[2] = [0.0, 0.0, 0.0, 0.0, 1e-9, 0.0]  # 1e-9 from it: E's entries would be ~1e9
    JA = robot.analytic_jacobian(Q, "tool0", on_singularity="nan")
    assert np.isnan(JA[1:3, 3:]).all() and np.isfinite(JA[1:3, :3]).all()
    others = np.r_[0, 3:n]
    assert np.isfinite(JA[others]).all() and np.abs(JA[others]).max() < 1e6
    for i in others[:3]:
        np.testing.assert_allclose(JA[i], robot.analytic_jacobian(Q[i], "tool0"), rtol=0, atol=1e-12)
    single = robot.analytic_jacobian(Q[2], "tool0", on_singularity="nan")
    assert np.isnan(single[3:]).all() and np.isfinite(single[:3]).all()
    chi = robot.pose_parameters(Q, "tool0", on_singularity="nan")
    assert np.isnan(chi[1:3, 3:]).all() and np.isfinite(chi[others]).all() and np.isfinite(chi[:, :3]).all()
    with pytest.raises(kinengine.RepresentationSingularityError, match="row 1 of the batch"):
        robot.analytic_jacobian(Q, "tool0")
