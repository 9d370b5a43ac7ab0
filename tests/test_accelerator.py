"""The optional C accelerator (kinengine/model/fastcall.c): built where a C compiler is, equal bit for bit to
the pure-Python path it replaces (results, refusals and messages), per-thread Data kept apart, and the whole
pure-Python path still tested (a subprocess with KINENGINE_PURE_PYTHON=1)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
import threading
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import kinengine
from kinengine.model import accelerator, coordinates

REFERENCES = ("local_world_aligned", "local", "world")
PURE = os.environ.get("KINENGINE_PURE_PYTHON", "") not in ("", "0")
needs_native = pytest.mark.skipif(not accelerator.AVAILABLE, reason="the C accelerator is not built here")


def _pure(monkeypatch: pytest.MonkeyPatch, make):
    """What ``make()`` builds with the accelerator switched off."""
    with monkeypatch.context() as m:
        m.setattr(accelerator, "native", None)
        return make()


def test_the_accelerator_is_built_where_a_compiler_is():
    """`pip install` builds the optional extension when a C compiler and Python's headers are present:
    then it must load, with numpy's C API (a silent fallback would hide a slow hot path)."""
    headers = Path(sysconfig.get_paths()["include"], "Python.h").exists()
    if PURE or not headers or shutil.which(os.environ.get("CC", "cc")) is None:
        pytest.skip("no C toolchain (or KINENGINE_PURE_PYTHON set): kinengine runs in pure Python")
    assert accelerator.AVAILABLE, "kinengine.model.fastcall is missing or failed to import numpy's C API"


@needs_native
def test_the_robot_handles_run_in_c(abb):
    fk = abb.frame("tool0")
    assert type(fk.pose).__name__ == "builtin_function_or_method"
    assert type(abb.engine.coordinates.ready).__name__ == "builtin_function_or_method"


def _inputs(q: np.ndarray) -> dict[str, object]:
    """Every kind of q the check distinguishes, for a (6,) configuration q."""
    readonly = q.copy()
    readonly.flags.writeable = False
    unaligned = np.frombuffer(b"\0" + q.tobytes(), dtype=np.float64, offset=1)
    return {
        "plain": q,
        "readonly": readonly,
        "unaligned": unaligned,
        "strided": np.repeat(q, 2)[::2],
        "reversed": q[::-1],
        "column": q.reshape(6, 1),
        "row": q.reshape(1, 6),
        "batch": np.tile(q, (3, 1)),
        "float32": q.astype(np.float32),
        "big_endian": q.astype(">f8"),
        "int64": np.arange(6),
        "bool": np.ones(6, dtype=bool),
        "complex": q.astype(complex),
        "long": np.r_[q, 0.0],
        "short": q[:5].copy(),
        "list": q.tolist(),
        "tuple": tuple(q.tolist()),
        "matrix": np.asmatrix(q),
        "masked": np.ma.masked_array(q, mask=[0, 0, 0, 0, 0, 1]),
        "0d": np.array(1.0),
        "none": None,
        "string": "q",
        "nan": np.r_[q[:5], np.nan],
        "inf": np.r_[-np.inf, q[1:]],
        "huge": np.r_[q[:5], 2e9],
        "cancelling": np.array([1e300, -1e300, 0, 0, 0, 0.0]),
        "at_limit": np.r_[q[:5], 1e9],
    }


def _outcome(fn):
    """('ok', result) or ('raised', exception type, message)."""
    try:
        return ("ok", fn())
    except Exception as error:
        return ("raised", type(error), str(error))


def _same(a, b) -> bool:
    if a[0] != b[0]:
        return False
    if a[0] == "raised":
        return a[1:] == b[1:]
    x, y = a[1], b[1]
    if isinstance(x, tuple):
        return len(x) == len(y) and all(np.array_equal(u, v) for u, v in zip(x, y, strict=True))
    return np.array_equal(x, y)


