"""Relative kinematics: T_BA = T_IB⁻¹ T_IA and the relative Jacobian (velocity of A's origin and ω of A as
seen from B, in expressed_in's axes), checked against central finite differences of the relative pose;
the analytic Jacobian of χ(T_BA) against finite differences of χ; batches against single calls."""

from __future__ import annotations

import numpy as np
import pytest
from custom_robots import mixed_chain_urdf
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import kinengine

CASES = [  # robot, A, B, expressed_in
    ("abb_irb120", "tool0", "link_3", None),
    ("abb_irb120", "tool0", "link_3", "link_1"),
    ("abb_irb120", "link_2", "tool0", "base_link"),  # B further down the chain than A
    ("panda", "panda_hand_tcp", "panda_link3", "panda_leftfinger"),
    ("mixed", "side", "finger_b", None),  # two branches, a mimic joint
    ("mixed", "tip", "side", "l2"),
]
_ROBOTS: dict[str, kinengine.Robot] = {}


def _robot(name):
    if name not in _ROBOTS:
        _ROBOTS[name] = (
            kinengine.load_urdf_string(mixed_chain_urdf()) if name == "mixed" else kinengine.load(name)
        )
    return _ROBOTS[name]


def relative_jacobian_fd(robot, q, a, b, e, h=1e-6):
    """Columns: (p_BA(q + h e_k) − p_BA(q − h e_k)) / 2h and log(C_BA(q − h)ᵀ C_BA(q + h)) / 2h (in A),
    both rotated into e's axes."""
    e = b if e is None else e
    T = robot.relative_pose(q, a, relative_to=b)
    C_EB = robot.relative_pose(q, b, relative_to=e)[:3, :3]
    J = np.empty((6, robot.dof))
    for k in range(robot.dof):
        dq = np.zeros(robot.dof)
        dq[k] = h
        Tp, Tm = robot.relative_pose(q + dq, a, relative_to=b), robot.relative_pose(q - dq, a, relative_to=b)
        v_B = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        w_A = Rotation.from_matrix(Tm[:3, :3].T @ Tp[:3, :3]).as_rotvec() / (2 * h)
        J[:3, k] = C_EB @ v_B
        J[3:, k] = C_EB @ T[:3, :3] @ w_A
    return J


def _interior(robot, rng):
    """A random q at least 1e-3 inside the limits (central differences stay inside)."""
    lo, hi = robot.lower_limits, robot.upper_limits
    q = robot.random_configuration(rng)
    return np.clip(
        q, np.where(np.isfinite(lo), lo + 1e-3, -np.inf), np.where(np.isfinite(hi), hi - 1e-3, np.inf)
    )


@pytest.mark.parametrize("name,a,b,e", CASES)
def test_relative_pose_is_inverse_B_times_A(name, a, b, e):
    robot = _robot(name)
    q = _interior(robot, np.random.default_rng(1))
    expected = np.linalg.inv(robot.frame_pose(q, b)) @ robot.frame_pose(q, a)
    np.testing.assert_allclose(robot.relative_pose(q, a, relative_to=b), expected, rtol=0, atol=1e-13)


@pytest.mark.parametrize("name,a,b,e", CASES)
def test_relative_jacobian_equals_finite_differences_of_the_relative_pose(name, a, b, e):
    robot = _robot(name)
    rng = np.random.default_rng(2)
    for _ in range(3):
        q = _interior(robot, rng)
        J = robot.relative_jacobian(q, a, relative_to=b, expressed_in=e)
        np.testing.assert_allclose(J, relative_jacobian_fd(robot, q, a, b, e), rtol=0, atol=2e-8)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(-2.0, 2.0), min_size=6, max_size=6))
def test_relative_jacobian_fd_for_varying_q(values):
    robot = _robot("abb_irb120")
    q = np.clip(values, robot.lower_limits + 1e-3, robot.upper_limits - 1e-3)
    J = robot.relative_jacobian(q, "tool0", relative_to="link_2", expressed_in="link_5")
    np.testing.assert_allclose(
        J, relative_jacobian_fd(robot, q, "tool0", "link_2", "link_5"), rtol=0, atol=2e-8
    )


def test_relative_to_the_root_is_the_geometric_jacobian_and_a_frame_relative_to_itself_is_zero():
    robot = _robot("abb_irb120")
    q = np.array([0.3, 0.2, -0.4, 0.5, 0.7, 1.0])
    np.testing.assert_allclose(
        robot.relative_jacobian(q, "tool0", relative_to="base_link"),
        robot.jacobian(q, "tool0"),
        rtol=0,
        atol=1e-14,
    )
    np.testing.assert_allclose(
        robot.relative_jacobian(q, "tool0", relative_to="base_link", expressed_in="tool0"),
        robot.jacobian(q, "tool0", "local"),
        rtol=0,
        atol=1e-14,
    )
    np.testing.assert_allclose(robot.relative_jacobian(q, "tool0", relative_to="tool0"), 0.0, atol=1e-15)
    np.testing.assert_allclose(robot.relative_pose(q, "tool0", relative_to="tool0"), np.eye(4), atol=1e-15)


