"""Issue 15 acceptance: fuzzers over the options of the Python API and of the command line.

* Python API: every keyword of every public Robot method (found by introspection, so new methods are
  fuzzed too) gets hostile values (wrong types, NaN, ±inf, huge and negative numbers, booleans,
  numpy scalars, strings, containers); the result is an answer or a ``KinematicsError`` whose message is
  one line. Left out: ``inverse_kinematics`` (its options can legitimately ask for hours of work,
  e.g. max_iterations=10**9; tests/test_ik.py owns them), ``plot``/``view`` (matplotlib, a web server)
  and ``check_inputs=False`` (documented as "the caller promises a valid q": no check by design).
* CLI: every option of list, info, pose, verify and show gets malformed values; the exit status is 0,
  or 2 with exactly one line ``kinengine: error: ...`` on stderr and nothing on stdout. ``bench`` and
  ``view`` are left out (a run takes seconds / starts a server); their argparse errors go through the
  same one-line parser.
"""

from __future__ import annotations

import argparse
import inspect
import math
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import kinengine
from kinengine import KinematicsError, KinematicSingularityError
from kinengine.cli import main
from kinengine.cli.main import build_parser

pytestmark = pytest.mark.slow  # hypothesis over every public method

ROBOT = kinengine.load("abb_irb120")
Q0 = ROBOT.neutral()

HOSTILE = [
    None,
    True,
    False,
    0,
    -1,
    1,
    2,
    10**400,
    1.5,
    -0.0,
    math.nan,
    math.inf,
    -math.inf,
    1e308,
    -1e308,
    np.int64(2),
    np.float32(0.5),
    np.bool_(True),
    "",
    "abc",
    "tool0",
    "joint_1",
    "x",
    "world",
    "local",
    "euler_zyx",
    "quaternion",
    "cartesian",
    "raise",
    "nan",
    "all",
    "\n",
    "a" * 300,
    b"tool0",
    [],
    [0],
    ["tool0"],
    ["x", "x"],
    [None],
    [1.5],
    (0, 1, 2),
    {},
    {"joint_1": 0.5},
    {"joint_1": "0.5"},
    object(),
    np.zeros(3),
    np.zeros(6),
    np.full(6, np.nan),
    np.zeros((2, 6)),
    np.zeros((0, 6)),
    np.eye(4),
    np.random.default_rng(0),
    complex(1, 1),
    slice(None),
    Ellipsis,
]

SKIPPED_METHODS = {"inverse_kinematics", "plot", "view"}
FIXED = {"check_inputs": True}  # check_inputs=False promises valid input: no check by design


def _methods() -> dict[str, inspect.Signature]:
    found = {}
    for name, function in inspect.getmembers(kinengine.Robot, inspect.isfunction):
        if not name.startswith("_") and name not in SKIPPED_METHODS:
            found[name] = inspect.signature(function)
    return found


METHODS = _methods()


@st.composite
def calls(draw, name: str):
    """(args, kwargs) for one call of Robot.<name>: q-like parameters mostly valid, the rest hostile."""
    signature = METHODS[name]
    args, kwargs = [], {}
    for parameter in list(signature.parameters.values())[1:]:
        if parameter.name in FIXED:
            kwargs[parameter.name] = FIXED[parameter.name]
            continue
        required = parameter.default is inspect.Parameter.empty
        if not required and not draw(st.booleans()):
            continue  # keep the default
        if parameter.name in ("q", "qdot", "base") and draw(st.integers(0, 3)):
            value = draw(st.sampled_from([Q0, Q0 + 0.3, np.tile(Q0 + 0.2, (3, 1))]))
        elif parameter.name == "values" and draw(st.booleans()):
            value = {"joint_1": draw(st.sampled_from(HOSTILE))}
        else:
            value = draw(st.sampled_from(HOSTILE))
        if parameter.kind is inspect.Parameter.KEYWORD_ONLY:
            kwargs[parameter.name] = value
        elif required:
            args.append(value)
        else:
            kwargs[parameter.name] = value
    return args, kwargs


def _assert_answer_or_one_line_error(call) -> None:
    try:
        call()
    except KinematicSingularityError:
        pass  # its message is the multi-line singularity report by design
    except KinematicsError as exc:
        assert "\n" not in str(exc), str(exc)


@pytest.mark.parametrize("name", sorted(METHODS))
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_every_public_method_answers_or_raises_a_kinematics_error(name, data):
    args, kwargs = data.draw(calls(name))
    _assert_answer_or_one_line_error(lambda: getattr(ROBOT, name)(*args, **kwargs))


