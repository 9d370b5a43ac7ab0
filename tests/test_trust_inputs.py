"""Controller, model-editing, viewer and command-line inputs at the trust boundary (issue 25 items 3-5)."""

from __future__ import annotations

import numpy as np
import pytest

import kinengine
from kinengine.control import ik_seeds
from kinengine.control.ik import inverse_kinematics

# --- inverse_kinematics targets ----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def abb():
    return kinengine.load("abb_irb120")


def test_complex_targets_are_refused(abb):
    T = abb.frame_pose(abb.neutral())
    for target in (T.astype(complex), T + 1e-3j, [list(row) for row in T.astype(complex)]):
        with pytest.raises(kinengine.ParameterizationError, match="holds complex numbers"):
            abb.inverse_kinematics(target)
    with pytest.raises(kinengine.ParameterizationError, match="holds complex numbers"):
        abb.inverse_kinematics(np.stack([T, T]).astype(complex))
    params = np.array([0.3, 0.0, 0.5, 0.0, 0.0, 0.0]) + 0j
    with pytest.raises(kinengine.ParameterizationError, match="holds complex numbers"):
        abb.inverse_kinematics(params, position="cartesian", rotation="euler_zyx")
    assert abb.inverse_kinematics(T.astype(complex).real).success  # the real part alone is a fine target


@pytest.mark.parametrize("bottom", [[0, 0, 0, 2], [1, 0, 0, 1], [0, 0, 1e-6, 1], [0, 0, 0, 0]])
def test_a_pose_whose_bottom_row_is_not_0001_is_refused(abb, bottom):
    T = abb.frame_pose(abb.neutral())
    bad = T.copy()
    bad[3] = bottom
    with pytest.raises(kinengine.ParameterizationError, match=r"bottom row is .*expected \[0, 0, 0, 1\]"):
        abb.inverse_kinematics(bad)
    with pytest.raises(kinengine.ParameterizationError, match=r"`target`\[1\]'s bottom row"):
        abb.inverse_kinematics(np.stack([T, bad]))


def test_seed_tables_are_bounded(mixed):
    """One table per frame was kept without bound; now one LRU of SEED_TABLES per robot, of at most
    SEED_TABLE_BYTES each, shared by single and batched solves."""
    frames = [f for f in mixed.frame_names if f != mixed.description.root]
    assert len(frames) > ik_seeds.SEED_TABLES
    for frame in frames * 2:
        T = mixed.frame_pose(mixed.neutral(), frame)
        inverse_kinematics(mixed, np.stack([T, T]), frame, max_iterations=1, restarts=1)
        inverse_kinematics(mixed, T, frame, max_iterations=1, restarts=0)
    tables = mixed.engine.memoized("ik seed tables", ik_seeds.SeedTables)
    assert 0 < len(tables.tables) <= ik_seeds.SEED_TABLES
    last = (frames[-1], True, True)
    assert last in tables.tables  # the most recent frame is kept
    for configs, tree in tables.tables.values():
        assert configs.nbytes + tree.data.nbytes <= 2 * ik_seeds.SEED_TABLE_BYTES
    T = mixed.frame_pose(mixed.neutral(), frames[0])  # a dropped table is made again on demand
    assert inverse_kinematics(mixed, np.stack([T, T]), frames[0]).success.all()


# --- model editing ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["tool\x00", "a\x01b", "half\ud800", "x" * 300])
def test_with_frame_names_xml_cannot_hold_are_option_errors(abb, name):
    with pytest.raises(kinengine.OptionError, match="a character XML cannot hold|Limits.max_name_length"):
        abb.with_frame(name, "tool0", np.eye(4))


def test_with_frame_offsets_get_the_urdf_bound(abb):
    """Two frames at 1e308 m gave poses [nan nan -inf]; placements get Limits.max_offset like URDF origins."""
    far = np.eye(4)
    far[:3, 3] = (1e308, 0.0, -1e308)
    with pytest.raises(kinengine.OptionError, match=r"beyond ±1e\+06 m \(Limits.max_offset"):
        abb.with_frame("a", "tool0", far)
    with pytest.raises(kinengine.OptionError, match="Limits.max_offset"):
        abb.with_frame("a", "tool0", ([0.0, 2e6, 0.0], [0.0, 0.0, 0.0]))
    edge = np.eye(4)
    edge[0, 3] = 1e6
    tool = abb.with_frame("a", "tool0", edge).with_frame("b", "a", edge)
    q = abb.neutral()
    expected = abb.frame_pose(q, "tool0") @ edge @ edge
    np.testing.assert_allclose(tool.frame_pose(q, "b"), expected, rtol=1e-12, atol=1e-6)


