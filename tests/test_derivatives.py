"""J̇ and kinematic Hessians equal central finite differences of the Jacobians, in every reference,
on serial arms, continuous joints, prismatic joints and mimic joints; closed forms on the planar arm."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from custom_robots import mixed_chain_urdf
from finite_differences import assert_close_relative

import kinengine

REFERENCES = ("local_world_aligned", "local", "world")

# A revolute mimic joint *below* its leader on the same chain (multiplier and offset).
STACKED_MIMIC_URDF = """<?xml version="1.0"?>
<robot name="stacked_mimic">
  <link name="base"/><link name="a"/><link name="b"/><link name="c"/><link name="tip"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/>
    <origin xyz="0 0 0.2" rpy="0.2 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/>
    <origin xyz="0.3 0 0.1" rpy="0 0.3 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="1" velocity="1"/>
    <mimic joint="j1" multiplier="0.7" offset="-0.3"/></joint>
  <joint name="j3" type="prismatic"><parent link="b"/><child link="c"/>
    <origin xyz="0.2 0.1 0" rpy="0 0 0.4"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.3" effort="1" velocity="1"/></joint>
  <joint name="j4" type="revolute"><parent link="c"/><child link="tip"/>
    <origin xyz="0.1 0 0.05" rpy="0 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
</robot>
"""

CASES = [
    ("abb_irb120", "tool0"),
    ("ur5", "tool0"),
    ("panda", "panda_hand"),
    ("kinova", None),  # continuous joints
    ("baxter", "l_gripper_r_finger"),  # below a prismatic mimic joint
    ("mixed", "finger_b"),  # below a revolute mimic joint (multiplier -1.5)
    ("mixed", "side"),  # a branch: only two joints move it
    ("stacked", "tip"),  # a mimic joint below its own leader
]


def _load(name: str) -> kinengine.Robot:
    if name == "mixed":
        return kinengine.load_urdf_string(mixed_chain_urdf())
    if name == "stacked":
        return kinengine.load_urdf_string(STACKED_MIMIC_URDF)
    return kinengine.load(name)


def _hessian_fd(robot, q, frame, reference, h=1e-6):
    """Central differences of J along each coordinate: (6, dof, dof), [:, :, k] = ∂J/∂q_k."""
    H = np.empty((6, robot.dof, robot.dof))
    for k in range(robot.dof):
        dq = np.zeros(robot.dof)
        dq[k] = h
        J_plus, J_minus = robot.jacobian(q + dq, frame, reference), robot.jacobian(q - dq, frame, reference)
        H[:, :, k] = (J_plus - J_minus) / (2 * h)
    return H


@pytest.mark.parametrize("name,frame", CASES)
@pytest.mark.parametrize("reference", REFERENCES)
def test_time_variation_equals_finite_differences_along_qdot(name, frame, reference):
    robot = _load(name)
    frame = frame or robot.end_effector
    rng = np.random.default_rng(11)
    h = 1e-6
    for _ in range(3):
        q, qdot = robot.random_configuration(rng), rng.normal(size=robot.dof)
        Jdot_fd = (
            robot.jacobian(q + h * qdot, frame, reference) - robot.jacobian(q - h * qdot, frame, reference)
        ) / (2 * h)
        Jdot = robot.jacobian_time_variation(q, qdot, frame, reference)
        assert Jdot.shape == (6, robot.dof)
        assert_close_relative(Jdot, Jdot_fd, 1e-6, f"{name} {frame} {reference}")


@pytest.mark.parametrize("name,frame", CASES)
@pytest.mark.parametrize("reference", REFERENCES)
def test_hessian_equals_finite_differences(name, frame, reference):
    robot = _load(name)
    frame = frame or robot.end_effector
    rng = np.random.default_rng(12)
    for _ in range(2):
        q = robot.random_configuration(rng)
        H = robot.kinematic_hessian(q, frame, reference)
        assert H.shape == (6, robot.dof, robot.dof)
        assert_close_relative(H, _hessian_fd(robot, q, frame, reference), 1e-6, f"{name} {frame} {reference}")


@pytest.mark.parametrize("name,frame", CASES)
def test_hessian_contracted_with_qdot_is_the_time_variation(name, frame):
    """Two independent paths: Pinocchio's time variation and our Lie-bracket Hessian."""
    robot = _load(name)
    frame = frame or robot.end_effector
    rng = np.random.default_rng(13)
    q, qdot = robot.random_configuration(rng), rng.normal(size=robot.dof)
    for reference in REFERENCES:
        Jdot = robot.jacobian_time_variation(q, qdot, frame, reference)
        H = robot.kinematic_hessian(q, frame, reference)
        np.testing.assert_allclose(H @ qdot, Jdot, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name,frame", [CASES[0], CASES[1], CASES[3]])  # no mimic joints
@pytest.mark.parametrize("reference", REFERENCES)
def test_pinocchio_frame_hessian_agrees_once_read_in_fortran_order(name, frame, reference):
    """getFrameKinematicHessian's (6, nv, nv) array must be re-read column-major to mean ∂J/∂q_k
    (and Pinocchio refuses mimic joints here: the Panda's fingers)."""
    if not hasattr(
        pin, "computeJointKinematicHessians"
    ):  # pin 3.4, the floor: kinengine's own is tested by FD
        pytest.skip(f"Pinocchio {pin.__version__} has no kinematic Hessians to compare with")
    robot = _load(name)
    frame = frame or robot.end_effector
    q = robot.random_configuration(14)
    model = robot.pinocchio_model()
    data = model.createData()
    pin.computeJointJacobians(model, data, robot.pinocchio_configuration(q))
    pin.computeJointKinematicHessians(model, data, robot.pinocchio_configuration(q))
    pin.updateFramePlacements(model, data)
    ref = kinengine.robot.resolve_reference(reference)
    raw = pin.getFrameKinematicHessian(model, data, robot.frame_id(frame), ref)
    ours = robot.kinematic_hessian(q, frame, reference)
    np.testing.assert_allclose(np.reshape(raw.ravel(), raw.shape, order="F"), ours, rtol=0, atol=1e-12)
    assert np.max(np.abs(raw - ours)) > 1e-3  # the raw C-order reading is not the Hessian


def test_pinocchio_time_variations_of_the_plain_joint_model_fold_to_ours_in_every_reference():
    """With plain joints Pinocchio's J̇ is right in all three references: J̇ = J̇_pin(q_pin, M q̇)·M."""
    robot = _load("mixed")
    model = robot.pinocchio_model()
    data = model.createData()
    M = robot.engine.coordinates.matrix
    rng = np.random.default_rng(15)
    q, qdot = robot.random_configuration(rng), rng.normal(size=robot.dof)
    pin.computeJointJacobiansTimeVariation(model, data, robot.pinocchio_configuration(q), M @ qdot)
    pin.updateFramePlacements(model, data)
    fid = robot.frame_id("finger_b")
    for reference in REFERENCES:
        ref = {"world": pin.WORLD, "local": pin.LOCAL, "local_world_aligned": pin.LOCAL_WORLD_ALIGNED}[
            reference
        ]
        theirs = pin.getFrameJacobianTimeVariation(model, data, fid, ref) @ M
        ours = robot.jacobian_time_variation(q, qdot, "finger_b", reference)
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12)


