"""The C batch chain (kinengine/kinematics/chainkernel.c) against the numpy chain and Pinocchio.

Every frame (a seeded sample of 12 on big robots) and reference of the shipped robots and the test URDFs
on random, special and large angles; its sin and cos against numpy's; any strides of inputs and outputs;
the errors it raises; threads; the routing of robot.kinematics; KINENGINE_PURE_PYTHON. Skipped where the
C chain is not built.
"""

from __future__ import annotations

import itertools
import os
import subprocess
import sys
import threading

import numpy as np
import pinocchio as pin
import pytest
from custom_robots import mixed_chain_urdf
from hypothesis import given, settings
from hypothesis import strategies as st
from test_batch import AXES_URDF, ONE_JOINT_URDF, ROBOTS, SPECIAL_ANGLES

import kinengine
from kinengine.kinematics import batch, compiler
from kinengine.kinematics.chain import Outputs, evaluate_chain

if compiler.KERNEL is None:
    pytest.skip("the C chain is not built (or KINENGINE_PURE_PYTHON is set)", allow_module_level=True)
Kernel = compiler.KERNEL

REFERENCES = {pin.LOCAL_WORLD_ALIGNED: "local_world_aligned", pin.WORLD: "world", pin.LOCAL: "local"}
# Up to 1e5 rad the kernel reduces the angle itself (vectorized fdlibm); beyond, libm's sin and cos.
LARGE = (1e4, -1e4, 1e5, -1e5, np.nextafter(1e5, 2e5), np.nextafter(1e5, 0), 1e5 + 1e-6, 123456.789)
LARGE += (1e6, -1e6, 3e7 + 0.25, 1e9, -1e9, np.nextafter(1e9, 0))
IDENTITY = [*np.eye(3).ravel(), 0.0, 0.0, 0.0]  # K = I, t = 0 (or R_f = I, t_f = 0)
ONE_ANGLE = np.array([1, 0, 0, 1, 0, 0, *IDENTITY, *IDENTITY], float).tobytes()  # Rz(q) on coordinate 0


def _load(name: str) -> kinengine.Robot:
    urdf = {"mixed_chain": mixed_chain_urdf, "axes": lambda: AXES_URDF, "one_joint": lambda: ONE_JOINT_URDF}
    return kinengine.load_urdf_string(urdf[name]()) if name in urdf else kinengine.load(name)


def _chain(robot: kinengine.Robot, frame: str):
    return compiler.compiled_chain(robot.engine, robot.frame_id(frame))


def _run(kernel, Q: np.ndarray, dof: int, code: int) -> tuple[np.ndarray, np.ndarray]:
    """The kernel's (T, J) for Q, into NaN-filled outputs (so every entry must be written)."""
    T, J = np.full((len(Q), 4, 4), np.nan), np.full((len(Q), 6, dof), np.nan)
    kernel.run(Q, T, J, code)
    return T, J


def _same(got: tuple, expected: tuple) -> bool:
    """Every array of ``got`` equals its counterpart bit for bit."""
    return all(np.array_equal(a, b) for a, b in zip(got, expected, strict=True))


def _configurations(robot: kinengine.Robot, rng: np.random.Generator) -> np.ndarray:
    """200 random rows; every coordinate at each special angle; special angles mixed; large angles on
    the continuous joints."""
    special = np.array(SPECIAL_ANGLES)
    mixed = rng.choice(special, (40, robot.dof))
    large = robot.random_configuration(rng, size=len(LARGE))
    large[:, robot.engine.coordinates.continuous] = np.array(LARGE)[:, None]
    rows = [
        robot.random_configuration(rng, size=200),
        np.repeat(special[:, None], robot.dof, 1),
        mixed,
        large,
    ]
    return np.vstack(rows)


