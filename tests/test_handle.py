"""robot.frame(name): the hot-loop handle equals the Robot's own calls bit for bit, checks its input
once (or not at all with check_inputs=False), validates the reference and serves several threads."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import kinengine
from kinengine import ConfigurationError, FrameNotFoundError, OptionError

REFERENCES = ("local_world_aligned", "local", "world")

ONE_DOF = """<robot name="one"><link name="a"/><link name="b"/><link name="c"/>
<joint name="j" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0 0 0.2"/><axis xyz="0 1 0"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
<joint name="f" type="fixed"><parent link="b"/><child link="c"/><origin xyz="0.3 0 0" rpy="0 0.2 0"/></joint>
</robot>"""
ZERO_DOF = """<robot name="zero"><link name="a"/><link name="b"/>
<joint name="f" type="fixed"><parent link="a"/><child link="b"/><origin xyz="0.3 0 0.1" rpy="0.1 0.2 0"/></joint>
</robot>"""


def robots(abb, mixed):
    return [
        (abb, "tool0"),
        (mixed, "finger_b"),
        (mixed, "tip"),
        (kinengine.load_urdf_string(ONE_DOF), "c"),
        (kinengine.load_urdf_string(ZERO_DOF), "b"),
    ]


@pytest.mark.parametrize("check_inputs", [True, False])
def test_handle_equals_robot_calls_bit_for_bit(abb, mixed, check_inputs):
    for robot, frame in robots(abb, mixed):
        fk = robot.frame(frame, check_inputs=check_inputs)
        for q in robot.random_configuration(7, size=5):
            q = np.ascontiguousarray(q)
            assert np.array_equal(fk.pose(q), robot.frame_pose(q, frame))
            for ref in REFERENCES:
                J = fk.jacobian(q, reference=ref)
                assert J.shape == (6, robot.dof)
                assert np.array_equal(J, robot.jacobian(q, frame, ref))
                T, J2 = fk.kinematics(q, reference=ref)
                assert np.array_equal(T, robot.frame_pose(q, frame))
                assert np.array_equal(J2, robot.jacobian(q, frame, ref))


def test_handle_matches_the_independent_reference(abb):
    from kinengine.reference import ReferenceKinematics

    ref = ReferenceKinematics.from_urdf_string(abb.urdf_text)
    fk = abb.frame("tool0")
    for q in abb.random_configuration(3, size=5):
        np.testing.assert_allclose(fk.pose(q), ref.frame_pose(q, "tool0"), atol=1e-12)
        np.testing.assert_allclose(
            fk.jacobian(q, reference="local"), ref.jacobian(q, "tool0", reference="local"), atol=1e-12
        )


def test_default_frame_and_pinocchio_enum(abb):
    fk = abb.frame()
    assert fk.name == abb.end_effector and fk.frame_id == abb.frame_id(abb.end_effector)
    q = abb.random_configuration(1)
    assert np.array_equal(fk.jacobian(q, pin.LOCAL), abb.jacobian(q, reference="local"))
    assert "check_inputs=True" in repr(fk)


def test_checked_handle_refuses_bad_input(abb):
    fk = abb.frame("tool0")
    q = abb.neutral()
    for bad in (np.full(6, np.nan), np.r_[q[:5], np.inf], np.zeros(5), np.zeros((2, 6)), "abc", None):
        for call in (fk.pose, fk.jacobian, fk.kinematics):
            with pytest.raises(ConfigurationError):
                call(bad)
    # converted like everywhere else: lists, ints, strided and float32 input
    assert np.array_equal(fk.pose([0, 0, 0, 0, 0, 0]), abb.frame_pose(q))
    assert np.array_equal(fk.pose(np.zeros(12)[::2]), abb.frame_pose(q))
    assert np.allclose(fk.pose(np.zeros(6, dtype=np.float32)), abb.frame_pose(q))


def test_references_and_options_are_validated(abb):
    fk = abb.frame("tool0")
    for bad in (True, 1.0, np.int64(2), "LOCAL", None):
        with pytest.raises(OptionError):
            fk.jacobian(abb.neutral(), reference=bad)
        with pytest.raises(OptionError):
            fk.kinematics(abb.neutral(), reference=bad)
    with pytest.raises(FrameNotFoundError):
        abb.frame("tool1")
    with pytest.raises(OptionError):
        abb.frame("tool0", check_inputs="no")


def test_unchecked_handle_trusts_the_caller(abb):
    fk = abb.frame("tool0", check_inputs=False)
    q = abb.random_configuration(4)
    assert np.array_equal(fk.pose(q), abb.frame_pose(q))
    assert not fk.check_inputs


def test_mimic_buffer_is_per_call_and_per_thread(mixed):
    """The q_pin scratch buffer never leaks into results: two threads, different q, each right."""
    fk = mixed.frame("finger_b")
    Q = mixed.random_configuration(5, size=200)
    expected = [mixed.kinematics(q, "finger_b") for q in Q]

    def work(offset):
        return [fk.kinematics(Q[(i + offset) % len(Q)]) for i in range(len(Q))]

    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(work, range(4)))
    for offset, result in enumerate(results):
        for i, (T, J) in enumerate(result):
            T0, J0 = expected[(i + offset) % len(Q)]
            assert np.array_equal(T, T0) and np.array_equal(J, J0)


def _full_model_answer(robot, frame, q):
    """Pinocchio's full model (every movable joint) at q_pin = M q + b, J folded by M: the plain definition."""
    model = robot.pinocchio_model()
    data = model.createData()
    fid = robot.frame_id(frame)
    qp = robot.pinocchio_configuration(q)
    pin.forwardKinematics(model, data, qp)
    T = pin.updateFramePlacement(model, data, fid).homogeneous
    M = robot.engine.coordinates.matrix
    Js = {r: pin.computeFrameJacobian(model, data, qp, fid, p).reshape(6, -1) @ M for r, p in PIN.items()}
    return T, Js


