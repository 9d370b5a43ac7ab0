"""Issue 15: no crash, hang or foreign exception anywhere in the API, fork or pickle.

Cases that crashed or hung before run in their own Python process with a timeout (and, where memory
is the point, an RLIMIT_AS cap); the child prints what it saw and the test checks it. Everything
else runs in-process. Every refusal must be a ``kinengine.KinematicsError`` with a one-line message.
"""

from __future__ import annotations

import copy
import os
import pickle
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import kinengine
from kinengine import (
    ConfigurationError,
    FrameNotFoundError,
    KinematicsError,
    KinematicSingularityError,
    OptionError,
    ParameterizationError,
    RepresentationSingularityError,
    URDFError,
)
from kinengine.errors import ResourceLimitError
from kinengine.urdf import Limits

pytestmark = pytest.mark.slow  # threads, processes and memory caps

REPO = Path(__file__).resolve().parents[1]
LIMIT = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'

CHAIN = textwrap.dedent("""
    def chain(n, kind="revolute"):
        body = "" if kind == "fixed" else '<limit lower="-1" upper="1" effort="1" velocity="1"/><axis xyz="0 0 1"/>'
        links = "".join(f'<link name="l{i}"/>' for i in range(n + 1))
        joints = "".join(f'<joint name="j{i}" type="{kind}"><parent link="l{i - 1}"/><child link="l{i}"/>'
                         f'<origin xyz="0 0 0.01"/>{body}</joint>' for i in range(1, n + 1))
        return f'<robot name="chain">{links}{joints}</robot>'
""")


def run_child(
    code: str, *, address_space: int | None = None, timeout: float = 120.0, env: dict[str, str] | None = None
) -> subprocess.CompletedProcess:
    """``code`` in a fresh Python (optionally under RLIMIT_AS); fails the test on a timeout."""
    prelude = "import resource\n"
    if address_space:
        prelude += f"resource.setrlimit(resource.RLIMIT_AS, ({address_space}, {address_space}))\n"
    try:
        return subprocess.run(
            [sys.executable, "-c", prelude + CHAIN + textwrap.dedent(code)],
            cwd=REPO,
            capture_output=True,
            text=True,
            timeout=timeout,
            env=env,
        )
    except subprocess.TimeoutExpired:
        pytest.fail(f"the child hung for {timeout} s")


def assert_one_line(error: BaseException) -> None:
    assert isinstance(error, KinematicsError)
    assert "\n" not in str(error), str(error)


@pytest.fixture(scope="module")
def R():
    return kinengine.load("abb_irb120")


# -- item 2: deep chains in small-stack threads ---------------------------------------------------------
def test_deepest_admitted_chain_loads_and_computes_in_a_128_KiB_thread():
    child = run_child("""
        import threading
        import numpy as np
        import kinengine
        box = []
        def work():
            robot = kinengine.load_urdf_string(chain(128))
            q = robot.neutral()
            T = robot.frame_pose(q, "l128")
            J = robot.jacobian(q, "l128")
            H = robot.kinematic_hessian(q, "l128")
            box.append((robot.dof, T[2, 3], np.abs(J[:2]).max(), H.shape))
        threading.stack_size(128 * 1024)
        thread = threading.Thread(target=work)
        thread.start()
        thread.join()
        print(box[0])
    """)
    assert child.returncode == 0, child.stderr
    dof, z, lateral, shape = eval(child.stdout)
    assert dof == 128 and shape == (6, 128, 128)
    assert z == pytest.approx(1.28, abs=1e-12)  # 128 links 0.01 m apart along z at q = 0
    assert lateral == 0.0  # every axis along z through the same line: no x/y velocity


def test_deepest_admitted_chain_loads_in_a_main_thread_with_a_256_KiB_stack_limit():
    # the main thread builds in place only when RLIMIT_STACK is at least twice what the tree needs
    child = run_child("""
        resource.setrlimit(resource.RLIMIT_STACK, (256 * 1024, resource.getrlimit(resource.RLIMIT_STACK)[1]))
        import kinengine
        robot = kinengine.load_urdf_string(chain(128))
        print(robot.dof, float(robot.frame_pose(robot.neutral(), "l128")[2, 3]))
    """)
    assert child.returncode == 0, child.stderr
    dof, z = child.stdout.split()
    assert dof == "128" and float(z) == pytest.approx(1.28, abs=1e-12)


