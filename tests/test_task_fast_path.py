"""Task.update(q)'s fast path (kinengine.control.task_fast) equals the general path (FrameBlock): every
attribute, along smooth trajectories and jumps (the continuity rule), at singular and near-singular poses,
with updates with and without q̇ interleaved, for every rotation parameterization, on the ABB IRB 120 and
the Panda (a mimic finger joint, a hand frame that the fingers do not move)."""

from __future__ import annotations

import numpy as np
import pytest

import kinengine
from kinengine.parameterizations import ROTATION_PARAMETERIZATIONS

ROTATIONS = list(ROTATION_PARAMETERIZATIONS)
ATTRIBUTES = (
    "pose",
    "chi",
    "jacobian",
    "analytic_jacobian",
    "singularity_distances",
    "twist",
    "jacobian_dot",
    "analytic_jacobian_dot",
    "chi_dot",
)
ROBOTS = {name: kinengine.load(name) for name in ("abb_irb120", "panda")}


def _pair(robot, rotation, **options):
    """(fast, general): two equal Tasks, the second with the fast path switched off; the first one's fast
    path counts the updates it handled."""
    fast = robot.task(robot.end_effector, position="cartesian", rotation=rotation, **options)
    general = robot.task(robot.end_effector, position="cartesian", rotation=rotation, **options)
    assert fast._fast is not None
    general._fast = None
    inner, handled = fast._fast, [0]

    def counting(*args):
        done = inner(*args)
        handled[0] += done
        return done

    fast._fast = counting
    return fast, general, handled


def _assert_same(fast, general):
    for name in ATTRIBUTES:
        a, b = getattr(fast, name), getattr(general, name)
        scale = max(1.0, float(np.max(np.abs(b[np.isfinite(b)]), initial=0.0)))
        np.testing.assert_allclose(a, b, rtol=1e-15, atol=1e-15 * scale, equal_nan=True, err_msg=name)


def _update(task, q, qdot=None):
    """The error an update raised (or None): attributes are written in both cases."""
    try:
        task.update(q, qdot)
    except kinengine.RepresentationSingularityError as error:
        return str(error)
    return None


@pytest.mark.parametrize("rotation", ROTATIONS)
@pytest.mark.parametrize("name", list(ROBOTS))
def test_fast_path_equals_general_path_along_trajectories(name, rotation):
    robot = ROBOTS[name]
    fast, general, handled = _pair(robot, rotation, on_singularity="nan")
    rng = np.random.default_rng(7)
    q0, amplitude = robot.random_configuration(rng), rng.uniform(0.5, 1.5, robot.dof)
    steps = 0
    for k, t in enumerate(np.linspace(0.0, 6.0, 120)):
        q = q0 + amplitude * np.sin(t + np.arange(robot.dof))
        qdot = amplitude * np.cos(t + np.arange(robot.dof))
        if k % 3:  # with q̇, then (every other step) without: rates NaN, never stale
            fast.update(q, qdot)
            general.update(q, qdot)
            _assert_same(fast, general)
            steps += 1
        if k % 3 != 1:
            fast.update(q)
            general.update(q)
            _assert_same(fast, general)
            steps += 1
    assert handled[0] >= steps - 20  # the fast path did run (not at singular poses)


@pytest.mark.parametrize("rotation", ROTATIONS)
@pytest.mark.parametrize("name", list(ROBOTS))
def test_fast_path_equals_general_path_across_jumps_and_reset(name, rotation):
    robot = ROBOTS[name]
    fast, general, handled = _pair(robot, rotation, on_singularity="nan")
    rng = np.random.default_rng(11)
    for k in range(40):  # unrelated configurations: the continuity rule moves χ by 2π, flips, ...
        q = robot.random_configuration(rng)
        fast.update(q)
        general.update(q)
        _assert_same(fast, general)
        if k == 20:
            fast.reset()
            general.reset()
    assert handled[0] >= 30


@pytest.mark.parametrize("continuous", [True, False])
@pytest.mark.parametrize("rotation", ROTATIONS)
def test_fast_path_hands_singular_and_near_singular_poses_over_unchanged(rotation, continuous):
    robot = ROBOTS["abb_irb120"]
    rng = np.random.default_rng(3)
    # joint values on multiples of π/2 put the ABB's axes in line: gimbal lock of many sequences,
    # θ = π of rotation vectors, q = 0 the identity of others
    specials = [np.zeros(6)] + [
        np.round(robot.random_configuration(rng) / (np.pi / 2)) * (np.pi / 2) for _ in range(12)
    ]
    specials = [np.clip(q, robot.lower_limits, robot.upper_limits) for q in specials]
    for on_singularity in ("nan", "raise"):
        fast, general, _ = _pair(robot, rotation, on_singularity=on_singularity, continuous=continuous)
        for q in specials:
            for offset in (0.0, 1e-9, 1e-7, 1e-5, 1e-3):  # on, within and beyond the threshold 1e-6
                q_k = q + offset * np.arange(1.0, 7.0)
                for qdot in (None, np.linspace(-1.0, 1.0, 6), None):
                    assert _update(fast, q_k, qdot) == _update(general, q_k, qdot)
                    _assert_same(fast, general)


@pytest.mark.parametrize("rotation", ["euler_zyx", "euler_zyz", "quaternion"])
def test_fast_path_follows_threshold_and_continuous_set_after_construction(rotation):
    robot = ROBOTS["abb_irb120"]
    fast, general, handled = _pair(robot, rotation, on_singularity="nan")
    rng = np.random.default_rng(5)
    for k in range(12):
        threshold, continuous = (0.5, False) if k % 2 else (1e-6, True)
        for task in (fast, general):
            task.singularity_threshold, task.continuous = threshold, continuous
        q = robot.random_configuration(rng)
        fast.update(q)
        general.update(q)
        _assert_same(fast, general)
    assert handled[0] >= 3


def test_fast_path_checks_inputs_as_the_general_path():
    robot = ROBOTS["abb_irb120"]
    fast, general, _ = _pair(robot, "euler_zyx")
    for bad in (np.zeros(5), np.array([np.nan] * 6), [0.0] * 7):
        with pytest.raises(kinengine.ConfigurationError) as fast_error:
            fast.update(bad)
        with pytest.raises(kinengine.ConfigurationError) as general_error:
            general.update(bad)
        assert str(fast_error.value) == str(general_error.value)
    q = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]  # a list: converted, then the fast path
    fast.update(q)
    general.update(q)
    _assert_same(fast, general)
