"""Singularity measures against geometry and closed forms: the IRB 120's wrist and elbow singularities,
the planar arm's manipulability, and identities that hold at random configurations."""

from __future__ import annotations

import numpy as np
import pytest

import kinengine
from kinengine.control.manipulability import (
    analyze_jacobian,
    describe_twist,
    manipulability,
    require_regular,
    singularity_report,
    velocity_ellipsoid,
)

L1, L2, L3 = 0.5, 0.35, 0.2  # planar_3dof link lengths [m]
ELBOW_STRETCHED = float(np.arctan2(-0.302, 0.07))  # IRB 120: joint 3 -> wrist centre (0.302, 0.07) in x-z


def _parallel(a, b, atol):
    a, b = np.asarray(a) / np.linalg.norm(a), np.asarray(b) / np.linalg.norm(b)
    return np.linalg.norm(np.cross(a, b)) <= atol


@pytest.fixture(scope="module")
def irb120():
    return kinengine.load("abb_irb120")


@pytest.fixture(scope="module")
def planar():
    return kinengine.load("planar_3dof")


def test_irb120_wrist_singularity_joints_4_and_6_aligned(irb120):
    """q5 = 0: axes 4 and 6 coincide, so q̇ ∝ e4 − e6 does nothing, and the lost wrench (Jᵀu = 0) has,
    about the wrist centre (where axes 4, 5, 6 meet), a moment along ω4 × ω5: rotating about that axis
    while holding the wrist centre is impossible."""
    q = np.array([0.3, 0.2, -0.4, 0.5, 0.0, 1.0])
    report = singularity_report(irb120, q, "tool0")
    assert report.is_singular and report.rank == 5 and len(report.lost_directions) == 1
    J = irb120.jacobian(q, "tool0")
    _, _, Vt = np.linalg.svd(J)
    np.testing.assert_allclose(np.abs(Vt[-1]), np.array([0, 0, 0, 1, 0, 1]) / np.sqrt(2), rtol=0, atol=1e-12)
    u = report.lost_directions[0].twist
    np.testing.assert_allclose(u @ J, 0.0, rtol=0, atol=1e-12)
    axes = {k: irb120.jacobian(q, f"link_{k}")[3:, k - 1] for k in (4, 5, 6)}
    np.testing.assert_allclose(axes[4], axes[6], rtol=0, atol=1e-12)
    p_tool = irb120.frame_pose(q, "tool0")[:3, 3]
    p_wrist = irb120.frame_pose(q, "link_5")[:3, 3]
    force, moment = u[:3], u[3:]
    moment_at_wrist = moment + np.cross(p_tool - p_wrist, force)
    assert np.linalg.norm(moment_at_wrist) > 0.1
    assert _parallel(moment_at_wrist, np.cross(axes[4], axes[5]), 1e-10)
    n = np.cross(axes[4], axes[5]) / np.linalg.norm(np.cross(axes[4], axes[5]))
    rotate_about_wrist = np.concatenate([np.cross(n, p_tool - p_wrist), n])  # twist at tool0, in I
    assert abs(u @ rotate_about_wrist) > 0.1  # not in the range of J
    along_axis_5 = np.concatenate([np.cross(axes[5], p_tool - p_wrist), axes[5]])
    residual = along_axis_5 - J @ np.linalg.lstsq(J, along_axis_5, rcond=None)[0]
    assert np.linalg.norm(residual) < 1e-12  # this one is reachable


def test_irb120_stretched_arm_loses_the_radial_linear_direction(irb120):
    """Joint 3 at atan2(-0.302, 0.07): the wrist centre lies on the line from joint 2 through joint 3, at
    full reach, and cannot move along that line; the whole J_e0 of tool0 then has rank 5."""
    q = np.array([0.3, 0.2, ELBOW_STRETCHED, 0.5, 0.7, 1.0])
    report = singularity_report(irb120, q, "link_5", "linear")
    assert report.rank == 2 and len(report.lost_directions) == 1
    p2 = irb120.frame_pose(q, "link_2")[:3, 3]
    p3 = irb120.frame_pose(q, "link_3")[:3, 3]
    p_wrist = irb120.frame_pose(q, "link_5")[:3, 3]
    assert _parallel(p_wrist - p2, p3 - p2, 1e-12)
    lost = report.lost_directions[0].twist
    np.testing.assert_allclose(lost[3:], 0.0, rtol=0, atol=0)
    assert _parallel(lost[:3], p_wrist - p2, 1e-10)
    assert report.lost_directions[0].description.startswith("linear along (")
    assert singularity_report(irb120, q, "tool0").rank == 5
    assert not singularity_report(irb120, np.array([0.3, 0.2, -0.4, 0.5, 0.7, 1.0]), "tool0").is_singular


def test_planar_arm_manipulability_closed_forms(planar):
    """Rows (vx, vz, wy): det J = l1 l2 sin q2. Rows (vx, vz), by Cauchy–Binet over the 2x2 minors:
    w² = (l1 l2 s2 + l1 l3 s23)² + (l1 l3 s23 + l2 l3 s3)² + (l2 l3 s3)²."""
    rng = np.random.default_rng(3)
    for q in rng.uniform(-np.pi, np.pi, size=(20, 3)):
        s2, s3, s23 = np.sin(q[1]), np.sin(q[2]), np.sin(q[1] + q[2])
        w3 = manipulability(planar, q, "ee", ("vx", "vz", "wy"))
        assert w3 == pytest.approx(L1 * L2 * abs(s2), rel=1e-12, abs=1e-15)
        w2 = manipulability(planar, q, "ee", ("vx", "vz"))
        expected = np.sqrt(
            (L1 * L2 * s2 + L1 * L3 * s23) ** 2 + (L1 * L3 * s23 + L2 * L3 * s3) ** 2 + (L2 * L3 * s3) ** 2
        )
        assert w2 == pytest.approx(expected, rel=1e-12, abs=1e-15)


