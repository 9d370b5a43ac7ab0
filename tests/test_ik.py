"""Differential IK: the acceptance run (1,000 random reachable targets per arm), parameter targets,
partial targets, continuous and mimic joints, the nullspace task, failures and input checks.

Every check of a solution is independent of the solver: the pose of the returned q by forward
kinematics, compared with scipy's rotation angle."""

from __future__ import annotations

import time

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import kinengine
from kinengine.control import ik
from kinengine.control.ik import inverse_kinematics


def _pose_errors(robot, q, frame, T):
    """(|Δp| [m], angle of C_d Cᵀ [rad]) of frame's pose at q against T, by forward kinematics."""
    F = robot.frame_pose(q, frame)
    angle = Rotation.from_matrix(T[:3, :3] @ F[:3, :3].T).magnitude()
    return float(np.linalg.norm(T[:3, 3] - F[:3, 3])), float(angle)


def _within_limits(robot, q):
    return bool(np.all(q >= robot.lower_limits) and np.all(q <= robot.upper_limits))


@pytest.mark.slow
@pytest.mark.parametrize("name", ["abb_irb120", "ur5", "panda"])
def test_acceptance_1000_random_reachable_targets(name):
    robot = kinengine.load(name)
    frame = robot.end_effector
    rng = np.random.default_rng(2024)
    targets = robot.frame_pose(robot.random_configuration(rng, size=1000), frame)
    start = time.perf_counter()
    results = [inverse_kinematics(robot, T, frame, rng=i) for i, T in enumerate(targets)]
    elapsed = time.perf_counter() - start
    successes = sum(r.success for r in results)
    print(
        f"\n{name}: {successes}/1000 solved, {1000 / elapsed:.0f} solves/s, "
        f"attempts used {np.bincount([r.restarts for r in results]).tolist()}"
    )
    assert successes >= 995
    for T, result in zip(targets, results, strict=False):
        assert result.restarts <= ik.NEAREST_SEEDS + 3
        assert _within_limits(robot, result.q)
        ep, er = _pose_errors(robot, result.q, frame, T)
        assert ep == pytest.approx(result.position_error, rel=1e-6, abs=1e-12)
        assert er == pytest.approx(result.rotation_error, rel=1e-5, abs=2e-8)
        if result.success:
            assert ep <= 1e-6 and er <= 1e-6 + 2e-8


@pytest.mark.parametrize(
    "position,rotation",
    [("cartesian", "quaternion"), ("spherical", "euler_zyz"), ("cylindrical", "rotation_vector")],
)
def test_parameter_targets_reach_the_pose_they_describe(position, rotation):
    robot = kinengine.load("abb_irb120")
    rng = np.random.default_rng(6)
    for _ in range(5):
        q_true = robot.random_configuration(rng)
        chi = robot.pose_parameters(q_true, "tool0", position, rotation)
        result = inverse_kinematics(robot, chi, "tool0", position=position, rotation=rotation, rng=rng)
        assert result.success
        ep, er = _pose_errors(robot, result.q, "tool0", robot.frame_pose(q_true, "tool0"))
        assert ep <= 1e-6 and er <= 1e-6 + 2e-8


def test_position_only_and_rotation_only_targets_leave_the_other_part_free():
    robot = kinengine.load("abb_irb120")
    rng = np.random.default_rng(7)
    T = robot.frame_pose(robot.random_configuration(rng), "tool0")
    only_p = inverse_kinematics(robot, T[:3, 3], "tool0", position="cartesian", rng=1)
    assert only_p.success and only_p.rotation_error == 0.0
    assert np.linalg.norm(robot.frame_pose(only_p.q, "tool0")[:3, 3] - T[:3, 3]) <= 1e-6
    angles = Rotation.from_matrix(T[:3, :3]).as_euler("ZYX")
    only_r = inverse_kinematics(robot, angles, "tool0", rotation="euler_zyx", rng=1)
    assert only_r.success and only_r.position_error == 0.0
    assert _pose_errors(robot, only_r.q, "tool0", T)[1] <= 1e-6 + 2e-8


def test_continuous_joints_are_returned_in_minus_pi_pi():
    robot = kinengine.load("kinova")
    continuous = ~np.isfinite(robot.lower_limits)
    assert continuous.any()
    rng = np.random.default_rng(8)
    for i in range(20):
        T = robot.frame_pose(robot.random_configuration(rng))
        result = inverse_kinematics(robot, T, rng=i)
        assert result.success and _within_limits(robot, result.q)
        assert np.all(np.abs(result.q[continuous]) <= np.pi)
        assert max(_pose_errors(robot, result.q, robot.end_effector, T)) <= 1e-6 + 2e-8