def test_planar_arm_hessian_matches_its_closed_form():
    """All axes parallel to y: ∂J_v[:, j]/∂q_k = e_y × (e_y × r_max(j,k)) = −r_max(j,k) with
    r_i = p_ee − p_joint_i; the angular rows are constant (every column is e_y): zero Hessian."""
    robot = kinengine.load("planar_3dof")
    q = np.array([0.4, -1.1, 0.7])
    p_ee = robot.frame_pose(q, "ee")[:3, 3]
    r = [p_ee - robot.frame_pose(q, f"link_{i}")[:3, 3] for i in (1, 2, 3)]
    expected = np.zeros((6, 3, 3))
    for j in range(3):
        for k in range(3):
            expected[:3, j, k] = -r[max(j, k)]
    np.testing.assert_allclose(robot.kinematic_hessian(q, "ee"), expected, rtol=0, atol=1e-14)


@pytest.mark.parametrize(
    "position,rotation",
    [
        ("cartesian", "euler_zyx"),
        ("spherical", "quaternion"),
        ("cylindrical", "euler_zyz"),
        (None, "rotation_vector"),
    ],
)
@pytest.mark.parametrize("name,frame", [CASES[0], CASES[3], CASES[5]])
def test_analytic_hessian_equals_finite_differences_of_the_analytic_jacobian(name, frame, position, rotation):
    robot = _load(name)
    frame = frame or robot.end_effector
    rng = np.random.default_rng(16)
    h = 1e-6
    q = robot.random_configuration(rng)
    HA = robot.analytic_hessian(q, frame, position, rotation)
    HA_fd = np.stack(
        [
            (
                robot.analytic_jacobian(q + h * e, frame, position, rotation)
                - robot.analytic_jacobian(q - h * e, frame, position, rotation)
            )
            / (2 * h)
            for e in np.eye(robot.dof)
        ],
        axis=-1,
    )
    assert HA.shape == HA_fd.shape
    assert_close_relative(HA, HA_fd, 1e-6, f"{name} {position} {rotation}")
    # J̇_A of the lead's Task (Ė·J + E·J̇, another path) is the contraction with q̇
    qdot = rng.normal(size=robot.dof)
    task = robot.task(frame, position=position, rotation=rotation, continuous=False)
    task.update(q, qdot)
    np.testing.assert_allclose(HA @ qdot, task.analytic_jacobian_dot, rtol=0, atol=1e-9)


def test_analytic_hessian_row_selection_and_representation_singularity():
    robot = _load("abb_irb120")
    q = np.array([0.3, 0.2, -0.4, 0.5, 0.7, 1.0])
    full = robot.analytic_hessian(q, "tool0", "cartesian", "euler_zyz")
    picked = robot.analytic_hessian(q, "tool0", "cartesian", "euler_zyz", rows=("z", "chi2_y"))
    np.testing.assert_array_equal(picked, full[[2, 4]])
    with pytest.raises(kinengine.RepresentationSingularityError, match="euler_zyx"):
        robot.analytic_hessian(robot.neutral(), "tool0", "cartesian", "euler_zyx")  # tool0 x axis vertical


def test_frames_no_joint_moves_have_zero_derivatives_and_inputs_are_checked():
    robot = _load("abb_irb120")
    q = robot.random_configuration(17)
    for reference in REFERENCES:
        np.testing.assert_array_equal(robot.kinematic_hessian(q, "base", reference), 0.0)
        np.testing.assert_array_equal(robot.jacobian_time_variation(q, np.ones(6), "base", reference), 0.0)
    with pytest.raises(kinengine.ConfigurationError, match="qdot"):
        robot.jacobian_time_variation(q, np.ones(5), "tool0")
    with pytest.raises(kinengine.ConfigurationError, match=r"\(6,\)"):
        robot.kinematic_hessian(np.zeros((2, 6)), "tool0")
    with pytest.raises(kinengine.FrameNotFoundError, match="tool0"):
        robot.kinematic_hessian(q, "tool")
    with pytest.raises(kinengine.KinematicsError, match="reference"):
        robot.kinematic_hessian(q, "tool0", "global")