@pytest.mark.filterwarnings("ignore::UserWarning")  # AXES_URDF's unnormalized axes
@pytest.mark.parametrize("name", ROBOTS + ("mixed_chain", "axes", "one_joint"))
def test_kernel_equals_numpy_chain_and_pinocchio(name):
    """To 1e-14 on every frame and reference, huge angles included: both sides reduce angles exactly (libm,
    numpy and the kernel are within 1 ulp of sin and cos for any |q| <= 1e9, kinengine's limit), so no
    error grows with |q| (measured: 1.6e-15 against numpy, 1.3e-15 against Pinocchio)."""
    robot, rng = _load(name), np.random.default_rng(7)
    Q = _configurations(robot, rng)
    frames = list(robot.frame_names)
    if len(frames) > 12:
        frames = [robot.end_effector, *rng.choice(frames, 11, replace=False)]
    for frame in frames:
        chain = _chain(robot, frame)
        T_pin = np.array([robot.frame_pose(q, frame) for q in Q])
        for reference, label in REFERENCES.items():
            T, J = _run(chain.kernel, Q, robot.dof, compiler.REFERENCE_CODES[reference])
            T_np, J_np = np.empty_like(T), np.empty_like(J)
            evaluate_chain(chain, Q.T, Outputs(T_np, J_np, reference))
            J_pin = np.array([robot.jacobian(q, frame, label) for q in Q]).reshape(J.shape)
            message = f"{name} {frame} {label}"
            np.testing.assert_allclose(T, T_np, rtol=0, atol=1e-14, err_msg=message)
            np.testing.assert_allclose(J, J_np, rtol=0, atol=1e-14, err_msg=message)
            np.testing.assert_allclose(T, T_pin, rtol=0, atol=1e-14, err_msg=message)
            np.testing.assert_allclose(J, J_pin, rtol=0, atol=1e-14, err_msg=message)


# -- sin and cos ------------------------------------------------------------------------------------
def _check_sin_cos(q: np.ndarray) -> None:
    """Rz(q) from the one-angle kernel: cos and sin within 2.3e-16 of numpy's (measured 1.1e-16)."""
    T = np.full((len(q), 4, 4), np.nan)
    Kernel(1, ONE_ANGLE).run(q.reshape(-1, 1), T, None, 0)
    np.testing.assert_allclose(T[:, 0, 0], np.cos(q), rtol=0, atol=2.3e-16)
    np.testing.assert_allclose(T[:, 1, 0], np.sin(q), rtol=0, atol=2.3e-16)
    assert np.array_equal(T[:, 0, 1], -T[:, 1, 0]) and np.array_equal(T[:, 1, 1], T[:, 0, 0])
    rest = T.copy()
    rest[:, :2, :2] = np.eye(2)
    assert np.array_equal(rest, np.broadcast_to(np.eye(4), T.shape))


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-1e9, 1e9), min_size=1, max_size=150))
def test_sin_cos_of_any_angle(angles):
    _check_sin_cos(np.array(angles))


@settings(max_examples=30, deadline=None)
@given(st.integers(-60000, 60000), st.integers(1, 3000))
def test_sin_cos_of_multiples_of_half_pi(start, count):
    _check_sin_cos(np.arange(start, start + count) * (np.pi / 2))


def test_sin_cos_over_decades_and_at_the_switch_to_libm():
    rng = np.random.default_rng(3)
    for size in (1.0, 10.0, 1e3, 1e5, 1e7, 1e9):
        _check_sin_cos(rng.uniform(-size, size, 200_000))
    edges = [np.nextafter(1e5, 0), 1e5, np.nextafter(1e5, 2e5), 2**20 * np.pi / 2, np.pi / 4, 0.0, -0.0]
    _check_sin_cos(np.array([*edges, *np.negative(edges), *SPECIAL_ANGLES, 5e-324, 1e-300]))
    _check_sin_cos(np.arange(-60000, 60001) * (np.pi / 2))


def test_nan_and_infinite_angles_give_nan():
    T = np.zeros((3, 4, 4))
    Kernel(1, ONE_ANGLE).run(np.array([[np.nan], [np.inf], [-np.inf]]), T, None, 0)
    assert np.isnan(T[:, :3, :3]).all()  # 0 x NaN reaches every product with the rotation
    assert np.array_equal(T[:, 3], np.broadcast_to([0.0, 0.0, 0.0, 1.0], (3, 4)))


# -- layout -----------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def axes():
    with pytest.warns(UserWarning):
        robot = _load("axes")
    return robot, robot.random_configuration(5, size=101)


