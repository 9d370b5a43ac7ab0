"""analytic_jacobian's looked-up path (options seen before, q a float64 (dof,) array) against the general path
(the same call with q as a list, or rows as a list): bitwise equal, errors raised every time, threads apart."""

from __future__ import annotations

import threading

import numpy as np
import pytest

import kinengine
from kinengine.errors import FrameNotFoundError, KinematicsError, RepresentationSingularityError
from kinengine.parameterizations import ROTATION_PARAMETERIZATIONS


@pytest.fixture(scope="module")
def robot() -> kinengine.Robot:
    return kinengine.load("abb_irb120")


PAIRS = [
    (position, rotation)
    for position in ("cartesian", "cylindrical", "spherical", None)
    for rotation in (*ROTATION_PARAMETERIZATIONS, None)
    if (position, rotation) != (None, None)  # no rows: refused (tests/test_analytic_jacobian.py)
]


@pytest.mark.parametrize(("position", "rotation"), PAIRS)
def test_the_looked_up_path_equals_the_general_path(robot, position, rotation):
    q = np.array([0.1, -0.3, 0.2, 0.5, 0.4, 0.6])
    fast = [robot.analytic_jacobian(q, "tool0", position, rotation) for _ in range(2)]  # made, then looked up
    general = robot.analytic_jacobian(q.tolist(), "tool0", position, rotation)  # a list: the general path
    assert np.array_equal(fast[0], fast[1]) and np.array_equal(fast[0], general)


def test_rows_as_tuple_and_as_list_agree_and_options_do_not_mix(robot):
    q = robot.random_configuration(3)
    a = robot.analytic_jacobian(q, rotation="euler_zyz", rows=("x", "z", "chi2_y"))
    b = robot.analytic_jacobian(
        q, rotation="euler_zyz", rows=["x", "z", "chi2_y"]
    )  # unhashable: general path
    c = robot.analytic_jacobian(q, rotation="euler_zyz")
    d = robot.analytic_jacobian(q, rotation="euler_zyz", singularity_threshold=1e-3)
    assert np.array_equal(a, b) and np.array_equal(a, c[[0, 2, 4]]) and np.array_equal(c, d)


def test_bad_options_raise_on_every_call(robot):
    q = robot.random_configuration(4)
    for _ in range(2):
        with pytest.raises(FrameNotFoundError):
            robot.analytic_jacobian(q, "no_such_frame")
        with pytest.raises(KinematicsError):
            robot.analytic_jacobian(q, rotation="euler_abc")
        with pytest.raises(KinematicsError):
            robot.analytic_jacobian(q, on_singularity="ignore")
        with pytest.raises(KinematicsError):
            robot.analytic_jacobian(q, singularity_threshold=-1.0)


def test_bad_q_and_batches_still_take_the_checks(robot):
    q = robot.random_configuration(5)
    robot.analytic_jacobian(q)  # the options are now looked up
    with pytest.raises(KinematicsError):
        robot.analytic_jacobian(q[:5])
    with pytest.raises(KinematicsError):
        robot.analytic_jacobian(np.full(6, np.nan))
    Q = robot.random_configuration(6, 3)
    assert np.allclose(robot.analytic_jacobian(Q), [robot.analytic_jacobian(row) for row in Q], atol=1e-12)
    assert np.array_equal(
        robot.analytic_jacobian(q.astype(np.float32)),
        robot.analytic_jacobian(q.astype(np.float32).astype(float)),
    )


def test_singular_poses_raise_and_nan_still_works(robot):
    q = np.zeros(6)  # at home tool0's z axis is the root's x axis: ZYX at χ2 = -π/2 (gimbal lock)
    for _ in range(2):
        with pytest.raises(RepresentationSingularityError):
            robot.analytic_jacobian(q, rotation="euler_zyx")
        assert np.isnan(robot.analytic_jacobian(q, rotation="euler_zyx", on_singularity="nan")[3:]).all()


def test_threads_evaluate_their_own_configurations(robot):
    Q = robot.random_configuration(7, 8)
    expected = [robot.analytic_jacobian(q.tolist(), rotation="euler_xyz") for q in Q]
    errors: list[float] = []

    def work(k: int) -> None:
        for _ in range(300):
            errors.append(
                float(np.abs(robot.analytic_jacobian(Q[k], rotation="euler_xyz") - expected[k]).max())
            )

    threads = [threading.Thread(target=work, args=(k,)) for k in range(len(Q))]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert len(errors) == 300 * len(Q) and max(errors) == 0.0
