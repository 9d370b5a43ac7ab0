"""URDF features that urdfdom accepts and real robot descriptions use (issue 12), each on a small URDF of ours.

* non-URDF blocks (``<gazebo>``, ``<transmission>``, ``<ros2_control>``) with namespace prefixes that are
  never declared, and a default ``xmlns`` on ``<robot>``: parsed as urdfdom parses them, DTDs and entities
  still refused;
* dynamics numbers kinematics never needs (negative effort and velocity, missing velocity, odd
  ``<dynamics>``, ``<safety_controller>`` and ``<calibration>``): not a reason to refuse; an error that does
  come from Pinocchio is a URDFError naming the joint and line;
* a joint with two ``<origin>`` elements: the first one wins, with a one-line warning;
* 0-dof and 1-dof robots on every Robot entry point: shaped results or a kinengine error, never a crash.

Every robot is checked against the independent reference (kinengine.reference: yourdfpy + numpy) and
central differences. Frames: I = root link frame; Jacobian rows [linear; angular].
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest
from custom_robots import mixed_chain_urdf, single_joint_gripper_urdf, single_revolute_urdf, suction_cup_urdf
from finite_differences import assert_close_relative, pose_jacobian_fd

import kinengine
from kinengine.errors import KinematicsError, URDFError
from kinengine.reference import REFERENCES, ReferenceKinematics
from kinengine.urdf import parse_urdf
from kinengine.verify import verify

EXTRAS = """
  <gazebo reference="l1">
    <sensor:camera name="wrist_camera"><sensor:image width="640" height="480"/></sensor:camera>
    <plugin name="p" filename="libgazebo_ros_control.so" gz:update_rate="100"><robotNamespace>/arm</robotNamespace></plugin>
  </gazebo>
  <transmission name="shoulder_transmission">
    <type>transmission_interface/SimpleTransmission</type>
    <joint name="shoulder"><hardwareInterface>hardware_interface/EffortJointInterface</hardwareInterface></joint>
    <actuator name="shoulder_motor"><mechanicalReduction>100</mechanicalReduction></actuator>
  </transmission>
  <ros2_control name="arm" type="system">
    <hardware><plugin>mock_components/GenericSystem</plugin></hardware>
    <joint name="shoulder"><command_interface name="position"/><state_interface name="position"/></joint>
  </ros2_control>
