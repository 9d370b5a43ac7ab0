"""Hostile and broken input, each case in its own Python process: no signal, no hang, bounded memory.

Every case runs in a child (``python -c``) whose address space is capped at 1 GiB with
RLIMIT_AS (measured on pin 4.1: importing numpy, Pinocchio and kinengine and loading the ABB
arm peaks at 0.20 GiB of address space, a worker thread adds 0.13 GiB of malloc arena, the
128-joint chain (the largest the default limits admit) with a Robot Data, a Task Data, Hessians,
IK and a batch peaks at 0.57 GiB; one Data of nv = 256, which the default limits refuse, alone
needs 1.06 GiB). The child calls the public API and exits 0 after catching exactly ``kinengine.KinematicsError``, printing ``RAISED <type>: <message>``; a case that
must succeed prints ``RETURNED``. Anything else (another exception, a crash by signal, a
hang past the timeout, MemoryError) fails that case alone. For refused URDFs the child also
replaces ``pinocchio.buildModelFromXML`` with a tripwire: the refusal must come before
Pinocchio builds anything. Cases run two at a time.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow  # one subprocess per hostile case

ADDRESS_SPACE = 1024**3  # [bytes] RLIMIT_AS of each child; measured peaks: 0.20 GiB, 0.57 GiB for the largest
TIMEOUT = 60.0  # [s] per child
REPO = Path(__file__).resolve().parents[1]

PRELUDE = """
import os, resource, sys, threading
resource.setrlimit(resource.RLIMIT_AS, ({limit}, {limit}))
import numpy as np
import pinocchio
import kinengine

tmp = sys.argv[1]
LIMIT = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'


def chain(n, kind="revolute", body=LIMIT + '<axis xyz="0 0 1"/>'):
    body = "" if kind == "fixed" else body
    links = "".join(f'<link name="l{{i}}"/>' for i in range(n + 1))
    joints = "".join(f'<joint name="j{{i}}" type="{{kind}}"><parent link="l{{i - 1}}"/><child link="l{{i}}"/>'
                     f'<origin xyz="0 0 0.01"/>{{body}}</joint>' for i in range(1, n + 1))
    return f'<robot name="chain">{{links}}{{joints}}</robot>'


def star(n, kind="revolute"):
    body = "" if kind == "fixed" else LIMIT
    links = "".join(f'<link name="l{{i}}"/>' for i in range(n))
    joints = "".join(f'<joint name="j{{i}}" type="{{kind}}"><parent link="base"/><child link="l{{i}}"/>{{body}}'
                     "</joint>" for i in range(n))
    return f'<robot name="star"><link name="base"/>{{links}}{{joints}}</robot>'


def one_joint(inner, kind="revolute"):
    return (f'<robot name="one"><link name="a"/><link name="b"/><joint name="j" type="{{kind}}">'
            f'<parent link="a"/><child link="b"/>{{inner}}</joint></robot>')


def in_worker(function, stack_kib):
    box = []

    def run():
        try:
            box.append((True, function()))
        except BaseException as exc:
            box.append((False, exc))

    threading.stack_size(stack_kib * 1024)
    thread = threading.Thread(target=run)
    thread.start()
    thread.join()
    threading.stack_size(0)
    returned, value = box[0]
    if not returned:
        raise value
    return value


def tripwire(*args, **kwargs):
    print("Pinocchio was asked to build a model", file=sys.stderr, flush=True)
    os._exit(70)


if {tripwire}:
    pinocchio.buildModelFromXML = tripwire


def case():
{body}


try:
    case()
except kinengine.KinematicsError as exc:
    print(f"RAISED {{type(exc).__name__}}: {{exc}}"[:3000])
else:
    print("RETURNED")