def test_raised_tree_depth_gets_a_bigger_build_stack():
    # 9,000 fixed levels need ~20 MiB of Pinocchio stack: more than the 16 MiB default build thread
    child = run_child(
        """
        import threading
        import kinengine
        from kinengine.urdf import Limits
        box = []
        limits = Limits(max_links=9001, max_joints=9000, max_tree_depth=9000)
        def work():
            robot = kinengine.load_urdf_string(chain(9000, "fixed"), limits=limits)
            box.append(float(robot.frame_pose([], "l9000")[2, 3]))
        threading.stack_size(256 * 1024)
        thread = threading.Thread(target=work)
        thread.start()
        thread.join()
        print(box[0])
    """,
        timeout=300,
    )
    assert child.returncode == 0, child.stderr
    assert float(child.stdout) == pytest.approx(90.0, rel=1e-12)


# -- item 3: Data per thread under a memory cap ------------------------------------------------------
def test_a_128_dof_robot_from_32_threads_under_a_memory_cap_ends_in_answers_or_resource_errors():
    child = run_child(
        """
        import threading
        from collections import Counter
        import numpy as np
        import kinengine
        robot = kinengine.load_urdf_string(chain(128))
        q = robot.neutral()
        expected = robot.jacobian(q, "l128")
        seen = []
        barrier = threading.Barrier(32, timeout=60)
        def work():
            try:
                seen.append("ok" if np.array_equal(robot.jacobian(q, "l128"), expected) else "WRONG")
            except kinengine.KinematicsError as exc:
                seen.append(type(exc).__name__ + ("" if "\\n" not in str(exc) else " MULTILINE"))
            try:
                barrier.wait()  # every thread keeps its Data until all have tried
            except threading.BrokenBarrierError:
                pass
        threading.stack_size(1024 * 1024)
        threads = [threading.Thread(target=work) for _ in range(32)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        print(dict(Counter(seen)))
    """,
        address_space=3 * 1024**3,
        timeout=300,
    )
    assert child.returncode == 0, child.stderr[-2000:]
    seen = eval(child.stdout)
    assert set(seen) <= {"ok", "ResourceLimitError"}, seen
    assert seen.get("ok", 0) >= 1 and sum(seen.values()) == 32


def test_resource_limit_error_is_a_memory_error_and_a_kinematics_error():
    assert issubclass(ResourceLimitError, MemoryError) and issubclass(ResourceLimitError, KinematicsError)


# -- items 5 and 6: fork, pickle, worker processes -------------------------------------------------
def test_a_forked_child_runs_a_large_batch_after_the_parent_ran_one():
    child = run_child(
        """
        import multiprocessing as mp
        import numpy as np
        import kinengine
        robot = kinengine.load("abb_irb120")
        Q = robot.random_configuration(0, 100_000)
        parent = robot.frame_pose(Q)                      # starts the batch thread pool
        def work(_):
            return robot.frame_pose(Q)[::9973].tolist()
        with mp.get_context("fork").Pool(2) as pool:
            results = pool.map(work, range(2), chunksize=1)
        print(all(np.array_equal(np.array(r), parent[::9973]) for r in results))
    """,
        timeout=120,
    )
    assert child.returncode == 0, child.stderr
    assert child.stdout.strip() == "True"


ERRORS = [
    URDFError("bad origin", source="arm.urdf", element="joint 'elbow'", line=12),
    FrameNotFoundError("tool_0", ["tool0", "flange"]),
    FrameNotFoundError("elbo", ["elbow"], kind="joint"),
    ConfigurationError("q has the wrong shape"),
    OptionError("tolerance must be >= 0"),
    ParameterizationError.unknown("rotation", "eulr", ["euler_zyx", "quaternion"]),
    RepresentationSingularityError("euler_zyx", 1e-9, 1e-6, ["quaternion"], "gimbal lock"),
    KinematicSingularityError("rank 5 < 6"),
    ResourceLimitError("too big"),
    KinematicsError("base"),
]


@pytest.mark.parametrize("error", ERRORS, ids=lambda e: type(e).__name__)
def test_every_error_round_trips_through_pickle_and_deepcopy(error):
    for again in (pickle.loads(pickle.dumps(error)), copy.deepcopy(error)):
        assert type(again) is type(error) and str(again) == str(error) and again.args == error.args
        assert again.__dict__ == error.__dict__


