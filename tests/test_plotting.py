"""``kinengine show`` and ``plot_robot``: the PNG is written for every shipped robot, and the numbers the
picture is built from (``ax.kinengine_drawing``) equal the kinematics: skeleton points = link origins of
the independent reference implementation, joint axes = the Jacobian's columns, ellipsoid = SVD of J_v."""

from __future__ import annotations

import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg
import matplotlib.pyplot as plt
import numpy as np
import pytest
from custom_robots import mixed_chain_urdf
from hypothesis import given, settings
from hypothesis import strategies as st

import kinengine
from kinengine.cli import main
from kinengine.model import available_robots, catalog_entry
from kinengine.presentation.plotting import drawing, plot_robot
from kinengine.reference import ReferenceKinematics

SHIPPED = tuple(n for n in available_robots() if catalog_entry(n).origin == "kinengine")
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
LOADERS = {
    **{name: (lambda name=name: kinengine.load(name)) for name in ("abb_irb120", "planar_3dof", "scara")},
    "ur5": lambda: kinengine.load("ur5"),
    "mixed": lambda: kinengine.load_urdf_string(mixed_chain_urdf()),
}


@pytest.fixture(scope="module")
def robots():
    return {name: load() for name, load in LOADERS.items()}


@pytest.fixture(scope="module")
def references(robots):
    return {
        name: ReferenceKinematics.from_urdf_string(r.urdf_text, joint_names=r.joint_names)
        for name, r in robots.items()
    }


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def _show(capsys, *args: str) -> tuple[int, str, str]:
    code = main(["show", *args])
    out, err = capsys.readouterr()
    return code, out, err


# -- the command line ----------------------------------------------------------------------------


@pytest.mark.parametrize("name", SHIPPED)
def test_show_writes_a_png_for_every_shipped_robot(name, tmp_path, capsys, robots):
    path = tmp_path / f"{name}.png"
    q = ",".join(str(v) for v in robots[name].random_configuration(rng=3))
    code, out, _ = _show(
        capsys, name, f"--q={q}", "--ellipsoid", robots[name].end_effector, "-o", str(path), "--dpi", "40"
    )
    assert code == 0 and out.strip() == str(path)
    data = path.read_bytes()
    assert data[:8] == PNG_SIGNATURE and len(data) > 0
    image = mpimg.imread(path)
    assert image.shape == (240, 240, 4)  # 6 x 6 in at 40 dpi, RGBA
    assert image[..., :3].min() < 0.5  # something dark (the links) was drawn


def test_every_shipped_robot_is_covered():
    assert set(SHIPPED) >= {"abb_irb120", "planar_3dof", "scara"}