def test_robot_with_mimic_joints():
    robot = kinengine.load("baxter")
    rng = np.random.default_rng(9)
    for i in range(5):
        T = robot.frame_pose(robot.random_configuration(rng), "left_gripper")
        result = inverse_kinematics(robot, T, "left_gripper", rng=i)
        assert result.success and _within_limits(robot, result.q)


def test_nullspace_target_pulls_a_redundant_arm_towards_it():
    robot = kinengine.load("panda")
    rng = np.random.default_rng(10)
    q_true, preferred = robot.random_configuration(rng), robot.random_configuration(rng)
    T = robot.frame_pose(q_true)
    q0 = np.clip(q_true + 0.05, robot.lower_limits, robot.upper_limits)
    plain = inverse_kinematics(robot, T, q0=q0, rng=0)
    pulled = inverse_kinematics(robot, T, q0=q0, rng=0, nullspace_target=preferred, nullspace_gain=0.2)
    assert plain.success and pulled.success
    assert np.linalg.norm(pulled.q - preferred) < np.linalg.norm(plain.q - preferred) - 0.1


def test_a_close_first_guess_stays_on_its_branch():
    robot = kinengine.load("ur5")
    q_true = np.array([0.4, -1.2, 1.5, -0.8, 1.1, 0.3])
    result = inverse_kinematics(robot, robot.frame_pose(q_true), q0=q_true + 0.02)
    assert result.success and result.restarts == 0 and result.iterations < 10
    np.testing.assert_allclose(result.q, q_true, rtol=0, atol=1e-4)  # same branch (others are > 0.1 away)


def test_unreachable_target_reports_failure_with_the_best_attempt():
    robot = kinengine.load("abb_irb120")
    T = np.eye(4)
    T[:3, 3] = [2.0, 0.0, 0.5]  # the IRB 120 reaches 0.58 m
    result = inverse_kinematics(robot, T, rng=3)
    assert not result.success and result.restarts <= ik.NEAREST_SEEDS + 3
    assert _within_limits(robot, result.q)
    ep, _er = _pose_errors(robot, result.q, "tool0", T)
    assert ep == pytest.approx(result.position_error, rel=1e-9) and ep > 1.0
    assert "did not converge" in str(result)


def test_same_rng_same_answer():
    robot = kinengine.load("panda")
    T = robot.frame_pose(robot.random_configuration(11))
    a = inverse_kinematics(robot, T, rng=5, restarts=2)
    b = inverse_kinematics(robot, T, rng=5, restarts=2)
    np.testing.assert_array_equal(a.q, b.q)


def test_inputs_are_checked():
    robot = kinengine.load("abb_irb120")
    with pytest.raises(kinengine.ParameterizationError, match=r"shape \(4, 4\)"):
        inverse_kinematics(robot, np.eye(3))
    with pytest.raises(kinengine.ParameterizationError, match="not a rotation matrix"):
        inverse_kinematics(robot, np.diag([1.0, 1.0, -1.0, 1.0]))
    with pytest.raises(kinengine.ParameterizationError, match=r"shape \(7,\)"):
        inverse_kinematics(robot, np.zeros(6), position="cartesian", rotation="quaternion")
    with pytest.raises(kinengine.ParameterizationError, match="unknown rotation parameterization"):
        inverse_kinematics(robot, np.zeros(6), position="cartesian", rotation="euler")
    with pytest.raises(kinengine.ConfigurationError, match="q0"):
        inverse_kinematics(robot, np.eye(4), q0=np.zeros(5))
    with pytest.raises(kinengine.ConfigurationError, match="nullspace_target"):
        inverse_kinematics(robot, np.eye(4), nullspace_target=[np.nan] * 6)
    with pytest.raises(kinengine.FrameNotFoundError):
        inverse_kinematics(robot, np.eye(4), "tool9")
    with pytest.raises(kinengine.OptionError, match="restarts"):
        inverse_kinematics(robot, np.eye(4), restarts=-1)


