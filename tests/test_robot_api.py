"""The foundation API: loading, names, configurations, batching, copies and errors."""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pinocchio as pin
import pytest
from custom_robots import mixed_chain_urdf

import kinengine
import kinengine.model


def test_available_robots_lists_shipped_and_example_robot_data_arms():
    names = kinengine.available_robots()
    for expected in (
        "abb_irb120",
        "planar_3dof",
        "scara",
        "ur3",
        "ur5",
        "ur10",
        "panda",
        "kinova",
        "xarm7",
        "z1",
        "so100",
        "so101",
        "baxter",
        "double_pendulum",
    ):
        assert expected in names


def test_load_by_name_path_and_string_agree(abb, tmp_path):
    by_path = kinengine.load(abb.source)
    by_string = kinengine.load_urdf_string(abb.urdf_text)
    q = abb.random_configuration(0)
    for other in (by_path, by_string):
        assert other.joint_names == abb.joint_names
        np.testing.assert_array_equal(other.frame_pose(q, "tool0"), abb.frame_pose(q, "tool0"))


def test_abb_description(abb):
    assert abb.name == "abb_irb120"
    assert abb.dof == 6
    assert abb.joint_names == tuple(f"joint_{i}" for i in range(1, 7))
    np.testing.assert_allclose(abb.upper_limits, [2.87979, 1.91986, 1.22173, 2.79253, 2.094395, 6.98132])
    np.testing.assert_allclose(
        abb.lower_limits, [-2.87979, -1.91986, -1.91986, -2.79253, -2.094395, -6.98132]
    )
    assert {"base_link", "base", "flange", "tool0", "link_6", "joint_3"} <= set(abb.frame_names)
    assert abb.end_effector == "tool0"
    assert "universe" not in abb.frame_names


def test_continuous_joint_is_one_angle_and_mimic_takes_no_coordinate(mixed):
    # depth-first from the root; siblings in joint-name order (as urdfdom and Pinocchio build the tree)
    assert mixed.joint_names == ("shoulder", "side_joint", "spin", "slide", "wrist", "finger_a_joint")
    assert mixed.dof == 6
    i = mixed.joint_names.index("spin")
    assert mixed.lower_limits[i] == -np.inf and mixed.upper_limits[i] == np.inf
    q = mixed.random_configuration(1)
    q2 = q.copy()
    q2[i] += 2 * np.pi  # one full turn of a continuous joint changes nothing
    np.testing.assert_allclose(mixed.frame_pose(q2, "tip"), mixed.frame_pose(q, "tip"), rtol=0, atol=1e-12)
    assert mixed.pinocchio_configuration(q).shape == (7,)


def test_random_configuration_within_limits_and_seeded(abb):
    qs = abb.random_configuration(np.random.default_rng(3), size=500)
    assert qs.shape == (500, 6)
    assert np.all(qs >= abb.lower_limits) and np.all(qs <= abb.upper_limits)
    np.testing.assert_array_equal(abb.random_configuration(11), abb.random_configuration(11))
    np.testing.assert_array_equal(abb.neutral(), np.zeros(6))


def test_configuration_by_joint_name(abb, mixed):
    q = abb.configuration({"joint_1": 0.1, "joint_2": -0.3})
    np.testing.assert_array_equal(q, [0.1, -0.3, 0, 0, 0, 0])
    with pytest.raises(kinengine.FrameNotFoundError, match="joint_3"):
        abb.configuration({"joint3": 0.1})
    np.testing.assert_array_equal(
        abb.configuration({"joint3": 0.1, "joint_6": 1.0}, strict=False), [0, 0, 0, 0, 0, 1.0]
    )
    with pytest.raises(kinengine.ConfigurationError, match="mimic joint that follows 'finger_a_joint'"):
        mixed.configuration({"finger_b_joint": 0.3})
    with pytest.raises(kinengine.ConfigurationError, match="finite"):
        abb.configuration({"joint_1": float("nan")})


def test_batched_results_equal_single_calls(mixed):
    qs = mixed.random_configuration(2, size=7)
    T = mixed.frame_pose(qs, "tip")
    assert T.shape == (7, 4, 4)
    for reference in ("world", "local", "local_world_aligned"):
        J = mixed.jacobian(qs, "tip", reference)
        assert J.shape == (7, 6, 6)
        for i in range(7):  # batches run on the compiled chain, single calls on Pinocchio: equal to rounding
            np.testing.assert_allclose(J[i], mixed.jacobian(qs[i], "tip", reference), rtol=0, atol=1e-14)
            np.testing.assert_allclose(T[i], mixed.frame_pose(qs[i], "tip"), rtol=0, atol=1e-14)