def test_show_defaults_to_robot_name_png_in_cwd(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    code, out, _ = _show(capsys, "planar_3dof", "--dpi", "30", "--view", "10,-80", "--frames", "")
    assert code == 0 and out.strip() == "planar_3dof.png"
    assert (tmp_path / "planar_3dof.png").read_bytes()[:8] == PNG_SIGNATURE


@pytest.mark.parametrize(
    "args, message",
    [
        (["--q", "0.1,0.2"], "Expected `q` to have shape (3,), got (2,)"),
        (["--q", "0.1,nan,0.2"], "every coordinate must be a finite number"),
        (["--frames", "ee,tool9"], "unknown frame 'tool9'"),
        (["--ellipsoid", "eee"], "unknown frame 'eee'. Did you mean 'ee'"),
        (["--view", "10"], "--view takes two angles ELEV,AZIM"),
        (["-o", "picture.xyz"], "choose another -o PATH"),
    ],
)
def test_show_bad_input_exits_2_with_a_message(args, message, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    code, out, err = _show(capsys, "planar_3dof", *args)
    assert code == 2 and out == ""
    assert err.startswith("kinengine: error: ") and message in err
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    "args, message",
    [
        (
            ["--q", "0.1,a,0.2"],
            "argument --q: expected comma-separated numbers such as 0.1,-0.3,2e-3; entry 2 is 'a'",
        ),
        (["--dpi", "0"], "argument --dpi: expected a whole number in [1, 600], got 0"),
        (["-o", "no/such/dir/x.png"], "folder 'no/such/dir' does not exist"),
    ],
)
def test_show_bad_arguments_are_argparse_errors_before_any_work(args, message, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["show", "planar_3dof", *args])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and message in err


@pytest.mark.slow
def test_importing_kinengine_and_its_cli_does_not_import_matplotlib():
    code = "import sys, kinengine, kinengine.cli; print('matplotlib' in sys.modules)"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "False"


# -- the data the picture is built from ------------------------------------------------------------


@pytest.mark.parametrize("name", list(LOADERS))
@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_skeleton_points_are_the_link_origins(name, seed, robots, references):
    """Segment i runs from the origin of URDF joint i's parent link to its child link's (the joint origin);
    both equal the reference implementation's link poses, and the segments form the tree."""
    robot, ref = robots[name], references[name]
    q = robot.random_configuration(rng=seed)
    d = drawing(robot, q)
    joints = robot.description.joints
    assert d.skeleton.shape == (len(joints), 2, 3) and d.skeleton_joints == tuple(j.name for j in joints)
    origin = {robot.description.root: np.zeros(3)}
    origin.update((j.child, ref.frame_pose(q, j.child)[:3, 3]) for j in joints)
    for (start, end), joint in zip(d.skeleton, joints, strict=False):
        np.testing.assert_allclose(start, origin[joint.parent], rtol=0, atol=1e-12)
        np.testing.assert_allclose(end, origin[joint.child], rtol=0, atol=1e-12)
        np.testing.assert_allclose(end, robot.frame_pose(q, joint.child)[:3, 3], rtol=0, atol=1e-12)
    ends = d.skeleton[:, 1]
    assert np.min(np.linalg.norm(ends - robot.frame_pose(q)[:3, 3], axis=1)) <= 1e-12  # reaches the tool


@pytest.mark.parametrize("name", list(LOADERS))
@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_joint_axes_are_the_jacobian_columns(name, seed, robots):
    """At the joint origin (its child link frame F): a revolute joint's axis is J_lwa(F)'s angular column,
    a prismatic joint's its linear column; a mimic joint's column (in its leader's) is multiplier · axis."""
    robot = robots[name]
    q = robot.random_configuration(rng=seed)
    d = drawing(robot, q)
    movable = [j for j in robot.description.joints if j.movable]
    assert list(d.joint_axes) == [j.name for j in movable]
    for joint in movable:
        origin, direction = d.joint_axes[joint.name]
        np.testing.assert_allclose(origin, robot.frame_pose(q, joint.child)[:3, 3], rtol=0, atol=1e-12)
        J = robot.jacobian(q, joint.child)
        leader = joint.mimic.joint if joint.mimic else joint.name
        rows = slice(0, 3) if joint.type == "prismatic" else slice(3, 6)
        column = J[rows, robot.joint_names.index(leader)]
        multiplier = joint.mimic.multiplier if joint.mimic else 1.0
        np.testing.assert_allclose(column, multiplier * direction, rtol=0, atol=1e-12)
        assert abs(np.linalg.norm(direction) - 1.0) <= 1e-12


@pytest.mark.parametrize(
    "name, frame",
    [
        ("abb_irb120", "tool0"),
        ("scara", "ee"),
        ("planar_3dof", "ee"),
        ("ur5", "tool0"),
        ("mixed", "finger_b"),
    ],
)
def test_ellipsoid_is_the_svd_of_the_translational_jacobian(name, frame, robots):
    robot = robots[name]
    for seed in range(5):
        q = robot.random_configuration(rng=seed)
        d = drawing(robot, q, ellipsoid=frame)
        e = d.ellipsoid
        Jv = robot.jacobian(q, frame)[:3]
        s = np.linalg.svd(Jv, compute_uv=False)
        np.testing.assert_allclose(e.center, robot.frame_pose(q, frame)[:3, 3], rtol=0, atol=1e-12)
        np.testing.assert_allclose(e.semi_axes[: s.size], s, rtol=0, atol=1e-12)
        np.testing.assert_allclose(e.semi_axes[s.size :], 0.0, rtol=0, atol=0)
        np.testing.assert_allclose(e.axes.T @ e.axes, np.eye(3), rtol=0, atol=1e-12)
        np.testing.assert_allclose(e.axes @ np.diag(e.semi_axes**2) @ e.axes.T, Jv @ Jv.T, rtol=0, atol=1e-12)
        assert d.ellipsoid_frame == frame and d.ellipsoid_scale > 0


def test_planar_arm_ellipse_closed_form(robots):
    """planar_3dof moves ee in the x-z plane: J_v J_vᵀ has no y row, so the third semi-axis is 0 along y."""
    robot = robots["planar_3dof"]
    q = np.array([0.9, -1.6, 0.8])
    e = drawing(robot, q, ellipsoid="ee").ellipsoid
    l1, l2, l3 = 0.5, 0.35, 0.2
    c = np.cumsum(q)
    x_row = np.array(
        [
            l1 * np.cos(c[0]) + l2 * np.cos(c[1]) + l3 * np.cos(c[2]),
            l2 * np.cos(c[1]) + l3 * np.cos(c[2]),
            l3 * np.cos(c[2]),
        ]
    )
    z_row = -np.array(
        [
            l1 * np.sin(c[0]) + l2 * np.sin(c[1]) + l3 * np.sin(c[2]),
            l2 * np.sin(c[1]) + l3 * np.sin(c[2]),
            l3 * np.sin(c[2]),
        ]
    )
    np.testing.assert_allclose(
        e.semi_axes[:2], np.linalg.svd(np.stack([x_row, z_row]), compute_uv=False), rtol=0, atol=1e-12
    )
    assert e.semi_axes[2] == 0.0
    np.testing.assert_allclose(np.abs(e.axes[:, 2]), [0.0, 1.0, 0.0], rtol=0, atol=1e-12)


# -- the picture ---------------------------------------------------------------------------------


def test_plot_robot_draws_its_drawing_with_equal_scales_and_a_title(robots):
    robot = robots["abb_irb120"]
    ax = plot_robot(robot, frames=["tool0", "base"], ellipsoid="tool0")
    d = ax.kinengine_drawing
    reference = drawing(robot, robot.neutral(), frames=["tool0", "base"], ellipsoid="tool0")
    np.testing.assert_array_equal(d.skeleton, reference.skeleton)
    assert list(d.frames) == ["tool0", "base"]
    np.testing.assert_array_equal(d.frames["tool0"], robot.frame_pose(robot.neutral(), "tool0"))
    # tool0 at home: p = (0.374, 0, 0.630) m, pitched by π/2 about y
    assert ax.get_title() == (
        "abb_irb120 at q = (0, 0, 0, 0, 0, 0) [rad]\n"
        "tool0 in base_link: p = (0.374, 0.000, 0.630) m, rotation vector "
        "(0.000, 1.571, 0.000) rad"
    )
    limits = np.array([ax.get_xlim(), ax.get_ylim(), ax.get_zlim()])
    np.testing.assert_allclose(np.diff(limits, axis=1), np.diff(limits[0])[0], rtol=1e-12)
    np.testing.assert_allclose(ax.get_box_aspect() / ax.get_box_aspect()[0], 1.0, rtol=1e-12)
    points = d.skeleton.reshape(-1, 3)
    assert np.all((points >= limits[:, 0]) & (points <= limits[:, 1]))
    labels = ax.get_legend_handles_labels()[1]
    assert (
        f"velocity ellipsoid of tool0, ×{d.ellipsoid_scale:g} (1 m/s per unit $|\\dot{{q}}|$ drawn as "
        f"{d.ellipsoid_scale:g} m)" in labels
    )
    assert "revolute joint axes" in labels and "prismatic joint axes" not in labels
    assert {t.get_text() for t in ax.texts} == {"tool0", "base"}


def test_plot_robot_into_given_axes_with_options(robots):
    robot = robots["scara"]
    fig = plt.figure()
    ax3d = fig.add_subplot(projection="3d")
    q = np.array([0.4, 0.8, -0.5, 0.1])
    ax = plot_robot(robot, q, ax3d, frames="ee", axis_length=0.05, title="my scara")
    assert ax is ax3d and ax.get_title() == "my scara" and ax.kinengine_drawing.axis_length == 0.05
    assert "prismatic joint axes" in ax.get_legend_handles_labels()[1]
    assert plot_robot(robot, q, fig.add_subplot(2, 2, 4, projection="3d"), title=False).get_title() == ""


def test_plot_robot_title_of_scara_names_both_units(robots):
    title = drawing(robots["scara"], [0.4, 0.8, -0.5, 0.1]).title
    assert title.startswith("scara at q = (0.4, 0.8, -0.5, 0.1) [rad, m]\nee in base_link: p = ")


@pytest.mark.parametrize(
    "call, error, message",
    [
        (
            lambda r: plot_robot(r, np.zeros((2, 6))),
            kinengine.ConfigurationError,
            r"shape \(6,\), got \(2, 6\); this function takes one configuration",
        ),
        (lambda r: plot_robot(r, [0.1] * 5), kinengine.ConfigurationError, r"shape \(6,\)"),
        (lambda r: plot_robot(r, frames=["tool00"]), kinengine.FrameNotFoundError, "Did you mean 'tool0'"),
        (lambda r: plot_robot(r, ellipsoid="flang"), kinengine.FrameNotFoundError, "Did you mean 'flange'"),
        (lambda r: plot_robot(r, axis_length=-1.0), kinengine.KinematicsError, "positive length"),
        (lambda r: plot_robot(r, ax=plt.figure().add_subplot()), kinengine.KinematicsError, "3D axes"),
    ],
)
def test_plot_robot_bad_input(call, error, message, robots):
    with pytest.raises(error, match=message):
        call(robots["abb_irb120"])


def test_robot_plot_method_delegates(robots):
    """robot.plot (the Robot wrapper; see the issue 8 report) returns plot_robot's axes."""
    robot = robots["abb_irb120"]
    if not hasattr(robot, "plot"):
        pytest.skip("Robot.plot not pasted into kinengine/robot.py yet")
    q = robot.random_configuration(rng=7)
    ax = robot.plot(q, frames=["tool0"], ellipsoid="tool0")
    d = ax.kinengine_drawing
    np.testing.assert_array_equal(d.q, q)
    np.testing.assert_array_equal(d.skeleton, drawing(robot, q).skeleton)
    np.testing.assert_array_equal(d.ellipsoid.semi_axes, robot.velocity_ellipsoid(q, "tool0").semi_axes)
