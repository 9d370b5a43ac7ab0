"""The vectorized batch path equals Robot's single-configuration path (Pinocchio) row by row.

Every evaluation strategy of kinengine.batch is exercised: the C chain (when built), the numpy chain
(forced even for small N) and the Pinocchio loop used for small batches, on one thread and split over
chunks and threads.
"""

from __future__ import annotations

import os
import resource
import tracemalloc

import numpy as np
import pinocchio as pin
import pytest
from custom_robots import mixed_chain_urdf
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from urdf_strategies import random_urdfs

import kinengine
from kinengine.analytic import evaluate as evaluate_module
from kinengine.kinematics import batch, chain, compiler
from kinengine.reference import ReferenceKinematics

REFERENCES = ("local_world_aligned", "local", "world")
SPECIAL_ANGLES = (0.0, -0.0, np.pi, -np.pi, np.pi / 2, -np.pi / 2, 3 * np.pi, 2 * np.pi, 1e-300, 5e-324)
ROBOTS = ("abb_irb120", "ur5", "panda", "kinova", "baxter")

# Unaligned, negative and unnormalized axes; a continuous joint about an unaligned axis; a mimic
# following a prismatic leader; a frame fixed to the root.
AXES_URDF = """<?xml version="1.0"?>
<robot name="axes">
  <link name="base"/><link name="a"/><link name="b"/><link name="c"/><link name="d"/><link name="e"/>
  <link name="plate"/>
  <joint name="plate_fixed" type="fixed"><parent link="base"/><child link="plate"/>
    <origin xyz="0.1 0.2 0.3" rpy="0.3 0.2 0.1"/></joint>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/>
    <origin xyz="0 0 0.2" rpy="0.2 0 0"/><axis xyz="0 1 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/>
    <origin xyz="0.1 0 0.2"/><axis xyz="0 0 -1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j3" type="continuous"><parent link="b"/><child link="c"/>
    <origin xyz="0 0.3 0" rpy="0 0.5 -0.4"/><axis xyz="-0.3 0.4 0.5"/></joint>
  <joint name="j4" type="prismatic"><parent link="c"/><child link="d"/>
    <origin xyz="0 0 0.1"/><axis xyz="-1 0 0"/>
    <limit lower="-0.2" upper="0.4" effort="1" velocity="1"/></joint>
  <joint name="j5" type="prismatic"><parent link="d"/><child link="e"/>
    <origin xyz="0.05 0 0.1" rpy="1 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
    <mimic joint="j4" multiplier="0.5" offset="-0.1"/></joint>
</robot>
"""

# One coordinate: Pinocchio returns its (6, 1) Jacobian as (6,).
ONE_JOINT_URDF = """<?xml version="1.0"?>
<robot name="one"><link name="base"/><link name="slider"/>
  <joint name="slide" type="prismatic"><parent link="base"/><child link="slider"/>
    <origin xyz="0.1 0 0.2" rpy="0 0.3 0"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>
"""


def _load(name: str) -> kinengine.Robot:
    if name == "mixed_chain":
        return kinengine.load_urdf_string(mixed_chain_urdf())
    if name == "axes":
        return kinengine.load_urdf_string(AXES_URDF)
    if name == "one_joint":
        return kinengine.load_urdf_string(ONE_JOINT_URDF)
    return kinengine.load(name)


@pytest.fixture(scope="module", params=ROBOTS + ("mixed_chain", "axes", "one_joint"))
def robot(request):
    return _load(request.param)


@pytest.fixture(params=["kernel", "numpy", "pinocchio"])
def strategy(request, monkeypatch):
    """Force one evaluation strategy whatever the batch size."""
    if request.param == "kernel" and compiler.KERNEL is None:
        pytest.skip("the C chain is not built here")
    if request.param != "kernel":
        monkeypatch.setattr(compiler, "KERNEL", None)
    monkeypatch.setattr(batch, "KERNEL_FROM", 1 if request.param == "kernel" else 10**9)
    monkeypatch.setattr(batch, "CALLS_PER_CONFIGURATION", 0 if request.param == "pinocchio" else 10**6)
    return request.param