@pytest.mark.parametrize(
    "option,values",
    [
        ("max_iterations", [1.5, np.nan, np.inf, -1, True, "5", 10**7]),
        ("restarts", [1.5, -1, np.nan, "1", None]),
        ("tol_position", [np.nan, -1e-6, np.inf, "1e-6", None, 10**400]),
        ("tol_rotation", [np.nan, -1.0, np.inf]),
        ("min_damping", [np.nan, -1.0, np.inf, "0"]),
        ("nullspace_gain", [np.nan, -0.1, 2.0, np.inf]),
        ("rng", ["abc", -1, 1.5, True]),
        ("rows", ["xyz", ["x", "q"], [], ["x", "x"], [6], 3]),
        ("weights", [[1.0] * 5, [np.nan] * 6, [-1.0] * 6, "abc"]),
    ],
)
def test_every_numeric_option_is_validated_without_hanging(abb, option, values):
    """Issue 15 (#4, #8): bad option values are an OptionError up front, never a hang or q = NaN."""
    T = np.eye(4)
    T[:3, 3] = [2.0, 0.0, 0.5]  # unreachable: a hang would show here
    for value in values:
        with pytest.raises(kinengine.OptionError):
            inverse_kinematics(abb, T, **{"restarts": 0, option: value})


def test_degenerate_targets_are_refused(abb):
    with pytest.raises(kinengine.ParameterizationError):
        inverse_kinematics(abb, np.zeros(9), rotation="rotation_matrix")
    with pytest.raises(kinengine.ParameterizationError):
        inverse_kinematics(abb, np.zeros(4), rotation="quaternion")
    far = np.eye(4)
    far[0, 3] = 1e200
    with pytest.raises(kinengine.ParameterizationError, match="farther"):
        inverse_kinematics(abb, far)
    with pytest.raises(kinengine.ParameterizationError, match="farther"):
        inverse_kinematics(abb, np.array([1e200, 0, 0]), position="cartesian")
    with pytest.raises(kinengine.ParameterizationError):
        inverse_kinematics(abb, "abc")
    with pytest.raises(kinengine.ParameterizationError):
        inverse_kinematics(abb, np.zeros((3, 4, 4)))  # a batch of zero rotations
    for ragged in (
        [[1.0, 0.0], [0.0]],
        [[[1.0, 0.0], [0.0]]],
    ):  # no array: refused by name, not numpy's error
        for method in ("numeric", "auto"):
            with pytest.raises(kinengine.ParameterizationError, match="Expected `target` to be a"):
                inverse_kinematics(abb, ragged, method=method)


def test_far_but_finite_target_gives_finite_errors(abb):
    T = np.eye(4)
    T[:3, 3] = [1e8, 0.0, 0.0]
    result = inverse_kinematics(abb, T, restarts=0, max_iterations=20)
    assert not result.success and np.isfinite(result.q).all()
    assert np.isfinite(result.position_error) and np.isfinite(result.rotation_error)


def test_five_dimensional_target_position_plus_tool_axis(abb):
    """rows=("x", "y", "z", "rx", "ry"): the tool's z axis matches the target's, rotation about it is free."""
    rng = np.random.default_rng(12)
    for i in range(10):
        T = abb.frame_pose(abb.random_configuration(rng))
        spun = T.copy()
        spun[:3, :3] = T[:3, :3] @ Rotation.from_rotvec([0, 0, 1.0]).as_matrix()  # same tool axis
        result = abb.inverse_kinematics(spun, rows=("x", "y", "z", "rx", "ry"), rng=i)
        assert result.success
        F = abb.frame_pose(result.q)
        assert np.linalg.norm(F[:3, 3] - T[:3, 3]) <= 1e-6
        assert np.arccos(np.clip(F[:3, 2] @ T[:3, 2], -1, 1)) <= 1e-5
        weighted = abb.inverse_kinematics(spun, rows=(0, 1, 2, 3, 4), weights=[1, 1, 1, 0.5, 0.5], rng=i)
        assert weighted.success