@settings(max_examples=150, deadline=None)
@given(
    kwargs=st.dictionaries(st.sampled_from(["end_effector", "limits"]), st.sampled_from(HOSTILE), max_size=2),
    target=st.sampled_from(
        [
            "abb_irb120",
            "panda",
            "",
            "a" * 300,
            "x.urdf",
            "/",
            "/dev/null",
            "\0",
            "/nonexistent/arm.urdf",
            "abb_irb120\n",
        ]
    ),
)
def test_load_answers_or_raises_a_kinematics_error(target, kwargs):
    _assert_answer_or_one_line_error(lambda: kinengine.load(target, **kwargs))


@settings(max_examples=100, deadline=None)
@given(
    field=st.sampled_from(
        [
            "max_bytes",
            "max_tags",
            "max_depth",
            "max_attribute_length",
            "max_name_length",
            "max_links",
            "max_joints",
            "max_movable_joints",
            "max_tree_depth",
            "max_offset",
            "max_multiplier",
        ]
    ),
    value=st.sampled_from(HOSTILE[:20]) | st.integers(-(10**12), 10**12) | st.floats(),
)
def test_limits_fields_are_checked(field, value):
    _assert_answer_or_one_line_error(lambda: kinengine.urdf.Limits(**{field: value}))


# -- the command line -----------------------------------------------------------------------------------
MALFORMED = [
    "",
    " ",
    "nan",
    "inf",
    "-inf",
    "1e400",
    "-1",
    "0",
    "1_0",
    "1 5",
    "\u0661",
    "\uff11",
    "0x10",
    "abc",
    "\n",
    "a\nb",
    "&#10;",
    "--",
    "-",
    "a" * 300,
    "/dev/full",
    "/",
    ".",
    "/nonexistent/x",
    "1,,2",
    "1,2",
    "0,0,0,0,0,0",
    "1e3",
    "5000",
    "100000000",
    "tool_0",
    "tool0",
    "é",
]
COMMANDS = ("list", "info", "pose", "verify", "show")
SKIPPED_OPTIONS = {
    "-h",
    "--help",
    "--xacro-arg",
    "--package",
}  # help exits 0; xacro options: tests/test_xacro.py


def _options() -> dict[str, list[tuple[str, bool]]]:
    """command -> [(option string, takes a value)] read from the parser itself."""
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    found = {}
    for command in COMMANDS:
        found[command] = [
            (action.option_strings[-1], action.nargs != 0)
            for action in sub.choices[command]._actions
            if action.option_strings
            and action.option_strings[-1] not in SKIPPED_OPTIONS
            and action.option_strings[0] not in SKIPPED_OPTIONS
        ]
    return found


OPTIONS = _options()


@st.composite
def command_lines(draw):
    command = draw(st.sampled_from(COMMANDS))
    argv = [command]
    if command != "list":
        argv.append(draw(st.sampled_from(["abb_irb120", "abb_irb120", "panda", "", "nope", "/", "a" * 300])))
    options = OPTIONS[command] or [("--help", False)]  # `list` takes no options: fuzz its arguments
    if not OPTIONS[command]:
        argv += draw(st.lists(st.sampled_from(MALFORMED), max_size=2))
        return argv
    for option, takes_value in draw(st.lists(st.sampled_from(options), min_size=1, max_size=3)):
        argv.append(option)
        if takes_value and draw(st.integers(0, 9)):
            argv.append(draw(st.sampled_from(MALFORMED)))
    if command == "verify" and "--samples" not in argv:
        argv += ["--samples", "1"]  # keep a run that happens to be valid short
    return argv


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(argv=command_lines())
def test_every_command_with_malformed_flags_exits_0_or_2_with_one_line(argv, capsys, tmp_path_factory):
    folder = tmp_path_factory.mktemp("cli")
    old = os.getcwd()
    os.chdir(folder)  # show writes <robot>.png here when its -o is not given
    try:
        try:
            code = main(argv)
        except SystemExit as exc:
            code = exc.code
    finally:
        os.chdir(old)
    captured = capsys.readouterr()
    assert code in (0, 1, 2), (argv, code, captured.err)
    if code == 1:  # verify: a check failed (the table says which); nothing else exits 1
        assert argv[0] == "verify" and captured.err.count("kinengine: internal error") == 0, captured.err
    if code == 2:
        errors = [line for line in captured.err.splitlines() if not line.startswith("kinengine: warning:")]
        assert len(errors) == 1 and errors[0].startswith("kinengine: error: "), (argv, captured.err)
        assert captured.out == "", argv
    assert "Traceback" not in captured.err