def _frames(robot: kinengine.Robot, rng: np.random.Generator) -> list[str]:
    """The end effector and a seeded sample of other frames (all of them for small robots)."""
    frames = list(robot.frame_names)
    if len(frames) > 12:
        frames = [robot.end_effector] + list(rng.choice(frames, 11, replace=False))
    return frames


def _single(robot, Q, frame, reference):
    return (
        np.array([robot.frame_pose(q, frame) for q in Q]),
        np.array([robot.jacobian(q, frame, reference) for q in Q]),
    )


def test_batch_equals_single_calls_for_every_reference(robot, strategy):
    rng = np.random.default_rng(11)
    Q = robot.random_configuration(rng, size=7)
    for frame in _frames(robot, rng):
        for reference in REFERENCES:
            T_ref, J_ref = _single(robot, Q, frame, reference)
            T, J = robot.kinematics(Q, frame, reference)
            assert T.shape == (7, 4, 4) and J.shape == (7, 6, robot.dof)
            np.testing.assert_allclose(T, T_ref, rtol=0, atol=1e-12, err_msg=f"{frame} pose")
            np.testing.assert_allclose(J, J_ref, rtol=0, atol=1e-12, err_msg=f"{frame} {reference}")
            np.testing.assert_allclose(robot.jacobian(Q, frame, reference), J, rtol=0, atol=1e-12)
        np.testing.assert_allclose(robot.frame_pose(Q, frame), T, rtol=0, atol=1e-12)


def test_chunks_split_over_threads_cover_every_row(monkeypatch):
    robot = _load("baxter")
    monkeypatch.setattr(batch, "CHUNK", 37)
    monkeypatch.setattr(batch, "MIN_PER_WORKER", 50)
    monkeypatch.setattr(batch, "WORKERS", 3)
    monkeypatch.setattr(batch, "CALLS_PER_CONFIGURATION", 10**6)
    Q = robot.random_configuration(4, size=301)
    T_ref, J_ref = _single(robot, Q, robot.end_effector, "local")
    T, J = robot.kinematics(Q, reference="local")
    np.testing.assert_allclose(T, T_ref, rtol=0, atol=1e-12)
    np.testing.assert_allclose(J, J_ref, rtol=0, atol=1e-12)


def test_default_strategy_agrees_across_batch_sizes():
    robot = _load("abb_irb120")
    for n in (1, 50, 200, 9000):
        Q = robot.random_configuration(n, size=n)
        rows = np.random.default_rng(n).choice(n, min(n, 20), replace=False)
        T, J = robot.kinematics(Q, "tool0", "world")
        T_ref, J_ref = _single(robot, Q[rows], "tool0", "world")
        np.testing.assert_allclose(T[rows], T_ref, rtol=0, atol=1e-12)
        np.testing.assert_allclose(J[rows], J_ref, rtol=0, atol=1e-12)


def test_continuous_joint_is_periodic_in_the_batch(strategy):
    robot = _load("kinova")
    Q = robot.random_configuration(2, size=5)
    shifted = Q + np.where(robot.engine.coordinates.continuous, 2 * np.pi, 0.0)
    np.testing.assert_allclose(robot.frame_pose(shifted), robot.frame_pose(Q), rtol=0, atol=1e-12)


def test_single_configuration_and_empty_batch_shapes(strategy):
    robot = _load("panda")
    q = robot.random_configuration(3)
    T, J = robot.kinematics(q, "panda_hand")
    np.testing.assert_allclose(T, robot.frame_pose(q, "panda_hand"), rtol=0, atol=1e-12)
    np.testing.assert_allclose(J, robot.jacobian(q, "panda_hand"), rtol=0, atol=1e-12)
    with pytest.raises(kinengine.ConfigurationError, match="empty batch"):
        robot.kinematics(np.empty((0, robot.dof)))