def test_locking_a_locked_joint_says_it_is_locked(abb):
    locked = abb.locked({"joint_1": 0.1})
    with pytest.raises(kinengine.ConfigurationError, match="joint 'joint_1' is already fixed"):
        locked.locked({"joint_1": 0.2})
    with pytest.raises(kinengine.FrameNotFoundError, match="nope"):
        locked.locked({"nope": 0.2})


# --- robots with 0 and 1 degrees of freedom -----------------------------------------------------------------

_ONE = (
    '<robot name="one"><link name="a"/><link name="b"/><joint name="j" type="{kind}"><parent link="a"/>'
    '<child link="b"/><origin xyz="0 0 0.5"/><axis xyz="{axis}"/>'
    '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>'
)
_ZERO = (
    '<robot name="zero"><link name="a"/><link name="b"/><joint name="f" type="fixed"><parent link="a"/>'
    '<child link="b"/><origin xyz="0 0 0.5"/></joint></robot>'
)


@pytest.mark.parametrize(
    "urdf", [_ZERO, _ONE.format(kind="revolute", axis="0 0 1"), _ONE.format(kind="prismatic", axis="1 0 0")]
)
def test_zero_and_one_dof_robots_through_every_pinocchio_call(urdf):
    """Poses, Jacobians, their derivatives, relative kinematics, manipulability and IK on nv = 0 and nv = 1
    (a subprocess: Pinocchio's C++ could crash), against the closed forms of a joint 0.5 m above the root."""
    import subprocess
    import sys

    code = f"""
import numpy as np, kinengine, warnings
warnings.simplefilter("ignore")
r = kinengine.load_urdf_string({urdf!r})
q = np.full(r.dof, 0.3)
T = r.frame_pose(q, "b")
expected = np.eye(4); expected[2, 3] = 0.5
if r.dof and r.description.joints[0].type == "revolute":
    c, s = np.cos(0.3), np.sin(0.3); expected[:2, :2] = [[c, -s], [s, c]]
elif r.dof:
    expected[0, 3] = 0.3
np.testing.assert_allclose(T, expected, atol=1e-15)
J = r.jacobian(q, "b")
column = [0, 0, 0, 0, 0, 1] if r.dof and r.description.joints[0].type == "revolute" else [1, 0, 0, 0, 0, 0]
np.testing.assert_allclose(J, np.array([column] * r.dof).T.reshape(6, r.dof), atol=1e-15)
assert r.jacobian(np.stack([q, q]), "b").shape == (2, 6, r.dof)
assert r.kinematic_hessian(q, "b").shape[-1] == r.dof
assert r.jacobian_time_variation(q, np.ones(r.dof), "b").shape == (6, r.dof)
assert r.analytic_jacobian(q, "b", position="cartesian", rotation="euler_zyx").shape == (6, r.dof)
np.testing.assert_allclose(r.relative_pose(q, "b", relative_to="a"), expected, atol=1e-15)
assert r.relative_jacobian(q, "b", relative_to="a").shape == (6, r.dof)
assert r.manipulability(q, "b") == 0.0
result = r.inverse_kinematics(T, "b")
assert result.success == (r.dof > 0 or np.allclose(T, expected)), result
assert r.inverse_kinematics(np.stack([T, T]), "b").success.all()
print("done")
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0 and done.stdout.strip() == "done", done.stderr[-2000:]


# --- viewer host and port ------------------------------------------------------------------------------------


@pytest.mark.parametrize("host", [None, "", "   ", 127])
def test_viewer_refuses_an_empty_or_missing_host(abb, host):
    pytest.importorskip("viser")
    from kinengine.presentation.viewer import view

    with pytest.raises(kinengine.OptionError, match="host must be an address to listen on"):
        view(abb, host=host, meshes=False)


@pytest.mark.parametrize("port", [True, False, -1, 65536, 80.0, "8080"])
def test_viewer_ports_are_ints_not_bools(abb, port):
    pytest.importorskip("viser")
    from kinengine.presentation.viewer import view

    with pytest.raises(kinengine.OptionError, match="port must be an integer 0..65535"):
        view(abb, port=port, meshes=False)


@pytest.mark.parametrize(
    "host, fragment",
    [("no-such-host.invalid", "does not resolve"), ("192.0.2.1", "cannot listen on host '192.0.2.1'")],
)
def test_viewer_unresolvable_or_foreign_host_fails_within_seconds(host, fragment):
    """viser retried ports without end; now one OptionError (a subprocess: the old code never returned)."""
    import subprocess
    import sys

    code = f"""