def _array_results(robot, q, qdot, target):
    """Every array a Robot entry point returns, by name, at q (dof,) with q̇ and an IK target."""
    report, ellipsoid = robot.singularity_report(q), robot.velocity_ellipsoid(q)
    batch = np.array([q, -q])
    return {
        "frame_pose": robot.frame_pose(q),
        "frame_pose_batch": robot.frame_pose(batch),
        **{f"jacobian_{r}": robot.jacobian(q, None, r) for r in ("world", "local", "local_world_aligned")},
        "jacobian_batch": robot.jacobian(batch, None, "local"),
        "pose_parameters": robot.pose_parameters(q, rotation="quaternion"),
        "pose_parameters_batch": robot.pose_parameters(batch, rotation="euler_zyz"),
        "analytic_jacobian": robot.analytic_jacobian(q, rotation="quaternion"),
        "analytic_jacobian_batch": robot.analytic_jacobian(batch, rotation="euler_zyz"),
        "jacobian_time_variation": robot.jacobian_time_variation(q, qdot),
        "kinematic_hessian": robot.kinematic_hessian(q, None, "world"),
        "analytic_hessian": robot.analytic_hessian(q, rotation="euler_zyz"),
        "singular_values": report.singular_values,
        "lost_directions": np.array([d.twist for d in report.lost_directions]),
        "manipulability_batch": robot.manipulability(batch),
        "ellipsoid_center": ellipsoid.center,
        "ellipsoid_axes": ellipsoid.axes,
        "ellipsoid_semi_axes": ellipsoid.semi_axes,
        "inverse_kinematics_q": robot.inverse_kinematics(target, rng=0).q,
        "configuration": robot.configuration({robot.joint_names[0]: 0.1}),
        "check_configuration": robot.check_configuration(q.tolist()),
        "pinocchio_configuration": robot.pinocchio_configuration(q),
        "neutral": robot.neutral(),
        "random_configuration": robot.random_configuration(0),
    }


@pytest.mark.parametrize("name", ["abb", "mixed"])
def test_results_are_copies_that_later_calls_do_not_overwrite(name, request):
    robot = request.getfixturevalue(name)
    q1, q2 = robot.random_configuration(0), robot.random_configuration(1)
    q1[-2] = q2[-2] = 0.7  # keep the IRB 120's wrist away from its singularity
    held = _array_results(robot, q1, np.linspace(-0.5, 0.5, robot.dof), robot.frame_pose(q2))
    snapshot = {k: v.copy() for k, v in held.items()}
    for k, v in held.items():  # a result owns its memory: no view into Pinocchio's Data or another result
        assert isinstance(v, np.ndarray) and v.dtype == np.float64, k
        assert not any(np.shares_memory(v, w) for j, w in held.items() if j != k and w.size and v.size), k
    again = _array_results(robot, q2, np.linspace(0.5, -0.5, robot.dof), robot.frame_pose(q1))
    for k, v in held.items():
        np.testing.assert_array_equal(v, snapshot[k], err_msg=k)
        if k not in ("neutral", "random_configuration", "configuration") and np.any(v):
            # (an answer that is exactly zero at both q is no test: e.g. the mixed chain's manipulability,
            # whose Jacobian is rank-deficient everywhere)
            assert not np.array_equal(v, again[k]), f"{k}: the second call should give another answer"
    held["frame_pose"][...] = 0.0  # writing into a result changes nothing the robot computes later
    np.testing.assert_array_equal(robot.frame_pose(q1), snapshot["frame_pose"])