def test_robot_without_coordinates(strategy):
    robot = kinengine.load_urdf_string(
        '<robot name="fixed"><link name="a"/><link name="b"/><joint name="f" '
        'type="fixed"><parent link="a"/><child link="b"/>'
        '<origin xyz="0.1 0.2 0.3" rpy="0.3 0.2 0.1"/></joint></robot>'
    )
    assert robot.jacobian(np.zeros((4, 0)), "b", "local").shape == (4, 6, 0)
    T = robot.frame_pose(np.zeros((4, 0)), "b")
    T_ref = robot.frame_pose(np.zeros(0), "b")
    np.testing.assert_allclose(T, np.broadcast_to(T_ref, (4, 4, 4)), rtol=0, atol=1e-12)


def test_bad_input_raises_kinengine_errors():
    robot = _load("abb_irb120")
    with pytest.raises(kinengine.ConfigurationError, match=r"\(N, 6\)"):
        robot.frame_pose(np.zeros((3, 5)))
    with pytest.raises(kinengine.ConfigurationError, match="finite"):
        robot.jacobian(np.full((2, 6), np.nan))
    with pytest.raises(kinengine.FrameNotFoundError):
        robot.frame_pose(np.zeros((2, 6)), "tool9")
    with pytest.raises(kinengine.KinematicsError, match="local_world_aligned"):
        robot.jacobian(np.zeros((2, 6)), "tool0", "global")


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(urdf=random_urdfs(max_links=7))
def test_random_trees_match_pinocchio(urdf):
    robot = kinengine.load_urdf_string(urdf)
    Q = robot.random_configuration(0, size=3)
    old = batch.CALLS_PER_CONFIGURATION
    try:
        for calls in (10**6, 0):  # numpy, then Pinocchio (hypothesis forbids function-scoped fixtures)
            batch.CALLS_PER_CONFIGURATION = calls
            for frame in robot.frame_names:
                for reference in REFERENCES:
                    T_ref, J_ref = _single(robot, Q, frame, reference)
                    T, J = robot.kinematics(Q, frame, reference)
                    np.testing.assert_allclose(T, T_ref, rtol=0, atol=1e-12)
                    np.testing.assert_allclose(J, J_ref, rtol=0, atol=1e-12)
    finally:
        batch.CALLS_PER_CONFIGURATION = old


# -- Robot's batched calls (routed through kinengine.batch) --------------------------------------------
ANALYTIC = (
    ("cartesian", "euler_zyz", None),
    ("cylindrical", "quaternion", None),
    ("spherical", "rotation_vector", None),
    ("cartesian", "angle_axis", ("x", "angle", "axis_z")),
    (None, "rotation_matrix", None),
    ("cartesian", "euler_zyx", None),
    ("spherical", None, None),
)
ROUTED = ("abb_irb120", "planar_3dof", "scara", "ur5", "panda", "mixed_chain")


def _regular_rows(robot, n: int, seed: int) -> tuple[np.ndarray, list[tuple]]:
    """n configurations at least 0.05 from the singular sets of the ANALYTIC cases that are regular for
    most configurations of this robot (returned too: e.g. ZYZ angles always lock on the SCARA)."""
    candidates = robot.random_configuration(seed, size=400)

    def regular(q, case):
        try:
            robot.analytic_jacobian(q, position=case[0], rotation=case[1], singularity_threshold=0.05)
        except kinengine.RepresentationSingularityError:
            return False
        return True

    ok = np.array([[regular(q, case) for case in ANALYTIC] for q in candidates])
    keep = ok.mean(axis=0) > 0.5
    rows = candidates[ok[:, keep].all(axis=1)]
    assert len(rows) >= n
    return rows[:n], [case for case, k in zip(ANALYTIC, keep, strict=False) if k]