import kinengine
from kinengine.presentation.viewer import view
try:
    view(kinengine.load("abb_irb120"), host={host!r}, meshes=False)
except kinengine.OptionError as exc:
    print(exc)
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    assert fragment in done.stdout


def test_viewer_on_every_interface_warns_and_says_where_it_listens(abb):
    pytest.importorskip("viser")
    from kinengine.presentation.viewer import view

    with pytest.warns(UserWarning, match="listens on every interface") as record:
        viewer = view(abb, host="0.0.0.0", port=0, meshes=False)
    try:
        assert len([w for w in record if "listens on" in str(w.message)]) == 1
        assert "\n" not in str(record[0].message)
        assert viewer.address == "0.0.0.0"
        assert viewer.url == f"http://127.0.0.1:{viewer.port}"
    finally:
        viewer.close()


def test_viewer_on_loopback_is_quiet(abb, recwarn):
    pytest.importorskip("viser")
    from kinengine.presentation.viewer import view

    viewer = view(abb, host="localhost", port=0, meshes=False)
    try:
        assert viewer.address in ("127.0.0.1", "::1")
        assert viewer.url.endswith(f":{viewer.port}")
        assert not [w for w in recwarn if "listens on" in str(w.message)]
    finally:
        viewer.close()


# --- command line ------------------------------------------------------------------------------------------


def test_cli_with_stdout_closed_says_so_in_one_line():
    import os
    import subprocess
    import sys

    done = subprocess.run(
        [sys.executable, "-m", "kinengine", "list"],
        stderr=subprocess.PIPE,
        text=True,
        timeout=120,
        preexec_fn=lambda: os.close(1),  # `kinengine list >&-`
    )
    assert done.returncode == 2
    assert done.stderr.splitlines() == [
        "kinengine: error: standard output is closed; run with an open stdout"
    ]


@pytest.mark.parametrize(
    ("urdf", "name", "dof"), [(_ZERO, "zero", 0), (_ONE.format(kind="revolute", axis="0 0 1"), "one", 1)]
)
def test_cli_bench_on_0_and_1_dof_robots_is_one_line_and_exit_2(tmp_path, capsys, urdf, name, dof):
    from kinengine.cli import main

    path = tmp_path / "small.urdf"
    path.write_text(urdf)
    assert main(["bench", "--quick", str(path)]) == 2
    assert capsys.readouterr().err.splitlines() == [
        f"kinengine: error: {name} has {dof} movable joint(s); kinengine bench times robots with 2 or more"
    ]


def test_cli_view_with_an_empty_host_is_one_line(capsys):
    pytest.importorskip("viser")
    from kinengine.cli import main

    assert main(["view", "abb_irb120", "--host", "", "--no-meshes"]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 1 and "host must be an address to listen on" in lines[0], lines


def test_cli_prints_warnings_of_a_command_that_succeeds(capsys):
    """Warnings are kept until the command ends, then printed one line each (dropped only on an error)."""
    from pathlib import Path

    from kinengine.cli import main

    path = Path(__file__).parent / "data" / "xacro" / "errors" / "emits_warning.xacro"
    assert main(["info", str(path)]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err == [f"kinengine: warning: {path}: xacro: xacro:property: unknown attribute(s): colour"]
