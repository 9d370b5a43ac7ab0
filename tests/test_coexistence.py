"""kinengine installs beside pink and mink: one fresh virtual environment with all three, ``pip check``
clean, and a script that uses the three on example-robot-data's UR5 in one process, each checked against
kinengine's frame poses (the same Pinocchio model for pink, the same URDF compiled by MuJoCo for mink)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from fresh_venv import clean_env, run

REPO = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.slow

SMOKE = r"""
import re

import mink
import mujoco
import numpy as np
import pink
import pinocchio as pin

import kinengine

robot = kinengine.load("ur5")
q = np.array([0.3, -1.0, 1.2, -0.5, 0.8, 0.2])
T = robot.frame_pose(q, "tool0")
goal = T.copy()
goal[:3, 3] += [0.0, 0.02, 0.03]

# pink on kinengine's Pinocchio model: the same tool0 pose, and a QP step towards the goal
model = robot.pinocchio_model()
configuration = pink.Configuration(model, model.createData(), robot.pinocchio_configuration(q))
assert np.allclose(configuration.get_transform_frame_to_world("tool0").homogeneous, T, atol=1e-12)
task = pink.tasks.FrameTask("tool0", position_cost=1.0, orientation_cost=1.0)
task.set_target(pin.SE3(goal[:3, :3], goal[:3, 3]))
v = pink.solve_ik(configuration, [task], dt=0.01, solver="daqp")
after = robot.frame_pose(q + 0.01 * v, "tool0")
assert np.linalg.norm(after[:3, 3] - goal[:3, 3]) < np.linalg.norm(T[:3, 3] - goal[:3, 3])

# mink on the same URDF compiled by MuJoCo (meshes dropped: kinematics only)
urdf = re.sub(r"<(visual|collision)\b.*?</\1>", "", robot.urdf_text, flags=re.S)
mj = mujoco.MjModel.from_xml_string(urdf)
cfg = mink.Configuration(mj)
cfg.update(q)
W = cfg.get_transform_frame_to_world("wrist_3_link", "body").as_matrix()
assert np.allclose(W, robot.frame_pose(q, "wrist_3_link"), atol=1e-9), (W, robot.frame_pose(q, "wrist_3_link"))
flange = robot.frame_pose(q, "wrist_3_link")
target = flange.copy()
target[:3, 3] += [0.0, 0.02, 0.03]
mtask = mink.FrameTask("wrist_3_link", "body", position_cost=1.0, orientation_cost=1.0)
mtask.set_target(mink.SE3.from_matrix(target))
w = mink.solve_ik(cfg, [mtask], dt=0.01, solver="daqp")
after = robot.frame_pose(q + 0.01 * w, "wrist_3_link")
assert np.linalg.norm(after[:3, 3] - target[:3, 3]) < np.linalg.norm(flange[:3, 3] - target[:3, 3])
print("kinengine", kinengine.__version__, "pink", pink.__version__, "mink ok; pin", pin.__version__)
"""


def _run(cmd: list[object], cwd: Path, timeout: float) -> str:
    return run(cmd, cwd=cwd, timeout=timeout, env=clean_env(MUJOCO_GL="disable")).stdout


def test_kinengine_pink_and_mink_in_one_environment(tmp_path: Path) -> None:
    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", venv], tmp_path, 300)
    python = venv / "bin" / "python"
    _run([python, "-m", "pip", "install", "-q", "--no-compile", REPO, "pin-pink", "mink"], tmp_path, 1800)
    assert "No broken requirements found." in _run([python, "-m", "pip", "check"], tmp_path, 120)
    script = tmp_path / "smoke.py"
    script.write_text(SMOKE, encoding="utf-8")
    out = _run([python, script], tmp_path, 600)
    assert out.startswith("kinengine "), out