@pytest.fixture(scope="module", params=ROUTED)
def routed(request):
    robot = _load(request.param) if request.param == "mixed_chain" else kinengine.load(request.param)
    return robot, *_regular_rows(robot, 9, seed=5)


@pytest.mark.parametrize("n", [1, 2, 5, 9])
def test_robot_batches_equal_single_calls(routed, strategy, n):
    robot, Q, cases = routed
    Q = Q[:n]
    assert len(cases) >= 5
    frame = robot.end_effector
    np.testing.assert_allclose(
        robot.frame_pose(Q, frame), [robot.frame_pose(q, frame) for q in Q], rtol=0, atol=1e-12
    )
    for reference in REFERENCES:
        np.testing.assert_allclose(
            robot.jacobian(Q, frame, reference),
            [robot.jacobian(q, frame, reference) for q in Q],
            rtol=0,
            atol=1e-12,
        )
    for position, rotation, rows in cases:
        JA = robot.analytic_jacobian(Q, frame, position, rotation, rows=rows)
        expected = [robot.analytic_jacobian(q, frame, position, rotation, rows=rows) for q in Q]
        assert JA.shape == (n,) + expected[0].shape
        np.testing.assert_allclose(JA, expected, rtol=0, atol=1e-12, err_msg=f"{position} {rotation} {rows}")


@pytest.mark.parametrize("name", ["abb_irb120", "mixed_chain"])
def test_robot_batches_split_over_chunks_and_threads(monkeypatch, name):
    robot = _load(name)
    monkeypatch.setattr(batch, "CHUNK", 37)
    monkeypatch.setattr(batch, "MIN_PER_WORKER", 50)
    monkeypatch.setattr(batch, "WORKERS", 3)
    Q, _ = _regular_rows(robot, 151, seed=6)  # 151 rows: 3 workers x 2 chunks of 25-26 rows
    for n in (25, 151):
        np.testing.assert_allclose(
            robot.frame_pose(Q[:n]), [robot.frame_pose(q) for q in Q[:n]], rtol=0, atol=1e-12
        )
        np.testing.assert_allclose(
            robot.jacobian(Q[:n], reference="local"),
            [robot.jacobian(q, reference="local") for q in Q[:n]],
            rtol=0,
            atol=1e-12,
        )
        for position, rotation, _rows in ANALYTIC[:3]:
            np.testing.assert_allclose(
                robot.analytic_jacobian(Q[:n], position=position, rotation=rotation),
                [robot.analytic_jacobian(q, position=position, rotation=rotation) for q in Q[:n]],
                rtol=0,
                atol=1e-12,
            )


def test_robot_batch_routing_takes_the_fast_path_for_each_size(monkeypatch):
    """Small batches loop (Pinocchio, or the single analytic call per row); large ones use the chain (the C
    chain, where built, from KERNEL_FROM = 2 rows for poses and Jacobians)."""
    robot = kinengine.load("abb_irb120")
    used = []

    def spy(module, name, label):
        original = getattr(module, name)
        monkeypatch.setattr(module, name, lambda *args, **kw: used.append(label) or original(*args, **kw))

    spy(batch, "run_chain", "chain")
    spy(batch, "_pinocchio_loop", "loop")
    spy(evaluate_module, "analytic_single", "analytic row")
    for n in (1, 2, 1000):
        Q = robot.random_configuration(n, size=n)
        robot.frame_pose(Q)
        robot.jacobian(Q)
        robot.analytic_jacobian(Q, rotation="quaternion")
    two = ["chain", "chain"] if compiler.KERNEL is not None else ["loop", "loop"]
    assert used == ["loop", "loop", "analytic row", *two, "analytic row", "analytic row"] + ["chain"] * 3


def test_empty_robot_batch_is_refused():
    robot = kinengine.load("abb_irb120")
    for call in (robot.frame_pose, robot.jacobian, robot.analytic_jacobian):
        with pytest.raises(kinengine.ConfigurationError, match="empty batch"):
            call(np.empty((0, 6)))


