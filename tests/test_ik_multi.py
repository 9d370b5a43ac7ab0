"""IK for several frames at once (issue 14): ``target`` a mapping {frame: T_IF (4, 4)}.

Every solution is checked independently of the solver: each frame's pose at the returned q by forward
kinematics (robot.frame_pose), its rotation angle by scipy. Weighted, conflicting position targets end at
the closed-form least-squares compromise."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import kinengine
from kinengine.control.ik import inverse_kinematics
from kinengine.control.ik_multi import MultiIKResult

TOL = 1e-6
ANGLE_SLACK = 2e-8  # scipy's angle of a near-identity rotation against log3's


@pytest.fixture(scope="module")
def panda():
    return kinengine.load("panda")  # 8 coordinates: 7 arm joints and a finger (its mimic folded in)


@pytest.fixture(scope="module")
def abb():
    return kinengine.load("abb_irb120")


def _errors(robot, q, frame, T, rows=None):
    """(position error [m], rotation angle [rad]) of frame at q against T, by forward kinematics; with
    rows, the kept position rows of C_dᵀ (p_d − p) (the rotation rows here are all or none)."""
    F = robot.frame_pose(q, frame)
    dp = T[:3, 3] - F[:3, 3]
    angle = float(Rotation.from_matrix(T[:3, :3] @ F[:3, :3].T).magnitude())
    if rows is None:
        return float(np.linalg.norm(dp)), angle
    kept = [("x", "y", "z").index(r) for r in rows if r in ("x", "y", "z")]
    rotation = angle if any(r in ("rx", "ry", "rz") for r in rows) else 0.0
    return float(np.linalg.norm((T[:3, :3].T @ dp)[kept])), rotation


def _within_limits(robot, q):
    return bool(np.isfinite(q).all() and np.all(q >= robot.lower_limits) and np.all(q <= robot.upper_limits))


def _check(robot, result, targets, rows=None):
    """The reported errors are forward kinematics' (each frame, and the maxima); success iff all within."""
    assert isinstance(result, MultiIKResult) and isinstance(result, kinengine.IKResult)
    assert _within_limits(robot, result.q)
    rows = rows or {}
    assert set(result.frame_errors) == set(targets)
    for frame, T in targets.items():
        ep, er = _errors(robot, result.q, frame, T, rows.get(frame))
        assert result.frame_errors[frame][0] == pytest.approx(ep, rel=1e-6, abs=1e-12)
        assert result.frame_errors[frame][1] == pytest.approx(er, rel=1e-5, abs=ANGLE_SLACK)
        if result.success:
            assert ep <= TOL and er <= TOL + ANGLE_SLACK
    assert result.position_error == max(e[0] for e in result.frame_errors.values())
    assert result.rotation_error == max(e[1] for e in result.frame_errors.values())
    assert result.success == all(p <= TOL and r <= TOL for p, r in result.frame_errors.values())


def test_panda_hand_and_link4_poses_from_random_reachable_configurations(panda):
    rng = np.random.default_rng(11)
    qs = panda.random_configuration(rng, size=30)
    solved = 0
    for i, q in enumerate(qs):
        targets = {
            "panda_hand": panda.frame_pose(q, "panda_hand"),
            "panda_link4": panda.frame_pose(q, "panda_link4"),
        }
        result = panda.inverse_kinematics(targets, rng=i)
        _check(panda, result, targets)
        solved += result.success
    assert solved >= 28  # measured 196/200 on random targets; the misses sit at joint limits


def test_three_frames_of_the_abb(abb):
    rng = np.random.default_rng(12)
    for i, q in enumerate(abb.random_configuration(rng, size=10)):
        targets = {frame: abb.frame_pose(q, frame) for frame in ("tool0", "link_4", "link_2")}
        result = abb.inverse_kinematics(targets, rng=i)
        assert result.success
        _check(abb, result, targets)


def test_a_frame_moved_by_a_mimic_joint_sets_its_leader(panda):
    """panda_rightfinger moves with finger_joint2, a mimic of q[7]: its position (with the hand's pose)
    fixes q[7] only through the folded Jacobian column."""
    rng = np.random.default_rng(17)
    rows = {"panda_rightfinger": ("x", "y", "z")}
    for i, q in enumerate(panda.random_configuration(rng, size=8)):
        targets = {f: panda.frame_pose(q, f) for f in ("panda_hand", "panda_rightfinger")}
        result = panda.inverse_kinematics(targets, rows=rows, rng=i)
        assert result.success
        _check(panda, result, targets, rows)
        assert result.q[7] == pytest.approx(q[7], abs=1e-5)


