"""examples/resolved_rate_circle.py runs headless, writes its plot and tracks the circle."""

from __future__ import annotations

import numpy as np
import pytest
from example_modules import example_module

import kinengine


@pytest.fixture(scope="module")
def example():
    yield from example_module("resolved_rate_circle")


def test_main_writes_a_png(example, tmp_path, capsys):
    out = tmp_path / "circle.png"
    assert example.main(["--output", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "max position error after 0.5 s" in capsys.readouterr().out


def test_tool_follows_the_circle_after_half_a_second(example):
    run = example.simulate()
    settled = run.t >= 0.5
    assert run.t[-1] == pytest.approx(5.0) and np.diff(run.t) == pytest.approx(1e-3)
    assert run.position_error[0] == pytest.approx(0.05)  # starts at the centre: 5 cm off the circle
    assert run.position_error[settled].max() < 1e-4
    assert run.rotation_error[settled].max() < 1e-4
    assert run.min_zyx_distance > 0.9 and run.min_sigma > 0.05  # regular all along
    # independently of the controller's bookkeeping: forward kinematics of the logged q at a quarter turn
    robot = kinengine.load("abb_irb120")
    centre = robot.frame_pose(example.Q_START, "tool0")[:3, 3]
    k = int(np.argmin(np.abs(run.t - 1.25)))
    p = robot.frame_pose(run.q[k], "tool0")[:3, 3]
    np.testing.assert_allclose(p, centre + [0.0, 0.0, 0.05], rtol=0, atol=1e-4)
    assert np.all(run.q >= robot.lower_limits) and np.all(run.q <= robot.upper_limits)
