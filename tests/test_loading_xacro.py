"""Loading xacro files and package paths through kinengine.load, load_urdf_string and the command line;
one warning per load (floating-base robots, parser notes); the panda_arm catalog entry.

The xacro files are written here, into a temporary ROS-like workspace: a macro file in package
``kin_parts`` included with ``$(find kin_parts)``, a ``*_macro.xacro`` + wrapper pair with arguments
(with defaults), properties, math and conditionals. Each must give the hand-expanded URDF to 1e-15.
"""

from __future__ import annotations

import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import kinengine
from kinengine import URDFError
from kinengine.cli.main import main
from kinengine.urdf.packages import resolve_uri

MACRO = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:property name="pi_half" value="${pi / 2}"/>
  <xacro:macro name="arm" params="prefix length:=0.4 wrist:=true">
    <link name="${prefix}base"/>
    <link name="${prefix}upper"/>
    <link name="${prefix}tool0"/>
    <joint name="${prefix}shoulder" type="revolute">
      <parent link="${prefix}base"/><child link="${prefix}upper"/>
      <origin xyz="0 0 ${length / 2}" rpy="0 0 ${pi_half}"/><axis xyz="0 0 1"/>
      <limit lower="${-pi_half}" upper="${pi_half}" effort="10" velocity="2"/>
    </joint>
    <xacro:if value="${wrist}">
      <link name="${prefix}wrist_link"/>
      <joint name="${prefix}wrist" type="prismatic">
        <parent link="${prefix}upper"/><child link="${prefix}wrist_link"/>
        <origin xyz="${length} 0 0"/><axis xyz="1 0 0"/>
        <limit lower="0" upper="${length / 4}" effort="10" velocity="1"/>
      </joint>
      <joint name="${prefix}flange" type="fixed">
        <parent link="${prefix}wrist_link"/><child link="${prefix}tool0"/>
        <origin xyz="0 0 0.05"/>
      </joint>
    </xacro:if>
    <xacro:unless value="${wrist}">
      <joint name="${prefix}flange" type="fixed">
        <parent link="${prefix}upper"/><child link="${prefix}tool0"/>
        <origin xyz="${length} 0 0.05"/>
      </joint>
    </xacro:unless>
  </xacro:macro>
</robot>
"""

WRAPPER = """<?xml version="1.0"?>
<robot name="small_arm" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:arg name="length" default="0.4"/>
  <xacro:arg name="wrist" default="true"/>
  <xacro:include filename="$(find kin_parts)/urdf/arm_macro.xacro"/>
  <xacro:arm prefix="" length="$(arg length)" wrist="$(arg wrist)"/>
</robot>
"""


def expected_urdf(length: float, wrist: bool) -> str:
    """The wrapper expanded by hand."""
    half = np.pi / 2
    tool = (
        f"""<link name="wrist_link"/>
  <joint name="wrist" type="prismatic"><parent link="upper"/><child link="wrist_link"/>
    <origin xyz="{length!r} 0 0"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="{length / 4!r}" effort="10" velocity="1"/></joint>
  <joint name="flange" type="fixed"><parent link="wrist_link"/><child link="tool0"/>
    <origin xyz="0 0 0.05"/></joint>"""
        if wrist
        else f"""<joint name="flange" type="fixed">
    <parent link="upper"/><child link="tool0"/><origin xyz="{length!r} 0 0.05"/></joint>"""
    )
    return f"""<robot name="small_arm">
  <link name="base"/><link name="upper"/><link name="tool0"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>
    <origin xyz="0 0 {length / 2!r}" rpy="0 0 {half!r}"/><axis xyz="0 0 1"/>
    <limit lower="{-half!r}" upper="{half!r}" effort="10" velocity="2"/></joint>
  {tool}