def test_rows_per_frame_hand_pose_and_link4_xy(panda):
    """rows={"panda_link4": ("x", "y")}: link4's x, y in its target frame D; the hand keeps six rows."""
    rng = np.random.default_rng(13)
    rows = {"panda_link4": ("x", "y")}
    solved = 0
    for i, q in enumerate(panda.random_configuration(rng, size=15)):
        T_link = panda.frame_pose(q, "panda_link4")
        T_link[:3, :3] = Rotation.from_rotvec(rng.normal(size=3)).as_matrix()  # D's axes, not link4's
        T_link[:3, 3] += T_link[:3, 2] * 0.3  # z in D is free: moved along it, the target stays exact
        targets = {"panda_hand": panda.frame_pose(q, "panda_hand"), "panda_link4": T_link}
        result = panda.inverse_kinematics(targets, rows=rows, rng=i)
        _check(panda, result, targets, rows)
        solved += result.success
    assert solved >= 13


def test_one_spec_applies_to_every_frame(abb):
    """rows=("x", "y", "z"): positions only, for both frames; rotations free (rotation error 0)."""
    rng = np.random.default_rng(14)
    q = abb.random_configuration(rng)
    targets = {"tool0": abb.frame_pose(q, "tool0"), "link_4": abb.frame_pose(q, "link_4")}
    targets["tool0"][:3, :3] = np.eye(3)  # ignored: position rows only
    result = abb.inverse_kinematics(targets, rows=("x", "y", "z"), weights=(1.0, 2.0, 3.0), rng=0)
    assert result.success and result.rotation_error == 0.0
    _check(abb, result, targets, dict.fromkeys(targets, ("x", "y", "z")))


@pytest.mark.parametrize("name,frame", [("panda", "panda_hand"), ("abb_irb120", "tool0")])
@pytest.mark.parametrize(
    "options",
    [
        {},
        {"rows": ("x", "y", "z", "rx", "ry", "rz"), "weights": (1.0, 2.0, 1.0, 0.5, 0.5, 3.0)},
        {"rows": ("x", "z"), "weights": (2.0, 0.5)},
        {"max_iterations": 3, "restarts": 2},
    ],
)
def test_one_frame_mapping_reaches_the_pose_checked_by_forward_kinematics(name, frame, options):
    """A one-frame mapping (the single-frame loop with a MultiIKResult): its errors are forward
    kinematics', it converges from any reachable pose when given iterations, and q0 is left untouched."""
    robot = kinengine.load(name)
    rng = np.random.default_rng(15)
    rows = options.get("rows")
    for i, q in enumerate(robot.random_configuration(rng, size=5)):
        T = robot.frame_pose(q, frame)
        for q0 in (np.clip(q + 0.3, robot.lower_limits, robot.upper_limits), None):
            given_q0 = None if q0 is None else q0.copy()
            result = inverse_kinematics(robot, {frame: T}, q0=given_q0, rng=i, **options)
            _check(robot, result, {frame: T}, {frame: rows} if rows else None)
            assert result.success or "max_iterations" in options
            assert q0 is None or np.array_equal(given_q0, q0)  # q0 left untouched


@pytest.mark.parametrize("w", [1.0, 3.0])
def test_conflicting_weighted_positions_meet_at_the_least_squares_compromise(panda, w):
    """panda_hand and panda_hand_tcp are L = 0.1034 m apart on the hand's z axis; their position targets
    are L + δ apart on a line (rotations free). min w|e_hand|² + |e_tcp|² splits δ: the hand misses by
    δ/(1 + w), the tcp by δ·w/(1 + w) (damped least squares stops where Jᵀ W e = 0)."""
    q = np.array([0.2, -0.3, 0.1, -1.8, 0.1, 1.6, 0.7, 0.02])
    T_hand, T_tcp = panda.frame_pose(q, "panda_hand"), panda.frame_pose(q, "panda_hand_tcp")
    axis = (T_tcp[:3, 3] - T_hand[:3, 3]) / np.linalg.norm(T_tcp[:3, 3] - T_hand[:3, 3])
    delta = 0.03
    T_tcp[:3, 3] += delta * axis
    targets = {"panda_hand": T_hand, "panda_hand_tcp": T_tcp}
    result = panda.inverse_kinematics(
        targets, q0=q, rows=("x", "y", "z"), weights={"panda_hand": (w, w, w)}, max_iterations=200, restarts=0
    )
    assert not result.success
    _check(panda, result, targets, dict.fromkeys(targets, ("x", "y", "z")))
    assert result.frame_errors["panda_hand"][0] == pytest.approx(delta / (1 + w), abs=1e-9)
    assert result.frame_errors["panda_hand_tcp"][0] == pytest.approx(delta * w / (1 + w), abs=1e-9)