def test_task_attributes_are_documented_read_only_views_that_the_next_update_overwrites(abb):
    # the Task's speed contract (kinengine/task.py): preallocated views, overwritten in place; copy what you keep
    task = abb.task("tool0", rotation="euler_zyz")
    names = (
        "pose",
        "chi",
        "jacobian",
        "analytic_jacobian",
        "twist",
        "chi_dot",
        "jacobian_dot",
        "analytic_jacobian_dot",
    )
    q1, q2 = abb.random_configuration(0), abb.random_configuration(1)
    task.update(q1, np.ones(6))
    held = {n: getattr(task, n) for n in names}
    kept = {n: getattr(task, n).copy() for n in names}
    task.update(q2, -np.ones(6))
    for n in names:
        assert held[n] is getattr(task, n)
        assert not held[n].flags.writeable
        assert not np.array_equal(held[n], kept[n]), n  # the held view now shows q2's values
    np.testing.assert_array_equal(kept["pose"], abb.frame_pose(q1, "tool0"))
    np.testing.assert_array_equal(held["pose"], abb.frame_pose(q2, "tool0"))


def test_the_pinocchio_model_handed_out_is_a_copy(abb):
    # Model and Data are made together inside the Robot and never mutated apart
    q = abb.random_configuration(3)
    T = abb.frame_pose(q, "tool0")
    model = abb.pinocchio_model()
    model.jointPlacements[1] = pin.SE3.Random()
    model.frames[model.getFrameId("tool0")].placement = pin.SE3.Random()
    model.lowerPositionLimit[:] = 0.0
    np.testing.assert_array_equal(abb.frame_pose(q, "tool0"), T)
    assert not np.array_equal(
        abb.pinocchio_model().jointPlacements[1].homogeneous, model.jointPlacements[1].homogeneous
    )


def test_pinocchio_reference_enum_is_accepted(abb):
    q = abb.random_configuration(4)
    for name, enum in (
        ("world", pin.WORLD),
        ("local", pin.LOCAL),
        ("local_world_aligned", pin.LOCAL_WORLD_ALIGNED),
    ):
        np.testing.assert_array_equal(abb.jacobian(q, "tool0", enum), abb.jacobian(q, "tool0", name))
    with pytest.raises(kinengine.KinematicsError, match="local_world_aligned"):
        abb.jacobian(q, "tool0", "global")


def test_default_frame_is_the_end_effector(abb):
    q = abb.random_configuration(5)
    np.testing.assert_array_equal(abb.frame_pose(q), abb.frame_pose(q, "tool0"))


def test_unknown_frame_suggests_close_names(abb):
    with pytest.raises(kinengine.FrameNotFoundError, match="Did you mean 'tool0'") as info:
        abb.frame_pose(abb.neutral(), "tool_0")
    assert isinstance(info.value, KeyError)
    assert "tool0" in str(info.value)
    with pytest.raises(kinengine.FrameNotFoundError):
        abb.jacobian(abb.neutral(), "nope")
    with pytest.raises(kinengine.FrameNotFoundError):
        abb.jacobian(abb.neutral(), ["tool0"])


@pytest.mark.parametrize(
    "bad,message",
    [
        (np.zeros(5), r"shape \(6,\) or \(N, 6\), got \(5,\)"),
        (np.zeros((2, 7)), r"got \(2, 7\)"),
        (np.zeros((2, 3, 6)), r"got \(2, 3, 6\)"),
        (np.array([0, 0, np.nan, 0, 0, 0]), r"q`\[2\] \(joint 'joint_3'\) is nan"),
        (np.array([0, 0, 0, np.inf, 0, 0]), "finite"),
        ("0,0,0,0,0,0", "string"),
        (None, "None"),
        (np.array(["a"] * 6, dtype=object), "non-numeric"),
        (np.ones(6, dtype=bool), "dtype bool"),
        (np.ones(6, dtype=complex), "dtype complex128"),
        (3.0, r"got \(\)"),
        ([[0.0] * 6, [0.0] * 5], "numeric"),
    ],
)
def test_bad_configurations_raise_configuration_error(abb, bad, message):
    with pytest.raises(kinengine.ConfigurationError, match=message) as info:
        abb.frame_pose(bad, "tool0")
    assert isinstance(info.value, ValueError)


def test_accepted_configuration_types_are_converted(abb):
    q = np.array([0.1, -0.2, 0.3, 0.4, -0.5, 0.6])
    expected = abb.frame_pose(q, "tool0")
    readonly = q.copy()
    readonly.flags.writeable = False
    strided = np.zeros(12)
    strided[::2] = q
    for variant in (q.tolist(), tuple(q), readonly, strided[::2], q.astype(object)):
        np.testing.assert_allclose(abb.frame_pose(variant, "tool0"), expected, rtol=0, atol=1e-15)
    np.testing.assert_allclose(abb.frame_pose(q.astype(np.float32), "tool0"), expected, rtol=0, atol=1e-6)
    np.testing.assert_array_equal(
        abb.frame_pose(np.arange(6), "tool0"), abb.frame_pose(np.arange(6.0), "tool0")
    )


