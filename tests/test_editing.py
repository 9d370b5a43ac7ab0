"""Model editing: Robot.with_frame (tool frames) and Robot.locked (joints held at a value).

Values are checked against the unedited robot (composition with the placement; the same pose and the
Jacobian with the locked columns removed), against the independent numpy reference reading the edited
robot's regenerated ``urdf_text``, and against scipy's Rotation for the rpy conversions.
"""

from __future__ import annotations

import numpy as np
import pytest
from custom_robots import mixed_chain_urdf
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import kinengine
from kinengine import ConfigurationError, FrameNotFoundError, OptionError, URDFError
from kinengine.model.editing import matrix_from_rpy, rpy_from_matrix
from kinengine.reference import ReferenceKinematics
from kinengine.verify import verify

REFERENCES = ("local_world_aligned", "local", "world")


def _transform(xyz, rpy) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("xyz", rpy).as_matrix()  # extrinsic x, y, z = URDF rpy
    T[:3, 3] = xyz
    return T


def _reference(robot) -> ReferenceKinematics:
    return ReferenceKinematics.from_urdf_string(robot.urdf_text, joint_names=robot.joint_names)


@pytest.fixture(scope="module")
def panda():
    return kinengine.load("panda")


@pytest.fixture(scope="module")
def mixed_robot():
    return kinengine.load_urdf_string(mixed_chain_urdf())


# -- rpy conversions -----------------------------------------------------------------------------
@settings(max_examples=200, deadline=None)
@given(st.tuples(*[st.floats(-np.pi, np.pi)] * 3))
def test_rpy_matches_scipy_and_round_trips(rpy):
    C = matrix_from_rpy(rpy)
    np.testing.assert_allclose(C, Rotation.from_euler("xyz", rpy).as_matrix(), atol=1e-15)
    np.testing.assert_allclose(matrix_from_rpy(rpy_from_matrix(C)), C, atol=1e-14)


@pytest.mark.parametrize("pitch", [np.pi / 2, -np.pi / 2])
def test_rpy_round_trip_at_gimbal_lock(pitch):
    C = matrix_from_rpy((0.3, pitch, -0.7))
    np.testing.assert_allclose(matrix_from_rpy(rpy_from_matrix(C)), C, atol=1e-12)


@pytest.mark.parametrize("gap", [1e-15, 1e-12, 1e-9, 1e-7, 1e-5, 1e-3])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_rpy_round_trip_near_gimbal_lock(gap, sign):
    """Near pitch = ±π/2 the yaw read from C is off by ε/cos(pitch); the roll must absorb it (it did not:
    5e-5 off at gap 1e-8, e.g. an MJCF quat="0.707107 0 0.707107 0")."""
    C = Rotation.from_euler("xyz", (0.3, sign * (np.pi / 2 - gap), -0.7)).as_matrix()
    np.testing.assert_allclose(matrix_from_rpy(rpy_from_matrix(C)), C, rtol=0, atol=1e-15)


# -- with_frame ------------------------------------------------------------------------------------
def test_with_frame_composes_the_placement(abb):
    T = _transform((0.01, -0.02, 0.15), (0.1, -0.4, 1.2))
    tcp = abb.with_frame("tcp", parent="tool0", placement=T)
    assert "tcp" in tcp.frame_names and "tcp" not in abb.frame_names
    assert tcp.dof == abb.dof and tcp.joint_names == abb.joint_names and tcp.end_effector == abb.end_effector
    Q = abb.random_configuration(1, size=20)
    np.testing.assert_allclose(tcp.frame_pose(Q, "tcp"), abb.frame_pose(Q, "tool0") @ T, atol=1e-14)
    # the rigid-body velocity transfer: v_tcp = v_tool0 + ω × (p_tcp − p_tool0), ω unchanged
    for q in Q[:5]:
        J0, J1 = abb.jacobian(q, "tool0"), tcp.jacobian(q, "tcp")
        r = tcp.frame_pose(q, "tcp")[:3, 3] - abb.frame_pose(q, "tool0")[:3, 3]
        np.testing.assert_allclose(J1[3:], J0[3:], atol=1e-14)
        np.testing.assert_allclose(J1[:3], J0[:3] - np.cross(r, J0[3:].T).T, atol=1e-14)