@pytest.mark.parametrize("code", [0, 1, 2])
def test_strided_inputs_and_outputs_equal_contiguous_bit_for_bit(axes, code):
    robot, Q = axes
    n, dof, kernel = len(Q), robot.dof, _chain(robot, robot.end_effector).kernel
    T, J = _run(kernel, Q, dof, code)
    wide = np.zeros((2 * n, dof + 3))
    wide[::2, 2 : 2 + dof] = Q
    for view in (np.asfortranarray(Q), wide[::2, 2 : 2 + dof], wide[::2].copy()[:, 2 : 2 + dof]):
        assert _same(_run(kernel, view, dof, code), (T, J))
    assert _same([a[::-1] for a in _run(kernel, Q[::-1], dof, code)], (T, J))
    T2, J2 = _run(kernel, np.broadcast_to(Q[3], Q.shape), dof, code)  # zero stride
    assert _same((T2, J2), (np.broadcast_to(T[3], T.shape), np.broadcast_to(J[3], J.shape)))
    T_buffer, J_buffer = np.full((4, 4, n), np.nan), np.full((6, dof, n), np.nan)  # as the IK batch
    kernel.run(Q, T_buffer.transpose(2, 0, 1), J_buffer.transpose(2, 0, 1), code)
    assert _same((T_buffer.transpose(2, 0, 1), J_buffer.transpose(2, 0, 1)), (T, J))
    T_every, J_every = np.full((2 * n, 4, 4), 7.0), np.full((n, 6, dof, 2), 7.0)
    kernel.run(Q, T_every[::-2], J_every[..., 1], code)
    assert _same((T_every[::-2], J_every[..., 1]), (T, J))
    assert (T_every[::2] == 7.0).all() and (J_every[..., 0] == 7.0).all()  # nothing written in between
    T_only, J_only = np.full_like(T, np.nan), np.full_like(J, np.nan)
    kernel.run(Q, T_only, None, code)
    kernel.run(Q, None, J_only, code)
    assert _same((T_only, J_only), (T, J))
    kernel.run(Q[:0], np.empty((0, 4, 4)), np.empty((0, 6, dof)), code)
    kernel.run(Q, None, None, code)


@pytest.mark.parametrize("code", [0, 1, 2])
def test_outputs_stored_past_the_caches_equal_small_calls_bit_for_bit(code):
    """One run() with 4 MiB of outputs or more stores them past the caches (non-temporal stores on x86-64):
    the same values, bit for bit, as calls small enough to store plainly, for T and J together or alone;
    also with rows 8 bytes off the 16-byte alignment those stores need (stored plainly then)."""
    robot = kinengine.load("ur5")
    Q, kernel = robot.random_configuration(11, size=12_000), _chain(robot, robot.end_effector).kernel
    assert len(Q) * (16 + 6 * robot.dof) * 8 >= 4 << 20
    T, J = _run(kernel, Q, robot.dof, code)
    T_small, J_small = np.full_like(T, np.nan), np.full_like(J, np.nan)
    for a in range(0, len(Q), 500):
        kernel.run(Q[a : a + 500], T_small[a : a + 500], J_small[a : a + 500], code)
    assert _same((T, J), (T_small, J_small))
    for offset in (1, 2):  # 8 bytes off 16-byte alignment, and aligned
        flat_T, flat_J = np.full(T.size + offset, np.nan), np.full(J.size + offset, np.nan)
        T_off, J_off = flat_T[offset:].reshape(T.shape), flat_J[offset:].reshape(J.shape)
        kernel.run(Q, T_off, J_off, code)
        assert _same((T_off, J_off), (T, J))
    n = 33_000  # T alone and J alone past 4 MiB in one run() too
    Q_big = robot.random_configuration(12, size=n)
    T_only, J_only = np.full((n, 4, 4), np.nan), np.full((n, 6, robot.dof), np.nan)
    kernel.run(Q_big, T_only, None, code)
    kernel.run(Q_big, None, J_only, code)
    T_small, J_small = np.full_like(T_only, np.nan), np.full_like(J_only, np.nan)
    for a in range(0, n, 1000):
        kernel.run(Q_big[a : a + 1000], T_small[a : a + 1000], J_small[a : a + 1000], code)
    assert _same((T_only, J_only), (T_small, J_small))
    label = {0: "local_world_aligned", 1: "world", 2: "local"}[code]
    J_pin = np.array([robot.jacobian(q, robot.end_effector, label) for q in Q[::997]])
    np.testing.assert_allclose(J[::997], J_pin, rtol=0, atol=1e-14)


def test_frame_fixed_to_the_root_and_zero_dof(axes):
    robot, Q = axes
    chain = _chain(robot, "plate")
    assert chain.steps == ()
    T, J = _run(chain.kernel, Q, robot.dof, 1)
    assert np.array_equal(T, np.broadcast_to(robot.frame_pose(Q[0], "plate"), T.shape))
    assert np.array_equal(J, np.zeros_like(J))
    kernel = Kernel(0, np.array([0, *IDENTITY[:9], 0.1, -0.2, 0.3]).tobytes())
    T, J = _run(kernel, np.empty((4, 0)), 0, 2)
    expected = np.eye(4)
    expected[:3, 3] = 0.1, -0.2, 0.3
    assert J.shape == (4, 6, 0) and np.array_equal(T, np.broadcast_to(expected, T.shape))


# -- errors -----------------------------------------------------------------------------------------
STEP = [0, 0, 1, 0, 0, *IDENTITY]