@pytest.mark.parametrize("name,a,b,e", CASES)
def test_batches_equal_single_calls(name, a, b, e):
    robot = _robot(name)
    Q = np.array([_interior(robot, np.random.default_rng(s)) for s in range(7)])
    T = robot.relative_pose(Q, a, relative_to=b)
    J = robot.relative_jacobian(Q, a, relative_to=b, expressed_in=e)
    assert T.shape == (7, 4, 4) and J.shape == (7, 6, robot.dof)
    for i, q in enumerate(Q):
        np.testing.assert_allclose(T[i], robot.relative_pose(q, a, relative_to=b), rtol=0, atol=1e-13)
        np.testing.assert_allclose(
            J[i], robot.relative_jacobian(q, a, relative_to=b, expressed_in=e), rtol=0, atol=1e-13
        )


@pytest.mark.parametrize("rotation", ["euler_zyx", "euler_zyz", "quaternion", "rotation_vector"])
@pytest.mark.parametrize("position", ["cartesian", "spherical"])
def test_analytic_jacobian_relative_to_equals_finite_differences_of_chi(position, rotation):
    robot = _robot("abb_irb120")
    rng = np.random.default_rng(3)
    Q = []
    while len(Q) < 3:
        q = _interior(robot, rng)
        chi = robot.pose_parameters(q, "tool0", position, rotation, relative_to="link_2")
        if (
            kinengine.parameterizations.get_rotation(rotation).singularity_distance(chi[3:]) > 0.2
            and np.linalg.norm(
                Rotation.from_matrix(
                    robot.relative_pose(q, "tool0", relative_to="link_2")[:3, :3]
                ).as_rotvec()
            )
            < np.pi - 0.2
        ):
            Q.append(q)
    for q in Q:
        JA = robot.analytic_jacobian(q, "tool0", position, rotation, relative_to="link_2")
        h, fd = 1e-6, np.empty_like(JA)
        for k in range(robot.dof):
            dq = np.zeros(robot.dof)
            dq[k] = h
            fd[:, k] = (
                robot.pose_parameters(q + dq, "tool0", position, rotation, relative_to="link_2")
                - robot.pose_parameters(q - dq, "tool0", position, rotation, relative_to="link_2")
            ) / (2 * h)
        np.testing.assert_allclose(JA, fd, rtol=0, atol=1e-7)
    batch = robot.analytic_jacobian(np.array(Q), "tool0", position, rotation, relative_to="link_2")
    for i, q in enumerate(Q):
        np.testing.assert_allclose(
            batch[i],
            robot.analytic_jacobian(q, "tool0", position, rotation, relative_to="link_2"),
            rtol=0,
            atol=1e-12,
        )


def test_relative_analytic_jacobian_singularity_raises_or_gives_nan_rows():
    robot = _robot("abb_irb120")
    q = np.zeros(6)  # tool0 relative to link_1: at q = 0 its ZYX pitch is at gimbal lock (as in I)
    chi = robot.pose_parameters(q, "tool0", None, "euler_zyx", relative_to="link_1", on_singularity="nan")
    assert np.isnan(chi).all()
    chi = robot.relative_pose(q, "tool0", relative_to="link_1")
    chi = kinengine.parameterizations.get_rotation("euler_zyx").from_rotation(chi[:3, :3], warn=False)
    assert abs(np.cos(chi[1])) < 1e-9
    # joint 1 moves both frames alike: the relative Jacobian has 5 columns, and q5 = 0 takes one rank away
    with pytest.raises(
        kinengine.RepresentationSingularityError, match=r"also kinematically singular.*rank 4 of 5"
    ):
        robot.analytic_jacobian(q, "tool0", relative_to="link_1")
    JA = robot.analytic_jacobian(np.array([q, q + 0.3]), "tool0", relative_to="link_1", on_singularity="nan")
    assert np.isnan(JA[0, 3:]).all() and np.isfinite(JA[0, :3]).all() and np.isfinite(JA[1]).all()


def test_unknown_frames_are_frame_not_found_errors():
    robot = _robot("abb_irb120")
    with pytest.raises(kinengine.FrameNotFoundError, match="tool0"):
        robot.relative_jacobian(np.zeros(6), "tool0", relative_to="tool1")
    with pytest.raises(kinengine.FrameNotFoundError):
        robot.relative_pose(np.zeros(6), "nope", relative_to="tool0")