def test_planar_arm_never_moves_out_of_its_plane(planar):
    report = singularity_report(planar, np.array([0.3, 0.5, -0.2]), "ee")
    assert report.rank == 3 and report.manipulability == 0.0 and report.condition_number == np.inf
    assert [d.description for d in report.lost_directions] == [
        "linear along y",
        "angular about x",
        "angular about z",
    ]
    stretched = singularity_report(planar, np.array([0.4, 0.0, 0.0]), "ee", ("vx", "vz", "wy"))
    (lost,) = stretched.lost_directions
    np.testing.assert_allclose(lost.twist, [np.sin(0.4), 0, np.cos(0.4), 0, 0, 0], rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", ["abb_irb120", "ur5", "panda", "kinova"])
def test_measures_agree_with_independent_formulas_at_random_configurations(name):
    robot = kinengine.load(name)
    rng = np.random.default_rng(4)
    qs = robot.random_configuration(rng, size=10)
    batch = manipulability(robot, qs)
    for q, w in zip(qs, batch, strict=False):
        J = robot.jacobian(q)
        report = singularity_report(robot, q)
        assert report.manipulability == pytest.approx(np.sqrt(np.linalg.det(J @ J.T)), rel=1e-9)
        assert w == pytest.approx(report.manipulability, rel=1e-12)
        assert report.condition_number == pytest.approx(np.linalg.cond(J), rel=1e-9)
        np.testing.assert_allclose(
            report.singular_values, np.sqrt(np.linalg.eigvalsh(J @ J.T)[::-1]), rtol=1e-9, atol=1e-12
        )
        for rows in ("linear", "angular"):
            Jr = J[:3] if rows == "linear" else J[3:]
            expected = np.sqrt(np.linalg.det(Jr @ Jr.T))
            assert manipulability(robot, q, rows=rows) == pytest.approx(expected, rel=1e-9)


def test_velocity_ellipsoid_axes_and_semi_axes(irb120):
    rng = np.random.default_rng(5)
    q = irb120.random_configuration(rng)
    ellipsoid = velocity_ellipsoid(irb120, q, "tool0")
    Jv = irb120.jacobian(q, "tool0")[:3]
    A, s = ellipsoid.axes, ellipsoid.semi_axes
    np.testing.assert_allclose(A @ np.diag(s**2) @ A.T, Jv @ Jv.T, rtol=0, atol=1e-12)
    np.testing.assert_allclose(A.T @ A, np.eye(3), rtol=0, atol=1e-12)
    np.testing.assert_allclose(ellipsoid.center, irb120.frame_pose(q, "tool0")[:3, 3], rtol=0, atol=0)
    for qdot in rng.normal(size=(200, 6)):
        v = Jv @ (qdot / np.linalg.norm(qdot))
        assert np.sum((A.T @ v) ** 2 / s**2) <= 1.0 + 1e-9  # every unit joint speed lands inside
    _, _, Vt = np.linalg.svd(Jv)
    np.testing.assert_allclose(np.linalg.norm(Jv @ Vt[0]), s[0], rtol=1e-12)  # and the longest axis is hit


def test_kinematic_singularity_error_is_not_a_representation_singularity(irb120):
    wrist = np.array([0.3, 0.2, -0.4, 0.5, 0.0, 1.0])
    with pytest.raises(kinengine.KinematicSingularityError, match="rank 5 < 6") as info:
        require_regular(irb120, wrist, "tool0")
    assert not isinstance(info.value, kinengine.RepresentationSingularityError)
    assert "no choice of pose parameterization" in str(info.value)
    assert info.value.report.rank == 5
    regular = np.array([0.3, 0.2, -0.4, 0.5, 0.7, 1.0])
    assert require_regular(irb120, regular, "tool0").rank == 6
    # q2 + q3 + q5 = 0 and q4 = q6 = 0 keep tool0's x axis vertical: ZYX angles are singular there ...
    vertical = np.array([0.4, 0.3, 0.2, 0.0, -0.5, 0.0])
    np.testing.assert_allclose(irb120.frame_pose(vertical, "tool0")[:3, 0], [0, 0, -1], rtol=0, atol=1e-15)
    with pytest.raises(kinengine.RepresentationSingularityError):
        irb120.analytic_jacobian(vertical, "tool0", rotation="euler_zyx")
    # ... while the robot itself is regular
    assert not singularity_report(irb120, vertical, "tool0").is_singular


def test_report_reads_well_and_rows_are_validated(planar):
    text = str(singularity_report(planar, np.array([0.3, 0.5, -0.2]), "ee"))
    assert text.startswith("kinematic singularity: J_e0 rows vx vy vz wx wy wz of frame 'ee' has rank 3 < 6")
    assert "linear along y" in text and "angular about z" in text
    regular = str(singularity_report(planar, np.array([0.3, 0.5, -0.2]), "ee", ["vx", "vz", "wy"]))
    assert regular.startswith("regular:") and "lost" not in regular
    assert describe_twist(np.array([0.6, 0, 0, 0, 0.8, 0])) == "0.60·linear along x + 0.80·angular about y"
    assert describe_twist(np.array([0, 0, -1.0, 0, 0, 0])) == "linear along -z"
    for bad in ("twist", ["vx", "vx"], [7], []):
        with pytest.raises(ValueError, match="rows"):
            analyze_jacobian(np.zeros((6, 3)), bad)
    with pytest.raises(ValueError, match=r"shape \(6, dof\)"):
        analyze_jacobian(np.zeros((5, 3)))