@pytest.mark.parametrize("row", [0, 4, 10])
def test_batched_representation_singularity_names_the_row(strategy, row):
    """The batch raises the single call's error (parameterization, distance, alternatives) for its row."""
    robot = kinengine.load("abb_irb120")
    Q, _ = _regular_rows(robot, 11, seed=7)
    other = 10 if row != 10 else 0
    Q[row] = Q[other] = robot.neutral()  # tool0 pitched by π/2: euler_zyx locks
    Q[other, 4] = 1.2e-8  # near, not at, the lock; the first of the two rows is named
    first = min(row, other)
    with pytest.raises(kinengine.RepresentationSingularityError) as single:
        robot.analytic_jacobian(Q[first], rotation="euler_zyx")
    named = f"row {first} of the batch"
    with pytest.raises(kinengine.RepresentationSingularityError, match=named) as batch_error:
        robot.analytic_jacobian(Q, rotation="euler_zyx")
    assert batch_error.value.parameterization == single.value.parameterization == "euler_zyx"
    assert batch_error.value.distance == pytest.approx(single.value.distance, rel=1e-6, abs=1e-15)
    assert batch_error.value.alternatives == single.value.alternatives
    assert str(single.value).split(": ", 1)[1] in str(batch_error.value)


def test_batched_position_singularity_is_checked_before_rotation(strategy):
    """planar_3dof at q = 0 has its tip on the z axis: cylindrical ρ = 0 (the rotation about y is regular)."""
    robot = kinengine.load("planar_3dof")
    Q = robot.random_configuration(8, size=6)
    Q[3] = 0.0
    with (
        pytest.raises(kinengine.RepresentationSingularityError, match="row 3 of the batch") as info,
        pytest.warns(UserWarning, match="ρ = 0"),
    ):
        robot.analytic_jacobian(Q, position="cylindrical", rotation="euler_zyx")
    assert info.value.parameterization == "cylindrical" and info.value.distance < 1e-12
    for q in (Q[3], Q):  # exactly on it E has no finite value: refused even with threshold 0
        with (
            pytest.raises(kinengine.RepresentationSingularityError, match="cylindrical"),
            pytest.warns(UserWarning, match="ρ = 0"),
        ):
            robot.analytic_jacobian(
                q, position="cylindrical", rotation="euler_zyx", singularity_threshold=0.0
            )


@pytest.mark.parametrize("name", ["abb_irb120", "mixed_chain"])
@pytest.mark.parametrize("n", [None, 1, 3, 40, 5000])
def test_kinematics_equals_frame_pose_and_jacobian_bit_for_bit(name, n):
    """robot.kinematics(q) is (frame_pose(q), jacobian(q)) exactly, single q and batches on either path."""
    robot = _load(name)
    frame = robot.end_effector
    Q = robot.random_configuration(11, size=n)
    for reference in REFERENCES:
        T, J = robot.kinematics(Q, frame, reference)
        assert np.array_equal(T, robot.frame_pose(Q, frame)), reference
        assert np.array_equal(J, robot.jacobian(Q, frame, reference)), reference


def test_kinematics_out_and_workers():
    robot = kinengine.load("abb_irb120")
    Q = robot.random_configuration(12, size=9000)
    out = (np.empty((9000, 4, 4)), np.empty((9000, 6, 6)))
    T, J = robot.kinematics(Q, out=out, workers=1)
    assert T is out[0] and J is out[1]
    T2, J2 = robot.kinematics(Q, workers=3)
    assert np.array_equal(T, T2) and np.array_equal(J, J2)
    for bad in (
        (np.empty((9000, 4, 4)),),
        (np.empty((9000, 4, 4)), np.empty((9000, 6, 5))),
        (np.empty((9000, 4, 4), dtype=np.float32), np.empty((9000, 6, 6))),
        [out[0], out[1]],
        (out[0], out[0]),
    ):
        with pytest.raises(kinengine.OptionError):
            robot.kinematics(Q, out=bad)
    for bad in (0, -1, 1.5, True, "2", 10**6):
        with pytest.raises(kinengine.OptionError):
            robot.kinematics(Q, workers=bad)
    with pytest.raises(kinengine.OptionError):
        robot.kinematics(Q[0], out=out)