def test_a_pool_whose_workers_raise_kinengine_errors_completes():
    # bound methods of a Robot pickle (the Robot is rebuilt in the worker), so spawn works with python -c
    child = run_child(
        """
        import multiprocessing as mp
        import kinengine
        robot = kinengine.load("abb_irb120")
        q0 = robot.neutral()  # ZYX gimbal lock at the ABB's home pose
        for context in ("fork", "spawn"):
            with mp.get_context(context).Pool(2) as pool:
                for function, args in ((robot.frame_pose, (q0, "tool_0")), (robot.analytic_jacobian, (q0,))):
                    try:
                        pool.apply_async(function, args).get(timeout=60)
                        print(context, "RETURNED")
                    except kinengine.KinematicsError as exc:
                        print(context, type(exc).__name__, getattr(exc, "name", None) or exc.alternatives[0])
    """,
        timeout=180,
    )
    assert child.returncode == 0, child.stderr
    assert child.stdout.splitlines() == [
        f"{c} {e}"
        for c in ("fork", "spawn")
        for e in ("FrameNotFoundError tool_0", "RepresentationSingularityError quaternion")
    ]


def test_a_robot_pickles_deep_copies_and_travels_to_worker_processes(R):
    q = R.random_configuration(3)
    for again in (pickle.loads(pickle.dumps(R)), copy.deepcopy(R)):
        assert again is not R and again.name == R.name and again.end_effector == R.end_effector
        assert again.urdf_text == R.urdf_text and again.joint_names == R.joint_names
        np.testing.assert_array_equal(again.jacobian(q), R.jacobian(q))
    child = run_child(
        """
        import multiprocessing as mp
        import numpy as np
        import kinengine
        robot = kinengine.load("panda", end_effector="panda_link7")
        q = robot.random_configuration(1)
        with mp.get_context("spawn").Pool(1) as pool:
            T = pool.apply_async(robot.frame_pose, (q,)).get(timeout=60)
            name, ee = pool.apply_async(getattr, (robot, "name")).get(timeout=60), \\
                pool.apply_async(getattr, (robot, "end_effector")).get(timeout=60)
        print(name, ee, np.array_equal(T, robot.frame_pose(q)))
    """,
        timeout=120,
    )
    assert child.returncode == 0, child.stderr
    assert child.stdout.split() == ["panda", "panda_link7", "True"]


# -- item 7: magnitudes ------------------------------------------------------------------------------
def _two_joints(first: str, second: str) -> str:
    return (
        '<robot name="m"><link name="a"/><link name="b"/><link name="c"/>'
        f'<joint name="j1" {first}<parent link="a"/><child link="b"/></joint>'
        f'<joint name="j2" {second}<parent link="b"/><child link="c"/></joint></robot>'
    )


@pytest.mark.parametrize(
    "text, message",
    [
        (
            _two_joints('type="fixed"><origin xyz="1e308 0 0"/>', 'type="fixed"><origin xyz="1e308 0 0"/>'),
            r"joint 'j1': origin xyz 1e\+308 is beyond ±1e\+06 m \(Limits.max_offset\)",
        ),
        (
            _two_joints(
                f'type="prismatic">{LIMIT}', f'type="prismatic">{LIMIT}<mimic joint="j1" multiplier="1e308"/>'
            ),
            r"joint 'j2': mimic multiplier 1e\+308 is beyond ±1e\+06 \(Limits.max_multiplier\)",
        ),
        (
            _two_joints(
                f'type="prismatic">{LIMIT}', f'type="prismatic">{LIMIT}<mimic joint="j1" offset="-1e308"/>'
            ),
            r"joint 'j2': mimic offset -1e\+308 is beyond ±1e\+06",
        ),
    ],
)
def test_magnitudes_that_would_overflow_together_are_refused_at_load(text, message):
    with pytest.raises(URDFError, match=message) as info:
        kinengine.load_urdf_string(text)
    assert_one_line(info.value)


def test_a_bigger_max_offset_admits_a_bigger_model():
    text = _two_joints('type="fixed"><origin xyz="2e6 0 0"/>', 'type="fixed"><origin xyz="2e6 0 0"/>')
    robot = kinengine.load_urdf_string(text, limits=Limits(max_offset=1e7))
    assert robot.frame_pose([], "c")[0, 3] == 4e6


