"""``kinengine ik`` on poses without a solution in the joint limits (bad input: test_cli_errors.py; the
closed-form IK itself: test_closed_form_ik.py)."""

from __future__ import annotations

import numpy as np
import pytest

import kinengine
from kinengine.cli import main

pytest.importorskip("eaik")


def _pose_options(robot: kinengine.Robot, q: np.ndarray) -> list[str]:
    """``--xyz`` and ``--rpy`` (URDF roll, pitch, yaw) of the end effector's pose at q, to full precision."""
    T = robot.frame_pose(q)
    yaw, pitch, roll = robot.pose_parameters(q, rotation="euler_zyx")[3:]
    xyz = ",".join(repr(float(v)) for v in T[:3, 3])
    return ["--xyz", xyz, "--rpy", f"{roll:.17g},{pitch:.17g},{yaw:.17g}"]


def test_a_pose_with_solutions_only_outside_the_limits_says_so(capsys):
    robot = kinengine.load("abb_irb120")
    q = np.array([0.78, -0.563, 1.71, 3.166, 0.963, 2.251])  # joint_4 beyond its 2.79 rad limit
    T = robot.frame_pose(q)
    assert robot.ik_solutions(T).count == 0 and robot.ik_solutions(T, within_limits=False).count == 8
    pose = _pose_options(robot, q)
    assert main(["ik", "abb_irb120", *pose]) == 0
    assert "8 solution(s) outside the joint limits (--all lists them)" in capsys.readouterr().out
    assert main(["ik", "abb_irb120", "--xyz", "2,0,0.5"]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == "the pose is out of reach"


def test_a_seven_joint_arm_is_solved_with_a_joint_locked(capsys):
    """--lock panda_joint7=0 solves the Panda in closed form; without it the error names the option."""
    panda = kinengine.load("panda_arm")
    q = np.array([0.3, -0.4, 0.2, -2.0, 0.6, 1.5, 0.0])
    T = panda.frame_pose(q)
    pose = _pose_options(panda, q)
    assert main(["ik", "panda_arm", *pose]) == 2
    assert "(on the command line: --lock JOINT=VALUE)" in capsys.readouterr().err
    assert main(["ik", "panda_arm", *pose, "--lock", "panda_joint7=0", "--json"]) == 0
    import json

    report = json.loads(capsys.readouterr().out)
    six = panda.locked({"panda_joint7": 0.0})
    assert report["joint_names"] == list(six.joint_names) and report["count"] >= 1
    for solution in report["solutions"]:
        np.testing.assert_allclose(six.frame_pose(np.array(solution)), T, rtol=0, atol=1e-9)
    assert any(np.allclose(s, q[:6], atol=1e-9) for s in report["solutions"])