# -- the throughput machinery: cos/sin from tan(q/2), strided Q, chunk sizes, reused scratch -------------
@settings(max_examples=50, deadline=None)
@given(
    angles=st.lists(
        st.floats(-1e4, 1e4, allow_nan=False) | st.sampled_from(SPECIAL_ANGLES), min_size=1, max_size=40
    )
)
def test_cos_sin_from_the_half_angle_tangent_match_numpy(angles):
    q = np.array(angles)
    cos, sin = chain._cos_sin(q[None], np.empty((4, len(q))))  # q (dof, n): here one coordinate
    np.testing.assert_allclose(cos[0], np.cos(q), rtol=0, atol=4.5e-16)  # 2 ulp of 1
    np.testing.assert_allclose(sin[0], np.sin(q), rtol=0, atol=4.5e-16)


@pytest.mark.parametrize("name", ["panda", "kinova", "ur5"])
def test_large_threaded_batches_match_single_calls_and_the_reference(name):
    """Default strategy (numpy chain, chunks over WORKERS threads): every frame kind, every reference,
    sampled rows against Pinocchio's single calls and the independent reference."""
    robot = kinengine.load(name)
    ref = ReferenceKinematics.from_file(robot.source, joint_names=robot.joint_names)
    Q = robot.random_configuration(21, size=20_000)
    rows = np.random.default_rng(3).choice(len(Q), 15, replace=False)
    frames = [robot.end_effector] + (["panda_leftfinger", "panda_rightfinger"] if name == "panda" else [])
    for frame in frames:
        for reference in REFERENCES:
            T, J = robot.kinematics(Q, frame, reference)
            T_ref, J_ref = _single(robot, Q[rows], frame, reference)
            np.testing.assert_allclose(T[rows], T_ref, rtol=0, atol=1e-14, err_msg=f"{frame}")
            np.testing.assert_allclose(J[rows], J_ref, rtol=0, atol=1e-14, err_msg=f"{frame} {reference}")
            np.testing.assert_allclose(T[rows], ref.frame_pose(Q[rows], frame), rtol=0, atol=1e-12)
            np.testing.assert_allclose(J[rows], ref.jacobian(Q[rows], frame, reference), rtol=0, atol=1e-12)


def test_q_inside_the_out_arrays_gives_the_answer_of_a_copy(strategy):
    """Q may be a view into the memory the outputs are written to (here J's): it is read as it was."""
    robot = _load("abb_irb120")
    n = 300
    Q = robot.random_configuration(9, size=n)
    expected = robot.kinematics(Q, reference="local")
    for target in (0, 1):
        out = (np.empty((n, 4, 4)), np.empty((n, 6, 6)))
        inside = out[target].reshape(-1)[: 6 * n].reshape(n, 6)  # a C-contiguous Q at the outputs' start
        inside[...] = Q
        T, J = robot.kinematics(inside, reference="local", out=out)
        np.testing.assert_allclose(T, expected[0], rtol=0, atol=1e-14)
        np.testing.assert_allclose(J, expected[1], rtol=0, atol=1e-14)


def test_strided_batches_give_the_contiguous_answer_bit_for_bit():
    robot = _load("abb_irb120")
    Q = robot.random_configuration(5, size=9000)
    T, J = robot.kinematics(Q, reference="world")
    for variant in (np.asfortranarray(Q), np.repeat(Q, 2, axis=0)[::2], np.hstack([Q, Q])[:, :6]):
        T2, J2 = robot.kinematics(variant, reference="world")
        assert np.array_equal(T, T2) and np.array_equal(J, J2)