</robot>
"""


@pytest.fixture(autouse=True)
def no_ros_package_path(monkeypatch):
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)


@pytest.fixture
def workspace(tmp_path) -> dict[str, Path]:
    """ws/src/kin_arm/urdf/arm.urdf.xacro (package kin_arm) and, elsewhere, package kin_parts in a folder
    of another name (found by its package.xml)."""
    parts = tmp_path / "vendor" / "parts_folder"
    (parts / "urdf").mkdir(parents=True)
    (parts / "package.xml").write_text("<package format='3'><name>kin_parts</name></package>")
    (parts / "urdf" / "arm_macro.xacro").write_text(MACRO)
    arm = tmp_path / "ws" / "src" / "kin_arm"
    (arm / "urdf").mkdir(parents=True)
    (arm / "package.xml").write_text("<package format='3'><name>kin_arm</name></package>")
    (arm / "urdf" / "arm.urdf.xacro").write_text(WRAPPER)
    return {"wrapper": arm / "urdf" / "arm.urdf.xacro", "parts": parts, "root": tmp_path}


def assert_same_model(robot, expected_text: str) -> None:
    expected = kinengine.load_urdf_string(expected_text)
    assert robot.joint_names == expected.joint_names
    assert sorted(robot.frame_names) == sorted(expected.frame_names)
    rng = np.random.default_rng(3)
    for q in [expected.neutral()] + [expected.random_configuration(rng) for _ in range(4)]:
        for frame in expected.frame_names:
            np.testing.assert_allclose(
                robot.frame_pose(q, frame), expected.frame_pose(q, frame), rtol=0, atol=1e-15
            )
            for reference in ("local_world_aligned", "local", "world"):
                np.testing.assert_allclose(
                    robot.jacobian(q, frame, reference),
                    expected.jacobian(q, frame, reference),
                    rtol=0,
                    atol=1e-15,
                )


# -- kinengine.load --------------------------------------------------------------------------------
def test_load_xacro_with_packages_argument(workspace):
    robot = kinengine.load(workspace["wrapper"], packages={"kin_parts": workspace["parts"]})
    assert_same_model(robot, expected_urdf(0.4, True))
    assert dict(robot.packages) == {"kin_parts": str(workspace["parts"])}
    assert "xacro" not in robot.urdf_text and robot.source == str(workspace["wrapper"])
    with pytest.raises(TypeError):
        robot.packages["x"] = "/tmp"  # read-only


def test_load_xacro_with_arguments_math_and_conditionals(workspace):
    robot = kinengine.load(
        str(workspace["wrapper"]),
        xacro_args={"length": 0.6, "wrist": "false"},
        packages={"kin_parts": str(workspace["parts"])},
    )
    assert robot.dof == 1
    assert_same_model(robot, expected_urdf(0.6, False))


def test_load_xacro_through_ros_package_path(workspace, monkeypatch):
    monkeypatch.setenv(
        "ROS_PACKAGE_PATH",
        os.pathsep.join([str(workspace["root"] / "nowhere"), str(workspace["root"] / "vendor")]),
    )
    assert_same_model(kinengine.load(workspace["wrapper"]), expected_urdf(0.4, True))


def test_load_xacro_through_its_own_tree(workspace):
    """kin_parts moved next to the wrapper's package: found by walking up from the file."""
    (workspace["parts"]).rename(workspace["root"] / "ws" / "src" / "kin_parts")
    assert_same_model(kinengine.load(workspace["wrapper"]), expected_urdf(0.4, True))


def test_xacro_errors_are_one_line_urdf_errors(workspace, tmp_path):
    with pytest.raises(URDFError, match="kin_parts") as exc:
        kinengine.load(workspace["wrapper"])  # kin_parts is nowhere it looks
    assert "\n" not in str(exc.value) and "packages=" in str(exc.value)
    needs = tmp_path / "needs.xacro"
    needs.write_text(
        '<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro"><link name="$(arg base)"/></robot>'
    )
    with pytest.raises(URDFError, match="base") as exc:
        kinengine.load(needs)
    assert "\n" not in str(exc.value)
    assert "b" in kinengine.load(needs, xacro_args={"base": "b"}).frame_names
    macro_only = tmp_path / "only_macros.xacro"
    macro_only.write_text(MACRO)
    with pytest.raises(URDFError):
        kinengine.load(macro_only)


def test_options_are_checked(workspace, abb_path):
    with pytest.raises(URDFError, match="xacro_args= is for .xacro files"):
        kinengine.load(abb_path, xacro_args={"a": "b"})
    with pytest.raises(URDFError, match="packages= takes a mapping"):
        kinengine.load(abb_path, packages=["kin_parts"])
    with pytest.raises(URDFError, match="packages= takes a mapping"):
        kinengine.load_urdf_string(expected_urdf(0.4, True), packages={"kin_parts": 3})