BAD_PROGRAMS = [(1, [1, *STEP, *IDENTITY][:-1]), (1, [2, *STEP, *IDENTITY]), (1, [1.5, *STEP, *IDENTITY])]
BAD_PROGRAMS += [(1, [np.nan, *STEP, *IDENTITY]), (1, [-1, *IDENTITY]), (1, []), (-1, [0, *IDENTITY])]
BAD_PROGRAMS += [(1, [1, 0, c, *STEP[2:], *IDENTITY]) for c in (0.5, 1, -1, np.nan, np.inf)]  # coordinate


@pytest.mark.parametrize("dof, values", BAD_PROGRAMS)
def test_bad_programs_are_refused(dof, values):
    with pytest.raises(ValueError, match="Kernel"):
        Kernel(dof, np.array(values, float).tobytes())
    with pytest.raises(ValueError, match="Kernel"):
        Kernel(dof, np.array(values, float).tobytes() + b"\0")  # not a whole number of float64


def test_step_count_that_overflows_the_length_check_is_refused():
    """17 × the step count would wrap around 2^64 to the program's length: bounded before it is multiplied."""
    values = np.zeros(1 + 4096 + 12)
    values[0] = 1085102592571150336.0  # 17 x this = 2^64 + 4096: 4096 modulo 2^64
    with pytest.raises(ValueError, match="Kernel"):
        Kernel(1, values.tobytes())


def test_bad_run_arguments_are_refused():
    kernel = Kernel(1, ONE_ANGLE)
    Q, T, J = np.zeros((3, 1)), np.zeros((3, 4, 4)), np.zeros((3, 6, 1))
    read_only = [T.copy(), J.copy()]
    for array in read_only:
        array.flags.writeable = False
    bad = [
        ((np.zeros((3, 2)), T, J, 0), ValueError),
        ((Q[:, 0], T, J, 0), ValueError),
        ((Q, np.zeros((3, 4, 3)), J, 0), ValueError),
        ((Q, np.zeros((2, 4, 4)), J, 0), ValueError),
        ((Q, T, np.zeros((3, 6, 2)), 0), ValueError),
        ((Q, T, np.zeros((3, 3, 1)), 0), ValueError),
        ((Q.astype(np.float32), T, J, 0), ValueError),
        ((Q.astype(int), T, J, 0), ValueError),
        ((Q.astype(">f8"), T, J, 0), ValueError),
        ((Q, T.astype(np.float32), J, 0), ValueError),
        ((Q, read_only[0], J, 0), ValueError),  # numpy: "buffer source array is read-only"
        ((Q, T, read_only[1], 0), ValueError),
        ((Q, T, J, 3), ValueError),
        ((Q, T, J, -1), ValueError),
        (([[0.0]] * 3, T, J, 0), TypeError),
        ((Q, T, J, None), TypeError),
        ((Q, T, J), TypeError),
    ]
    for arguments, error in bad:
        with pytest.raises(error):
            kernel.run(*arguments)
    assert not T.any() and not J.any()  # refused before anything is written
    kernel.run(Q, T, J, 0)  # still works
    assert np.array_equal(T[:, 0, 0], np.ones(3))