"""


def _decorated(text: str, extras: str = EXTRAS, robot_attributes: str = "") -> str:
    return text.replace('<robot name="mixed">', f'<robot name="mixed"{robot_attributes}>').replace(
        "</robot>", extras + "</robot>"
    )


def _assert_matches_reference(robot, reference_text: str, seed: int = 0) -> None:
    """Poses and Jacobians of every frame vs the reference of ``reference_text`` (1e-12) and vs FD (1e-7)."""
    ref = ReferenceKinematics.from_urdf_string(reference_text, joint_names=robot.joint_names)
    rng = np.random.default_rng(seed)
    for q in (robot.neutral(), rng.uniform(-1, 1, robot.dof)):
        for frame in robot.frame_names:
            np.testing.assert_allclose(
                robot.frame_pose(q, frame), ref.frame_pose(q, frame), rtol=0, atol=1e-12
            )
            for reference in REFERENCES:
                J = robot.jacobian(q, frame, reference)
                np.testing.assert_allclose(J, ref.jacobian(q, frame, reference), rtol=0, atol=1e-12)
                if robot.dof:
                    J_fd = pose_jacobian_fd(lambda x: robot.frame_pose(x, frame), q, reference)
                    assert_close_relative(J, J_fd, 1e-7, f"{frame} {reference}")


# -- namespaces ------------------------------------------------------------------------------------
def test_blocks_with_undeclared_prefixes_are_ignored_like_urdfdom_does():
    plain = mixed_chain_urdf()
    text = _decorated(plain)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing to warn about
        robot = kinengine.load_urdf_string(text)
    assert robot.description.to_xml() == parse_urdf(plain).to_xml()
    _assert_matches_reference(robot, plain)
    _assert_matches_reference(robot, text)  # the reference reads it as urdfdom does too
    assert verify(robot, samples=4).passed


def test_a_default_xmlns_on_robot_is_read_as_plain_urdf():
    plain = mixed_chain_urdf()
    text = _decorated(
        plain, robot_attributes=' xmlns="http://www.ros.org" xmlns:xacro="http://www.ros.org/wiki/xacro"'
    )
    robot = kinengine.load_urdf_string(text)
    assert robot.description.to_xml() == parse_urdf(plain).to_xml()
    _assert_matches_reference(robot, plain, seed=1)
    assert verify(robot, samples=4).passed


def test_declared_prefixes_keep_their_declarations_and_a_scoped_one_works_outside_its_scope():
    extras = (
        '<gazebo xmlns:sensor="http://gazebosim.org/sensor"><sensor:camera/></gazebo>\n'
        "<gazebo><sensor:ray/></gazebo>\n"
    )  # urdfdom reads the second block although 'sensor' is out of scope
    robot = kinengine.load_urdf_string(_decorated(mixed_chain_urdf(), extras))
    assert robot.dof == 6


def test_utf16_documents_with_undeclared_prefixes_load():
    text = _decorated(mixed_chain_urdf()).replace(
        '<?xml version="1.0"?>', '<?xml version="1.0" encoding="UTF-16"?>'
    )
    robot = kinengine.load_urdf_string(text.encode("utf-16"))
    assert robot.description.to_xml() == parse_urdf(mixed_chain_urdf()).to_xml()


def test_line_numbers_stay_those_of_the_file():
    text = _decorated(mixed_chain_urdf()).replace('<axis xyz="0 1 0"/>', '<axis xyz="0 0 0"/>', 1)
    line = text[: text.index('<axis xyz="0 0 0"/>')].count("\n") + 1
    with pytest.raises(URDFError, match="is zero") as info:
        kinengine.load_urdf_string(text)
    assert info.value.line == line


@pytest.mark.parametrize(
    "prolog, body, message",
    [
        ('<!DOCTYPE robot [<!ENTITY x "0 0 1">]>\n', "<sensor:camera/>", "<!DOCTYPE> is not allowed"),
        ('<!DOCTYPE robot SYSTEM "file:///etc/passwd">\n', "<gz:x/>", "<!DOCTYPE> is not allowed"),
        ("", '<gazebo><sensor:camera name="&x;"/></gazebo>', "not well-formed XML"),  # an undeclared entity
        ("", "<gazebo><sensor:camera></gazebo>", "not well-formed XML"),  # malformed, never recovered
    ],
)
def test_dtds_entities_and_malformed_documents_are_still_refused(prolog, body, message):
    text = prolog + '<robot name="r">\n<link name="a"/>\n' + body + "\n</robot>"
    with pytest.raises(URDFError, match=message):
        kinengine.load_urdf_string(text)


def test_hundreds_of_undeclared_prefixes_are_refused_with_the_fix():
    body = "<gazebo>" + "".join(f"<p{i}:x/>" for i in range(257)) + "</gazebo>"
    with pytest.raises(
        URDFError, match="257 namespace prefixes that <robot> does not declare .* declare them"
    ):
        kinengine.load_urdf_string(f'<robot name="r">\n<link name="a"/>\n{body}\n</robot>')


def test_an_undeclared_xacro_prefix_is_still_a_xacro_macro():
    with pytest.raises(URDFError, match="<xacro:include> is a xacro macro"):
        kinengine.load_urdf_string(
            '<robot name="r">\n<link name="a"/>\n<xacro:include filename="x.xacro"/>\n</robot>'
        )


# -- dynamics numbers kinematics never needs --------------------------------------------------------
ODD_DYNAMICS = """<?xml version="1.0"?>
<robot name="odd">
  <link name="base"/><link name="l1"/><link name="l2"/><link name="l3"/>
  <joint name="unknown_effort" type="revolute">
    <parent link="base"/><child link="l1"/><origin xyz="0 0 0.2"/><axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" effort="-1" velocity="-1"/>
    <dynamics damping="-1" friction="-0.5"/>
    <safety_controller soft_lower_limit="3" soft_upper_limit="-3" k_position="-10" k_velocity="-1"/>
    <calibration rising="-7"/>
  </joint>
  <joint name="no_velocity" type="prismatic">
    <parent link="l1"/><child link="l2"/><origin xyz="0.1 0 0.1"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.3" effort="5"/>
    <dynamics/>
    <calibration falling="0.1"/>
  </joint>
  <joint name="bare_limit" type="continuous">
    <parent link="l2"/><child link="l3"/><origin xyz="0 0.1 0" rpy="0.2 0 0"/><axis xyz="0 1 0"/>
    <limit/>
    <safety_controller k_velocity="0"/>
  </joint>