def test_plain_urdf_keeps_packages_for_package_uris(workspace, tmp_path):
    urdf = tmp_path / "robot.urdf"
    urdf.write_text(
        expected_urdf(0.4, True).replace(
            '<link name="upper"/>',
            '<link name="upper"><visual><geometry><mesh filename="package://kin_parts/m.stl"/>'
            "</geometry></visual></link>",
        )
    )
    robot = kinengine.load(urdf, packages={"kin_parts": workspace["parts"]})
    assert (
        resolve_uri("package://kin_parts/m.stl", packages=robot.packages, start=Path(robot.source))
        == workspace["parts"].resolve() / "m.stl"
    )
    from_text = kinengine.load_urdf_string(urdf.read_text(), packages={"kin_parts": workspace["parts"]})
    assert dict(from_text.packages) == {"kin_parts": str(workspace["parts"])}
    assert dict(kinengine.load("abb_irb120").packages) == {}


# -- command line ----------------------------------------------------------------------------------
@pytest.mark.slow
def test_cli_info_on_a_xacro_in_a_subprocess(workspace):
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "kinengine",
            "info",
            str(workspace["wrapper"]),
            "--xacro-arg",
            "length=0.6",
            "--xacro-arg",
            "wrist=false",
            "--package",
            f"kin_parts={workspace['parts']}",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr
    assert "small_arm: 1 dof" in run.stdout and "shoulder" in run.stdout and "wrist" not in run.stdout
    assert run.stderr == ""


def test_cli_commands_take_xacro_options(workspace, capsys, tmp_path):
    options = [str(workspace["wrapper"]), "--package", f"kin_parts={workspace['parts']}"]
    assert main(["pose", *options, "--q", "0.3,0.05"]) == 0
    assert "small_arm (2 dof)" in capsys.readouterr().out
    assert main(["verify", *options, "--samples", "3"]) == 0
    assert "PASSED" in capsys.readouterr().out
    assert main(["show", *options, "-o", str(tmp_path / "arm.png")]) == 0
    assert (tmp_path / "arm.png").stat().st_size > 0
    capsys.readouterr()
    assert main(["info", str(workspace["wrapper"])]) == 2  # kin_parts not found
    err = capsys.readouterr().err
    assert err.startswith("kinengine: error:") and "--package kin_parts=" in err and err.count("\n") == 1


def test_cli_refuses_a_malformed_option(workspace, capsys):
    with pytest.raises(SystemExit):
        main(["info", str(workspace["wrapper"]), "--xacro-arg", "length"])
    assert "expected NAME=VALUE" in capsys.readouterr().err


# -- one warning per load ---------------------------------------------------------------------------
LEGGED = """<robot name="biped">
  <link name="pelvis"/>
  <link name="left_thigh"/><link name="right_thigh"/>
  <link name="left_foot"/>
  <joint name="left_hip" type="revolute"><parent link="pelvis"/><child link="left_thigh"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="right_hip" type="revolute"><parent link="pelvis"/><child link="right_thigh"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="left_knee" type="revolute"><parent link="left_thigh"/><child link="left_foot"/>
    <origin xyz="0 0 -0.4"/><axis xyz="0 2 0"/><limit lower="0" upper="2" effort="1" velocity="1"/>
    <mimic joint="left_hip"/></joint>
  {extra}
</robot>
"""
IGNORED_MIMICS = """<link name="a"/><link name="b"/>
  <joint name="fa" type="fixed"><parent link="pelvis"/><child link="a"/><mimic joint="left_hip"/></joint>
  <joint name="fb" type="fixed"><parent link="pelvis"/><child link="b"/><mimic joint="left_hip"/></joint>"""


def _warnings_of(load) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        load()
    return [str(w.message) for w in caught]