@needs_native
@pytest.mark.parametrize("check_inputs", [True, False])
@pytest.mark.parametrize("robot_name", ["abb_irb120", "ur5", "kinova", "panda"])
def test_c_handles_equal_pure_python_bit_for_bit(robot_name, check_inputs, monkeypatch):
    robot = kinengine.load(robot_name)
    frame = robot.end_effector
    fast = robot.frame(frame, check_inputs=check_inputs)
    pure = _pure(monkeypatch, lambda: robot.frame(frame, check_inputs=check_inputs))
    assert fast.pose is not pure.pose
    for q in robot.random_configuration(11, size=20):
        assert np.array_equal(fast.pose(q), pure.pose(q))
        for ref in (*REFERENCES, pin.LOCAL, pin.WORLD):
            assert np.array_equal(fast.jacobian(q, ref), pure.jacobian(q, ref))
            assert np.array_equal(fast.jacobian(q, reference=ref), pure.jacobian(q, reference=ref))
            assert _same(_outcome(lambda: fast.kinematics(q, ref)), _outcome(lambda: pure.kinematics(q, ref)))
        assert _same(_outcome(lambda: fast.kinematics(q)), _outcome(lambda: pure.kinematics(q)))
        R, p = fast.placement()
        assert np.array_equal(R, pure.pose(q)[:3, :3]) and np.array_equal(p, pure.pose(q)[:3, 3])


@needs_native
@pytest.mark.filterwarnings("ignore:the matrix subclass:PendingDeprecationWarning")
def test_c_handles_convert_and_refuse_exactly_as_pure_python(abb, monkeypatch):
    """Every input kind, every call form: the same result, or the same exception with the same message."""
    q = abb.random_configuration(5)
    for batches in (False, True):
        make = (lambda: abb.frame("tool0")) if not batches else (lambda: abb._handle("tool0"))
        fast, pure = make(), _pure(monkeypatch, make)
        for name, x in _inputs(q).items():
            calls = {
                "pose": lambda h, x=x: h.pose(x),
                "pose(q=)": lambda h, x=x: h.pose(q=x),
                "pose extra": lambda h, x=x: h.pose(x, "local"),
                "jacobian": lambda h, x=x: h.jacobian(x),
                "jacobian local": lambda h, x=x: h.jacobian(x, "local"),
                "jacobian reference=": lambda h, x=x: h.jacobian(x, reference="world"),
                "jacobian unknown": lambda h, x=x: h.jacobian(x, "body"),
                "jacobian bad keyword": lambda h, x=x: h.jacobian(x, frame="world"),
                "jacobian 1": lambda h, x=x: h.jacobian(x, 1),
                "kinematics": lambda h, x=x: h.kinematics(x),
                "kinematics local": lambda h, x=x: h.kinematics(x, reference="local"),
                "kinematics none": lambda h, x=x: h.kinematics(x, None),
            }
            for call, fn in calls.items():
                a, b = _outcome(lambda fn=fn: fn(fast)), _outcome(lambda fn=fn: fn(pure))
                assert _same(a, b), (batches, name, call, a[:1] + a[1:2], b[:1] + b[1:2])
        for fn in (lambda h: h.pose(), lambda h: h.jacobian(), lambda h: h.kinematics(q, "local", 1)):
            assert _same(_outcome(lambda fn=fn: fn(fast)), _outcome(lambda fn=fn: fn(pure)))


@needs_native
@settings(max_examples=300, deadline=None)
@given(
    values=st.lists(
        st.floats(allow_nan=True, allow_infinity=True, width=64) | st.sampled_from([1e9, -1e9, 1e300]),
        min_size=0,
        max_size=8,
    ),
    dtype=st.sampled_from(["<f8", ">f8", "<f4", "<i8", "<c16"]),
    step=st.sampled_from([1, 2]),
)
def test_c_ready_is_exactly_its_definition(values, dtype, step):
    """ready(q) in C: exactly a native float64 C-contiguous (dof,) ndarray with every |q_i| <= 1e9; the
    pure-Python predicate (a bound on the norm) never says yes where C says no."""
    dof = 6
    c_ready = accelerator.ready_check(dof, 1e9)
    assert c_ready is not None
    with np.errstate(all="ignore"):  # NaN and inf cast to integers: any value will do
        x = np.repeat(np.array(values, dtype=np.float64).astype(dtype), step)[::step]
    expected = (
        type(x) is np.ndarray
        and x.dtype == np.float64
        and x.dtype.isnative
        and x.shape == (dof,)
        and x.flags.c_contiguous
        and bool(np.all(np.abs(x) <= 1e9))
    )
    assert c_ready(x) is expected
    with pytest.MonkeyPatch.context() as m:
        m.setattr(accelerator, "native", None)
        py_ready = coordinates._ready_vector(dof)
    if py_ready(x):
        assert expected