PIN = {"local_world_aligned": pin.LOCAL_WORLD_ALIGNED, "local": pin.LOCAL, "world": pin.WORLD}


@pytest.mark.parametrize("robot_name", ["panda", "mixed"])
def test_frames_of_mimic_robots_on_the_locked_model_equal_the_full_model(robot_name, request):
    """A frame that no mimic joint moves is computed on Pinocchio's reduced model (mimic joints locked, q
    untouched); a frame a mimic joint moves on a model of its own joints (when they are q one for one) or
    through the map. Every one equals the full model at q_pin = M q + b."""
    robot = kinengine.load("panda") if robot_name == "panda" else request.getfixturevalue("mixed")
    kin = robot.engine
    mapped = {name: kin.frame_path(kin.frame_id(name)).mapped for name in robot.frame_names}
    if robot_name == "panda":  # the right finger's own joints (arm + mimicking finger) are q one for one
        assert not any(mapped.values())
        models = {name: kin.frame_path(kin.frame_id(name)).model.nq for name in robot.frame_names}
        assert models["panda_hand"] == models["panda_rightfinger"] == robot.dof < robot.pinocchio_model().nq
    else:
        assert any(mapped.values()) and not all(mapped.values())
    for q in robot.random_configuration(11, size=5):
        for name in robot.frame_names:
            fk = robot.frame(name, check_inputs=False)
            T, Js = _full_model_answer(robot, name, q)
            np.testing.assert_allclose(fk.pose(q), T, rtol=0, atol=1e-14)
            for ref, J in Js.items():
                np.testing.assert_allclose(
                    fk.jacobian(q, ref), J, rtol=0, atol=1e-14, err_msg=f"{name} {ref}"
                )
                T2, J2 = fk.kinematics(q, ref)
                assert np.array_equal(T2, fk.pose(q)) and np.array_equal(J2, fk.jacobian(q, ref))
            R, p = fk.placement()
            np.testing.assert_array_equal(R, fk.pose(q)[:3, :3])
            np.testing.assert_array_equal(p, fk.pose(q)[:3, 3])
            assert not R.flags.writeable