def test_check_limits_names_joint_value_and_limits(abb):
    q = abb.neutral()
    q[2] = 1.5
    abb.frame_pose(q, "tool0")  # off by default
    with pytest.raises(kinengine.ConfigurationError, match=r"joint 'joint_3' at 1.5, outside its limits"):
        abb.frame_pose(q, "tool0", check_limits=True)
    with pytest.raises(kinengine.ConfigurationError, match="joint_3"):
        abb.check_configuration(q)


def test_load_errors_are_urdf_errors(tmp_path):
    with pytest.raises(kinengine.URDFError, match="unknown robot 'ur55'.*ur5"):
        kinengine.load("ur55")
    with pytest.raises(kinengine.URDFError, match="missing.urdf"):
        kinengine.load(tmp_path / "missing.urdf")
    with pytest.raises(kinengine.URDFError, match="robot name or a path"):
        kinengine.load(42)
    with pytest.raises(kinengine.URDFError):
        kinengine.load_urdf_string("<robot name='x'><link name='a'/>")
    with pytest.raises(kinengine.URDFError, match="str or bytes"):
        kinengine.load_urdf_string(None)


def _answers(robot, q):
    """Everything one thread computes at q, as arrays (sequential and threaded runs compare equal)."""
    return (
        robot.frame_pose(q, "tool0"),
        robot.jacobian(q, "tool0", "local"),
        robot.analytic_jacobian(q, "tool0", rotation="quaternion"),
        robot.kinematic_hessian(q, "tool0"),
        robot.inverse_kinematics(robot.frame_pose(q + 0.05, "tool0"), "tool0", q0=q, rng=0).q,
        robot.frame_pose(np.array([q, -q]), "tool0"),
    )


def test_one_robot_from_eight_threads_gives_the_sequential_answers(abb):
    qs = abb.random_configuration(9, size=48)
    expected = [_answers(abb, q) for q in qs]

    def work(offset):  # each thread walks all configurations from its own start
        wrong = []
        for k in range(len(qs)):
            i = (k + offset) % len(qs)
            if not all(np.array_equal(a, b) for a, b in zip(_answers(abb, qs[i]), expected[i], strict=False)):
                wrong.append(i)
        return wrong

    with ThreadPoolExecutor(max_workers=8) as pool:
        results = list(pool.map(work, range(0, 48, 6)))
    assert results == [[]] * 8


def test_load_from_eight_threads_at_once_gives_equal_robots():
    texts = [kinengine.model.catalog_entry("abb_irb120").path.read_text(), mixed_chain_urdf()]
    barrier = threading.Barrier(8)

    def work(i):
        barrier.wait()  # all eight parse and build at the same moment
        robot = kinengine.load("abb_irb120") if i % 4 == 0 else kinengine.load_urdf_string(texts[i % 2])
        q = np.linspace(-0.3, 0.3, robot.dof)
        return robot.joint_names, robot.frame_names, robot.frame_pose(q), robot.jacobian(q)

    with ThreadPoolExecutor(max_workers=8) as pool:
        results = list(pool.map(work, range(8)))
    for i, result in enumerate(results):
        reference = results[i % 2]
        assert result[:2] == reference[:2]
        np.testing.assert_array_equal(result[2], reference[2])
        np.testing.assert_array_equal(result[3], reference[3])
    assert results[0][0] == tuple(f"joint_{i}" for i in range(1, 7))
    assert results[1][0] == ("shoulder", "side_joint", "spin", "slide", "wrist", "finger_a_joint")