@pytest.mark.parametrize("name", ["abb_irb120", "panda", "baxter"])
def test_batched_ik_equals_single_ik_per_target(name):
    """Same algorithm vectorized: the targets converge in both (to the same tolerance), within limits."""
    robot = kinengine.load(name)
    frame = "left_gripper" if name == "baxter" else robot.end_effector
    solutions = robot.random_configuration(np.random.default_rng(13), size=60)
    targets = robot.frame_pose(solutions, frame)
    batch = robot.inverse_kinematics(targets, frame, rng=0)
    assert len(batch) == 60 and batch.q.shape == (60, robot.dof)
    single = np.array([robot.inverse_kinematics(T, frame, rng=0).success for T in targets])
    # the random restarts draw in another order: a rare hard target (its solutions against a joint limit,
    # ~0.1 % of random ones) may converge in one solver only
    assert batch.success.sum() >= 58 and single.sum() >= 58 and (batch.success == single).sum() >= 57
    for T, result in zip(targets, batch, strict=False):
        assert isinstance(result, kinengine.IKResult) and _within_limits(robot, result.q)
        ep, er = _pose_errors(robot, result.q, frame, T)
        assert not result.success or (ep <= 1e-6 and er <= 1e-6 + 2e-8)
        assert ep == pytest.approx(result.position_error, rel=1e-6, abs=1e-12)
    # a target batch with one start for all, or one start per target
    again = robot.inverse_kinematics(targets[:5], frame, q0=solutions[0] + 0.01)
    assert len(again) == 5 and again[0].success and again.restarts[0] == 0
    per_target = robot.inverse_kinematics(targets[:5], frame, q0=batch.q[:5])
    assert per_target.success.all() and (per_target.iterations == 0).all()
    assert "5/5 converged" in str(per_target)


def test_batched_ik_rows_and_nullspace(abb):
    targets = abb.frame_pose(abb.random_configuration(np.random.default_rng(14), size=20))
    five = abb.inverse_kinematics(targets, rows=("x", "y", "z", "rx", "ry"), rng=0)
    # one target's solution has q1 0.5 % of its range from the limit: seeds drawn inside the ranges (and
    # ranked by the full pose, the free rotation too) reach it only after 10 restarts
    assert five.success.sum() >= 19
    F = abb.frame_pose(five.q[five.success])
    assert np.abs(F[:, :3, 3] - targets[five.success, :3, 3]).max() <= 1e-6
    panda = kinengine.load("panda")
    rng = np.random.default_rng(15)
    solutions, preferred = panda.random_configuration(rng, size=20), panda.random_configuration(rng)
    targets = panda.frame_pose(solutions)
    q0 = np.clip(solutions + 0.05, panda.lower_limits, panda.upper_limits)
    plain = panda.inverse_kinematics(targets, q0=q0, rng=0)
    pulled = panda.inverse_kinematics(targets, q0=q0, rng=0, nullspace_target=preferred, nullspace_gain=0.2)
    singles = [
        panda.inverse_kinematics(T, q0=s, rng=0, nullspace_target=preferred, nullspace_gain=0.2)
        for T, s in zip(targets, q0, strict=False)
    ]
    assert plain.success.all() and pulled.success.mean() >= 0.9
    ok = pulled.success & np.array([r.success for r in singles])
    distance = np.linalg.norm(pulled.q - preferred, axis=1)
    assert np.mean(distance[ok]) < np.mean(np.linalg.norm(plain.q - preferred, axis=1)[ok])
    assert np.mean([r.success for r in singles]) >= 0.9
    with pytest.raises(kinengine.OptionError):
        abb.inverse_kinematics(targets, q0=np.zeros((3, 6)))


def test_every_entry_of_a_pose_target_is_checked(abb):
    """A (4, 4) target is refused for a non-finite entry anywhere, a rotation block off orthonormal by more
    than 1e-6 or with det < 0, and a position beyond MAX_TARGET_DISTANCE; within those bounds it is solved."""
    T = abb.frame_pose(abb.random_configuration(np.random.default_rng(21)))
    for i in range(4):
        for j in range(4):
            for bad in (np.nan, np.inf, -np.inf):
                U = T.copy()
                U[i, j] = bad
                with pytest.raises(kinengine.ParameterizationError, match="holds NaN or inf"):
                    inverse_kinematics(abb, U)
    with pytest.raises(kinengine.ParameterizationError, match=r"got \(3, 4\)"):
        inverse_kinematics(abb, T[:3])
    batch = np.stack([T, T, T])
    batch[2, 0, 3] = np.nan
    with pytest.raises(kinengine.ParameterizationError, match=r"`target`\[2\] holds NaN or inf \(1 of 3"):
        inverse_kinematics(abb, batch)
    flipped = T.copy()
    flipped[:3, 2] *= -1.0  # orthonormal columns, det = -1: a reflection
    with pytest.raises(kinengine.ParameterizationError, match="not a rotation matrix"):
        inverse_kinematics(abb, flipped)
    for off, accepted in ((3e-6, False), (1e-7, True)):
        U = T.copy()
        U[0, 1] += off  # columns 0 and 1 no longer orthogonal (to ~off), column 1 no longer unit
        if accepted:
            assert inverse_kinematics(abb, U.tolist(), rng=0).position_error <= 1e-6
        else:
            with pytest.raises(kinengine.ParameterizationError, match="not a rotation matrix"):
                inverse_kinematics(abb, U)
    for axis in range(3):
        far = np.eye(4)
        far[axis, 3] = -2e9
        with pytest.raises(kinengine.ParameterizationError, match="farther"):
            inverse_kinematics(abb, far)