def test_with_frame_accepts_xyz_rpy_and_equals_the_matrix(abb):
    xyz, rpy = (0.0, 0.05, 0.2), (0.3, 0.2, -0.1)
    a = abb.with_frame("tcp", "tool0", (xyz, rpy))
    b = abb.with_frame("tcp", "tool0", _transform(xyz, rpy))
    c = abb.with_frame("tcp", "tool0", np.array([xyz, rpy]))
    q = abb.random_configuration(3)
    np.testing.assert_allclose(a.frame_pose(q, "tcp"), b.frame_pose(q, "tcp"), atol=1e-15)
    np.testing.assert_array_equal(a.frame_pose(q, "tcp"), c.frame_pose(q, "tcp"))


def test_joint_frame_parent_equals_its_child_link(panda):
    placement = ((0.0, 0.0, 0.1), (0.1, 0.2, 0.3))
    by_joint = panda.with_frame("tcp", "panda_joint7", placement)
    by_link = panda.with_frame("tcp", "panda_link7", placement)
    Q = panda.random_configuration(2, size=10)
    np.testing.assert_allclose(by_joint.frame_pose(Q, "tcp"), by_link.frame_pose(Q, "tcp"), atol=1e-15)
    np.testing.assert_allclose(
        by_joint.frame_pose(Q, "tcp"),
        panda.frame_pose(Q, "panda_joint7") @ _transform(*placement),
        atol=1e-14,
    )


def test_new_frame_is_in_urdf_text_and_checked_by_the_reference(mixed_robot):
    tcp = mixed_robot.with_frame("tcp", "finger_b_joint", ((0.01, 0.0, 0.03), (0.0, 0.5, 0.0)))
    assert '<link name="tcp"/>' in tcp.urdf_text
    ref = _reference(tcp)
    Q = tcp.random_configuration(4, size=16)
    np.testing.assert_allclose(tcp.frame_pose(Q, "tcp"), ref.frame_pose(Q, "tcp"), atol=1e-12)
    for reference in REFERENCES:
        np.testing.assert_allclose(
            tcp.jacobian(Q, "tcp", reference), ref.jacobian(Q, "tcp", reference), atol=1e-12
        )
    report = verify(tcp, samples=4)
    assert report.passed and report.frames == len(tcp.frame_names)


def test_new_frame_works_with_task_and_ik(abb):
    tcp = abb.with_frame("tcp", "tool0", ((0.0, 0.0, 0.1), (0.0, 0.0, 0.0)))
    q = np.array([0.2, -0.3, 0.4, 0.1, 0.5, -0.2])
    result = tcp.inverse_kinematics(tcp.frame_pose(q, "tcp"), "tcp", q0=q + 0.05, rng=0)
    assert result.success
    np.testing.assert_allclose(tcp.frame_pose(result.q, "tcp"), tcp.frame_pose(q, "tcp"), atol=1e-6)
    task = tcp.task("tcp")
    task.update(q)
    np.testing.assert_allclose(task.pose, tcp.frame_pose(q, "tcp"), atol=1e-15)


def test_with_frame_errors(abb):
    T = np.eye(4)
    with pytest.raises(FrameNotFoundError, match="tool0"):
        abb.with_frame("tcp", "tool", T)
    with pytest.raises(URDFError, match="already used"):
        abb.with_frame("link_6", "tool0", T)
    with pytest.raises(URDFError, match="already used"):
        abb.with_frame("joint_6", "tool0", T)
    with pytest.raises(URDFError, match="name"):
        abb.with_frame("", "tool0", T)
    bad = np.eye(4)
    bad[0, 0] = 2.0
    for placement in (bad, np.eye(3), np.full((4, 4), np.nan), ((0, 0), (0, 0, 0)), "tool0", None):
        with pytest.raises(OptionError, match="placement"):
            abb.with_frame("tcp", "tool0", placement)
    tcp = abb.with_frame("tcp", "tool0", T)
    with pytest.raises(URDFError, match="already used"):
        tcp.with_frame("tcp", "tool0", T)