def test_huge_prismatic_coordinates_are_refused_before_pinocchio():
    big = 'type="prismatic"><limit lower="-1e308" upper="1e308" effort="1" velocity="1"/>'
    robot = kinengine.load_urdf_string(_two_joints(big, big))
    for q in ([1e308, 1e308], [1e308, -1e308], [2e9, 0.0], np.array([[0.0, 0.0], [1e308, 1e308]])):
        for call in (robot.frame_pose, robot.jacobian, robot.kinematics):
            with pytest.raises(ConfigurationError, match=r"beyond ±1e\+09") as info:
                call(q)
            assert_one_line(info.value)
    with pytest.raises(ConfigurationError, match=r"within ±1e\+09"):
        robot.configuration({"j1": 1e308})
    samples = robot.random_configuration(0, 1000)  # limits of ±1e308 are sampled within ±1e9
    assert np.isfinite(samples).all() and np.abs(samples).max() <= 1e9
    assert np.isfinite(robot.frame_pose(samples)).all()
    T = robot.frame_pose([1e9, 1e9], "c")
    assert T[0, 3] == 2e9  # both prismatic axes default to x; the largest admitted values add exactly


def test_verify_and_sampling_survive_limits_of_1e308():
    from kinengine.verify import verify

    text = _two_joints(
        'type="prismatic"><limit lower="-1e308" upper="1e308" effort="1" velocity="1"/>',
        'type="revolute"><axis xyz="0 0 1"/><limit lower="-1e308" upper="1e308" effort="1" velocity="1"/>',
    )
    robot = kinengine.load_urdf_string(text)
    assert verify(robot, samples=3).passed


# -- item 8 (non-IK): singularity_threshold ------------------------------------------------------------
BAD_THRESHOLDS = [
    float("nan"),
    -1.0,
    -1e-12,
    float("inf"),
    None,
    "1e-6",
    [1e-6],
    True,
    1e400 * 10,
    complex(1, 0),
]


@pytest.mark.parametrize("threshold", BAD_THRESHOLDS, ids=repr)
def test_a_bad_singularity_threshold_is_an_option_error_on_every_path(R, threshold):
    q0 = R.neutral()  # ZYX gimbal lock: a NaN or negative threshold used to return 3.5e15 entries here
    calls = [
        lambda: R.analytic_jacobian(q0, singularity_threshold=threshold),
        lambda: R.analytic_jacobian(np.tile(q0, (3, 1)), singularity_threshold=threshold),
        lambda: R.analytic_hessian(q0, singularity_threshold=threshold),
        lambda: R.task(singularity_threshold=threshold),
        lambda: R.pose_parameters(q0, on_singularity="raise", singularity_threshold=threshold),
    ]
    for call in calls:
        with pytest.raises(OptionError, match="singularity_threshold") as info:
            call()
        assert_one_line(info.value)


def test_single_and_batch_paths_agree_at_gimbal_lock(R):
    q0 = R.neutral()
    for call in (
        lambda q: R.analytic_jacobian(q),
        lambda q: R.analytic_jacobian(q, singularity_threshold=0.0),
    ):
        outcomes = []
        for q in (q0, q0[None, :]):
            try:
                outcomes.append(("returned", np.asarray(call(q)).reshape(-1, 6)))
            except RepresentationSingularityError:
                outcomes.append(("raised", None))
        assert outcomes[0][0] == outcomes[1][0]