def test_stalled_attempts_give_way_after_stall_from_iterations(abb):
    """A target 5 m away (the IRB 120 reaches 0.58 m): no attempt's error shrinks by 20 % in 3 iterations, so
    each one but the last gives way after STALL_FROM iterations; the last never gives way, but ends when
    stuck (STUCK_SPAN iterations without a new best score), well before max_iterations."""
    from kinengine.control import ik_step
    from kinengine.control.ik_seeds import frame_seeds
    from kinengine.control.ik_target import FrameGoal, Options, checked_problem

    T = np.eye(4)
    T[:3, 3] = [5.0, 0.0, 0.5]
    result = inverse_kinematics(abb, T, rng=0, restarts=2, max_iterations=50)
    options = Options(1e-6, 1e-6, 50, 2, None, 0.1, 1e-6, False)
    problem = checked_problem(abb, None, None, None, options)
    attempts = len(frame_seeds(abb, [FrameGoal(problem, T[:3, 3], T[:3, :3])], None)) + 2
    assert not result.success
    last = result.iterations - (attempts - 1) * ik_step.STALL_FROM
    assert ik_step.STUCK_SPAN <= last < 50
    ep, _ = _pose_errors(abb, result.q, "tool0", T)
    assert ep == pytest.approx(result.position_error, rel=1e-9) and ep > 4.0


def test_a_crawling_attempt_gives_way_unless_it_is_the_last():
    """An attempt whose score falls 8 % an iteration (not stalled: 0.92³ < STALL_RATIO) gives way after CRAWL
    iterations unless it is the last; the rule reads the same for one attempt and for columns."""
    from kinengine.control.ik_step import CRAWL, STALL_RATIO, gives_way

    history = [1e-3 * 0.92**k for k in range(CRAWL)]
    score = history[-1] * 0.92
    assert score < STALL_RATIO * history[-3]
    assert gives_way(CRAWL, score, history, False, 0, False)
    assert not gives_way(CRAWL - 1, score, history, False, 0, False)
    assert not gives_way(CRAWL, score, history, True, 0, False)
    columns = gives_way(
        np.array([CRAWL, CRAWL, CRAWL - 1]),
        np.full(3, score),
        np.array(history[-3:])[:, None].repeat(3, axis=1),
        np.array([False, True, False]),
        np.zeros(3),
        np.zeros(3, dtype=bool),
    )
    assert columns.tolist() == [True, False, False]


def test_the_attempt_from_the_callers_q0_is_never_ended_as_stuck():
    """A stuck attempt (STUCK_SPAN iterations without a new best) ends, the last one too, unless it starts
    from the caller's q0: that one may crawl to max_iterations (the Panda arm with joint 4 on its upper
    limit, q0 0.05 rad from the solution, converges in 83 iterations; it was cut at 14 and the answer came
    from a random restart 5 rad away). Checked by forward kinematics, one target and a batch."""
    from kinengine.control.ik_step import STUCK_SPAN, gives_way

    assert gives_way(20, 1e-3, [1e-3] * 20, True, STUCK_SPAN, False)
    assert not gives_way(20, 1e-3, [1e-3] * 20, True, STUCK_SPAN, True)
    robot = kinengine.load("panda_arm")
    rng = np.random.default_rng(3)
    for _ in range(56):
        q = robot.random_configuration(rng=rng)
        q[3] = robot.upper_limits[3] - rng.uniform(0, 1e-3)
        T = robot.frame_pose(q)
        q0 = np.clip(q + rng.normal(0, 0.05, 7), robot.lower_limits, robot.upper_limits)
    one = robot.inverse_kinematics(T, q0=q0, restarts=0, method="numeric", max_iterations=500)
    assert one.success and one.iterations > STUCK_SPAN + 4
    assert np.max(np.abs(one.q - q0)) < 0.5  # the caller's branch, not a restart's
    ep, _ = _pose_errors(robot, one.q, robot.end_effector, T)
    assert ep <= 1e-6
    both = robot.inverse_kinematics(np.stack([T, T]), q0=np.stack([q0, q0]), restarts=0, max_iterations=500)
    assert both.success.all() and np.max(np.abs(both.q - q0)) < 0.5