# -- threads and routing ----------------------------------------------------------------------------
def test_threads_on_disjoint_slices_equal_one_thread_bit_for_bit():
    robot = _load("panda")
    Q = robot.random_configuration(9, size=4001)
    kernel = _chain(robot, robot.end_effector).kernel
    T, J = _run(kernel, Q, robot.dof, 2)
    T4, J4 = np.full_like(T, np.nan), np.full_like(J, np.nan)
    bounds, barrier = (0, 997, 2003, 3001, 4001), threading.Barrier(4)

    def work(a: int, b: int) -> None:
        barrier.wait()
        for _ in range(5):
            kernel.run(Q[a:b], T4[a:b], J4[a:b], 2)

    threads = [threading.Thread(target=work, args=ab) for ab in itertools.pairwise(bounds)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert _same((T4, J4), (T, J))


class _Spy:
    """Stands in for a chain's kernel: records the rows of each run and passes the call on."""

    def __init__(self, kernel) -> None:
        self.kernel, self.rows = kernel, []

    def run(self, Q, T, J, code) -> None:
        self.rows.append(len(Q))
        self.kernel.run(Q, T, J, code)


def test_kinematics_routes_to_the_kernel_and_equals_numpy(monkeypatch):
    robot = _load("mixed_chain")
    chain = _chain(robot, robot.end_effector)
    spy = _Spy(chain.kernel)
    monkeypatch.setattr(chain, "kernel", spy)
    monkeypatch.setattr(batch, "KERNEL_MIN_PER_WORKER", 100)
    Q = robot.random_configuration(4, size=1001)
    T1, J1 = robot.kinematics(Q, reference="world", workers=1)
    assert spy.rows == [1001]
    monkeypatch.setattr(batch, "WORKERS", 3)
    T3, J3 = robot.kinematics(Q, reference="world")
    assert sorted(spy.rows[1:]) == [333, 334, 334]
    assert _same((T3, J3), (T1, J1))
    spy.rows.clear()
    robot.kinematics(Q[:1])  # one row: Pinocchio's loop
    robot.kinematics(Q[: batch.KERNEL_FROM])
    robot.analytic_jacobian(Q[:50], rotation="quaternion")  # analytic Jacobians stay on numpy
    assert spy.rows == [batch.KERNEL_FROM]
    monkeypatch.setattr(compiler, "KERNEL", None)
    T_np, J_np = robot.kinematics(Q, reference="world")
    assert spy.rows == [batch.KERNEL_FROM]
    np.testing.assert_allclose(T_np, T1, rtol=0, atol=1e-14)
    np.testing.assert_allclose(J_np, J1, rtol=0, atol=1e-14)


def test_pure_python_switch_turns_the_kernel_off():
    code = (
        "import numpy as np, kinengine\n"
        "from kinengine.kinematics import compiler\n"
        "print(compiler.KERNEL)\n"
        "r = kinengine.load('abb_irb120')\n"
        "Q = r.random_configuration(1, size=64)\n"
        "T, J = r.kinematics(Q, reference='local')\n"
        "T_ref = [r.frame_pose(q) for q in Q]\n"
        "J_ref = [r.jacobian(q, reference='local') for q in Q]\n"
        "print(max(np.abs(T - T_ref).max(), np.abs(J - J_ref).max()))\n"
    )
    env = {**os.environ, "KINENGINE_PURE_PYTHON": "1"}
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    kernel, error = done.stdout.split()
    assert kernel == "None" and float(error) <= 1e-14


@pytest.mark.parametrize("offset", [1, 3, 4, 7])
def test_unaligned_batches_and_outputs_equal_pure_python(monkeypatch, offset):
    """A C-contiguous float64 Q (and out=) at an odd byte offset (np.frombuffer) runs on the C chain through an
    aligned copy: bit for bit the C chain's T and J of the aligned Q, and the numpy chain's to rounding."""
    robot = kinengine.load("ur5")
    Q = robot.random_configuration(11, 300)
    unaligned = np.frombuffer(bytearray(offset + Q.nbytes), np.float64, count=Q.size, offset=offset)
    unaligned = unaligned.reshape(Q.shape)
    unaligned[...] = Q
    assert not unaligned.flags.aligned and unaligned.flags.c_contiguous
    outputs = tuple(
        np.frombuffer(bytearray(offset + 8 * int(np.prod(shape))), np.float64, offset=offset).reshape(shape)
        for shape in ((len(Q), 4, 4), (len(Q), 6, robot.dof))
    )
    spy = _Spy(_chain(robot, robot.end_effector).kernel)
    monkeypatch.setattr(_chain(robot, robot.end_effector), "kernel", spy)
    expected = robot.kinematics(Q)
    assert _same(robot.kinematics(unaligned), expected)
    robot.kinematics(unaligned, out=outputs)
    assert _same(outputs, expected) and sum(spy.rows) == 3 * len(Q)  # all three on the C chain
    monkeypatch.setattr(compiler, "KERNEL", None)  # the numpy chain
    for got, numpy_chain in zip(outputs, robot.kinematics(unaligned), strict=True):
        np.testing.assert_allclose(got, numpy_chain, rtol=0, atol=1e-14)


def test_kernel_sin_cos_agree_with_libm_and_a_wrong_one_is_refused_with_one_warning(monkeypatch):
    """The import-time check: the built kernel's sin/cos are within SIN_COS_TOLERANCE of math.sin/math.cos; a
    kernel whose sin/cos are off (as -ffast-math made them) is not used, with one RuntimeWarning."""
    from kinengine.kinematics import chainkernel

    assert compiler.sin_cos_error(chainkernel.sin_check) <= compiler.SIN_COS_TOLERANCE

    right = chainkernel.sin_check

    def off(angles: bytes) -> bytes:
        values = np.frombuffer(right(angles)).copy()
        values[7] += 0.707
        return values.tobytes()

    monkeypatch.setattr(chainkernel, "sin_check", off)
    with pytest.warns(RuntimeWarning, match="fast-math") as caught:
        kernel, why = compiler._kernel_type()
    assert kernel is None and "sin/cos differ" in str(why)
    assert len(caught) == 1