def test_chunks_keep_the_scratch_within_its_share_of_the_output():
    robot = _load("abb_irb120")
    c = batch.compiled_chain(robot.engine, robot.frame_id("tool0"))
    lwa = pin.LOCAL_WORLD_ALIGNED
    per_row = 8 * chain.scratch_rows(c, True, True)  # bytes of scratch per row and thread
    for n in (10_000, 100_000, 1_000_000):
        rows = batch.chunk_rows(c, n, 2, True, True, None, lwa)
        assert batch.MIN_CHUNK <= rows <= batch.CHUNK
        if rows > batch.MIN_CHUNK:
            assert 2 * rows * per_row <= batch.MEMORY_SHARE * n * 8 * (16 + 36)
    assert batch.chunk_rows(c, 10**7, 2, True, True, None, lwa) == batch.CHUNK
    assert len(os.sched_getaffinity(0)) == batch.WORKERS


def test_a_repeated_batch_allocates_no_new_scratch():
    """After one call the threads' scratch is reused: a second call into out= allocates only the chunks'
    short-lived temporaries (a few % of the output) and touches almost no new pages."""
    robot = _load("ur5")
    n = 60_000
    Q = robot.random_configuration(8, size=n)
    out = (np.empty((n, 4, 4)), np.empty((n, 6, 6)))
    robot.kinematics(Q, out=out)
    faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    tracemalloc.start()
    try:
        robot.kinematics(Q, out=out)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert resource.getrusage(resource.RUSAGE_SELF).ru_minflt - faults < 200  # 29 MB of output: 7000 pages
    assert peak < 0.1 * (out[0].nbytes + out[1].nbytes)


ROTATED_URDF = """<?xml version="1.0"?>
<robot name="rotated"><link name="base"/><link name="a"/><link name="b"/><link name="tip"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/>
    <origin xyz="0 0 0.3" rpy="1.5707963267948966 0 -1.5707963267948966"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/>
    <origin xyz="0.2 0 0" rpy="{tilt} 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="f" type="fixed"><parent link="b"/><child link="tip"/><origin xyz="0.1 0 0"/></joint>
</robot>
"""


@pytest.mark.parametrize("tilt", ["3.141592653589793", "1e-9", "1.570796325"])
def test_compiled_constants_drop_rounding_residue_only(tilt):
    """rpy = ±π/2 leaves 6e-17 entries (cos π/2): compiled as exact zeros and ±1; a real 1e-9 rad tilt
    (or a truncated π/2) is kept. Either way batches equal Pinocchio's single calls."""
    robot = kinengine.load_urdf_string(ROTATED_URDF.format(tilt=tilt))
    compiled = batch.compiled_chain(robot.engine, robot.frame_id("tip"))
    entries = [len(column) for column in compiled.steps[0].rotation]
    assert entries == [1, 1, 1]  # the first joint's K: a signed permutation
    assert all(abs(value) == 1.0 for column in compiled.steps[0].rotation for _, value in column)
    tilted = sum(len(column) for column in compiled.steps[1].rotation)
    assert tilted == (3 if tilt == "3.141592653589793" else 5)
    Q = robot.random_configuration(2, size=5000)
    rows = np.arange(0, 5000, 499)
    for reference in REFERENCES:
        T, J = robot.kinematics(Q, "tip", reference)
        T_ref, J_ref = _single(robot, Q[rows], "tip", reference)
        np.testing.assert_allclose(T[rows], T_ref, rtol=0, atol=1e-14)
        np.testing.assert_allclose(J[rows], J_ref, rtol=0, atol=1e-14)


