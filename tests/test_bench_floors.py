"""Every analytic_jacobian floor of ``kinengine bench`` computes what robot.analytic_jacobian computes (to 1e-12),
and the task floor gives the task's χ and analytic Jacobian: the bench compares like with like."""

from __future__ import annotations

import numpy as np
import pytest

import kinengine
from kinengine.cli.bench.cases import regular_configuration
from kinengine.cli.bench.floors import FLOOR_ANALYTIC, floors
from kinengine.parameterizations import ROTATION_PARAMETERIZATIONS

ROBOTS = ("abb_irb120", "ur5")


@pytest.fixture(scope="module", params=ROBOTS)
def setup(request):
    robot = kinengine.load(request.param)
    frame = robot.end_effector
    rotations = list(ROTATION_PARAMETERIZATIONS)
    q, _ = regular_configuration(robot, frame, rotations)
    return robot, frame, q, floors(robot, frame, q)


@pytest.mark.parametrize("rotation", list(ROTATION_PARAMETERIZATIONS))
def test_every_analytic_floor_equals_kinengine(setup, rotation):
    robot, frame, q, floor = setup
    assert rotation in FLOOR_ANALYTIC
    expected = robot.analytic_jacobian(q, frame, rotation=rotation)
    got = floor[rotation]()
    assert got.shape == expected.shape
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)


@pytest.mark.parametrize("seed", range(5))
def test_analytic_floors_at_random_configurations(seed):
    robot = kinengine.load("abb_irb120")
    frame = robot.end_effector
    q = robot.random_configuration(seed)
    floor = floors(robot, frame, q)
    for rotation in ROTATION_PARAMETERIZATIONS:
        expected = robot.analytic_jacobian(q, frame, rotation=rotation)
        np.testing.assert_allclose(floor[rotation](), expected, rtol=0, atol=1e-12, err_msg=rotation)


def test_task_floor_equals_task(setup):
    robot, frame, q, floor = setup
    task = robot.task(frame, position="cartesian", rotation="euler_zyx")
    task.update(q)
    chi, JA = floor["task"]()
    np.testing.assert_allclose(chi, task.chi, rtol=0, atol=1e-12)
    np.testing.assert_allclose(JA, task.analytic_jacobian, rtol=0, atol=1e-12)
