"""Every public entry point that takes a configuration q (or a velocity q̇) against every kind of input.

Each (entry point, input) pair has one defined outcome:

* refused: exactly ``ConfigurationError`` (a KinematicsError and a ValueError) whose message names
  the argument (`q`, `qdot`, `q0`, `base`) and the problem;
* accepted (lists, tuples, ints, float32, object arrays of numbers, strided, reversed, big-endian,
  read-only, Fortran-ordered): exactly the answer of the same values as a contiguous float64 array,
  and the input is left unchanged;
* batches (N, dof): row i of the answer equals the single call at row i where the entry point takes
  batches; a ConfigurationError saying it takes one configuration where it does not.

The single checking point is ``kinengine.joint_space.JointSpace.check``; the robot is the ABB IRB 120
(6 revolute joints) and, for the continuous-joint and mimic paths, tests/custom_robots.py's chain.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pytest

import kinengine
from kinengine.cli import main as cli_main

Q = np.array([0.1, -0.2, 0.3, 0.4, -0.5, 0.6])  # [rad], within the IRB 120's limits, regular
QDOT = np.array([-0.5, -0.3, -0.1, 0.1, 0.3, 0.5])  # [rad/s]
INTS = [1, 1, -1, 1, 1, -1]  # [rad], regular too


def _task(robot, q, qdot):
    task = robot.task(robot.end_effector, rotation="quaternion")
    task.update(q, qdot)
    return np.concatenate(
        [
            task.pose.ravel(),
            task.chi,
            task.jacobian.ravel(),
            task.analytic_jacobian.ravel(),
            task.twist,
            task.jacobian_dot.ravel(),
        ]
    )


def _ellipsoid(e) -> np.ndarray:
    return np.concatenate([e.center, e.axes.ravel(), e.semi_axes])


@dataclass(frozen=True)
class EntryPoint:
    """``call(robot, x)`` with x in the place of argument ``name``; ``batch``: takes (N, dof);
    ``default_on_none``: None is a legal value there (no q̇, default start, neutral base)."""

    id: str
    call: Callable
    name: str = "q"
    batch: bool = False
    default_on_none: bool = False

    def __call__(self, robot, x) -> np.ndarray:
        return np.asarray(self.call(robot, x))


def _target(robot):
    return robot.frame_pose(robot.random_configuration(7))


ENTRY_POINTS = [
    EntryPoint("frame_pose", lambda r, x: r.frame_pose(x), batch=True),
    EntryPoint("jacobian_local_world_aligned", lambda r, x: r.jacobian(x), batch=True),
    EntryPoint("jacobian_local", lambda r, x: r.jacobian(x, None, "local"), batch=True),
    EntryPoint("jacobian_world", lambda r, x: r.jacobian(x, None, "world"), batch=True),
    EntryPoint(
        "analytic_jacobian", lambda r, x: r.analytic_jacobian(x, None, "spherical", "quaternion"), batch=True
    ),
    EntryPoint(
        "pose_parameters", lambda r, x: r.pose_parameters(x, None, "cylindrical", "euler_zyz"), batch=True
    ),
    EntryPoint("task_update_q", lambda r, x: _task(r, x, None)),
    EntryPoint("task_update_qdot", lambda r, x: _task(r, Q[: r.dof], x), name="qdot", default_on_none=True),
    EntryPoint(
        "jacobian_time_variation_q", lambda r, x: r.jacobian_time_variation(x, QDOT[: r.dof], None, "local")
    ),
    EntryPoint(
        "jacobian_time_variation_qdot",
        lambda r, x: r.jacobian_time_variation(Q[: r.dof], x, None, "local"),
        name="qdot",
    ),
    EntryPoint("kinematic_hessian", lambda r, x: r.kinematic_hessian(x, None, "local")),
    EntryPoint("analytic_hessian", lambda r, x: r.analytic_hessian(x, None, "spherical", "quaternion")),
    EntryPoint("singularity_report", lambda r, x: r.singularity_report(x).singular_values),
    EntryPoint("manipulability", lambda r, x: r.manipulability(x), batch=True),
    EntryPoint("velocity_ellipsoid", lambda r, x: _ellipsoid(r.velocity_ellipsoid(x))),
    EntryPoint("require_regular", lambda r, x: r.require_regular(x).singular_values),
    EntryPoint(
        "inverse_kinematics_q0",
        lambda r, x: r.inverse_kinematics(_target(r), q0=x, rng=0).q,
        name="q0",
        default_on_none=True,
    ),
    EntryPoint(
        "configuration_base", lambda r, x: r.configuration({}, base=x), name="base", default_on_none=True
    ),
    EntryPoint("check_configuration", lambda r, x: r.check_configuration(x, check_limits=False), batch=True),
]
IDS = [e.id for e in ENTRY_POINTS]


def _masked():
    return np.ma.masked_array(Q, mask=[0, 1, 0, 0, 0, 0])


# (id, input, message): refused by every entry point; {name} stands for the argument's name
REFUSED = [
    ("wrong_length", np.zeros(5), r"Expected `{name}` to have shape \(6,\)( or \(N, 6\))?, got \(5,\)$"),
    ("too_long_list", [0.0] * 7, r"Expected `{name}` to have shape \(6,\)( or \(N, 6\))?, got \(7,\)$"),
    ("3d", np.zeros((2, 3, 6)), r"Expected `{name}` to have shape .*, got \(2, 3, 6\)$"),
    ("column", np.zeros((6, 1)), r"Expected `{name}` to have shape .*, got \(6, 1\)$"),
    ("scalar", 3.0, r"Expected `{name}` to have shape .*, got \(\)$"),
    ("empty_array", np.zeros(0), r"Expected `{name}` to have shape .*, got \(0,\)$"),
    ("empty_list", [], r"Expected `{name}` to have shape .*, got \(0,\)$"),
    (
        "nan",
        np.array([0, 0, np.nan, 0, 0, 0]),
        r"`{name}`\[2\] \(joint 'joint_3'\) is nan: every coordinate must "
        r"be a finite number",
    ),
    ("plus_inf", np.array([0, 0, 0, np.inf, 0, 0]), r"`{name}`\[3\] \(joint 'joint_4'\) is inf"),
    ("minus_inf", [0, 0, 0, 0, 0, -np.inf], r"`{name}`\[5\] \(joint 'joint_6'\) is -inf"),
    (
        "nan_float32",
        np.array([np.nan] + [0] * 5, dtype=np.float32),
        r"`{name}`\[0\] \(joint 'joint_1'\) is nan",
    ),
    ("string", "0,0,0,0,0,0", r"Expected `{name}` to be numeric with shape .*, got a string"),
    ("bytes", b"\x00" * 6, r"Expected `{name}` to be numeric with shape .*, got a string"),
    ("str_array", np.array(["0"] * 6), r"Expected `{name}` to hold real numbers .*, got dtype <U1"),
    ("list_of_strings", ["0.1"] * 6, r"Expected `{name}` to hold real numbers .*, got dtype <U3"),
    (
        "object_array_of_strings",
        np.array(["a"] * 6, dtype=object),
        "an object array with non-numeric entries",
    ),
    (
        "object_array_with_none",
        np.array([0.0, None, 0, 0, 0, 0], dtype=object),
        "an object array with None entries",
    ),
    ("list_with_none", [0.0, 0.0, None, 0.0, 0.0, 0.0], "an object array with None entries"),
    ("dict", {"joint_1": 0.1}, "got a dict with non-numeric entries"),
    ("set", set(range(6)), "got a set with non-numeric entries"),
    ("ragged", [[0.0] * 6, [0.0] * 5], r"Expected `{name}` to be numeric with shape .*inhomogeneous"),
    ("complex", Q.astype(complex), r"got dtype complex128"),
    ("bool", np.ones(6, dtype=bool), r"got dtype bool"),
    ("list_of_bools", [True, False] * 3, r"got dtype bool"),
    ("datetime", np.zeros(6, dtype="datetime64[s]"), r"got dtype datetime64\[s\]"),
    ("structured", np.zeros(6, dtype=[("a", float)]), r"got dtype \[\('a', '<f8'\)\]"),
    ("huge_python_int", [10**400] + [0] * 5, "with a number too large for a float64"),
    ("masked", _masked(), "a masked array with masked entries; fill them"),
]
REFUSED_IDS = [r[0] for r in REFUSED]


@pytest.mark.parametrize("case", REFUSED, ids=REFUSED_IDS)
@pytest.mark.parametrize("entry", ENTRY_POINTS, ids=IDS)
def test_bad_input_is_refused_with_a_configuration_error_naming_the_problem(abb, entry, case):
    _, value, message = case
    with pytest.raises(kinengine.ConfigurationError) as info:
        entry(abb, value)
    assert type(info.value) is kinengine.ConfigurationError
    assert isinstance(info.value, ValueError)
    assert re.search(message.format(name=re.escape(entry.name)), str(info.value)), str(info.value)


@pytest.mark.parametrize("entry", ENTRY_POINTS, ids=IDS)
def test_none_is_refused_or_means_the_documented_default(abb, entry):
    if entry.default_on_none:  # Task.update(q) without q̇, IK from its own seeds, the neutral base
        expected = {
            "qdot": lambda: _task(abb, Q, None),
            "q0": lambda: entry(abb, None),
            "base": lambda: abb.neutral(),
        }[entry.name]()
        np.testing.assert_array_equal(entry(abb, None), expected)
        return
    with pytest.raises(
        kinengine.ConfigurationError,
        match=rf"Expected `{entry.name}` to be an array of shape "
        r"\(6,\)( or \(N, 6\))?, got None",
    ):
        entry(abb, None)


def _accepted(v: np.ndarray) -> dict[str, object]:
    """Inputs carrying the values of v (float64 (dof,)) that every entry point accepts."""
    strided = np.zeros(2 * v.size)
    strided[::2] = v
    readonly = v.copy()
    readonly.flags.writeable = False
    wide = np.zeros((3, v.size), order="F")
    wide[1] = v
    return {
        "list": v.tolist(),
        "tuple": tuple(v.tolist()),
        "float64": v.copy(),
        "read_only": readonly,
        "strided_view": strided[::2],
        "reversed_view": v[::-1].copy()[::-1],
        "row_of_fortran_array": wide[1],
        "big_endian": v.astype(">f8"),
        "float32": v.astype(np.float32),
        "float16": v.astype(np.float16),
        "int64": np.array(INTS[: v.size]),
        "int32": np.array(INTS[: v.size], np.int32),
        "uint8": np.array([1, 1, 1, 1, 1, 2][: v.size], np.uint8),
        "list_of_ints": INTS[: v.size],
        "object_array_of_floats": v.astype(object),
        "numpy_scalars": [np.float32(x) for x in v],
        "masked_without_masked_entries": np.ma.masked_array(v, mask=np.zeros(v.size, bool)),
    }


def _snapshot(x: object) -> tuple:
    return (type(x), np.array(x, dtype=float).tobytes(), getattr(x, "flags", None) and x.flags.writeable)


@pytest.mark.parametrize("variant", list(_accepted(Q)))
@pytest.mark.parametrize("entry", ENTRY_POINTS, ids=IDS)
def test_accepted_inputs_give_the_float64_answer_and_are_left_unchanged(abb, entry, variant):
    x = _accepted(QDOT if entry.name == "qdot" else Q)[variant]
    before = _snapshot(x)
    expected = entry(abb, np.ascontiguousarray(np.asarray(x, dtype=np.float64)))
    result = entry(abb, x)
    np.testing.assert_array_equal(result, expected)
    assert result.dtype == np.float64
    assert _snapshot(x) == before
    if isinstance(x, np.ndarray):
        assert not np.shares_memory(result, x)


def test_float32_and_int_answers_equal_the_float64_answers_of_the_same_values(abb):
    q32 = Q.astype(np.float32)
    np.testing.assert_array_equal(abb.frame_pose(q32), abb.frame_pose(q32.astype(np.float64)))
    np.testing.assert_allclose(abb.frame_pose(q32), abb.frame_pose(Q), rtol=0, atol=1e-6)  # float32 rounding
    np.testing.assert_array_equal(abb.jacobian(np.arange(6) % 2), abb.jacobian(np.arange(6.0) % 2))


@pytest.mark.parametrize(
    "entry",
    [
        e
        for e in ENTRY_POINTS
        if e.id
        in (
            "frame_pose",
            "jacobian_local",
            "analytic_jacobian",
            "task_update_q",
            "task_update_qdot",
            "jacobian_time_variation_qdot",
            "kinematic_hessian",
            "inverse_kinematics_q0",
            "configuration_base",
        )
    ],
    ids=lambda e: e.id,
)
@pytest.mark.parametrize("variant", ["list", "strided_view", "read_only", "big_endian", "float32", "int64"])
def test_continuous_and_mimic_joints_take_the_same_inputs(mixed, entry, variant):
    # the continuous joint is mapped to (cos, sin) in joint_space.to_pinocchio: another path than the IRB 120's
    v = np.array([0.3, 2.0, 0.1, -0.4, 0.2, 0.5]) if entry.name != "qdot" else QDOT
    x = _accepted(v)[variant]
    before = _snapshot(x)
    np.testing.assert_array_equal(entry(mixed, x), entry(mixed, np.asarray(x, dtype=np.float64)))
    assert _snapshot(x) == before


# -- batches -----------------------------------------------------------------------------------------------
BATCH = np.array([Q, Q[::-1] * 0.5, Q * -0.7])


def _batches() -> dict[str, object]:
    strided = np.zeros((6, 12))
    strided[::2, ::2] = BATCH
    readonly = BATCH.copy()
    readonly.flags.writeable = False
    return {
        "float64": BATCH.copy(),
        "fortran_order": np.asfortranarray(BATCH),
        "strided_view": strided[::2, ::2],
        "read_only": readonly,
        "list_of_lists": BATCH.tolist(),
        "tuple_of_arrays": tuple(BATCH),
        "float32": BATCH.astype(np.float32),
        "int64": np.round(BATCH * 3).astype(np.int64),
        "one_row": BATCH[:1].copy(),
    }


@pytest.mark.parametrize("variant", list(_batches()))
@pytest.mark.parametrize("entry", [e for e in ENTRY_POINTS if e.batch], ids=lambda e: e.id)
def test_batches_give_one_answer_per_row(abb, entry, variant):
    x = _batches()[variant]
    before = _snapshot(x)
    values = np.ascontiguousarray(np.asarray(x, dtype=np.float64))
    result = entry(abb, x)
    assert result.shape[0] == len(values)
    np.testing.assert_array_equal(result, entry(abb, values))
    for i, row in enumerate(values):
        np.testing.assert_allclose(result[i], entry(abb, row), rtol=0, atol=1e-12)
    assert _snapshot(x) == before


@pytest.mark.parametrize("entry", [e for e in ENTRY_POINTS if e.batch], ids=lambda e: e.id)
def test_a_bad_row_in_a_batch_is_named_and_an_empty_batch_refused(abb, entry):
    bad = BATCH.copy()
    bad[2, 4] = np.nan
    with pytest.raises(kinengine.ConfigurationError, match=r"`q`\[2, 4\] \(joint 'joint_5'\) is nan"):
        entry(abb, bad)
    with pytest.raises(
        kinengine.ConfigurationError,
        match=r"Expected `q` to have shape \(6,\) or \(N, 6\), "
        r"got \(3, 5\)$",
    ):
        entry(abb, BATCH[:, :5])
    with pytest.raises(
        kinengine.ConfigurationError,
        match=r"at least one configuration, got an empty batch "
        r"\(0, 6\)",
    ):
        entry(abb, np.zeros((0, 6)))


@pytest.mark.parametrize("entry", [e for e in ENTRY_POINTS if not e.batch], ids=lambda e: e.id)
@pytest.mark.parametrize("shape", [(3, 6), (1, 6), (0, 6)])
def test_entry_points_without_batches_say_so(abb, entry, shape):
    with pytest.raises(
        kinengine.ConfigurationError,
        match=rf"Expected `{entry.name}` to have shape \(6,\), got \({shape[0]}, 6\); this function "
        "takes one configuration: call it once per row",
    ):
        entry(abb, np.zeros(shape))


# -- joint limits on request -----------------------------------------------------------------------------
CHECKS_LIMITS = [
    ("frame_pose", lambda r, q, **k: r.frame_pose(q, **k)),
    ("jacobian", lambda r, q, **k: r.jacobian(q, None, "local", **k)),
    ("pose_parameters", lambda r, q, **k: r.pose_parameters(q, rotation="quaternion", **k)),
    ("analytic_jacobian", lambda r, q, **k: r.analytic_jacobian(q, rotation="quaternion", **k)),
    ("check_configuration", lambda r, q, **k: r.check_configuration(q, **k)),
]


@pytest.mark.parametrize("call", [c[1] for c in CHECKS_LIMITS], ids=[c[0] for c in CHECKS_LIMITS])
def test_check_limits_names_the_joint_the_value_and_the_limits(abb, call):
    outside = Q.copy()
    outside[2] = 1.5  # joint_3: [-1.91986, 1.22173] rad
    with pytest.raises(
        kinengine.ConfigurationError,
        match=r"^`q` puts joint 'joint_3' at 1.5, outside its limits \[-1.91986, 1.22173\]; "
        r"clip q or pass check_limits=False$",
    ):
        call(abb, outside, check_limits=True)
    batch = np.array([Q, Q, Q])
    batch[1, 5] = -7.0  # joint_6: [-6.98132, 6.98132] rad
    with pytest.raises(
        kinengine.ConfigurationError,
        match=r"^`q`\[1\] puts joint 'joint_6' at -7.0, outside its limits \[-6.98132, 6.98132\]",
    ):
        call(abb, batch, check_limits=True)
    limits = np.array([abb.lower_limits, abb.upper_limits])  # the limits themselves are inside
    np.testing.assert_array_equal(call(abb, limits, check_limits=True), call(abb, limits, check_limits=False))
    with pytest.raises(kinengine.ConfigurationError, match="is nan"):  # finiteness is checked first
        call(abb, np.full(6, np.nan), check_limits=True)


@pytest.mark.parametrize("call", [c[1] for c in CHECKS_LIMITS[:4]], ids=[c[0] for c in CHECKS_LIMITS[:4]])
def test_limits_are_not_checked_unless_asked_and_continuous_joints_have_none(abb, mixed, call):
    outside = Q.copy()
    outside[2] = 1.5
    np.testing.assert_array_equal(call(abb, outside), call(abb, outside, check_limits=False))
    q = np.array([0.3, 0.2, 100.0, 0.1, 0.2, 0.5])  # 'spin' is continuous: ±inf limits
    assert mixed.joint_names[2] == "spin"
    np.testing.assert_array_equal(call(mixed, q, check_limits=True), call(mixed, q))


def test_check_configuration_checks_limits_by_default(abb):
    outside = Q.copy()
    outside[0] = 3.0
    with pytest.raises(kinengine.ConfigurationError, match="joint 'joint_1' at 3.0, outside its limits"):
        abb.check_configuration(outside)


def test_check_configuration_returns_a_fresh_contiguous_float64_copy(abb):
    q = Q.copy()
    out = abb.check_configuration(q)
    np.testing.assert_array_equal(out, q)
    assert not np.shares_memory(out, q)
    with pytest.raises(kinengine.ConfigurationError, match="one configuration"):
        abb.check_configuration(np.stack([Q, Q]), batch=False)
    for x in _accepted(Q).values():
        out = abb.check_configuration(x, check_limits=False)
        assert out.dtype == np.float64 and out.flags.c_contiguous and out.shape == (6,)


# -- the command line ------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "text, message",
    [
        ("nan,0,0,0,0,0", r"`q`\[0\] \(joint 'joint_1'\) is nan: every coordinate must be a finite number"),
        ("0,0,0,-inf,0,0", r"`q`\[3\] \(joint 'joint_4'\) is -inf"),
        ("1e400,0,0,0,0,0", r"`q`\[0\] \(joint 'joint_1'\) is inf"),  # float('1e400') overflows to inf
        ("0.1,0.2", r"Expected `q` to have shape \(6,\).*got \(2,\)"),
        ("0,0,0,0,0,0,0", r"got \(7,\)"),
    ],
)
def test_cli_pose_refuses_bad_q_with_one_line_and_status_2(capsys, text, message):
    assert cli_main(["pose", "abb_irb120", "--q", text]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("kinengine: error: "), captured.err
    assert re.search(message, lines[0]), lines[0]


@pytest.mark.parametrize(
    "text",
    [
        "a,b,c,d,e,f",
        "0x1,0,0,0,0,0",
        "1;2;3;4;5;6",
        "",
        "1,,0,0,0,0,0",
        "1 5,0,0,0,0,0",
        "1_0,0,0,0,0,0",
        "\u0661,0,0,0,0,0",
        "\uff11,0,0,0,0,0",
        "0.5\u00a0,0,0,0,0,0",
    ],
)
def test_cli_pose_refuses_non_numbers_before_loading(capsys, text):
    # strict float literals (ASCII, no underscores, no inner spaces): "1 5" is not 15, "1_0" not 10
    with pytest.raises(SystemExit) as info:
        cli_main(["pose", "abb_irb120", "--q", text])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1
    assert "argument --q: expected comma-separated numbers such as 0.1,-0.3,2e-3; entry" in err


def test_cli_pose_integers_give_the_float_answer(capsys):
    assert cli_main(["pose", "abb_irb120", "--q", "1,0,-1,1,0,1", "--rotation", "quaternion"]) == 0
    with_ints = capsys.readouterr().out
    assert (
        cli_main(["pose", "abb_irb120", "--q", "1.0, 0.0, -1.0, 1.0, 0.0, 1.0", "--rotation", "quaternion"])
        == 0
    )
    assert capsys.readouterr().out == with_ints
    assert "q [rad | m] = [ 1.  0. -1.  1.  0.  1.]" in with_ints


@pytest.mark.parametrize(
    "argv", [["--q", "-0.5,0.2,0,0,0.3,0"], ["--q=-0.5,0.2,0,0,0.3,0"], ["--q", "-.5,.2,0,0,.3,0"]]
)
def test_cli_q_may_start_with_a_minus_sign(capsys, argv):
    assert cli_main(["pose", "abb_irb120", *argv]) == 0
    out = capsys.readouterr().out
    assert "q [rad | m] = [-0.5  0.2  0.   0.   0.3  0. ]" in out