def test_ready_is_exactly_the_inputs_check_returns_unchanged(abb):
    """ready(q) (the one check's fast path) holds for C-contiguous float64 (6,) arrays with every |q_i| <=
    1e9 and for nothing else; check() returns a ready q itself and refuses a NaN, an inf, or entries that
    only cancel in a sum (+1e300, -1e300)."""
    coords = abb.engine.coordinates
    q = abb.random_configuration(3)
    readonly = q.copy()
    readonly.flags.writeable = False
    for x in (q, readonly, np.zeros(6), np.full(6, 1e9 / np.sqrt(6) * 0.999)):
        assert coords.ready(x) and coords.check(x) is x
    not_ready = {
        "strided": np.repeat(q, 2)[::2],
        "reversed": q[::-1],
        "column": q.reshape(6, 1),
        "row": q.reshape(1, 6),
        "float32": q.astype(np.float32),
        "big_endian": q.astype(">f8"),
        "int64": np.arange(6),
        "long": np.r_[q, 0.0],
        "short": q[:5].copy(),
        "list": q.tolist(),
        "masked": np.ma.masked_array(q, mask=[0, 0, 0, 0, 0, 1]),
        "0d": np.array(1.0),
    }
    for name, x in not_ready.items():
        assert not coords.ready(x), name
    for bad in (
        [1e300, -1e300, 0, 0, 0, 0],
        [np.nan, 0, 0, 0, 0, 0],
        [0, 0, np.inf, 0, 0, 0],
        [2e9, 0, 0, 0, 0, 0],
    ):
        x = np.array(bad, dtype=float)
        assert not coords.ready(x)
        with pytest.raises(ConfigurationError, match=r"`q`\[\d\]"):
            abb.frame_pose(x)
        with pytest.raises(ConfigurationError):
            abb.frame("tool0").jacobian(x)
    with pytest.raises(ConfigurationError):  # the same hole in a batch (a large one: max/min, not a sum)
        abb.frame_pose(np.tile([1e300, -1e300, 0, 0, 0, 0.0], (100, 1)))
    with pytest.raises(ConfigurationError):
        abb.frame_pose(np.array([[1e300, -1e300, 0, 0, 0, 0.0]]))


@settings(max_examples=300, deadline=None)
@given(
    st.lists(
        st.floats(allow_nan=True, allow_infinity=True, width=64)
        | st.sampled_from([1e300, -1e300, 1e9, -1e9]),
        min_size=6,
        max_size=6,
    )
)
def test_ready_never_passes_an_entry_the_check_refuses(values):
    coords = _ABB.engine.coordinates
    x = np.array(values, dtype=float)
    entries_ok = bool(np.all(np.isfinite(x)) and np.all(np.abs(x) <= 1e9))
    if coords.ready(x):
        assert entries_ok and coords.check(x) is x
    if entries_ok and np.all(np.abs(x) <= 1e9 / np.sqrt(6)):
        assert coords.ready(x)
    if not entries_ok:
        with pytest.raises(ConfigurationError):
            coords.check(x)


_ABB = kinengine.load("abb_irb120")


def test_a_reference_resolves_alike_on_every_path(abb):
    """The handle's lookup and resolve_reference (check_limits, the kinematic Hessian) take and refuse the same
    references; the values are Pinocchio's own LOCAL Jacobian."""
    q = abb.random_configuration(5)
    model = abb.pinocchio_model()
    expected = pin.computeFrameJacobian(model, model.createData(), q, abb.frame_id("tool0"), pin.LOCAL)
    fk = abb.frame("tool0")
    for reference in ("local", np.str_("local"), pin.LOCAL):
        assert np.array_equal(fk.jacobian(q, reference), expected)
        assert np.array_equal(abb.jacobian(q, "tool0", reference, check_limits=True), expected)
        assert abb.kinematic_hessian(q, "tool0", reference).shape == (6, 6, 6)
    for bad in (True, 1.0, np.int64(2), "LOCAL", b"local", ["local"]):
        with pytest.raises(OptionError):
            fk.jacobian(q, bad)
        with pytest.raises(OptionError):
            abb.jacobian(q, "tool0", bad, check_limits=True)