def test_frames_stack(abb):
    T = _transform((0.0, 0.0, 0.1), (0.0, 0.0, 0.3))
    two = abb.with_frame("a", "tool0", T).with_frame("b", "a", T)
    q = abb.random_configuration(5)
    np.testing.assert_allclose(two.frame_pose(q, "b"), abb.frame_pose(q, "tool0") @ T @ T, atol=1e-14)


# -- locked ----------------------------------------------------------------------------------------
def _check_locked(full, locked, values, rng, n=12):
    """locked's poses and Jacobians = full's at the locked values, locked columns removed."""
    kept = [full.joint_names.index(name) for name in locked.joint_names]
    assert locked.joint_names == tuple(n for n in full.joint_names if n not in values)
    Q = full.random_configuration(rng, size=n)
    for name, value in values.items():
        Q[:, full.joint_names.index(name)] = value
    Qk = Q[:, kept]
    ref = _reference(locked)
    for frame in full.frame_names:
        np.testing.assert_allclose(locked.frame_pose(Qk, frame), full.frame_pose(Q, frame), atol=1e-13)
        np.testing.assert_allclose(ref.frame_pose(Qk, frame), full.frame_pose(Q, frame), atol=1e-12)
        for reference in REFERENCES:
            J = full.jacobian(Q, frame, reference)[:, :, kept]
            np.testing.assert_allclose(locked.jacobian(Qk, frame, reference), J, atol=1e-13)
            np.testing.assert_allclose(ref.jacobian(Qk, frame, reference), J, atol=1e-12)


def test_panda_finger_locked(panda):
    arm = panda.locked({"panda_finger_joint1": 0.04})
    assert (panda.dof, arm.dof) == (8, 7)
    assert arm.joint_names == panda.joint_names[:7]
    assert arm.end_effector == panda.end_effector and "panda_finger_joint2" in arm.frame_names
    # the mimic follower is fixed at 0.04 too: the fingers are 2 · 0.04 apart
    q = arm.random_configuration(0)
    gap = arm.frame_pose(q, "panda_leftfinger")[:3, 3] - arm.frame_pose(q, "panda_rightfinger")[:3, 3]
    assert np.linalg.norm(gap) == pytest.approx(0.08, abs=1e-12)
    _check_locked(panda, arm, {"panda_finger_joint1": 0.04}, 1)


@settings(max_examples=15, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.sets(
        st.sampled_from(["shoulder", "spin", "slide", "wrist", "finger_a_joint", "side_joint"]), max_size=4
    ),
)
def test_locked_equals_full_robot_with_columns_removed(mixed_robot, seed, names):
    rng = np.random.default_rng(seed)
    sample = mixed_robot.random_configuration(rng)
    values = {name: float(sample[mixed_robot.joint_names.index(name)]) for name in names}
    locked = mixed_robot.locked(values)
    _check_locked(mixed_robot, locked, values, rng, n=4)


def test_locking_a_mimic_leader_fixes_its_follower_at_multiplier_value_plus_offset(mixed_robot):
    locked = mixed_robot.locked({"finger_a_joint": 0.3})
    assert "finger_a_joint" not in locked.joint_names
    follower = next(j for j in locked.description.joints if j.name == "finger_b_joint")
    assert follower.type == "fixed" and follower.mimic is None
    q = locked.random_configuration(0)
    tip = locked.frame_pose(q, "tip")
    # finger_b: origin (0, -0.03, 0.04), axis y, at -1.5 · 0.3 + 0.2
    expected = tip @ _transform((0.0, -0.03, 0.04), (0.0, -1.5 * 0.3 + 0.2, 0.0))
    np.testing.assert_allclose(locked.frame_pose(q, "finger_b"), expected, atol=1e-14)


def test_locked_prismatic_folds_translation_along_the_axis(mixed_robot):
    locked = mixed_robot.locked({"slide": 0.2})
    joint = next(j for j in locked.description.joints if j.name == "slide")
    C = matrix_from_rpy((0.3, 0.0, 0.0))
    np.testing.assert_allclose(
        joint.xyz, np.array([0.1, 0.0, 0.25]) + C @ (0.2 * np.array([0.6, 0.0, 0.8])), atol=1e-15
    )
    np.testing.assert_allclose(joint.rpy, (0.3, 0.0, 0.0), atol=1e-15)


