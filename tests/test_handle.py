"""robot.frame(name): the hot-loop handle equals the Robot's own calls bit for bit, checks its input
once (or not at all with check_inputs=False), validates the reference and serves several threads."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pinocchio as pin
import pytest

import kinengine
from kinengine import ConfigurationError, FrameNotFoundError, OptionError

REFERENCES = ("local_world_aligned", "local", "world")

ONE_DOF = """<robot name="one"><link name="a"/><link name="b"/><link name="c"/>
<joint name="j" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0 0 0.2"/><axis xyz="0 1 0"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
<joint name="f" type="fixed"><parent link="b"/><child link="c"/><origin xyz="0.3 0 0" rpy="0 0.2 0"/></joint>
</robot>"""
ZERO_DOF = """<robot name="zero"><link name="a"/><link name="b"/>
<joint name="f" type="fixed"><parent link="a"/><child link="b"/><origin xyz="0.3 0 0.1" rpy="0.1 0.2 0"/></joint>
</robot>"""


def robots(abb, mixed):
    return [
        (abb, "tool0"),
        (mixed, "finger_b"),
        (mixed, "tip"),
        (kinengine.load_urdf_string(ONE_DOF), "c"),
        (kinengine.load_urdf_string(ZERO_DOF), "b"),
    ]


@pytest.mark.parametrize("check_inputs", [True, False])
def test_handle_equals_robot_calls_bit_for_bit(abb, mixed, check_inputs):
    for robot, frame in robots(abb, mixed):
        fk = robot.frame(frame, check_inputs=check_inputs)
        for q in robot.random_configuration(7, size=5):
            q = np.ascontiguousarray(q)
            assert np.array_equal(fk.pose(q), robot.frame_pose(q, frame))
            for ref in REFERENCES:
                J = fk.jacobian(q, reference=ref)
                assert J.shape == (6, robot.dof)
                assert np.array_equal(J, robot.jacobian(q, frame, ref))
                T, J2 = fk.kinematics(q, reference=ref)
                assert np.array_equal(T, robot.frame_pose(q, frame))
                assert np.array_equal(J2, robot.jacobian(q, frame, ref))


def test_handle_matches_the_independent_reference(abb):
    from kinengine.reference import ReferenceKinematics

    ref = ReferenceKinematics.from_urdf_string(abb.urdf_text)
    fk = abb.frame("tool0")
    for q in abb.random_configuration(3, size=5):
        np.testing.assert_allclose(fk.pose(q), ref.frame_pose(q, "tool0"), atol=1e-12)
        np.testing.assert_allclose(
            fk.jacobian(q, reference="local"), ref.jacobian(q, "tool0", reference="local"), atol=1e-12
        )


def test_default_frame_and_pinocchio_enum(abb):
    fk = abb.frame()
    assert fk.name == abb.end_effector and fk.frame_id == abb.frame_id(abb.end_effector)
    q = abb.random_configuration(1)
    assert np.array_equal(fk.jacobian(q, pin.LOCAL), abb.jacobian(q, reference="local"))
    assert "check_inputs=True" in repr(fk)


def test_checked_handle_refuses_bad_input(abb):
    fk = abb.frame("tool0")
    q = abb.neutral()
    for bad in (np.full(6, np.nan), np.r_[q[:5], np.inf], np.zeros(5), np.zeros((2, 6)), "abc", None):
        for call in (fk.pose, fk.jacobian, fk.kinematics):
            with pytest.raises(ConfigurationError):
                call(bad)
    # converted like everywhere else: lists, ints, strided and float32 input
    assert np.array_equal(fk.pose([0, 0, 0, 0, 0, 0]), abb.frame_pose(q))
    assert np.array_equal(fk.pose(np.zeros(12)[::2]), abb.frame_pose(q))
    assert np.allclose(fk.pose(np.zeros(6, dtype=np.float32)), abb.frame_pose(q))


def test_references_and_options_are_validated(abb):
    fk = abb.frame("tool0")
    for bad in (True, 1.0, np.int64(2), "LOCAL", None):
        with pytest.raises(OptionError):
            fk.jacobian(abb.neutral(), reference=bad)
        with pytest.raises(OptionError):
            fk.kinematics(abb.neutral(), reference=bad)
    with pytest.raises(FrameNotFoundError):
        abb.frame("tool1")
    with pytest.raises(OptionError):
        abb.frame("tool0", check_inputs="no")


def test_unchecked_handle_trusts_the_caller(abb):
    fk = abb.frame("tool0", check_inputs=False)
    q = abb.random_configuration(4)
    assert np.array_equal(fk.pose(q), abb.frame_pose(q))
    assert not fk.check_inputs


def test_mimic_buffer_is_per_call_and_per_thread(mixed):
    """The q_pin scratch buffer never leaks into results: two threads, different q, each right."""
    fk = mixed.frame("finger_b")
    Q = mixed.random_configuration(5, size=200)
    expected = [mixed.kinematics(q, "finger_b") for q in Q]

    def work(offset):
        return [fk.kinematics(Q[(i + offset) % len(Q)]) for i in range(len(Q))]

    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(work, range(4)))
    for offset, result in enumerate(results):
        for i, (T, J) in enumerate(result):
            T0, J0 = expected[(i + offset) % len(Q)]
            assert np.array_equal(T, T0) and np.array_equal(J, J0)