status = dict(line.split(":", 1) for line in open("/proc/self/status") if line.startswith("Vm"))
print("memory", status["VmPeak"].strip(), "address space,", status["VmHWM"].strip(), "resident", file=sys.stderr)
"""


@dataclass(frozen=True)
class Case:
    """``body`` (the child's function body; ``tmp`` is a private directory) and its expected outcome:
    ``raises`` (a kinengine error type name) with a message ``fragment``, or ``raises=None``: returns."""

    id: str
    body: str
    raises: str | None = "URDFError"
    fragment: str = ""
    pinocchio_may_build: bool = False


ROBOT = 'robot = kinengine.load("abb_irb120")\nq = robot.neutral()\n'
XXE = (
    '<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY secret SYSTEM "file://{path}">]>\n'
    '<robot name="&secret;"><link name="a"/></robot>'
)
LAUGHS = (
    '<?xml version="1.0"?>\n<!DOCTYPE lolz [<!ENTITY lol "lol">'
    + "".join(
        f'<!ENTITY lol{i} "{("&lol" + str(i - 1) + ";" if i > 1 else "&lol;") * 10}">' for i in range(1, 10)
    )
    + ']>\n<robot name="&lol9;"><link name="a"/></robot>'
)
NO_DTD = "is not allowed: kinengine reads no DTD"

CASES = [
    # -- XML attacks --------------------------------------------------------------------------------
    Case(
        "xxe_file",
        f"""
        path = os.path.join(tmp, "secret.txt")
        open(path, "w").write("SECRET-CONTENT")
        kinengine.load_urdf_string({XXE!r}.format(path=path))""",
        fragment="<!DOCTYPE> " + NO_DTD,
    ),
    Case(
        "xxe_fifo",
        f"""
        path = os.path.join(tmp, "fifo")
        os.mkfifo(path)  # opening it for reading would block forever
        kinengine.load_urdf_string({XXE!r}.format(path=path))""",
        fragment="<!DOCTYPE> " + NO_DTD,
    ),
    Case(
        "xxe_utf16_bytes",
        f"""
        path = os.path.join(tmp, "secret.txt")
        open(path, "w").write("SECRET-CONTENT")
        text = {XXE!r}.format(path=path).replace('version="1.0"', 'version="1.0" encoding="UTF-16"')
        kinengine.load_urdf_string(text.encode("utf-16"))""",
        fragment="<!DOCTYPE> " + NO_DTD,
    ),
    Case(
        "xxe_in_a_urdf_file_via_load",
        f"""
        path = os.path.join(tmp, "secret.txt")
        open(path, "w").write("SECRET-CONTENT")
        urdf = os.path.join(tmp, "robot.urdf")
        open(urdf, "w").write({XXE!r}.format(path=path))
        kinengine.load(urdf)""",
        fragment="robot.urdf:2: <!DOCTYPE> " + NO_DTD,
    ),
    Case(
        "entity_declaration_without_doctype",
        """
        kinengine.load_urdf_string('<!ENTITY x "y"><robot name="r"><link name="a"/></robot>')""",
        fragment="<!ENTITY> " + NO_DTD,
    ),
    Case("billion_laughs", f"kinengine.load_urdf_string({LAUGHS!r})", fragment="<!DOCTYPE> " + NO_DTD),
    Case(
        "fifo_as_the_urdf_path",
        """
        path = os.path.join(tmp, "robot.urdf")
        os.mkfifo(path)
        kinengine.load(path)""",
        fragment="not a regular file (a device, FIFO or socket)",
    ),
    Case(
        "deep_xml_nesting",
        """
        kinengine.load_urdf_string('<robot name="r"><link name="a"/>' + "<x>" * 100_000 + "</x>" * 100_000
                                   + "</robot>")""",
        fragment="depth",
    ),
    Case(
        "moderately_deep_xml_nesting_in_a_small_thread",
        """
        text = '<robot name="r"><link name="a"/>' + "<x>" * 200 + "</x>" * 200 + "</robot>"
        in_worker(lambda: kinengine.load_urdf_string(text), stack_kib=256)""",
        fragment="nested deeper than Limits.max_depth = 64",
    ),
    Case(
        "huge_attribute",
        """
        kinengine.load_urdf_string('<robot name="r"><link name="a" extra="' + "x" * 5_000_000 + '"/></robot>')""",
        fragment="attribute",
    ),
    Case(
        "huge_document",
        """
        kinengine.load_urdf_string('<robot name="r"><link name="a"/>' + " " * (40 * 2**20) + "</robot>")""",
        fragment="more than Limits.max_bytes = 33554432",
    ),
    Case(
        "truncated_file",
        """
        text = open(kinengine.model.catalog_entry("abb_irb120").path).read()
        kinengine.load_urdf_string(text[:len(text) // 2])""",
        fragment="not well-formed XML",
    ),
    Case(
        "sdf_model_root",
        """
        kinengine.load_urdf_string('<model name="m"><link name="a"/></model>')""",
        fragment="the root element is <model>, expected <robot>",
    ),
    # -- model size: refused before Pinocchio's recursive parser or createData() runs ------------------
    Case(
        "chain_of_10k_joints",
        "kinengine.load_urdf_string(chain(10_000))",
        fragment="10001 links, more than Limits.max_links = 4096",
    ),
    Case(
        "chain_of_10k_joints_in_a_512_KiB_worker_thread",
        "in_worker(lambda: kinengine.load_urdf_string(chain(10_000)), stack_kib=512)",
        fragment="10001 links, more than Limits.max_links = 4096",
    ),
    Case(
        "chain_of_10k_joints_from_a_file_in_a_worker_thread",
        """
        path = os.path.join(tmp, "chain.urdf")
        open(path, "w").write(chain(10_000))
        in_worker(lambda: kinengine.load(path), stack_kib=512)""",
        fragment="chain.urdf",
    ),
    Case(
        "chain_of_4k_fixed_joints",
        "kinengine.load_urdf_string(chain(4_000, 'fixed'))",
        fragment="link 'l129' is more than Limits.max_tree_depth = 128 joints below the root 'l0'",
    ),
    Case(
        "chain_of_4k_fixed_joints_in_a_512_KiB_worker_thread",
        "in_worker(lambda: kinengine.load_urdf_string(chain(4_000, 'fixed')), stack_kib=512)",
        fragment="Limits.max_tree_depth = 128",
    ),
    Case(
        "chain_of_129_revolute_joints",
        "kinengine.load_urdf_string(chain(129))",
        fragment="129 movable joints, more than Limits.max_movable_joints = 128",
    ),
    Case(
        "star_of_129_revolute_joints",
        "kinengine.load_urdf_string(star(129))",
        fragment="129 movable joints, more than Limits.max_movable_joints = 128",
    ),
    Case(
        "chain_of_128_revolute_joints_and_one_mimic",
        """
        text = chain(129).replace('<origin xyz="0 0 0.01"/>' + LIMIT + '<axis xyz="0 0 1"/></joint></robot>',
                                  LIMIT + '<mimic joint="j1"/></joint></robot>')
        assert text.count("<mimic") == 1
        kinengine.load_urdf_string(text)""",
        fragment="129 movable joints, more than Limits.max_movable_joints = 128",
    ),
    Case(
        "chain_of_129_revolute_joints_from_a_file_in_a_worker_thread",
        """
        path = os.path.join(tmp, "chain.urdf")
        open(path, "w").write(chain(129))
        in_worker(lambda: kinengine.load(path), stack_kib=512)""",
        fragment="chain.urdf, robot 'chain': the robot has 129 movable joints",
    ),
    # -- values Pinocchio would accept and compute nonsense from ---------------------------------------
    Case(
        "zero_axis",
        "kinengine.load_urdf_string(one_joint(LIMIT + '<axis xyz=\"0 0 0\"/>'))",
        fragment='<axis xyz="0 0 0"> is zero',
    ),
    Case(
        "nan_origin",
        "kinengine.load_urdf_string(one_joint(LIMIT + '<origin xyz=\"0 nan 0\"/>'))",
        fragment="'nan' is not finite",
    ),
    Case(
        "lower_above_upper",
        """
        kinengine.load_urdf_string(one_joint('<limit lower="1" upper="-1" effort="1" velocity="1"/>'))""",
        fragment="lower limit 1.0 is greater than upper limit -1.0",
    ),
    Case(
        "mimic_of_a_missing_joint",
        "kinengine.load_urdf_string(one_joint(LIMIT + '<mimic joint=\"ghost\"/>'))",
        fragment="mimics joint 'ghost', which is not defined",
    ),
    Case(
        "floating_joint",
        "kinengine.load_urdf_string(one_joint('', kind='floating'))",
        fragment="a fixed-base model cannot have a floating joint",
    ),
    Case(
        "cycle_of_4001_links",
        """
        text = chain(4000, 'fixed').replace("</robot>", '<joint name="back" type="fixed"><parent link="l4000"/>'
                                        '<child link="l0"/></joint></robot>')
        kinengine.load_urdf_string(text)""",
        fragment="there is no root link: joints",
    ),
    Case(
        "link_with_two_parents",
        """
        text = star(3, "fixed").replace("</robot>", '<joint name="again" type="fixed"><parent link="l0"/>'
                                                    '<child link="l1"/></joint></robot>')
        kinengine.load_urdf_string(text)""",
        fragment="link 'l1' already has parent joint 'j1'",
    ),
    Case(
        "cycle_of_mimic_joints",
        """
        text = chain(3).replace(LIMIT + '<axis xyz="0 0 1"/></joint><joint name="j3"',
                                LIMIT + '<mimic joint="j3"/></joint><joint name="j3"')
        text = text.replace('<axis xyz="0 0 1"/></joint></robot>', '<mimic joint="j2"/></joint></robot>')
        kinengine.load_urdf_string(text)""",
        fragment="is part of a cycle of mimic joints",
    ),
    Case(
        "a_million_tags",
        """
        kinengine.load_urdf_string('<robot name="r"><link name="a"/>' + "<x/>" * 1_000_001 + "</robot>")""",
        fragment="markup tags, more than Limits.max_tags = 1000000",
    ),
    # -- names and configurations: resolved and checked in Python, never an unchecked index -------------
    Case(
        "unknown_frame_to_jacobian",
        ROBOT + "robot.jacobian(q, 'tool_0')",
        raises="FrameNotFoundError",
        fragment="unknown frame 'tool_0'. Did you mean 'tool0'",
        pinocchio_may_build=True,
    ),
    Case(
        "frame_index_equal_to_nframes",
        ROBOT + "robot.jacobian(q, robot.pinocchio_model().nframes)",
        raises="FrameNotFoundError",
        fragment="unknown frame ",
        pinocchio_may_build=True,
    ),
    Case(
        "negative_int_frame",
        ROBOT + "robot.analytic_jacobian(q, -1)",
        raises="FrameNotFoundError",
        fragment="unknown frame -1",
        pinocchio_may_build=True,
    ),
    Case(
        "list_as_frame",
        ROBOT + "robot.pose_parameters(q, ['tool0'])",
        raises="FrameNotFoundError",
        fragment="unknown frame ['tool0']. Did you mean 'tool0'",
        pinocchio_may_build=True,
    ),
    Case(
        "none_as_frame_id",
        ROBOT + "robot.frame_id(None)",
        raises="FrameNotFoundError",
        fragment="unknown frame None",
        pinocchio_may_build=True,
    ),
    Case(
        "none_among_task_frames",
        ROBOT + "robot.task(['tool0', None])",
        raises="OptionError",
        fragment="got None",
        pinocchio_may_build=True,
    ),
    Case(
        "bytes_as_frame_in_a_batch",
        ROBOT + "robot.jacobian(np.zeros((3, 6)), b'tool0')",
        raises="FrameNotFoundError",
        fragment="unknown frame b'tool0'",
        pinocchio_may_build=True,
    ),
    Case(
        "wrong_shape_q",
        ROBOT + "robot.jacobian(np.zeros(7), 'tool0')",
        raises="ConfigurationError",
        fragment="Expected `q` to have shape (6,) or (N, 6), got (7,)",
        pinocchio_may_build=True,
    ),
    Case(
        "nan_q",
        ROBOT + "robot.frame_pose(np.array([0, 0, 0, np.nan, 0, 0]))",
        raises="ConfigurationError",
        fragment="`q`[3] (joint 'joint_4') is nan",
        pinocchio_may_build=True,
    ),
    Case(
        "inf_in_a_batch_of_q",
        ROBOT + "qs = np.zeros((4, 6)); qs[2, 1] = -np.inf\nrobot.analytic_jacobian(qs)",
        raises="ConfigurationError",
        fragment="`q`[2, 1] (joint 'joint_2') is -inf",
        pinocchio_may_build=True,
    ),
    Case(
        "q_with_a_python_int_too_large_for_a_double",
        ROBOT + "robot.kinematic_hessian([10**400] + [0] * 5)",
        raises="ConfigurationError",
        fragment="with a number too large for a float64",
        pinocchio_may_build=True,
    ),
    Case(
        "masked_q",
        ROBOT + "robot.jacobian(np.ma.masked_array(q, mask=[1, 0, 0, 0, 0, 0]))",
        raises="ConfigurationError",
        fragment="masked array with masked entries",
        pinocchio_may_build=True,
    ),
    Case(
        "batch_to_an_entry_point_without_batches",
        ROBOT + "robot.velocity_ellipsoid(np.zeros((3, 6)))",
        raises="ConfigurationError",
        fragment="takes one configuration",
        pinocchio_may_build=True,
    ),
    Case(
        "empty_batch",
        ROBOT + "robot.analytic_jacobian(np.zeros((0, 6)))",
        raises="ConfigurationError",
        fragment="got an empty batch (0, 6)",
        pinocchio_may_build=True,
    ),
    Case(
        "wrong_shape_qdot_to_a_task",
        ROBOT + "robot.task().update(q, np.zeros(5))",
        raises="ConfigurationError",
        fragment="Expected `qdot` to have shape (6,), got (5,)",
        pinocchio_may_build=True,
    ),
    # -- the largest models the default limits admit build and run within the memory cap -------------
    Case(
        "deepest_admitted_chain_in_a_1_MiB_worker_thread",
        """
        robot = in_worker(lambda: kinengine.load_urdf_string(chain(128)), stack_kib=1024)
        assert robot.dof == 128
        J = in_worker(lambda: robot.jacobian(robot.neutral(), "l128"), stack_kib=1024)
        task = robot.task("l128")
        task.update(robot.neutral())
        np.testing.assert_allclose(task.jacobian, J, rtol=0, atol=1e-12)
        q = robot.random_configuration(0)
        H = in_worker(lambda: robot.kinematic_hessian(q, "l128"), stack_kib=1024)
        assert H.shape == (6, 128, 128) and np.isfinite(H).all()
        assert robot.analytic_hessian(q, "l128", rotation="quaternion").shape == (7, 128, 128)
        target = robot.frame_pose(robot.random_configuration(1), "l128")
        assert robot.inverse_kinematics(target, "l128", rng=0).success
        assert robot.frame_pose(robot.random_configuration(2, size=64), "l128").shape == (64, 4, 4)""",
        raises=None,
        pinocchio_may_build=True,
    ),
    Case(
        "star_of_128_revolute_joints_computes",
        """
        robot = kinengine.load_urdf_string(star(128))
        q = robot.random_configuration(0)
        J = robot.jacobian(q, "l127")
        assert robot.dof == 128 and np.count_nonzero(np.abs(J).sum(axis=0)) == 1  # only j127 moves l127
        assert robot.kinematic_hessian(q, "l127").shape == (6, 128, 128)""",
        raises=None,
        pinocchio_may_build=True,
    ),
    Case(
        "star_of_4000_fixed_joints",
        """
        robot = kinengine.load_urdf_string(star(4000, "fixed"))
        assert robot.dof == 0 and len(robot.frame_names) == 1 + 2 * 4000
        np.testing.assert_array_equal(robot.frame_pose(robot.neutral(), "l3999"), np.eye(4))""",
        raises=None,
        pinocchio_may_build=True,
    ),
]


def run_case(case: Case, tmp: Path) -> subprocess.CompletedProcess | str:
    """The finished child, or "timeout" if it ran past TIMEOUT."""
    directory = tmp / case.id
    directory.mkdir()
    code = PRELUDE.format(
        limit=ADDRESS_SPACE,
        tripwire=not case.pinocchio_may_build,
        body=textwrap.indent(textwrap.dedent(case.body).strip(), "    "),
    )
    env = {**os.environ, "PYTHONPATH": str(REPO), "OPENBLAS_NUM_THREADS": "1"}
    try:
        return subprocess.run(
            [sys.executable, "-c", code, str(directory)],
            capture_output=True,
            text=True,
            timeout=TIMEOUT,
            env=env,
            cwd=directory,
        )
    except subprocess.TimeoutExpired:
        return "timeout"


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory) -> dict[str, subprocess.CompletedProcess | str]:
    tmp = tmp_path_factory.mktemp("hostile")
    with ThreadPoolExecutor(max_workers=2) as pool:
        return dict(zip([c.id for c in CASES], pool.map(lambda c: run_case(c, tmp), CASES), strict=False))


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_hostile_case_ends_with_the_expected_kinengine_error(case, outcomes):
    outcome = outcomes[case.id]
    assert outcome != "timeout", f"{case.id}: no answer within {TIMEOUT} s"
    report = f"exit status {outcome.returncode}\nstdout: {outcome.stdout[-3000:]}\nstderr: {outcome.stderr[-3000:]}"
    assert outcome.returncode == 0, report  # negative: killed by that signal
    lines = outcome.stdout.splitlines()
    assert len(lines) == 1, report
    if case.raises is None:
        assert lines[0] == "RETURNED", report
    else:
        assert lines[0].startswith(f"RAISED {case.raises}: "), report
        assert case.fragment in lines[0], report
    assert "SECRET-CONTENT" not in outcome.stdout + outcome.stderr