NEAR_AXES_URDF = """<?xml version="1.0"?>
<robot name="near_axes"><link name="base"/><link name="a"/><link name="b"/><link name="c"/><link name="tip"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/>
    <origin xyz="0 0 0.15"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/>
    <origin xyz="0 0.002 -0.12" rpy="-{half} 0 {pi}"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j3" type="revolute"><parent link="b"/><child link="c"/>
    <origin xyz="0 -0.41 0" rpy="0 {pi} 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="f" type="fixed"><parent link="c"/><child link="tip"/>
    <origin xyz="0.1 0 0.2" rpy="{half} 0 {pi}"/></joint>
</robot>
"""


def test_joints_off_axis_by_a_truncated_pi_cost_one_product_each_and_match_pinocchio():
    """π/2 and π written with 11 digits (as in the Kinova's URDF) leave K_i 5e-12 off a signed permutation:
    a real tilt that Pinocchio keeps, so the chain keeps it too, in the one product per joint that also
    moves p (the rotation's entries cost a numpy call each before). Batches equal Pinocchio's single calls
    within 1e-14."""
    exact, truncated = (
        kinengine.load_urdf_string(NEAR_AXES_URDF.format(half=half, pi=pi))
        for half, pi in (("1.5707963267948966", "3.141592653589793"), ("1.57079632679", "3.14159265359"))
    )
    chains = [batch.compiled_chain(r.engine, r.frame_id("tip")) for r in (exact, truncated)]
    products = [[move[0] for move in c.plan.moves[1:]] + [c.plan.matrix] for c in chains]  # j1: folded
    assert all(A is not None for A in products[1])  # j2, j3, tip: K_i and t_i in one product each
    assert chains[1].pose_calls == chains[0].pose_calls  # as many numpy calls as the exact rotations
    tilts = [np.abs(A[:3, :3] - np.round(A[:3, :3])).max() for A in products[1]]
    assert all(1e-13 < tilt < 1e-11 for tilt in tilts)  # the 5e-12 and 2e-13 residues are kept
    Q = exact.random_configuration(4, size=5000)
    rows = np.arange(0, 5000, 499)
    for reference in REFERENCES:
        for robot in (exact, truncated):
            T, J = robot.kinematics(Q, "tip", reference)
            T_ref, J_ref = _single(robot, Q[rows], "tip", reference)
            np.testing.assert_allclose(T[rows], T_ref, rtol=0, atol=1e-14)
            np.testing.assert_allclose(J[rows], J_ref, rtol=0, atol=1e-14)
    assert np.abs(truncated.frame_pose(Q[rows], "tip") - exact.frame_pose(Q[rows], "tip")).max() > 1e-13
    kinova, abb = (_load(name) for name in ("kinova", "abb_irb120"))  # Kinova: 11-digit π/2 and π
    calls = [batch.compiled_chain(r.engine, r.frame_id(r.end_effector)).pose_calls for r in (kinova, abb)]
    assert calls[0] <= calls[1]


def test_work_shared_again_from_a_pool_thread_runs_in_that_thread():
    # closed-form IK shares its post-processing among the pool's threads, and each share's forward
    # kinematics or numeric repair may share again: from a pool thread that must not wait for the pool
    import threading

    from kinengine.kinematics import batch

    calls: list[tuple[int, str, str]] = []

    def inner(a: int, b: int) -> None:
        calls.append((a, threading.current_thread().name, outer_thread[a // 10]))

    outer_thread = ["", ""]

    def outer(a: int, b: int) -> None:
        outer_thread[a] = threading.current_thread().name
        batch.in_shares([(10 * a, 0), (10 * a + 1, 0)], inner, 2)

    worker = threading.Thread(target=batch.in_shares, args=([(0, 1), (1, 2)], outer, 2), daemon=True)
    worker.start()
    worker.join(timeout=30)
    assert not worker.is_alive(), "in_shares waited for itself"
    assert sorted(c[0] for c in calls) == [0, 1, 10, 11]
    pooled = [c for c in calls if c[2].startswith(batch.POOL_PREFIX)]
    assert pooled and all(name == parent for _, name, parent in pooled)  # a pool thread's shares stayed there