def test_robot_methods_delegate_to_their_modules(abb):
    import pinocchio as pin

    from kinengine.analytic import pose_map
    from kinengine.analytic.hessian import analytic_hessian
    from kinengine.control import ik, manipulability
    from kinengine.kinematics import derivatives

    kin, fid = abb.engine, abb.frame_id("tool0")
    q, qdot = abb.random_configuration(12), np.linspace(-0.5, 0.5, 6)
    np.testing.assert_array_equal(
        abb.jacobian_time_variation(q, qdot, "tool0", "local"),
        derivatives.jacobian_time_variation(kin, q, qdot, fid, pin.LOCAL),
    )
    np.testing.assert_array_equal(
        abb.kinematic_hessian(q, "tool0"), derivatives.kinematic_hessian(kin, q, fid, pin.LOCAL_WORLD_ALIGNED)
    )
    np.testing.assert_array_equal(
        abb.analytic_hessian(q, "tool0", rotation="quaternion"),
        analytic_hessian(kin, q, fid, pose_map("cartesian", "quaternion"), 1e-6),
    )
    assert abb.manipulability(q) == manipulability.manipulability(abb, q)
    report = abb.singularity_report(q, "tool0")
    np.testing.assert_array_equal(
        report.singular_values, manipulability.singularity_report(abb, q).singular_values
    )
    np.testing.assert_array_equal(
        abb.velocity_ellipsoid(q).semi_axes, manipulability.velocity_ellipsoid(abb, q).semi_axes
    )
    wrist = abb.neutral()
    with pytest.raises(kinengine.KinematicSingularityError):
        abb.require_regular(wrist, "tool0")
    target = abb.frame_pose(q, "tool0")
    result = abb.inverse_kinematics(target, "tool0", rng=0)
    assert isinstance(result, kinengine.IKResult) and result.success
    assert result.q.tolist() == ik.inverse_kinematics(abb, target, "tool0", rng=0).q.tolist()


def _leader_and_follower(multiplier: float, offset: float, follower_limits: str) -> str:
    return f"""<robot name="gripper"><link name="base"/><link name="a"/><link name="b"/>
  <joint name="elbow" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="follower" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0.2 0 0"/>
    <axis xyz="0 0 1"/><limit {follower_limits} effort="1" velocity="1"/>
    <mimic joint="elbow" multiplier="{multiplier}" offset="{offset}"/></joint></robot>"""


def test_a_mimic_joint_narrows_its_leader_limits():
    robot = kinengine.load_urdf_string(_leader_and_follower(2.0, 0.1, 'lower="-4" upper="4"'))
    # follower = 2·elbow + 0.1 within [-4, 4]  <=>  elbow within [-2.05, 1.95]
    np.testing.assert_allclose(robot.lower_limits, [-2.05])
    np.testing.assert_allclose(robot.upper_limits, [1.95])
    with pytest.raises(
        kinengine.ConfigurationError,
        match=r"joint 'elbow' at 2.0, outside its limits \[-2.05, 1.95\] \(narrowed so that "
        r"mimic joint 'follower' = 2·q \+ 0.1 within \[-4, 4\]\)",
    ):
        robot.frame_pose([2.0], check_limits=True)
    follower = 2.0 * robot.random_configuration(rng=0, size=1000)[:, 0] + 0.1
    assert follower.min() >= -4.0 and follower.max() <= 4.0
    negative = kinengine.load_urdf_string(_leader_and_follower(-0.5, 0.0, 'lower="-0.25" upper="1"'))
    np.testing.assert_allclose([negative.lower_limits[0], negative.upper_limits[0]], [-2.0, 0.5])


def test_mimic_limits_that_no_leader_value_satisfies_are_warned_about_and_not_enforced():
    with pytest.warns(
        UserWarning,
        match="no value of joint 'elbow' keeps it within its limits and mimic joint "
        "'follower' = 1·q \\+ 0 within \\[10, 11\\]; the mimic joint's limits "
        "are not enforced",
    ):
        robot = kinengine.load_urdf_string(_leader_and_follower(1.0, 0.0, 'lower="10" upper="11"'))
    np.testing.assert_allclose([robot.lower_limits[0], robot.upper_limits[0]], [-3.0, 3.0])


@pytest.mark.parametrize("size", [-1, 2.5, "3", True])
def test_random_configuration_refuses_a_bad_size(abb, size):
    with pytest.raises(kinengine.OptionError, match="`size` must be None or a number of configurations >= 0"):
        abb.random_configuration(rng=0, size=size)


def test_neutral_is_zero_clipped_into_the_limits():
    panda = kinengine.load("panda")
    q = panda.neutral()
    panda.check_configuration(q)  # within limits
    joint4 = panda.joint_names.index("panda_joint4")
    assert q[joint4] == panda.upper_limits[joint4] < 0
    assert np.count_nonzero(q) == 1
    np.testing.assert_array_equal(kinengine.load("abb_irb120").neutral(), np.zeros(6))