# -- item 9: an unknown end effector -------------------------------------------------------------------
def test_an_unknown_end_effector_is_a_frame_not_found_error_with_suggestions():
    with pytest.raises(
        FrameNotFoundError, match=r"unknown frame 'panda_hnd'. Did you mean 'panda_hand'"
    ) as info:
        kinengine.load("panda", end_effector="panda_hnd")
    assert_one_line(info.value)
    cli = subprocess.run(
        [sys.executable, "-m", "kinengine", "pose", "panda", "--frame", "panda_hnd"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert cli.returncode == 2 and cli.stdout == ""
    assert cli.stderr.splitlines() == [cli.stderr.strip()] and "Did you mean 'panda_hand'" in cli.stderr


# -- item 10: urdf_text is what was parsed --------------------------------------------------------------
def _declared(robot, encoding: str) -> str:
    body = re.sub(r"^<\?xml[^>]*\?>\s*", "", robot.urdf_text)
    return f'<?xml version="1.0" encoding="{encoding}"?>\n' + body.replace(
        'name="abb_irb120"', 'name="bras_é"', 1
    )


@pytest.mark.parametrize(
    "encoding, codec", [("UTF-16", "utf-16"), ("ISO-8859-1", "latin-1"), ("UTF-8", "utf-8")]
)
def test_files_in_other_encodings_keep_their_text_and_verify(R, tmp_path, encoding, codec):
    from kinengine.verify import verify

    path = tmp_path / "bras.urdf"
    path.write_bytes(_declared(R, encoding).encode(codec))
    robot = kinengine.load(path)
    assert robot.name == "bras_é"
    assert robot.urdf_text.startswith('<?xml version="1.0" encoding="UTF-8"?>')
    assert robot.urdf_text.split("\n", 1)[1] == _declared(R, encoding).split("\n", 1)[1]
    assert verify(robot, samples=2).passed
    from_bytes = kinengine.load_urdf_string(path.read_bytes())
    assert from_bytes.urdf_text == robot.urdf_text


def test_a_file_is_read_once(R, tmp_path, monkeypatch):
    path = tmp_path / "arm.urdf"
    path.write_text(R.urdf_text, encoding="utf-8")
    opened = []
    real_open = os.open

    def counting_open(name, *args, **kwargs):
        if os.fspath(name) == str(path):
            opened.append(name)
        return real_open(name, *args, **kwargs)

    def forbidden(*args, **kwargs):
        raise AssertionError("a second read of the URDF file")

    monkeypatch.setattr(os, "open", counting_open)
    monkeypatch.setattr(Path, "read_text", forbidden)
    monkeypatch.setattr(Path, "read_bytes", forbidden)
    robot = kinengine.load(path)
    assert len(opened) == 1 and robot.urdf_text == R.urdf_text


# -- item 11: configuration values ------------------------------------------------------------------------
@pytest.mark.parametrize(
    "value", ["0.5", b"0.5", True, np.bool_(False), None, [0.5], 10**400, float("nan"), complex(0.5, 0), 1e10]
)
def test_configuration_refuses_non_numbers(R, value):
    with pytest.raises(ConfigurationError, match="joint 'joint_1'") as info:
        R.configuration({"joint_1": value})
    assert_one_line(info.value)


def test_configuration_accepts_real_numbers(R):
    for value in (0.5, 1, np.float32(0.5), np.int64(1), np.float64(-0.25)):
        assert R.configuration({"joint_1": value})[0] == float(value)


# -- item 12: reference ----------------------------------------------------------------------------------
@pytest.mark.parametrize("reference", [True, False, 1.0, 0, np.int64(2), "LOCAL", None, b"world"], ids=repr)
def test_only_reference_names_and_pinocchio_enums_are_references(R, reference):
    q = R.neutral()
    calls = [
        lambda: R.jacobian(q, reference=reference),
        lambda: R.jacobian(np.tile(q, (2, 1)), reference=reference),
        lambda: R.kinematics(q, reference=reference),
        lambda: R.jacobian_time_variation(q, q, reference=reference),
        lambda: R.kinematic_hessian(q, reference=reference),
    ]
    if hasattr(R, "frame"):  # the hot-loop frame handle
        handle = R.frame()
        calls += [
            lambda: handle.jacobian(q, reference=reference),
            lambda: handle.kinematics(q, reference=reference),
        ]
    for call in calls:
        with pytest.raises(OptionError, match="unknown reference") as info:
            call()
        assert_one_line(info.value)


# -- item 13: limits are copies --------------------------------------------------------------------------
def test_mutating_the_returned_limits_changes_nothing():
    robot = kinengine.load("panda")
    neutral, lower, upper = robot.neutral(), robot.lower_limits, robot.upper_limits
    for limits in (robot.lower_limits, robot.upper_limits):
        limits.setflags(write=True)
        limits[:] = 0.0
    np.testing.assert_array_equal(robot.neutral(), neutral)
    np.testing.assert_array_equal(robot.lower_limits, lower)
    np.testing.assert_array_equal(robot.upper_limits, upper)
    with pytest.raises(ConfigurationError):
        robot.check_configuration(upper + 1.0)


# -- foreign exceptions ---------------------------------------------------------------------------------
FOREIGN = {
    "rows as an int": lambda R: R.analytic_jacobian(R.random_configuration(0), rows=5),
    "rows as a dict": lambda R: R.pose_parameters(R.neutral(), rows={"x": 1}),
    "rows holding a float": lambda R: R.pose_parameters(R.neutral(), rows=[0.5]),
    "position as a list": lambda R: R.analytic_jacobian(R.neutral(), position=["cartesian"]),
    "rotation as a list": lambda R: R.pose_parameters(R.neutral(), rotation=["euler_zyx"]),
    "rotation as a dict": lambda R: R.task(rotation={}),
    "rotation as an int": lambda R: R.analytic_hessian(R.neutral(), rotation=3),
    "tolerance as a string": lambda R: R.singularity_report(R.neutral(), tolerance="1"),
    "tolerance as a list": lambda R: R.singularity_report(R.neutral(), tolerance=[1e-6]),
    "tolerance None": lambda R: R.require_regular(R.neutral(), tolerance=None),
    "tolerance NaN": lambda R: R.singularity_report(R.neutral(), tolerance=float("nan")),
    "end_effector as a list": lambda R: kinengine.load("abb_irb120", end_effector=["tool0"]),
    "configuration of 10**400": lambda R: R.configuration({"joint_1": 10**400}),
    "rng 'abc'": lambda R: R.random_configuration(rng="abc"),
    "rng -1": lambda R: R.random_configuration(rng=-1),
    "rng 1.5": lambda R: R.random_configuration(rng=1.5),
    "size 10**12": lambda R: R.random_configuration(size=10**12),
    "Limits(max_depth=-1)": lambda R: Limits(max_depth=-1),
    "Limits(max_depth=10**9)": lambda R: Limits(max_depth=10**9),
    "Limits(max_attribute_length=inf)": lambda R: Limits(max_attribute_length=float("inf")),
    "Limits(max_bytes=True)": lambda R: Limits(max_bytes=True),
    "load(limits=dict)": lambda R: kinengine.load("abb_irb120", limits={}),
    "load_urdf_string(limits=dict)": lambda R: kinengine.load_urdf_string(
        R.urdf_text, limits={"max_bytes": 1}
    ),
    "load('a' * 300)": lambda R: kinengine.load("a" * 300),
    "load('a' * 300 + '.urdf')": lambda R: kinengine.load("a" * 300 + ".urdf"),
    "load of a NUL path": lambda R: kinengine.load("arm\0.urdf"),
    "verify(samples=-1)": lambda R: __import__("kinengine.verify").verify.verify(R, samples=-1),
    "verify(seed=-1)": lambda R: __import__("kinengine.verify").verify.verify(R, seed=-1),
    "verify(samples=10**8)": lambda R: __import__("kinengine.verify").verify.verify(R, samples=10**8),
}


@pytest.mark.parametrize("name", list(FOREIGN))
def test_bad_options_are_kinematics_errors_with_one_line(R, name):
    with pytest.raises(KinematicsError) as info:
        FOREIGN[name](R)
    assert_one_line(info.value)


def test_a_path_in_an_unreadable_folder_is_a_urdf_error(tmp_path):
    folder = tmp_path / "locked"
    folder.mkdir()
    (folder / "arm.urdf").write_text("<robot/>")
    folder.chmod(0)
    try:
        for target in (folder / "arm.urdf", str(folder / "arm")):
            with pytest.raises(URDFError) as info:
                kinengine.load(target)
            assert_one_line(info.value)
    finally:
        folder.chmod(0o700)


def test_a_large_batch_from_an_atexit_handler_runs():
    child = run_child("""
        import atexit
        import kinengine
        robot = kinengine.load("abb_irb120")
        Q = robot.random_configuration(0, 200_000)
        expected = robot.frame_pose(Q)  # threaded, while the interpreter runs
        def late():  # after shutdown no thread starts: the calling thread does every chunk
            T = robot.frame_pose(Q)
            print("ok", T.shape, bool((T == expected).all()))
        atexit.register(late)
    """)
    assert child.returncode == 0 and child.stderr == "", child.stderr
    assert child.stdout.strip() == "ok (200000, 4, 4) True"


def test_a_robot_with_locked_joints_pickles_as_it_is():
    robot = kinengine.load("panda_arm")  # the Panda with its finger locked: an edited description
    again = pickle.loads(pickle.dumps(robot))
    q = robot.random_configuration(5)
    assert again.dof == robot.dof == 7 and again.joint_names == robot.joint_names
    np.testing.assert_array_equal(again.kinematics(q)[1], robot.kinematics(q)[1])