def test_inconsistent_and_unreachable_targets_fail_within_the_limits(panda):
    rng = np.random.default_rng(16)
    q1, q2 = panda.random_configuration(rng, size=2)
    conflicting = {
        "panda_hand": panda.frame_pose(q1, "panda_hand"),
        "panda_link4": panda.frame_pose(q2, "panda_link4"),
    }
    far = panda.frame_pose(q1, "panda_hand")
    far[:3, 3] += (3.0, 0.0, 0.0)
    unreachable = {"panda_hand": far, "panda_link4": panda.frame_pose(q1, "panda_link4")}
    for targets in (conflicting, unreachable):
        result = panda.inverse_kinematics(targets, rng=0, restarts=2)
        assert not result.success and result.position_error > 1e-3
        _check(panda, result, targets)
    assert "did not converge" in str(result)


def test_option_errors_name_the_fix(panda):
    q = np.zeros(panda.dof)
    T = panda.frame_pose(q, "panda_hand")
    two = {"panda_hand": T, "panda_link4": panda.frame_pose(q, "panda_link4")}
    Option, Frame, Param = (
        kinengine.OptionError,
        kinengine.FrameNotFoundError,
        kinengine.ParameterizationError,
    )
    cases = [
        (Option, "leave `frame`", {"target": two, "frame": "panda_hand"}),
        (Option, "leave `frame`", {"target": two, "position": "cartesian"}),
        (Option, "at least one frame", {"target": {}}),
        (Frame, "nope", {"target": {"nope": T}}),
        (Option, "not a frame of the target", {"target": two, "rows": {"panda_link7": ("x",)}}),
        (Option, "not a frame of the target", {"target": two, "weights": {"nope": (1.0,) * 6}}),
        (Option, "or None for all six rows", {"target": two, "rows": {}}),
        (
            Option,
            "one number per kept row",
            {"target": two, "rows": {"panda_link4": ("x", "y")}, "weights": (1.0,) * 6},
        ),
        (Option, "`rows` entries", {"target": two, "rows": {"panda_link4": ("w",)}}),
        (Option, "frame names", {"target": {3: T}}),
        (Param, "must be a pose (4, 4)", {"target": {"panda_hand": T[:3]}}),
        (Param, "must be a pose (4, 4)", {"target": {"panda_hand": "T"}}),
        (Param, "target['panda_hand']`: `target`'s rotation", {"target": {"panda_hand": 2 * T}}),
        (Option, "tol_position", {"target": two, "tol_position": -1.0}),
        (Option, "restarts", {"target": two, "restarts": 1.5}),
        (kinengine.ConfigurationError, "q0", {"target": two, "q0": np.zeros((2, panda.dof))}),
    ]
    for error, words, kwargs in cases:
        with pytest.raises(error) as info:
            panda.inverse_kinematics(**kwargs)
        assert words in str(info.value), (kwargs, str(info.value))


ABB = kinengine.load("abb_irb120")
_LINK4_POSITION = {"link_4": ("x", "y", "z")}


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    fractions=st.lists(st.floats(0.02, 0.98), min_size=6, max_size=6),
    offset=st.lists(st.floats(-0.1, 0.1), min_size=6, max_size=6),
    seed=st.integers(0, 2**16),
)
def test_abb_tool0_and_link4_position_from_any_reachable_q(fractions, offset, seed):
    """tool0's pose + link_4's position of a reachable q: from a q0 within 0.1 rad per joint the solve always
    converges; from the stored seeds it reports errors that forward kinematics confirms."""
    lower, upper = ABB.lower_limits, ABB.upper_limits
    q = lower + np.array(fractions) * (upper - lower)
    targets = {"tool0": ABB.frame_pose(q, "tool0"), "link_4": ABB.frame_pose(q, "link_4")}
    near = ABB.inverse_kinematics(
        targets, q0=np.clip(q + np.array(offset), lower, upper), rows=_LINK4_POSITION, restarts=0
    )
    assert near.success
    _check(ABB, near, targets, _LINK4_POSITION)
    free = ABB.inverse_kinematics(targets, rows=_LINK4_POSITION, rng=seed)
    _check(ABB, free, targets, _LINK4_POSITION)


def test_a_robot_without_joints_reports_its_frames_errors():
    """No joint moves any frame: the mapping target is answered from the fixed pose (Pinocchio crashed on
    a Jacobian with nv = 0 when the stacked solver asked for one), errors by forward kinematics."""
    robot = kinengine.load_urdf_string(
        '<robot name="fixed"><link name="a"/><link name="b"/><joint name="j" type="fixed"><parent link="a"/>'
        '<child link="b"/><origin xyz="0 0 1"/></joint></robot>'
    )
    T = robot.frame_pose(np.zeros(0), "b")
    T[0, 3] += 0.5
    result = inverse_kinematics(robot, {"b": T, "a": np.eye(4)})
    _check(robot, result, {"b": T, "a": np.eye(4)})
    assert not result.success and result.frame_errors["b"][0] == pytest.approx(0.5, abs=1e-12)
