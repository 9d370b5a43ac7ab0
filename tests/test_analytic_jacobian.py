"""Analytic Jacobians J_A = E(χ)·J_e0 against finite differences of χ(q), closed forms and singularities."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from custom_robots import mixed_chain_urdf
from finite_differences import assert_close_relative

import kinengine
from kinengine.parameterizations import POSITION_PARAMETERIZATIONS, ROTATION_PARAMETERIZATIONS

POSITIONS = sorted(POSITION_PARAMETERIZATIONS)
ROTATIONS = sorted(ROTATION_PARAMETERIZATIONS)
ROBOTS = {
    "abb_irb120": lambda: kinengine.load("abb_irb120"),
    "ur5": lambda: kinengine.load("ur5"),
    "panda": lambda: kinengine.load("panda"),
    "mixed_chain": lambda: kinengine.load_urdf_string(mixed_chain_urdf()),
}


@pytest.fixture(scope="module", params=sorted(ROBOTS))
def robot(request):
    return ROBOTS[request.param]()


def _regular_samples(robot, position, rotation, count, seed):
    """Configurations at which χ is well away from singular sets and branch cuts (θ = π, w = 0)."""
    rng = np.random.default_rng(seed)
    pmap_p = POSITION_PARAMETERIZATIONS[position]
    pmap_r = ROTATION_PARAMETERIZATIONS[rotation]
    found = []
    while len(found) < count:
        q = robot.random_configuration(rng)
        T = robot.frame_pose(q)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            chi_p = pmap_p.from_position(T[:3, 3])
            chi_r = pmap_r.from_rotation(T[:3, :3])
        angle = np.linalg.norm(kinengine_rotvec(T[:3, :3]))
        if (
            np.min(pmap_p.singularity_distance(chi_p)) > 0.05
            and np.min(pmap_r.singularity_distance(chi_r)) > 0.05
            and angle < np.pi - 0.05
        ):
            found.append(q)
    return found


def kinengine_rotvec(C):
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(C).as_rotvec()


@pytest.mark.parametrize("rotation", ROTATIONS)
@pytest.mark.parametrize("position", POSITIONS)
def test_analytic_jacobian_matches_finite_differences(robot, position, rotation):
    h = 1e-6
    for q in _regular_samples(robot, position, rotation, 2, seed=hash((position, rotation)) % 2**32):
        JA = robot.analytic_jacobian(q, position=position, rotation=rotation)
        chi = robot.pose_parameters(q, position=position, rotation=rotation)
        assert JA.shape == (chi.size, robot.dof)
        fd = np.empty_like(JA)
        for k in range(robot.dof):
            dq = np.zeros(robot.dof)
            dq[k] = h
            d = robot.pose_parameters(q + dq, position=position, rotation=rotation) - robot.pose_parameters(
                q - dq, position=position, rotation=rotation
            )
            fd[:, k] = ((d + np.pi) % (2 * np.pi) - np.pi) / (2 * h)  # angles unwrapped
        assert_close_relative(JA, fd, 1e-6, f"{position}+{rotation}")


def test_row_counts_and_partial_parameterizations(robot):
    q = robot.random_configuration(0)
    sizes = {"euler_zyx": 3, "quaternion": 4, "angle_axis": 4, "rotation_vector": 3, "rotation_matrix": 9}
    for rotation, m in sizes.items():
        assert robot.pose_parameters(q, position="cartesian", rotation=rotation).shape == (3 + m,)
        assert robot.pose_parameters(q, position=None, rotation=rotation).shape == (m,)
    J = robot.jacobian(q)
    np.testing.assert_allclose(
        robot.analytic_jacobian(q, position="cartesian", rotation=None), J[:3], rtol=0, atol=1e-15
    )
    with pytest.raises(kinengine.KinematicsError, match="both None"):
        robot.analytic_jacobian(q, position=None, rotation=None)


def test_batched_analytic_jacobian_equals_single_calls(robot):
    qs = robot.random_configuration(1, size=5)
    JA = robot.analytic_jacobian(qs, position="spherical", rotation="quaternion")
    chi = robot.pose_parameters(qs, position="spherical", rotation="quaternion")
    assert JA.shape == (5, 7, robot.dof) and chi.shape == (5, 7)
    for i, q in enumerate(qs):
        np.testing.assert_allclose(
            JA[i], robot.analytic_jacobian(q, position="spherical", rotation="quaternion"), rtol=0, atol=1e-14
        )
        np.testing.assert_allclose(
            chi[i], robot.pose_parameters(q, position="spherical", rotation="quaternion"), rtol=0, atol=1e-14
        )


def test_unknown_names_list_the_valid_ones():
    robot = kinengine.load("abb_irb120")
    q = robot.neutral()
    with pytest.raises(kinengine.KinematicsError, match="euler_zyz"):
        robot.analytic_jacobian(q, rotation="euler_abc")
    with pytest.raises(kinengine.KinematicsError, match="cylindrical"):
        robot.pose_parameters(q, position="polar")
    with pytest.raises(kinengine.KinematicsError, match="unknown row"):
        robot.pose_parameters(q, rows=("nope",))


def test_abb_at_zero_is_on_the_zyx_and_xyz_singularities_and_the_error_says_what_to_use():
    robot = kinengine.load("abb_irb120")
    q = robot.neutral()
    for rotation in ("euler_zyx", "euler_xyz"):
        with pytest.raises(kinengine.RepresentationSingularityError, match="quaternion") as info:
            robot.analytic_jacobian(q, "tool0", rotation=rotation)
        assert info.value.parameterization == rotation
        assert info.value.distance < 1e-12
        assert "euler_zyz" in info.value.alternatives or "quaternion" in info.value.alternatives
        assert isinstance(info.value, kinengine.KinematicsError)
        # the same default for χ as for J_A (one AnalyticOptions): the angles are not unique there
        with pytest.raises(kinengine.RepresentationSingularityError, match="quaternion"):
            robot.pose_parameters(q, "tool0", rotation=rotation)
        with pytest.warns(UserWarning):  # on_singularity=None: the angles alone, with a warning
            chi = robot.pose_parameters(q, "tool0", rotation=rotation, on_singularity=None)
        assert np.all(np.abs(chi) < 10)  # valid angles, no 1e15
    # near, not only at, the singular set: tool0 pitched by π/2 − 1e-8
    near = q.copy()
    near[4] = 1e-8
    with pytest.raises(kinengine.RepresentationSingularityError):
        robot.analytic_jacobian(near, "tool0", rotation="euler_zyx")
    # a regular alternative works there
    assert np.all(np.isfinite(robot.analytic_jacobian(q, "tool0", rotation="euler_zyz")))
    # the threshold is configurable
    far = q.copy()
    far[4] = 1e-3
    robot.analytic_jacobian(far, "tool0", rotation="euler_zyx")
    with pytest.raises(kinengine.RepresentationSingularityError):
        robot.analytic_jacobian(far, "tool0", rotation="euler_zyx", singularity_threshold=1e-2)


def test_planar_arm_operational_space_jacobian_equals_the_closed_form():
    """Example 2.8.6: χ = (x, z, q1 + q2 + q3); the printed eq. 2.138 has c213 where c123 belongs."""
    robot = kinengine.load("planar_3dof")
    d = robot.description
    l0, l1, l2 = (d.joint(f"joint_{i}").xyz[2] for i in (1, 2, 3))
    l3 = d.joint("ee_joint").xyz[2]
    rows = ("x", "z", "chi1_y")  # euler_yxz: C = R_y(χ1)·R_x(χ2)·R_z(χ3); a pure R_y(θ) has χ1 = θ
    rng = np.random.default_rng(2138)
    for q in robot.random_configuration(rng, size=100):
        s1, s12, s123 = np.sin(q[0]), np.sin(q[0] + q[1]), np.sin(q.sum())
        c1, c12, c123 = np.cos(q[0]), np.cos(q[0] + q[1]), np.cos(q.sum())
        chi = robot.pose_parameters(q, "ee", rotation="euler_yxz", rows=rows)
        angle = (q.sum() + np.pi) % (2 * np.pi) - np.pi
        np.testing.assert_allclose(
            chi,
            [l1 * s1 + l2 * s12 + l3 * s123, l0 + l1 * c1 + l2 * c12 + l3 * c123, angle],
            rtol=0,
            atol=1e-12,
        )
        expected = np.array(
            [
                [l1 * c1 + l2 * c12 + l3 * c123, l2 * c12 + l3 * c123, l3 * c123],
                [-(l1 * s1 + l2 * s12 + l3 * s123), -(l2 * s12 + l3 * s123), -l3 * s123],
                [1.0, 1.0, 1.0],
            ]
        )
        np.testing.assert_allclose(
            robot.analytic_jacobian(q, "ee", rotation="euler_yxz", rows=rows), expected, rtol=0, atol=1e-12
        )


def test_scara_four_coordinate_operational_space():
    """Example 2.8.4: χ_o = (x, y, z, φ) with φ = α + β + γ about the vertical axis."""
    robot = kinengine.load("scara")
    d = robot.description
    l0, l1, l2 = d.joint("alpha").xyz[2], d.joint("beta").xyz[0], d.joint("gamma").xyz[0]
    tool = d.joint("ee_joint").xyz[2]  # the tool tip sits below the quill
    rows = ("x", "y", "z", "chi1_z")
    for q in robot.random_configuration(np.random.default_rng(284), size=100):
        a, b, g, zeta = q
        chi = robot.pose_parameters(q, "ee", rotation="euler_zyx", rows=rows)
        phi = (a + b + g + np.pi) % (2 * np.pi) - np.pi
        np.testing.assert_allclose(
            chi,
            [l1 * np.cos(a) + l2 * np.cos(a + b), l1 * np.sin(a) + l2 * np.sin(a + b), l0 - zeta + tool, phi],
            rtol=0,
            atol=1e-12,
        )
        JA = robot.analytic_jacobian(q, "ee", rotation="euler_zyx", rows=rows)
        expected = np.array(
            [
                [-l1 * np.sin(a) - l2 * np.sin(a + b), -l2 * np.sin(a + b), 0, 0],
                [l1 * np.cos(a) + l2 * np.cos(a + b), l2 * np.cos(a + b), 0, 0],
                [0, 0, 0, -1],
                [1, 1, 1, 0],
            ]
        )
        np.testing.assert_allclose(JA, expected, rtol=0, atol=1e-12)
