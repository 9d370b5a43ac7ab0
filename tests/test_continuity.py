"""A Task's Euler angles stay continuous through and near every sequence's singular set.

The test robot is a spherical wrist whose three joints turn about the axes a, b, c of a sequence "abc":
its tool's rotation is R_a(q1) R_b(q2) R_c(q3), so q itself is a set of Euler angles of the tool. Along a
trajectory in q (steps of 0.01 rad) the Task's χ must follow a continuous branch: consecutive updates never
jump by more than a small bound, except exactly at the singular set (there the Task gives NaN rows
or raises), and χ always reproduces the tool's rotation.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import kinengine
from kinengine.control.continuity import continuity_rule
from kinengine.parameterizations import get_rotation
from kinengine.parameterizations.euler import EULER_SEQUENCES

AXES = {"x": "1 0 0", "y": "0 1 0", "z": "0 0 1"}


def wrist_urdf(seq: str) -> str:
    """Three revolute joints about seq's axes at one point, then a 'tool' frame 0.1 m out along z."""
    links = "".join(f'<link name="l{i}"/>' for i in range(4)) + '<link name="tool"/>'
    joints = "".join(
        f"""
  <joint name="j{i + 1}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>
    <origin xyz="0 0 {0.2 if i == 0 else 0}"/><axis xyz="{AXES[axis]}"/>
    <limit lower="-10" upper="10" effort="1" velocity="1"/></joint>"""
        for i, axis in enumerate(seq)
    )
    return f"""<?xml version="1.0"?>
<robot name="wrist_{seq}">{links}{joints}
  <joint name="tool_fixed" type="fixed"><parent link="l3"/><child link="tool"/><origin xyz="0 0 0.1"/></joint>
</robot>"""


def _singular_value(seq: str) -> float:
    return 0.0 if seq[0] == seq[2] else math.pi / 2


def _assert_one_branch(chi, Q):
    """The whole path on one branch: χ − χ(0) equals q − q(0) (the start picked the generating solution) or
    the same with χ2's sign flipped (it picked the other one, (χ1 + π, s − χ2, χ3 + π))."""
    d, dq = chi - chi[0], Q - Q[0]
    flip = np.array([1.0, -1.0, 1.0])
    assert np.abs(d - dq).max() < 1e-7 or np.abs(d - dq * flip).max() < 1e-7


def _run(seq: str, chi2_path: np.ndarray, on_singularity: str = "nan"):
    robot = kinengine.load_urdf_string(wrist_urdf(seq))
    name = f"euler_{seq}"
    task = robot.task("tool", position=None, rotation=name, on_singularity=on_singularity)
    n = len(chi2_path)
    Q = np.stack([0.4 + 0.01 * np.arange(n), chi2_path, -0.7 + 0.01 * np.arange(n)], axis=1)
    chis, rows_nan, distances = [], [], []
    for q in Q:
        task.update(q)
        chis.append(task.chi.copy())
        rows_nan.append(bool(np.isnan(task.analytic_jacobian).any()))
        distances.append(float(task.singularity_distances[0]))
        C = robot.frame_pose(q, "tool")[:3, :3]
        np.testing.assert_allclose(get_rotation(name).to_rotation(task.chi), C, rtol=0, atol=1e-9)
    return Q, np.array(chis), np.array(rows_nan), np.array(distances)


@pytest.mark.parametrize("seq", EULER_SEQUENCES)
def test_through_the_singular_set_chi_follows_the_generating_angles(seq):
    """χ2 sweeps across the singular value (0.01 rad steps, passing it at 0.005 rad): the canonical χ2
    turns back there and χ1, χ3 jump by π; the Task's χ does not and equals q (the generating angles)."""
    s = _singular_value(seq)
    path = s - 0.305 + 0.01 * np.arange(61)
    Q, chi, nan, _ = _run(seq, path)
    assert not nan.any()
    jumps = np.abs(np.diff(chi, axis=0)).max(axis=1)
    assert jumps.max() < 0.02 + 1e-6, jumps.max()
    # the whole path is one branch: χ equals q, up to one overall equivalent shift decided at the start
    _assert_one_branch(chi, Q)


@pytest.mark.parametrize("seq", EULER_SEQUENCES)
@pytest.mark.parametrize("closest", [0.02, 0.003])
def test_near_the_singular_set_chi_is_continuous(seq, closest):
    """χ2 comes within ``closest`` of the singular value and turns back: no jump."""
    s = _singular_value(seq)
    t = np.linspace(-1.0, 1.0, 81)
    path = s - closest - 0.3 * t**2
    Q, chi, nan, distances = _run(seq, path)
    assert not nan.any()
    assert distances.min() == pytest.approx(abs(math.sin(closest)), rel=1e-6)
    assert np.abs(np.diff(chi, axis=0)).max() < 0.03
    _assert_one_branch(chi, Q)


@pytest.mark.parametrize("seq", ["zyx", "zyz", "xzx", "yxz"])
def test_exactly_at_the_singular_set_nan_rows_or_raise_and_then_continuous_again(seq):
    s = _singular_value(seq)
    path = s - 0.1 + 0.01 * np.arange(21)  # hits the singular value exactly at step 10
    path[10] = s
    Q, chi, nan, distances = _run(seq, path)
    assert nan[10] and not nan[:10].any() and not nan[11:].any()
    assert distances[10] < 1e-12
    jumps = np.abs(np.diff(chi, axis=0)).max(axis=1)
    assert jumps[:9].max() < 0.02 + 1e-6 and jumps[11:].max() < 0.02 + 1e-6
    robot = kinengine.load_urdf_string(wrist_urdf(seq))
    task = robot.task("tool", position=None, rotation=f"euler_{seq}")
    with pytest.raises(kinengine.RepresentationSingularityError):
        task.update(Q[10])


@pytest.mark.parametrize("seq", EULER_SEQUENCES)
def test_rule_picks_the_nearest_equivalent_euler_angles(seq):
    """Both solutions and their 2π shifts are the same rotation; the rule returns the nearest one."""
    param = get_rotation(f"euler_{seq}")
    rule = continuity_rule(param.name)
    rng = np.random.default_rng(4)
    for _ in range(50):
        chi = rng.uniform(-3, 3, 3)
        C = param.to_rotation(chi)
        previous = chi + rng.normal(scale=0.01, size=3) + 2 * np.pi * rng.integers(-2, 3, 3)
        canonical = param.from_rotation(C, warn=False)
        picked = np.array(rule(canonical.tolist(), previous.tolist()))
        np.testing.assert_allclose(param.to_rotation(picked), C, rtol=0, atol=1e-12)
        assert np.abs(picked - previous).max() < 0.1


def test_abb_zyz_near_chi2_pi_no_longer_jumps():
    """The issue's case: the ABB with ZYZ near χ2 = π, updates 0.01 rad apart."""
    robot = kinengine.load("abb_irb120")
    task = robot.task("tool0", position=None, rotation="euler_zyz")
    q = np.array([0.2, 0.3, 0.2, 0.1, 0.0, 0.4])
    # joint 5 tilts the tool; find where the tool's z axis points straight down (χ2 = π) and sweep past it
    q5 = np.linspace(-2.0, 2.0, 4001)
    zz = [robot.frame_pose(np.r_[q[:4], v, q[5]], "tool0")[2, 2] for v in q5]
    best = q5[int(np.argmin(zz))]
    previous = None
    for v in best - 0.3 + 0.0037 + 0.01 * np.arange(60):
        task.update(np.r_[q[:4], v, q[5]])
        if previous is not None:
            assert np.abs(task.chi - previous).max() < 0.2
        previous = task.chi.copy()