</robot>
"""


def test_odd_dynamics_numbers_load_and_never_reach_pinocchio():
    robot = kinengine.load_urdf_string(ODD_DYNAMICS)
    assert robot.joint_names == ("unknown_effort", "no_velocity", "bare_limit")
    first = robot.description.joint("unknown_effort")
    assert (first.effort, first.velocity) == (-1.0, -1.0)  # the file's numbers are kept
    assert robot.description.joint("no_velocity").velocity is None
    model = robot.pinocchio_model()
    assert (model.effortLimit >= 0).all() and (model.velocityLimit >= 0).all()
    np.testing.assert_array_equal(
        [robot.lower_limits, robot.upper_limits], [[-2, 0, -np.inf], [2, 0.3, np.inf]]
    )
    _assert_matches_reference(robot, ODD_DYNAMICS)
    assert verify(robot, samples=4).passed


def test_an_error_from_pinocchio_names_the_joint_and_line(monkeypatch):
    import pinocchio as pin

    import kinengine.model.pinocchio_model as pinocchio_model

    if int(pin.__version__.split(".")[0]) < 4:
        pytest.skip(f"Pinocchio {pin.__version__} builds a negative effort limit: no error to name")

    monkeypatch.setattr(pinocchio_model, "_nonnegative", lambda value: value)  # let effort -1 through
    with pytest.raises(URDFError, match="Pinocchio could not build it: .*effort") as info:
        kinengine.load_urdf_string(ODD_DYNAMICS)
    assert info.value.element == "joint 'unknown_effort'" and info.value.line == 4
    assert str(info.value).startswith("<string>:4, joint 'unknown_effort': Pinocchio could not build it")


# -- repeated elements -----------------------------------------------------------------------------
def test_the_first_of_two_origins_wins_with_a_one_line_warning():
    one = mixed_chain_urdf()
    two = one.replace(
        '<origin xyz="0.1 0 0.25" rpy="0.3 0 0"/>',
        '<origin xyz="0.1 0 0.25" rpy="0.3 0 0"/>\n    <origin xyz="9 9 9" rpy="1 1 1"/>',
    )
    line = two[: two.index('<joint name="slide"')].count("\n") + 1
    with pytest.warns(UserWarning) as caught:
        robot = kinengine.load_urdf_string(two)
    messages = [str(w.message) for w in caught]
    assert messages == [
        f"<string>: joint 'slide' (line {line}) has 2 <origin> elements (lines {line + 2}, {line + 3}); "
        "the first one is used, as urdfdom does"
    ]
    assert "\n" not in messages[0]
    assert robot.description.to_xml() == parse_urdf(one).to_xml()
    _assert_matches_reference(robot, two)  # yourdfpy reads the first one too
    _assert_matches_reference(robot, one)


# -- 0-dof and 1-dof robots on every entry point -----------------------------------------------------
SMALL = {
    "suction_cup": suction_cup_urdf(),
    "single_revolute": single_revolute_urdf(),
    "single_joint_gripper": single_joint_gripper_urdf(),
    "lone_link": '<robot name="lone"><link name="only"/></robot>',
}


def _entry_points(robot):
    """Every public Robot entry point at a valid q, with the shape (or check) of its result."""
    n, q, qdot = robot.dof, robot.neutral(), np.full(robot.dof, 0.3)
    Q = np.zeros((3, n))
    task = robot.task()
    yield "frame_pose", lambda: robot.frame_pose(q), (4, 4)
    yield "frame_pose batch", lambda: robot.frame_pose(Q), (3, 4, 4)
    for ref in REFERENCES:
        yield f"jacobian {ref}", lambda ref=ref: robot.jacobian(q, reference=ref), (6, n)
        yield (
            f"jacobian_time_variation {ref}",
            lambda ref=ref: robot.jacobian_time_variation(q, qdot, reference=ref),
            (6, n),
        )
        yield f"kinematic_hessian {ref}", lambda ref=ref: robot.kinematic_hessian(q, reference=ref), (6, n, n)
    yield "jacobian batch", lambda: robot.jacobian(Q), (3, 6, n)
    yield "kinematics", lambda: robot.kinematics(q)[1], (6, n)
    yield "kinematics batch", lambda: robot.kinematics(Q)[1], (3, 6, n)
    yield "pose_parameters", lambda: robot.pose_parameters(q), (6,)
    yield "analytic_jacobian", lambda: robot.analytic_jacobian(q), (6, n)
    yield "analytic_jacobian batch", lambda: robot.analytic_jacobian(Q), (3, 6, n)
    yield "analytic_hessian", lambda: robot.analytic_hessian(q), (6, n, n)
    yield "task.update", lambda: (task.update(q), task.analytic_jacobian)[1], (6, n)
    yield "task.update qdot", lambda: (task.update(q, qdot), task.analytic_jacobian_dot)[1], (6, n)
    yield "singularity_report", lambda: robot.singularity_report(q).singular_values, (min(6, n),)
    yield "manipulability", lambda: np.asarray(robot.manipulability(q)), ()
    yield "manipulability batch", lambda: robot.manipulability(Q), (3,)
    yield "velocity_ellipsoid", lambda: robot.velocity_ellipsoid(q).semi_axes, (3,)
    yield "inverse_kinematics", lambda: robot.inverse_kinematics(robot.frame_pose(q), q0=q).q, (n,)
    yield "inverse_kinematics batch", lambda: robot.inverse_kinematics(robot.frame_pose(Q)).q, (3, n)
    yield (
        "inverse_kinematics frames",
        lambda: robot.inverse_kinematics({robot.end_effector: robot.frame_pose(q)}).q,
        (n,),
    )
    yield "random_configuration", lambda: robot.random_configuration(0, size=4), (4, n)
    yield "random_configuration one", lambda: robot.random_configuration(0), (n,)


@pytest.mark.parametrize("name", list(SMALL))
def test_small_robots_answer_every_entry_point_with_shaped_finite_results(name):
    robot = kinengine.load_urdf_string(SMALL[name])
    assert robot.dof == (0 if name in ("suction_cup", "lone_link") else 1)
    for label, call, shape in _entry_points(robot):
        try:
            out = np.asarray(call())
        except KinematicsError:
            continue  # a kinengine error is an answer too
        assert out.shape == shape, label
        assert np.isfinite(out).all() or label.startswith("singularity"), label
    assert verify(robot, samples=4).passed


@pytest.mark.parametrize("name", ["single_revolute", "single_joint_gripper"])
def test_one_dof_derivatives_match_finite_differences(name):
    robot = kinengine.load_urdf_string(SMALL[name])
    _assert_matches_reference(robot, SMALL[name])
    q, qdot, h = np.array([0.02]), np.array([0.7]), 1e-6
    for frame in robot.frame_names:
        for ref in REFERENCES:
            dJ = (robot.jacobian(q + h * qdot, frame, ref) - robot.jacobian(q - h * qdot, frame, ref)) / (
                2 * h
            )
            assert_close_relative(
                robot.jacobian_time_variation(q, qdot, frame, ref), dJ, 1e-7, f"J̇ {frame} {ref}"
            )
            H = robot.kinematic_hessian(q, frame, ref)
            assert_close_relative(H[:, :, 0] * qdot[0], dJ, 1e-7, f"∂J/∂q {frame} {ref}")
        JA = lambda x: robot.analytic_jacobian(x, frame)  # noqa: E731
        assert_close_relative(
            robot.analytic_hessian(q, frame)[:, :, 0],
            (JA(q + h) - JA(q - h)) / (2 * h),
            1e-6,
            f"∂J_A/∂q {frame}",
        )
        task = robot.task(frame)
        task.update(q, qdot)
        dJ = (robot.jacobian(q + h * qdot, frame) - robot.jacobian(q - h * qdot, frame)) / (2 * h)
        assert_close_relative(task.jacobian_dot, dJ, 1e-7, f"task J̇ {frame}")
        np.testing.assert_allclose(task.chi_dot, robot.analytic_jacobian(q, frame) @ qdot, rtol=0, atol=1e-13)


def test_zero_dof_robot_answers_empty_derivatives_in_a_subprocess():
    # J̇ of a 0-dof robot used to kill the process (a segmentation fault in Pinocchio 4.1): run it apart
    code = textwrap.dedent(f"""
        import numpy as np, kinengine
        robot = kinengine.load_urdf_string({suction_cup_urdf()!r})
        for ref in ("local_world_aligned", "local", "world"):
            assert robot.jacobian_time_variation([], [], reference=ref).shape == (6, 0)
            assert robot.kinematic_hessian([], reference=ref).shape == (6, 0, 0)
        assert robot.analytic_hessian([]).shape == (6, 0, 0)
        task = robot.task()
        task.update([], [])
        assert task.jacobian_dot.shape == (6, 0) and np.isfinite(task.chi_dot).all()
        print("ok")
    """)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr


def test_zero_dof_pose_is_the_fixed_chain():
    robot = kinengine.load_urdf_string(suction_cup_urdf())
    _assert_matches_reference(robot, suction_cup_urdf())
    T = robot.frame_pose([], "cup_tip")
    c, s, c2, s2 = np.cos(0.7), np.sin(0.7), np.cos(0.2), np.sin(0.2)
    Rz, Rx = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]), np.array([[1, 0, 0], [0, c2, -s2], [0, s2, c2]])
    np.testing.assert_allclose(T[:3, :3], Rz @ Rx, rtol=0, atol=1e-15)
    np.testing.assert_allclose(T[:3, 3], [0, 0, 0.05] + Rz @ [0.01, 0, 0.03], rtol=0, atol=1e-15)