def test_floating_base_robot_loads_with_one_warning_naming_the_root(tmp_path):
    path = tmp_path / "biped.urdf"
    path.write_text(LEGGED.format(extra=IGNORED_MIMICS))
    messages = _warnings_of(lambda: kinengine.load(path))
    assert len(messages) == 1, messages
    assert "root link 'pelvis' held fixed" in messages[0] and messages[0].startswith(str(path))
    assert "3 notes on the description" in messages[0]  # a normalized axis and two ignored <mimic>s
    with pytest.warns(UserWarning, match="held fixed"):
        robot = kinengine.load_urdf_string(LEGGED.format(extra=""))
    assert len(robot.description.warnings) == 1
    messages = _warnings_of(lambda: kinengine.load_urdf_string(LEGGED.format(extra="")))
    assert len(messages) == 1 and "held fixed" in messages[0] and "normalized" in messages[0]


def test_arms_load_without_a_floating_base_warning(abb_path):
    assert _warnings_of(lambda: kinengine.load(abb_path)) == []
    assert _warnings_of(lambda: kinengine.load("panda")) == []


PROPS = """<?xml version="1.0"?>
<robot name="{name}"><link name="base_link"/>
  {links}
</robot>
"""


@pytest.mark.parametrize(
    ("name", "links", "flying"),
    [
        ("wx250s", ["wx250s/gripper_prop_link", "wx250s/left_finger_link"], False),  # Interbotix's gripper
        ("quad", ["prop_0", "prop_1", "prop_2", "prop_3"], True),
        ("hex", ["rotor_0_link"], True),
    ],
)
def test_a_gripper_prop_is_not_a_propeller(name, links, flying):
    text = "\n  ".join(
        f'<link name="{link}"/><joint name="j{i}" type="fixed"><parent link="base_link"/>'
        f'<child link="{link}"/></joint>'
        for i, link in enumerate(links)
    )
    messages = _warnings_of(lambda: kinengine.load_urdf_string(PROPS.format(name=name, links=text)))
    assert any("looks like a flying robot" in m for m in messages) == flying, messages


def test_talos_loads_with_one_warning():
    path = _erd("talos_data/robots/talos_reduced.urdf")
    messages = _warnings_of(lambda: kinengine.load(path))
    assert len(messages) == 1, messages
    assert "root link 'base_link' held fixed" in messages[0]


# -- catalog: panda_arm -------------------------------------------------------------------------------
def test_panda_arm_is_the_panda_with_its_finger_locked():
    panda, arm = kinengine.load("panda"), kinengine.load("panda_arm")
    assert arm.name == "panda_arm" and arm.dof == 7 and arm.joint_names == panda.joint_names[:7]
    assert arm.end_effector == "panda_hand_tcp"
    q = arm.random_configuration(0)
    full = np.append(q, 0.0)
    np.testing.assert_allclose(arm.frame_pose(q), panda.frame_pose(full, "panda_hand_tcp"), atol=1e-15)
    np.testing.assert_allclose(arm.jacobian(q), panda.jacobian(full, "panda_hand_tcp")[:, :7], atol=1e-15)
    assert "panda_arm" in kinengine.available_robots()


def test_info_names_gripper_coordinates(capsys):
    assert main(["info", "panda"]) == 0
    out = capsys.readouterr().out
    assert "gripper coordinates: panda_finger_joint1" in out and "kinengine.load('panda_arm')" in out
    assert main(["info", "abb_irb120"]) == 0
    assert "gripper" not in capsys.readouterr().out


@pytest.fixture
def abb_path() -> Path:
    from kinengine.model import catalog_entry

    return catalog_entry("abb_irb120").path


def _erd(relative: str) -> Path:
    import importlib.metadata

    path = (
        Path(
            importlib.metadata.distribution("example-robot-data").locate_file(
                "cmeel.prefix/share/example-robot-data/robots"
            )
        )
        / relative
    )
    if not path.is_file():
        pytest.skip(f"example-robot-data has no {relative}")
    return path


def test_concurrent_loads_each_warn_once_and_leave_warnings_working():
    import threading

    text = LEGGED.format(extra=IGNORED_MIMICS)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        threads = [threading.Thread(target=kinengine.load_urdf_string, args=(text,)) for _ in range(4)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        warnings.warn("after the loads", UserWarning, stacklevel=1)
    messages = [str(w.message) for w in caught]
    assert sum("held fixed" in m for m in messages) == 4 and messages.count("after the loads") == 1, messages
    assert len(messages) == 5, messages