@needs_native
def test_each_thread_keeps_its_own_data(abb):
    """Threads calling one handle at once get their own q's pose and Jacobian, and placement() shows the
    pose of the thread's own last call — also in a new thread started after another ended."""
    fk = abb.frame("tool0")
    Q = abb.random_configuration(3, size=4)
    expected = [(abb.frame_pose(q), abb.jacobian(q)) for q in Q]
    failures: list[str] = []
    barrier = threading.Barrier(len(Q))

    def work(k: int) -> None:
        barrier.wait()
        for _ in range(400):
            T = fk.pose(Q[k])
            R, p = fk.placement()
            J = fk.jacobian(Q[k])
            T2, J2 = fk.kinematics(Q[k])
            if not (
                np.array_equal(T, expected[k][0])
                and np.array_equal(R, T[:3, :3])
                and np.array_equal(p, T[:3, 3])
                and np.array_equal(J, expected[k][1])
                and np.array_equal(T2, T)
                and np.array_equal(J2, J)
            ):
                failures.append(f"thread {k}")
                return

    threads = [threading.Thread(target=work, args=(k,)) for k in range(len(Q))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not failures
    for k in range(3):  # short-lived threads one after the other (thread idents are reused; ids are not)
        seen = []
        t = threading.Thread(target=lambda k=k: (fk.pose(Q[k]), seen.append(fk.placement()[1].copy())))
        t.start()
        t.join()
        assert np.array_equal(seen[0], expected[k][0][:3, 3])


@pytest.mark.slow
@pytest.mark.skipif(PURE, reason="this is the pure-Python run")
def test_the_pure_python_path_passes_the_handle_and_input_tests():
    """The fallback a machine without a C compiler runs: the handle, input-check and analytic fast-path
    tests in a subprocess with KINENGINE_PURE_PYTHON=1 (the accelerator off)."""
    tests = Path(__file__).parent
    env = dict(os.environ, KINENGINE_PURE_PYTHON="1")
    probe = subprocess.run(
        [sys.executable, "-c", "from kinengine.model import accelerator; print(accelerator.AVAILABLE)"],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert probe.stdout.strip() == "False", probe.stderr
    files = [
        "test_handle.py",
        "test_configuration_input.py",
        "test_analytic_fast_path.py",
        "test_accelerator.py",
    ]
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *(str(tests / f) for f in files)],
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-2000:]


def test_c_sources_declare_their_gil_use_and_copy_no_library_structs():
    """Both C extensions declare Py_mod_gil (free-threaded CPython would otherwise re-enable the GIL on import),
    read numpy arrays through numpy's public API or the buffer protocol, never a copied struct layout, and
    the fast-math guard and portable restrict stay in the chain kernel."""
    root = Path(__file__).resolve().parents[1] / "kinengine"  # the sources (an installed wheel has none)
    fastcall = (root / "model" / "fastcall.c").read_text()
    kernel = (root / "kinematics" / "chainkernel.c").read_text()
    for source in (fastcall, kernel):
        assert "Py_mod_gil" in source and "PyModuleDef_Init" in source
        assert "typedef struct {\n    PyObject_HEAD\n    char *data;" not in source  # numpy's private fields
    assert "#include <numpy/arrayobject.h>" in fastcall and "PyArray_IS_C_CONTIGUOUS" in fastcall
    assert "__FAST_MATH__" in kernel and "*KE_RESTRICT" in kernel and "*restrict" not in kernel
