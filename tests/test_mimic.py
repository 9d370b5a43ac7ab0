"""Mimic joints of every shape issue 12 names, against the independent reference and finite differences.

Shapes (tests/custom_robots.py): a continuous joint following a revolute one, a mimic joint sorted
before its leader, a mimic of a mimic (multiplier and offset composed), a prismatic joint following a
revolute one with an offset, and all of them in one tree (``mimic_chain_urdf``); hypothesis trees with
the same shapes. Checked: the coordinate map, poses and Jacobians (three references) against
:mod:`kinengine.reference` (yourdfpy + numpy) and central differences, J̇ (three references), the
kinematic and analytic Hessians and the Task's rates against central differences of kinengine's own
Jacobians, and ``kinengine.verify``. Frames: I = root link frame; Jacobian rows [linear; angular].
The mimic-narrowed joint limits: enforced when a range is left, warned about once otherwise.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from custom_robots import MIMIC_SHAPES, mimic_chain_urdf, robotiq_like_gripper_urdf
from finite_differences import assert_close_relative as _assert_close_relative
from finite_differences import pose_jacobian_fd
from hypothesis import given, settings
from hypothesis import strategies as st
from urdf_strategies import random_urdfs

import kinengine
from kinengine.reference import REFERENCES, ReferenceKinematics
from kinengine.verify import verify

TEXTS = {**MIMIC_SHAPES, "all_shapes": mimic_chain_urdf()}
H = 1e-6  # central-difference step [rad | m]
FD_RTOL = 1e-7  # central differences with h = 1e-6: O(h²) truncation, O(ε/h) rounding


@pytest.fixture(scope="module", params=list(TEXTS))
def case(request):
    text = TEXTS[request.param]
    robot = kinengine.load_urdf_string(text)
    ref = ReferenceKinematics.from_urdf_string(text, joint_names=robot.joint_names)
    return robot, ref


def _configurations(robot, n: int = 3, seed: int = 0) -> np.ndarray:
    """(n + 1, dof): a random point inside the limits, and n in [-2, 2] (outside limits too: the maps are global)."""
    rng = np.random.default_rng(seed)
    return np.vstack([robot.random_configuration(rng), rng.uniform(-2, 2, (n, robot.dof))])


def assert_close_relative(actual: np.ndarray, expected: np.ndarray, rtol: float, what: str = "") -> None:
    """finite_differences.assert_close_relative, also for the empty arrays of a 0-dof tree."""
    assert actual.shape == expected.shape, (what, actual.shape, expected.shape)
    if expected.size:
        _assert_close_relative(actual, expected, rtol, what)


def _fd(f, q: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """d/dt f(q + t·direction) at t = 0 by central differences."""
    return (f(q + H * direction) - f(q - H * direction)) / (2 * H)


# -- the coordinate map ----------------------------------------------------------------------------
def test_mimic_chains_compose_multiplier_and_offset():
    robot = kinengine.load_urdf_string(TEXTS["mimic_of_mimic"])
    assert robot.joint_names == ("proximal",)
    # middle = 1.2·q + 0.1, distal = 0.8·middle − 0.2 = 0.96·q − 0.12
    np.testing.assert_allclose(robot.pinocchio_configuration([0.5]), [0.5, 0.7, 0.36], rtol=0, atol=1e-15)
    chain = kinengine.load_urdf_string(TEXTS["all_shapes"])
    assert chain.joint_names == ("shoulder", "elbow", "wrist", "z_leader")
    q = np.array([0.1, 0.2, 0.3, 0.4])
    a = -0.5 * 0.4 + 0.2  # a_mimic follows z_leader
    b = 1.5 * a - 0.1  # b_mimic follows a_mimic
    c = 0.1 * b + 0.02  # c_mimic (prismatic) follows b_mimic
    expected = {
        "shoulder": 0.1,
        "elbow": 0.2,
        "spin_continuous": 2 * 0.2 + 0.5,
        "follow_wrist": -0.3,
        "wrist": 0.3,
        "a_mimic": a,
        "b_mimic": b,
        "c_mimic": c,
        "z_leader": 0.4,
    }
    names = [chain.pinocchio_model().names[i] for i in range(1, chain.pinocchio_model().njoints)]
    np.testing.assert_allclose(
        chain.pinocchio_configuration(q), [expected[n] for n in names], rtol=0, atol=1e-15
    )


def test_the_pinocchio_model_has_one_plain_joint_per_movable_joint(case):
    robot, _ = case
    model = robot.pinocchio_model()
    movable = [j for j in robot.description.joints if j.movable]
    assert model.nq == model.nv == len(movable) and list(model.names)[1:] == [j.name for j in movable]
    assert all(model.joints[i].nq == 1 for i in range(1, model.njoints))


def test_a_mimic_joint_sorted_before_its_leader_comes_first_in_pinocchio():
    robot = kinengine.load_urdf_string(TEXTS["mimic_before_leader"])
    assert list(robot.pinocchio_model().names)[1:] == ["a_cylinder_joint", "b_arm_joint"]
    np.testing.assert_allclose(robot.pinocchio_configuration([1.0]), [0.6, 1.0], rtol=0, atol=1e-15)


# -- poses and Jacobians ---------------------------------------------------------------------------
def test_poses_and_jacobians_match_the_reference(case):
    robot, ref = case
    for q in _configurations(robot):
        for frame in robot.frame_names:
            np.testing.assert_allclose(
                robot.frame_pose(q, frame), ref.frame_pose(q, frame), rtol=0, atol=1e-12, err_msg=frame
            )
            for reference in REFERENCES:
                np.testing.assert_allclose(
                    robot.jacobian(q, frame, reference),
                    ref.jacobian(q, frame, reference),
                    rtol=0,
                    atol=1e-12,
                    err_msg=f"{frame} {reference}",
                )


def test_jacobians_match_finite_differences_of_poses(case):
    robot, _ = case
    for q in _configurations(robot, seed=1):
        for frame in robot.frame_names:
            for reference in REFERENCES:
                J_fd = pose_jacobian_fd(lambda x: robot.frame_pose(x, frame), q, reference)
                assert_close_relative(
                    robot.jacobian(q, frame, reference), J_fd, FD_RTOL, f"{frame} {reference}"
                )


# -- derivatives -----------------------------------------------------------------------------------
def _leaf_frames(robot) -> list[str]:
    parents = {j.parent for j in robot.description.joints}
    return [link.name for link in robot.description.links if link.name not in parents]


def test_jacobian_time_variation_matches_finite_differences_in_every_reference(case):
    robot, _ = case
    rng = np.random.default_rng(2)
    for q in _configurations(robot, seed=2):
        qdot = rng.uniform(-1, 1, robot.dof)
        for frame in _leaf_frames(robot):
            for reference in REFERENCES:
                expected = _fd(lambda x: robot.jacobian(x, frame, reference), q, qdot)
                assert_close_relative(
                    robot.jacobian_time_variation(q, qdot, frame, reference),
                    expected,
                    FD_RTOL,
                    f"J̇ {frame} {reference}",
                )


def test_kinematic_hessian_matches_finite_differences_in_every_reference(case):
    robot, _ = case
    for q in _configurations(robot, seed=3):
        for frame in _leaf_frames(robot):
            for reference in REFERENCES:
                H_fd = np.stack(
                    [_fd(lambda x: robot.jacobian(x, frame, reference), q, e) for e in np.eye(robot.dof)],
                    axis=-1,
                )
                H_k = robot.kinematic_hessian(q, frame, reference)
                assert H_k.shape == (6, robot.dof, robot.dof)
                assert_close_relative(H_k, H_fd, FD_RTOL, f"∂J/∂q {frame} {reference}")


@pytest.mark.parametrize("rotation", ["euler_zyx", "quaternion", "rotation_vector"])
def test_analytic_hessian_matches_finite_differences(case, rotation):
    robot, _ = case
    for q in _configurations(robot, seed=4):
        for frame in _leaf_frames(robot):

            def JA(x):
                return robot.analytic_jacobian(x, frame, "cartesian", rotation)

            H_fd = np.stack([_fd(JA, q, e) for e in np.eye(robot.dof)], axis=-1)
            assert_close_relative(
                robot.analytic_hessian(q, frame, "cartesian", rotation),
                H_fd,
                1e-6,
                f"∂J_A/∂q {frame} {rotation}",
            )


def test_task_rates_match_finite_differences(case):
    robot, _ = case
    frames = _leaf_frames(robot)
    task = robot.task(frames, "cartesian", "euler_zyx", continuous=False)
    rng = np.random.default_rng(5)
    for q in _configurations(robot, seed=5):
        qdot = rng.uniform(-1, 1, robot.dof)
        task.update(q, qdot)
        J = np.vstack([robot.jacobian(q, f) for f in frames])
        JA = np.vstack([robot.analytic_jacobian(q, f) for f in frames])
        np.testing.assert_allclose(task.jacobian, J, rtol=0, atol=1e-13)
        np.testing.assert_allclose(task.analytic_jacobian, JA, rtol=0, atol=1e-12)
        np.testing.assert_allclose(task.twist, J @ qdot, rtol=0, atol=1e-13)
        np.testing.assert_allclose(task.chi_dot, JA @ qdot, rtol=0, atol=1e-12)
        chi = lambda x: np.concatenate([robot.pose_parameters(x, f) for f in frames])  # noqa: E731
        assert_close_relative(task.chi_dot, _fd(chi, q, qdot), FD_RTOL, "χ̇")
        Jdot_fd = _fd(lambda x: np.vstack([robot.jacobian(x, f) for f in frames]), q, qdot)
        assert_close_relative(task.jacobian_dot, Jdot_fd, FD_RTOL, "J̇_e0")
        JAdot_fd = _fd(lambda x: np.vstack([robot.analytic_jacobian(x, f) for f in frames]), q, qdot)
        assert_close_relative(task.analytic_jacobian_dot, JAdot_fd, 1e-6, "J̇_A")


def test_verify_passes(case):
    robot, _ = case
    report = verify(robot, samples=5)
    assert report.passed, report.table()


# -- limits narrowed by mimic joints ---------------------------------------------------------------
def test_a_gripper_whose_mimic_limits_collapse_its_leader_warns_once_and_keeps_moving():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = kinengine.load_urdf_string(robotiq_like_gripper_urdf())
    messages = [str(w.message) for w in caught]
    assert len(messages) == 1, messages
    assert (
        "only one value of joint 'finger_joint' keeps it within its limits and mimic joint "
        "'left_inner_finger_joint' = -1·q + 0 within [0, 0.8757]; the mimic joint's limits are not enforced"
        in messages[0]
    )
    assert "likewise mimic joint 'right_inner_finger_joint'" in messages[0]
    assert "'finger_joint' keeps [0, 0.8]" in messages[0]
    # the leader keeps its own limits (the inner knuckle, multiplier 1 within [0, 0.8757], narrows nothing)
    np.testing.assert_array_equal([robot.lower_limits, robot.upper_limits], [[0.0], [0.8]])
    robot.check_configuration([0.5])  # within limits: no error
    samples = robot.random_configuration(rng=0, size=200)[:, 0]
    assert samples.min() < 0.1 and samples.max() > 0.7
    # it moves: the inner finger turns by −q, the outer knuckle by q
    np.testing.assert_allclose(robot.pinocchio_configuration([0.5]), [0.5, -0.5, 0.5, 0.5, -0.5], atol=1e-15)
    assert not np.allclose(
        robot.frame_pose([0.0], "left_inner_finger"), robot.frame_pose([0.5], "left_inner_finger")
    )
    target = robot.frame_pose([0.6], "left_inner_finger")[:3, 3]
    result = robot.inverse_kinematics(target, "left_inner_finger", q0=[0.1], position="cartesian")
    assert result.success and abs(result.q[0] - 0.6) < 1e-5
    assert verify(robot, samples=5).passed


def test_mimic_limits_that_leave_a_range_are_enforced():
    robot = kinengine.load_urdf_string(TEXTS["mimic_of_mimic"])
    # middle = 1.2·q + 0.1 within [-1.5, 1.5]  <=>  q within [-4/3, 7/6]; distal = 0.96·q − 0.12 narrows nothing more
    np.testing.assert_allclose([robot.lower_limits[0], robot.upper_limits[0]], [-4 / 3, 7 / 6], rtol=1e-15)
    with pytest.raises(kinengine.ConfigurationError, match="narrowed so that mimic joint 'middle'"):
        robot.frame_pose([1.2], check_limits=True)
    middle = 1.2 * robot.random_configuration(rng=1, size=500)[:, 0] + 0.1
    assert middle.min() >= -1.5 and middle.max() <= 1.5


# -- hypothesis: random trees with every mimic shape -------------------------------------------------
@pytest.mark.slow
@settings(max_examples=40, deadline=None)
@given(random_urdfs(max_links=7), st.integers(0, 2**32 - 1))
def test_random_trees_with_mimic_shapes_match_the_reference_and_finite_differences(text, seed):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # collapsing mimic limits are warned about
        robot = kinengine.load_urdf_string(text)
    ref = ReferenceKinematics.from_urdf_string(text, joint_names=robot.joint_names)
    rng = np.random.default_rng(seed)
    q, qdot = rng.uniform(-2, 2, robot.dof), rng.uniform(-1, 1, robot.dof)
    for frame in robot.frame_names:
        np.testing.assert_allclose(robot.frame_pose(q, frame), ref.frame_pose(q, frame), rtol=0, atol=1e-12)
        for reference in REFERENCES:
            J = robot.jacobian(q, frame, reference)
            np.testing.assert_allclose(J, ref.jacobian(q, frame, reference), rtol=0, atol=1e-12)
            J_fd = pose_jacobian_fd(lambda x: robot.frame_pose(x, frame), q, reference)
            assert_close_relative(J, J_fd, FD_RTOL, f"{frame} {reference}")
    frame = robot.end_effector
    for reference in REFERENCES:
        expected = _fd(lambda x: robot.jacobian(x, frame, reference), q, qdot)
        assert_close_relative(
            robot.jacobian_time_variation(q, qdot, frame, reference), expected, FD_RTOL, "J̇"
        )
        H_k = robot.kinematic_hessian(q, frame, reference)
        np.testing.assert_allclose(
            H_k @ qdot, robot.jacobian_time_variation(q, qdot, frame, reference), rtol=0, atol=1e-11
        )


def test_a_mimic_joint_named_like_a_link_matches_the_reference():
    """A joint and a link of one name (allowed by URDF) where Pinocchio cannot lock the mimic joint into a
    reduced model (found by test_fuzz_urdf: a raw ValueError before): the general path answers."""
    limit = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'
    urdf = f"""<robot name="same_names">
      <link name="base"/><link name="a"/><link name="j2"/><link name="c"/>
      <joint name="j1" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>{limit}</joint>
      <joint name="j2" type="revolute"><parent link="a"/><child link="j2"/><origin xyz="0.1 0 0"/>
        <axis xyz="0 1 0"/>{limit}<mimic joint="j1" multiplier="2" offset="0.1"/></joint>
      <joint name="j3" type="revolute"><parent link="j2"/><child link="c"/><origin xyz="0.1 0 0.05"/>
        <axis xyz="0 1 0"/>{limit}</joint>
    </robot>"""
    robot = kinengine.load_urdf_string(urdf)
    ref = ReferenceKinematics.from_urdf_string(urdf, joint_names=robot.joint_names)
    for q in robot.random_configuration(rng=0, size=5):
        for frame in robot.frame_names:
            np.testing.assert_allclose(robot.frame_pose(q, frame), ref.frame_pose(q, frame), atol=1e-12)
            for reference in REFERENCES:
                np.testing.assert_allclose(
                    robot.jacobian(q, frame, reference), ref.jacobian(q, frame, reference), atol=1e-12
                )
