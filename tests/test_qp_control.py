"""DifferentialIK as a controller (issue 30): feed-forward tracking, acceleration limits, limits="scale",
status and stall detection, strict priority levels, pluggable inequality blocks, input checks (issue 25),
and the papercuts (velocity/effort limits, J̇ speed path, damped_solve, manipulability gradient)."""

from __future__ import annotations

import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pinocchio as pin
import pytest
from example_modules import load_example

import kinengine
from kinengine import DifferentialIK, PoseTarget, PostureTarget, damped_solve

REGULAR = np.array([0.3, 0.2, -0.4, 0.5, 0.7, 1.0])
DT = 1e-3


@pytest.fixture(scope="module")
def abb():
    return kinengine.load("abb_irb120")


@pytest.fixture(scope="module")
def panda():
    return kinengine.load("panda")


# -- issue 25 §3: controller inputs ------------------------------------------------------------------
def test_zero_dof_robot_solves_in_a_subprocess_without_crashing():
    code = textwrap.dedent(
        """
        import numpy as np, kinengine
        robot = kinengine.load_urdf_string('<robot name="r"><link name="a"/><link name="b"/>'
            '<joint name="j" type="fixed"><parent link="a"/><child link="b"/>'
            '<origin xyz="0.1 0 0"/></joint></robot>')
        assert robot.dof == 0
        T = robot.frame_pose(np.zeros(0), "b")
        ik = kinengine.DifferentialIK(robot, [kinengine.PoseTarget("b", T)])
        qdot, status = ik.solve(np.zeros(0), 0.01, info=True)
        assert qdot.shape == (0,) and status.residual == 0.0, (qdot, status)
        far = T.copy(); far[0, 3] += 1.0
        ik = kinengine.DifferentialIK(robot, [kinengine.PoseTarget("b", far, twist=np.ones(6))])
        qdot = ik.solve(np.zeros(0), 0.01)
        assert qdot.shape == (0,) and abs(ik.last_error[0] - 1.0) < 1e-12
        print("ok")
        """
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0 and result.stdout.strip() == "ok", result.stderr[-2000:]


def test_one_dof_robot_converges():
    robot = kinengine.load_urdf_string(
        '<robot name="r"><link name="a"/><link name="b"/><joint name="j" type="revolute">'
        '<parent link="a"/><child link="b"/><axis xyz="0 0 1"/><origin xyz="0 0 0"/>'
        '<limit lower="-2" upper="2" effort="3" velocity="1"/></joint>'
        '<link name="c"/><joint name="f" type="fixed"><parent link="b"/><child link="c"/>'
        '<origin xyz="0.5 0 0"/></joint></robot>'
    )
    target = robot.frame_pose(np.array([0.4]), "c")
    ik = DifferentialIK(robot, [PoseTarget("c", target)])
    q = np.zeros(1)
    for _ in range(100):
        q = q + ik.solve(q, 0.05) * 0.05
    np.testing.assert_allclose(q, [0.4], atol=1e-9)
    np.testing.assert_array_equal(robot.velocity_limits, [1.0])
    np.testing.assert_array_equal(robot.effort_limits, [3.0])


def _scaled(C, s):
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = C, [0.3, 0.0, 0.5]
    return T


@pytest.mark.parametrize(
    "T_target",
    [
        np.full((4, 4), np.nan),
        np.where(np.eye(4) > 0, np.inf, 0.0),
        _scaled(np.zeros((3, 3)), 0),
        _scaled(2 * np.eye(3), 2),  # scaled rotation
        _scaled(np.array([[1, 0.2, 0], [0, 1, 0], [0, 0, 1.0]]), 0),  # sheared
        _scaled(np.diag([1.0, 1.0, -1.0]), 0),  # a reflection
        np.eye(3),  # 3x3
        "eye",
    ],
    ids=["nan", "inf", "zero", "scaled", "sheared", "reflection", "3x3", "string"],
)
def test_bad_pose_targets_are_option_errors_at_solve(abb, T_target):
    ik = DifferentialIK(abb, [PoseTarget("tool0", abb.frame_pose(REGULAR, "tool0"))])
    ik.tasks[0].T_target = T_target  # assigned between steps, as a tracking loop does
    with pytest.raises(kinengine.OptionError, match="T_target"):
        ik.solve(REGULAR, 0.01)
    # the same check inverse_kinematics makes: it refuses the same value
    with pytest.raises(kinengine.KinematicsError):
        abb.inverse_kinematics(T_target, "tool0", q0=REGULAR)


def test_bad_numbers_and_shapes_are_option_or_configuration_errors(abb):
    good = abb.frame_pose(REGULAR, "tool0")
    ik = DifferentialIK(abb, [PoseTarget("tool0", good), PostureTarget(np.zeros(6))])
    for dt in ("0.01", None, np.nan, -0.01, 0.0, True, np.inf):
        with pytest.raises(kinengine.OptionError, match="dt"):
            ik.solve(REGULAR, dt)
    pose, posture = ik.tasks
    for name, value in (("gain", np.nan), ("gain", 0.0), ("weight", np.nan), ("weight", -1.0), ("gain", "1")):
        setattr(pose, name, value)
        with pytest.raises(kinengine.OptionError, match=name):
            ik.solve(REGULAR, 0.01)
        setattr(pose, name, 1.0)
        setattr(posture, name, value)
        with pytest.raises(kinengine.OptionError, match=name):
            ik.solve(REGULAR, 0.01)
        setattr(posture, name, {"gain": 1.0, "weight": 1e-3}[name])
    for twist in (np.full(6, np.nan), np.ones(3), "fast"):
        pose.twist = twist
        with pytest.raises(kinengine.OptionError, match="twist"):
            ik.solve(REGULAR, 0.01)
    pose.twist = None
    for q_ref in (np.full(6, np.nan), np.zeros(5), "home"):
        posture.q_ref = q_ref
        with pytest.raises(kinengine.ConfigurationError):
            ik.solve(REGULAR, 0.01)
    posture.q_ref = np.zeros(6)
    assert np.isfinite(ik.solve(REGULAR, 0.01)).all()
    for options in (
        {"damping": np.nan},
        {"lm_damping": -1.0},
        {"limits": "bend"},
        {"acceleration_limits": np.zeros(6)},
        {"acceleration_limits": {"joint_9": 1.0}},
        {"stall_window": 0},
        {"constraints": [object()]},
    ):
        with pytest.raises(kinengine.OptionError):
            DifferentialIK(abb, [PoseTarget("tool0", good)], **options)
    with pytest.raises(kinengine.OptionError, match="priority level"):
        DifferentialIK(abb, PoseTarget("tool0", good))  # a target, not a list of them
    with pytest.raises(kinengine.OptionError, match="gain"):
        DifferentialIK(abb, [PoseTarget("tool0", good, gain=np.nan)])


# -- feed-forward ----------------------------------------------------------------------------------
_circle = load_example("moving_target_tracking").circle
"""(T (4, 4), twist (6,)) of a circle in tool0's y-z plane of I at 0.1 m/s (the example's)."""


def _track_circle(robot, feed_forward, steps=3000):
    q = np.array([0.0, 0.2, 0.1, 0.0, 0.8, 0.0])
    T0 = robot.frame_pose(q, "tool0")
    target = PoseTarget("tool0", T0, gain=0.05)
    ik = DifferentialIK(robot, [target])
    errors = []
    for k in range(steps):
        target.T_target, twist = _circle(T0, k * DT)
        target.twist = twist if feed_forward else None
        q = q + ik.solve(q, DT) * DT
        T_next, _ = _circle(T0, (k + 1) * DT)
        errors.append(np.linalg.norm(robot.frame_pose(q, "tool0")[:3, 3] - T_next[:3, 3]))
    return np.array(errors)


def test_abb_circle_at_1khz_with_gain_0_05_tracks_within_1e_5_m_with_the_twist(abb):
    with_ff = _track_circle(abb, True)
    assert with_ff[1000:].max() <= 1e-5  # steady state (after 1 s): measured 2e-6 m
    without = _track_circle(abb, False)
    # the pure feedback lags by |v| dt / k = 0.1 m/s · 1 ms / 0.05 = 2 mm
    np.testing.assert_allclose(without[1000:].mean(), 0.1 * DT / 0.05, rtol=0.05)


def test_feed_forward_of_a_turning_relative_target_follows_a_joint_trajectory(panda):
    """T*(t) = T_BA(q*(t)) in link1, twist = J_BA(q*) q̇*: the rotation rows' feed-forward is exact too."""
    robot = panda
    q_star = np.array([0.2, -0.3, 0.1, -2.0, 0.2, 1.7, 0.4, 0.02])
    rate = np.array([0.3, -0.2, 0.25, 0.3, -0.4, 0.3, 0.5, 0.0])
    target = PoseTarget("panda_hand_tcp", np.eye(4), gain=0.05, relative_to="panda_link1")
    ik = DifferentialIK(robot, [target], velocity_limits={"panda_finger_joint1": 0.0})
    q, worst = q_star.copy(), 0.0
    for k in range(1500):
        qk = q_star + rate * k * DT
        target.T_target = robot.relative_pose(qk, "panda_hand_tcp", relative_to="panda_link1")
        target.twist = robot.relative_jacobian(qk, "panda_hand_tcp", relative_to="panda_link1") @ rate
        q = q + ik.solve(q, DT) * DT
        worst = max(worst, float(np.abs(ik.last_error).max()))
    assert worst <= 1e-5  # [m] and [rad]; without the twist: ~|V| dt / k = 1e-2
    target.twist = None
    ik.solve(q, DT)
    assert np.abs(ik.last_error).max() > 1e-4


# -- limits ----------------------------------------------------------------------------------------
def test_acceleration_limits_are_never_exceeded_in_a_step_sequence(abb):
    a = np.array([2.0, 2.0, 3.0, 5.0, 5.0, 8.0])
    target = PoseTarget("tool0", abb.frame_pose(REGULAR + 0.4, "tool0"), gain=0.05)
    ik = DifferentialIK(abb, [target], acceleration_limits=a)
    q, previous, dt = REGULAR.copy(), np.zeros(6), 0.01
    changes = []
    for k in range(400):
        if k == 200:  # a jump of the target mid-way: the solver must brake and turn within a
            target.T_target = abb.frame_pose(REGULAR, "tool0")
        qdot = ik.solve(q, dt)
        changes.append(np.abs(qdot - previous) / (a * dt))
        assert np.all(np.abs(qdot) <= ik.velocity_limits * (1 + 1e-12))
        q, previous = q + qdot * dt, qdot
        assert np.all(q >= abb.lower_limits - 1e-9) and np.all(q <= abb.upper_limits + 1e-9)
    changes = np.array(changes)
    assert changes.max() <= 1 + 1e-9
    assert changes.max() >= 1 - 1e-9  # the limit was reached (else this test proves nothing)
    assert np.abs(ik.last_error).max() < 1e-3  # and it still gets there
    # the caller's q̇ replaces the kept one
    qdot = ik.solve(q, dt, previous_qdot=np.full(6, 0.5))
    assert np.all(np.abs(qdot - 0.5) <= a * dt * (1 + 1e-12))


def _angle(a, b):
    """The angle between two vectors, accurate near 0 (not arccos of a dot product)."""
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    return float(2 * np.arctan2(np.linalg.norm(a - b), np.linalg.norm(a + b)))


def test_limits_scale_keeps_the_direction_and_clip_bends_it(abb):
    far = abb.frame_pose(REGULAR, "tool0")
    far[0, 3] += 0.3  # +x, far beyond one step at the velocity limits
    free = DifferentialIK(
        abb, [PoseTarget("tool0", far)], velocity_limits=np.full(6, np.inf), position_limits=False
    )
    scale = DifferentialIK(abb, [PoseTarget("tool0", far)], limits="scale")
    clip = DifferentialIK(abb, [PoseTarget("tool0", far)])
    unconstrained = free.solve(REGULAR, DT * 10)
    scaled, status = scale.solve(REGULAR, DT * 10, info=True)
    clipped = clip.solve(REGULAR, DT * 10)
    assert status.qp_status == "scaled" and 0 < status.scale < 1 and status.bounds_active
    assert np.all(np.abs(scaled) <= scale.velocity_limits * (1 + 1e-12))
    assert _angle(scaled, unconstrained) <= 1e-9
    np.testing.assert_allclose(scaled, status.scale * unconstrained, rtol=1e-12)
    _, J = abb.kinematics(REGULAR, "tool0")
    assert _angle(J[:3] @ scaled, J[:3] @ unconstrained) <= 1e-9  # the Cartesian direction too
    assert _angle(clipped, unconstrained) > 1e-3  # clip turns it


# -- status ----------------------------------------------------------------------------------------
def test_stall_near_the_abb_wrist_singularity_is_reported_once(abb):
    """q5 near 0 (wrist singular) with q4 near its limit: the target needs q4 beyond it; the step presses
    joint_4 on its bound while the error stays."""
    q = np.array([0.0, 0.2, 0.1, 2.6, 0.05, 0.0])
    beyond = q.copy()
    beyond[3], beyond[5] = 3.0, -0.2
    ik = DifferentialIK(
        abb, [PoseTarget("tool0", abb.frame_pose(beyond, "tool0"), gain=0.05)], warn_on_stall=True
    )
    statuses = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for _ in range(600):
            qdot, status = ik.solve(q, DT, info=True)
            statuses.append(status)
            q = q + qdot * DT
    stalls = [w for w in caught if issubclass(w.category, kinengine.StallWarning)]
    assert len(stalls) == 1 and "joint_4" in str(stalls[0].message)
    last = statuses[-1]
    assert last.stalled and last.qp_status == "optimal" and last.active_joints == ("joint_4",)
    assert last.active_upper[3] and q[3] == pytest.approx(abb.upper_limits[3], abs=1e-12)
    assert last.residual > 1e-3 and not statuses[0].stalled
    ik.reset()  # a new episode may warn again
    for _ in range(100):  # a window of 100 steps after the reset: no verdict yet
        q = q + ik.solve(q, DT) * DT
    with pytest.warns(kinengine.StallWarning):
        ik.solve(q, DT)
    # a reachable target: no stall, the residual goes to zero
    easy = DifferentialIK(abb, [PoseTarget("tool0", abb.frame_pose(REGULAR + 0.05, "tool0"), gain=0.5)])
    q = REGULAR.copy()
    for _ in range(300):
        qdot, status = easy.solve(q, 0.01, info=True)
        q = q + qdot * 0.01
        assert not status.stalled
    assert status.residual < 1e-9 and status.qp_status == "unconstrained"


# -- priorities ------------------------------------------------------------------------------------
RANK5 = np.array([-0.4945, 0.7391, 1.1497, -0.4277, -1.5708, 1.7763, 2.4768, 0.02])
"""A Panda configuration where the hand's Jacobian has rank 5 (σ6 ≈ 5e-6; found by minimizing σ6)."""


def _panda_pass(robot, arrangement):
    rng = np.random.default_rng(3)
    rate = np.zeros(robot.dof)
    rate[:7] = rng.normal(size=7)
    rate *= 0.3 / np.linalg.norm(rate)
    target = PoseTarget("panda_hand_tcp", np.eye(4), gain=0.5)
    posture = PostureTarget(robot.neutral(), weight=1e-3)
    lock = {"panda_finger_joint1": 0.0}
    levels = {"none": ([target],), "weighted": ([target, posture],), "levels": ([target], [posture])}[
        arrangement
    ]
    ik = DifferentialIK(robot, *levels, velocity_limits=lock)
    q, worst = RANK5 - rate, 0.0
    for k in range(2001):
        qk = RANK5 + rate * (k * DT - 1.0)
        target.T_target, J = robot.kinematics(qk, "panda_hand_tcp")
        target.twist = J @ rate
        q = q + ik.solve(q, DT) * DT
        worst = max(worst, float(np.linalg.norm(ik.last_error[:3])))
    return worst, q


def test_panda_through_its_rank_5_configuration_with_the_posture_at_a_lower_level(panda):
    assert np.linalg.svd(panda.jacobian(RANK5, "panda_hand_tcp"), compute_uv=False)[5] < 1e-5
    strict, q_strict = _panda_pass(panda, "levels")
    weighted, _ = _panda_pass(panda, "weighted")
    alone, q_alone = _panda_pass(panda, "none")
    assert strict <= 5e-4 and alone <= 5e-4  # measured: 1e-6 m and 2e-8 m
    assert weighted > 5e-4  # the weighted posture pulls the hand off: 1.7 cm measured
    # the lower level did act: closer to the posture in the null space
    assert np.linalg.norm(q_strict - panda.neutral()) < np.linalg.norm(q_alone - panda.neutral()) - 1e-3


def test_a_lower_level_never_changes_the_higher_levels_step(abb):
    """Position at level 1 (3 rows), a rotation target at level 2: the level-1 rows of the step equal the
    step of level 1 alone; level 2 only adds a null-space motion."""
    T = abb.frame_pose(REGULAR + 0.1, "tool0")
    pos = PoseTarget("tool0", T, rows=("x", "y", "z"), gain=0.3)
    rot = PoseTarget("tool0", abb.frame_pose(REGULAR - 0.2, "tool0"), rows=("rx", "ry", "rz"), gain=0.3)
    free = {"velocity_limits": np.full(6, np.inf), "position_limits": False}
    both = DifferentialIK(abb, [pos], [rot], **free).solve(REGULAR, 0.01)
    first = DifferentialIK(abb, [pos], **free).solve(REGULAR, 0.01)
    _, J = abb.kinematics(REGULAR, "tool0")
    np.testing.assert_allclose(J[:3] @ both, J[:3] @ first, atol=1e-10)
    assert np.linalg.norm(both - first) > 1e-3


# -- weights in pink's and mink's convention ---------------------------------------------------------
def test_cost_is_the_square_root_of_the_weight(abb):
    T = abb.frame_pose(REGULAR + 0.05, "tool0")
    a = DifferentialIK(abb, [PoseTarget("tool0", T, cost=2.0), PostureTarget(np.zeros(6), cost=1e-3)])
    b = DifferentialIK(abb, [PoseTarget("tool0", T, weight=4.0), PostureTarget(np.zeros(6), weight=1e-6)])
    assert a.tasks[1].weight == 1e-6
    np.testing.assert_array_equal(a.solve(REGULAR, 0.01), b.solve(REGULAR, 0.01))


# -- a plugged-in inequality block -----------------------------------------------------------------
class _Wall:
    """tool0's x stays below x_max: J_x q̇ <= (x_max − x) / dt (a distance that may not be crossed)."""

    def __init__(self, robot, x_max):
        self.robot, self.x_max = robot, x_max

    def inequalities(self, robot, q, dt):
        T, J = self.robot.kinematics(q, "tool0")
        return J[:1], np.array([(self.x_max - T[0, 3]) / dt])


@pytest.mark.parametrize("limits", ["clip", "scale"])
def test_a_plugged_in_constraint_holds_at_every_step(abb, limits):
    x0 = abb.frame_pose(REGULAR, "tool0")[0, 3]
    far = abb.frame_pose(REGULAR, "tool0")
    far[0, 3] += 0.1
    wall = _Wall(abb, x0 + 0.02)
    ik = DifferentialIK(abb, [PoseTarget("tool0", far, gain=0.2)], constraints=[wall], limits=limits)
    q = REGULAR.copy()
    for _ in range(200):
        qdot, status = ik.solve(q, 0.01, info=True)
        q = q + qdot * 0.01
        assert abb.frame_pose(q, "tool0")[0, 3] <= wall.x_max + 1e-4  # linearized: to second order
    assert status.active_constraints.tolist() == [True]
    assert abb.frame_pose(q, "tool0")[0, 3] == pytest.approx(wall.x_max, abs=1e-4)


def test_a_free_steps_status_is_built_from_that_step_when_read(abb):
    """A step with no bound active records numbers and ``ik.status`` builds the DiffIKStatus from them:
    the residual is ‖e‖ of the selected rows of ``last_error``, the step count is that step's, nothing is
    active (a far wall's row included), and the next step replaces it."""
    T = abb.frame_pose(REGULAR + 0.01, "tool0")
    ik = DifferentialIK(
        abb, [PoseTarget("tool0", T, rows=("x", "y", "z", "rx", "ry"))], constraints=[_Wall(abb, 10.0)]
    )
    q, residuals = REGULAR.copy(), []
    for k in range(1, 4):
        qdot, status = ik.solve(q, 0.01, info=True)
        residuals.append(status.residual)
        assert status is ik.status and status.step == k and status.qp_status == "unconstrained"
        assert status.residual == pytest.approx(np.linalg.norm(ik.last_error[:5]), rel=1e-12, abs=1e-15)
        assert status.active_lower.shape == status.active_upper.shape == (6,)
        assert not (status.active_lower.any() or status.active_upper.any() or status.stalled)
        assert status.active_constraints.tolist() == [False] and status.active_joints == ()
        q = q + qdot * 0.01
    assert residuals[0] > 1e-3 and residuals[2] < 1e-6  # full Newton steps (gain 1) converge
    ik.solve(q, 0.01)
    assert ik.status is not status and ik.status.step == 4


def test_a_joint_outside_its_limits_is_driven_back_and_named(abb):
    """q beyond joint_1's upper limit: its step is the velocity limit back toward the range (the formula's
    bounds have no solution), the status names it, and after enough steps it is back in its range."""
    q = REGULAR.copy()
    q[0] = abb.upper_limits[0] + 0.1
    ik = DifferentialIK(abb, [PoseTarget("tool0", abb.frame_pose(q, "tool0"))])
    qdot, status = ik.solve(q, 0.01, info=True)
    assert qdot[0] == pytest.approx(-ik.velocity_limits[0], rel=1e-9)
    assert status.outside_limits == ("joint_1",)
    for _ in range(5):
        q = q + ik.solve(q, 0.01) * 0.01
    assert q[0] <= abb.upper_limits[0] + 1e-12
    ik.solve(q, 0.01)
    assert ik.status.outside_limits == ()


# -- papercuts -------------------------------------------------------------------------------------
def test_velocity_and_effort_limits_come_from_the_urdf(panda):
    joints = {j.name: j for j in panda.description.joints}
    np.testing.assert_array_equal(panda.velocity_limits, [joints[n].velocity for n in panda.joint_names])
    np.testing.assert_array_equal(panda.effort_limits, [joints[n].effort for n in panda.joint_names])
    robot = kinengine.load_urdf_string(
        '<robot name="r"><link name="a"/><link name="b"/><joint name="j" type="continuous">'
        '<parent link="a"/><child link="b"/><axis xyz="0 0 1"/></joint></robot>'
    )
    np.testing.assert_array_equal(robot.velocity_limits, [np.inf])
    np.testing.assert_array_equal(robot.effort_limits, [np.inf])


def test_info_prints_the_velocity_and_effort_limits(capsys):
    from kinengine.cli.main import main

    assert main(["info", "panda"]) == 0
    out = capsys.readouterr().out
    assert "velocity" in out and "effort" in out
    row = next(line for line in out.splitlines() if " panda_joint5 " in line).split()
    assert [float(x) for x in row[-2:]] == [2.61, 12.0]


def test_jacobian_time_variation_inline_path_equals_the_full_path(abb):
    rng = np.random.default_rng(5)
    for _ in range(5):
        q, qdot = abb.random_configuration(rng), rng.normal(size=6)
        for reference in ("world", "local", "local_world_aligned"):
            fast = abb.jacobian_time_variation(q, qdot, "tool0", reference)  # the second call is inline
            full = abb.jacobian_time_variation(list(q), list(qdot), "tool0", reference)
            np.testing.assert_array_equal(fast, full)
            h = 1e-6
            fd = (
                abb.jacobian(q + h * qdot, "tool0", reference)
                - abb.jacobian(q - h * qdot, "tool0", reference)
            ) / (2 * h)
            np.testing.assert_allclose(fast, fd, atol=1e-7)
    with pytest.raises(kinengine.ConfigurationError):
        abb.jacobian_time_variation(np.full(6, np.nan), np.zeros(6), "tool0", "local")


def test_damped_solve_never_raises_at_a_singular_jacobian(abb):
    J = abb.jacobian(np.zeros(6), "tool0")  # q5 = 0: rank 5
    e = np.arange(6.0)
    with pytest.raises(np.linalg.LinAlgError):
        np.linalg.solve(J, e)
    x = damped_solve(J, e, 1e-4)
    np.testing.assert_allclose(x, np.linalg.solve(J.T @ J + 1e-4 * np.eye(6), J.T @ e), rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(damped_solve(J, e, 0.0), np.linalg.pinv(J, rcond=1e-12) @ e, atol=1e-9)
    np.testing.assert_array_equal(damped_solve(np.zeros((6, 6)), e, 0.0), np.zeros(6))
    E = np.stack([e, -e], axis=1)
    np.testing.assert_allclose(damped_solve(J, E, 1e-4)[:, 1], -x, rtol=1e-12)
    for bad in ((J, np.ones(5), 0.1), (J, e, -1.0), (J, e, np.nan), (np.full((6, 6), np.nan), e, 0.1)):
        with pytest.raises(kinengine.OptionError):
            damped_solve(*bad)


@pytest.mark.parametrize("name, frame", [("abb_irb120", "tool0"), ("panda", "panda_hand_tcp")])
def test_manipulability_gradient_matches_finite_differences(name, frame):
    robot = kinengine.load(name)
    rng = np.random.default_rng(11)
    for rows in ("all", "linear", ("vx", "wz")):
        for _ in range(3):
            q = robot.random_configuration(rng)
            grad = robot.manipulability_gradient(q, frame, rows)
            h = 1e-6
            fd = np.array(
                [
                    (
                        robot.manipulability(q + h * d, frame, rows)
                        - robot.manipulability(q - h * d, frame, rows)
                    )
                    / (2 * h)
                    for d in np.eye(robot.dof)
                ]
            )
            np.testing.assert_allclose(grad, fd, rtol=1e-5, atol=1e-8)


def test_manipulability_gradient_ascent_leaves_the_wrist_singularity(abb):
    q = np.array([0.3, 0.2, -0.4, 0.5, 1e-3, 1.0])
    w0 = abb.manipulability(q, "tool0")
    for _ in range(50):
        q = q + 0.01 * abb.manipulability_gradient(q, "tool0") / max(1e-12, abs(w0))
    assert abb.manipulability(q, "tool0") > 10 * w0
    assert pin.__version__  # the Hessian comes from Pinocchio's joint Jacobians