def test_coordinates_that_move_no_frame_are_left_out_and_pulled_to_the_nullspace_target():
    """The Panda's finger does not move panda_hand (its Jacobian column is zero): it is left out of the step
    (the seven arm joints, one for one with Pinocchio's q), and set to the nullspace target; a finger frame
    (moved through the mimic finger) keeps every coordinate; solutions checked by forward kinematics."""
    from kinengine.control.ik_step import moving

    robot = kinengine.load("panda")
    rng = np.random.default_rng(41)
    hand = moving(robot.engine, (robot.frame_id("panda_hand"),))
    finger = moving(robot.engine, (robot.frame_id("panda_leftfinger"),))
    assert (hand.coords, hand.pin, hand.free.tolist()) == (slice(0, 7), slice(0, 7), [7])
    assert (finger.coords, finger.pin, finger.free.tolist()) == (slice(0, 8), None, [])
    for q in robot.random_configuration(rng, size=5):
        J = robot.jacobian(q, "panda_hand")
        assert np.all(J[:, 7] == 0.0) and np.all(np.abs(J[:, :7]).max(axis=0) > 1e-3)
        assert np.abs(robot.jacobian(q, "panda_leftfinger")[:, 7]).max() > 0.5
    preferred = np.clip(robot.random_configuration(rng), robot.lower_limits, robot.upper_limits)
    solutions = robot.random_configuration(rng, size=6)
    for frame, pull in (("panda_hand", preferred), ("panda_leftfinger", None)):
        targets = robot.frame_pose(solutions, frame)
        batch = robot.inverse_kinematics(targets, frame, rng=0, nullspace_target=pull)
        singles = [robot.inverse_kinematics(T, frame, rng=0, nullspace_target=pull) for T in targets]
        # one finger target (solved as on main) ends 3 cm off, in a local minimum, by both solvers
        assert batch.success.sum() >= 5 and batch.success.tolist() == [r.success for r in singles]
        for q, T, ok in zip(
            [*batch.q, *(r.q for r in singles)], [*targets] * 2, [*batch.success] * 2, strict=True
        ):
            assert _within_limits(robot, q) and (max(_pose_errors(robot, q, frame, T)) <= 1e-6) == ok
        if frame == "panda_hand":  # the finger, free, at its nullspace target
            assert np.all(batch.q[:, 7] == preferred[7]) and all(r.q[7] == preferred[7] for r in singles)


def test_a_singular_damped_matrix_falls_back_to_least_squares(abb):
    """Zero tolerances and zero damping at a wrist singularity (q5 = 0): once the error is at rounding level
    J W⁻¹Jᵀ + λ² I is singular to working precision and Cholesky fails; the step is then the least-squares
    solution, so the solve ends with a finite q on the target, not with a LinAlgError."""
    q_true = np.array([0.3, 0.2, 0.1, 0.0, 0.0, 0.0])
    T = abb.frame_pose(q_true)
    result = inverse_kinematics(
        abb, T, q0=q_true + 0.01, tol_position=0, tol_rotation=0, min_damping=0, max_iterations=30, restarts=0
    )
    assert np.isfinite(result.q).all() and _within_limits(abb, result.q)
    ep, er = _pose_errors(abb, result.q, "tool0", T)
    assert ep <= 1e-12 and er <= 1e-12


def test_a_full_pose_step_equals_the_explicitly_weighted_six_row_step(abb):
    """A full pose's least squares weights the rotation rows by ROTATION_ROW_WEIGHT (done on the damping
    diagonal, in the frame F); the six rows in the target frame with weights w = (1, 1, 1, ρ², ρ², ρ²) take
    the same steps in another frame and another code path, so both end on the same q, attempt and count."""
    from kinengine.control import ik_step

    rho_sq = ik_step.ROTATION_ROW_WEIGHT**2
    targets = abb.frame_pose(abb.random_configuration(np.random.default_rng(3), size=30))
    for i, T in enumerate(targets):
        full = inverse_kinematics(abb, T, rng=i, method="numeric")
        rows = inverse_kinematics(abb, T, weights=[1.0, 1.0, 1.0, rho_sq, rho_sq, rho_sq], rng=i)
        assert full.success and rows.success
        assert (full.iterations, full.restarts) == (rows.iterations, rows.restarts)
        np.testing.assert_allclose(full.q, rows.q, rtol=0, atol=1e-10)