def test_locked_errors(mixed_robot, panda):
    with pytest.raises(ConfigurationError, match="outside its limits"):
        panda.locked({"panda_finger_joint1": 0.05})
    with pytest.raises(ConfigurationError, match="outside its limits"):
        mixed_robot.locked({"slide": -0.2})
    with pytest.raises(ConfigurationError, match="mimic"):
        panda.locked({"panda_finger_joint2": 0.01})
    with pytest.raises(FrameNotFoundError, match="panda_joint1"):
        panda.locked({"panda_joint_1": 0.0})
    with pytest.raises(ConfigurationError):
        panda.locked({"panda_joint1": "a"})
    with pytest.raises(ConfigurationError):
        panda.locked([("panda_joint1", 0.0)])


def test_edits_leave_the_original_robot_alone(panda):
    before = (panda.dof, panda.frame_names, panda.urdf_text)
    panda.locked({"panda_finger_joint1": 0.0}).with_frame("x", "panda_hand", np.eye(4))
    assert (panda.dof, panda.frame_names, panda.urdf_text) == before


def test_edited_robot_pickles(mixed_robot):
    import pickle

    edited = mixed_robot.locked({"wrist": 0.5}).with_frame("tcp", "tip", np.eye(4))
    copy = pickle.loads(pickle.dumps(edited))
    q = edited.random_configuration(0)
    np.testing.assert_allclose(copy.frame_pose(q, "tcp"), edited.frame_pose(q, "tcp"), atol=0)


def test_new_frame_is_drawn(abb):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    T = _transform((0.0, 0.0, 0.1), (0.0, 0.0, 0.0))
    tcp = abb.with_frame("tcp", "tool0", T)
    ax = tcp.plot(frames=["tcp"])
    try:
        drawing = ax.kinengine_drawing
        np.testing.assert_allclose(
            drawing.frames["tcp"], abb.frame_pose(abb.neutral(), "tool0") @ T, atol=1e-15
        )
        assert "tcp_joint" in drawing.skeleton_joints
    finally:
        plt.close(ax.figure)


def test_edited_urdf_text_keeps_the_visuals_and_describes_the_edited_robot(panda):
    arm = panda.locked({"panda_finger_joint1": 0.02}).with_frame(
        "tcp", "panda_hand", ((0, 0, 0.1), (0, 0, 0))
    )
    assert arm.urdf_text.count("<mesh") == panda.urdf_text.count("<mesh") > 0
    again = kinengine.load_urdf_string(arm.urdf_text)
    assert again.joint_names == arm.joint_names and sorted(again.frame_names) == sorted(arm.frame_names)
    Q = arm.random_configuration(0, size=5)
    for frame in ("tcp", "panda_leftfinger", "panda_rightfinger"):
        np.testing.assert_allclose(again.frame_pose(Q, frame), arm.frame_pose(Q, frame), atol=1e-15)


@settings(max_examples=20, deadline=None)
@given(st.data())
def test_any_parent_any_placement_matches_composition_and_reference(mixed_robot, data):
    parent = data.draw(st.sampled_from(mixed_robot.frame_names))
    xyz = data.draw(st.tuples(*[st.floats(-1, 1)] * 3))
    rpy = data.draw(st.tuples(*[st.floats(-np.pi, np.pi)] * 3))
    tcp = mixed_robot.with_frame("tcp", parent, (xyz, rpy))
    Q = tcp.random_configuration(data.draw(st.integers(0, 2**32 - 1)), size=3)
    np.testing.assert_allclose(
        tcp.frame_pose(Q, "tcp"), mixed_robot.frame_pose(Q, parent) @ _transform(xyz, rpy), atol=1e-13
    )
    ref = _reference(tcp)
    for reference in REFERENCES:
        np.testing.assert_allclose(
            tcp.jacobian(Q, "tcp", reference), ref.jacobian(Q, "tcp", reference), atol=1e-12
        )
