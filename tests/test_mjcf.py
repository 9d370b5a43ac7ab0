"""MJCF models through MuJoCo's own compiler (issue 32): kinengine's poses and Jacobians against MuJoCo's
own ``mj_kinematics`` / ``mj_jacBody`` / ``mj_jacSite`` run directly, closed forms for the joint anchors,
``kinengine verify`` on the URDF kinengine writes, and every refusal."""

from __future__ import annotations

import math
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import kinengine
from kinengine import MJCFError, URDFError
from kinengine.cli import main
from kinengine.mjcf.crosscheck import cross_check
from kinengine.urdf import Limits
from kinengine.verify import verify

mujoco = pytest.importorskip("mujoco")

DATA = Path(__file__).parent / "data" / "mjcf"
FEATURES = DATA / "features.xml"
TWO_TREES = DATA / "two_trees.xml"
KINEMATICS_ONLY = DATA / "kinematics_only.xml"


def _load(path: Path, **kwargs: object) -> kinengine.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return kinengine.load(path, **kwargs)


def _write(tmp_path: Path, body: str, extra: str = "", name: str = "robot.xml") -> Path:
    path = tmp_path / name
    path.write_text(f'<mujoco model="t"><worldbody>{body}</worldbody>{extra}</mujoco>', encoding="utf-8")
    return path


ARM = '<body name="b" pos="0 0 0.1"><joint name="j" axis="0 0 1" range="-1 1"/><geom size=".05"/></body>'


# -- against MuJoCo's own kinematics -----------------------------------------------------------------
@pytest.mark.parametrize("path, root", [(FEATURES, None), (TWO_TREES, None), (TWO_TREES, "table")])
def test_every_body_and_site_pose_and_jacobian_equals_mujoco(path, root):
    robot = _load(path, root=root)
    check = cross_check(robot, samples=20, seed=1)
    model = mujoco.MjModel.from_xml_path(str(path))
    assert check.configurations == 21
    assert check.position <= 1e-12 and check.rotation <= 1e-12 and check.jacobian <= 1e-12
    if path == FEATURES:  # every body (but the world) and every site is compared
        assert check.frames == model.nbody - 1 + model.nsite


def test_a_kinematics_only_file_loads_and_its_poses_equal_mujocos():
    """Bodies, joints and a site without any geom or inertial: MuJoCo refuses it as it stands (no mass),
    kinengine compiles it with tiny mass bounds; poses are MuJoCo's mj_kinematics of that compiled model."""
    with pytest.raises(ValueError, match="mass and inertia of moving bodies"):
        mujoco.MjModel.from_xml_path(str(KINEMATICS_ONLY))
    robot = _load(KINEMATICS_ONLY)
    spec = mujoco.MjSpec.from_file(str(KINEMATICS_ONLY))
    spec.compiler.boundmass = spec.compiler.boundinertia = 1e-12
    model = spec.compile()
    data = mujoco.MjData(model)
    assert robot.joint_names == ("j1", "j2", "j3", "j4") and model.nq == 4
    for q in robot.random_configuration(7, size=10):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        for b in range(1, model.nbody):
            T = robot.frame_pose(q, model.body(b).name)
            np.testing.assert_allclose(T[:3, 3], data.xpos[b], rtol=0, atol=1e-12)
            np.testing.assert_allclose(T[:3, :3], data.xmat[b].reshape(3, 3), rtol=0, atol=1e-12)
        T = robot.frame_pose(q, "tool")
        np.testing.assert_allclose(T[:3, 3], data.site_xpos[0], rtol=0, atol=1e-12)
        np.testing.assert_allclose(T[:3, :3], data.site_xmat[0].reshape(3, 3), rtol=0, atol=1e-12)
    report = verify(robot, samples=5)
    assert report.passed, report.table()
    assert main(["verify", str(KINEMATICS_ONLY), "--samples", "3"]) == 0


def test_a_file_that_zeroes_the_mass_bounds_is_told_the_fix(tmp_path):
    path = tmp_path / "zero.xml"
    text = KINEMATICS_ONLY.read_text().replace('angle="radian"', 'angle="radian" boundmass="0"')
    path.write_text(text)
    with pytest.raises(MJCFError, match=r"mass and inertia .*sets <compiler> boundmass: remove it") as caught:
        kinengine.load(path)
    assert caught.value.source == str(path)


def test_a_site_pose_and_jacobian_by_hand_at_one_configuration():
    """The same comparison written out against MuJoCo for one site, with the mimic coupling in the columns."""
    robot = _load(FEATURES)
    model = mujoco.MjModel.from_xml_path(str(FEATURES))
    data = mujoco.MjData(model)
    q = robot.configuration({"j1": 0.4, "j2": -0.3, "j3": 0.05, "j4": 2.5, "fa": 0.01})
    for name, value in zip(robot.joint_names, q, strict=True):
        data.joint(name).qpos = value
    data.joint("fb").qpos = 0.01 + 0.005 - 1.5 * (q[robot.joint_names.index("fa")] - 0.0)  # polycoef
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)
    T = robot.frame_pose(q, "fb_tip")
    np.testing.assert_allclose(T[:3, 3], data.site("fb_tip").xpos, rtol=0, atol=1e-12)
    np.testing.assert_allclose(T[:3, :3], data.site("fb_tip").xmat.reshape(3, 3), rtol=0, atol=1e-12)
    jacp, jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    mujoco.mj_jacSite(model, data, jacp, jacr, model.site("fb_tip").id)
    jac = np.vstack([jacp, jacr])
    dof = {name: model.joint(name).dofadr[0] for name in ("j1", "j2", "j3", "j4", "fa", "fb")}
    expected = np.column_stack([jac[:, dof[n]] for n in robot.joint_names])
    expected[:, robot.joint_names.index("fa")] += -1.5 * jac[:, dof["fb"]]
    J = robot.jacobian(q, "fb_tip", "local_world_aligned")
    np.testing.assert_allclose(J, expected, rtol=0, atol=1e-12)


def test_a_joint_off_the_body_origin_turns_about_its_anchor():
    """j2 sits at pos (0.05, -0.02, 0.01) of link2: turning it moves link2's origin but not that point."""
    robot = _load(FEATURES)
    anchor = np.array([0.05, -0.02, 0.01, 1.0])
    i = robot.joint_names.index("j2")
    seen = []
    for angle in (-1.2, -0.3, 0.0, 0.7):
        q = robot.neutral()
        q[robot.joint_names.index("j3")] = 0.0
        q[i] = angle
        seen.append(robot.frame_pose(q, "link2") @ anchor)
    np.testing.assert_allclose(np.ptp(np.array(seen), axis=0), 0.0, rtol=0, atol=1e-15)
    origins = [robot.frame_pose(np.where(np.arange(robot.dof) == i, a, 0.0), "link2")[:3, 3] for a in (0, 1)]
    assert np.linalg.norm(origins[1] - origins[0]) > 1e-3


# -- the description ----------------------------------------------------------------------------------
def test_joint_types_limits_in_radians_mimic_and_frames():
    robot = _load(FEATURES)
    d = robot.description
    assert robot.joint_names == ("j1", "j2", "j3", "j4", "fa")  # fb follows fa
    assert (d.joint("j1").type, d.joint("j1").lower, d.joint("j1").upper) == (
        "revolute",
        -math.radians(120),
        math.radians(120),
    )
    assert d.joint("j2").lower == pytest.approx(-math.pi / 2, abs=1e-15)  # angle="degree" read as degrees
    assert (d.joint("j3").type, d.joint("j3").lower, d.joint("j3").upper) == ("prismatic", -0.1, 0.2)
    assert d.joint("j4").type == "continuous" and d.joint("j4").lower is None
    mimic = d.joint("fb").mimic
    assert mimic is not None and mimic.joint == "fa"
    assert (mimic.multiplier, mimic.offset) == (-1.5, pytest.approx(0.01 + 0.005))  # q0(fb) + c0 - c1 q0(fa)
    assert {"world", "base", "link1", "link2", "tool", "fb_tip", "world_marker"} <= set(robot.frame_names)
    assert robot.description.root == "world"
    assert robot.source == str(FEATURES)


def test_urdf_text_is_an_equivalent_urdf_and_verify_passes():
    robot = _load(FEATURES)
    twin = kinengine.load_urdf_string(robot.urdf_text)
    q = robot.random_configuration(3, size=5)
    for frame in ("link2", "tool", "fb_tip"):
        np.testing.assert_allclose(twin.frame_pose(q, frame), robot.frame_pose(q, frame), rtol=0, atol=0)
    report = verify(robot, samples=5)
    assert report.passed, report.table()


def test_the_command_line_loads_and_verifies_an_mjcf_file(capsys):
    assert main(["verify", str(FEATURES), "--samples", "3"]) == 0
    assert "features" in capsys.readouterr().out


def test_the_command_line_takes_root_for_a_tree(capsys):
    assert main(["info", str(TWO_TREES), "--root", "table"]) == 0
    out = capsys.readouterr().out
    assert "slide" in out and "shoulder" not in out


def test_an_mjcf_robot_pickles_and_takes_the_model_edits():
    import pickle

    robot = _load(FEATURES)
    q = robot.random_configuration(5)
    twin = pickle.loads(pickle.dumps(robot))
    np.testing.assert_allclose(twin.frame_pose(q, "tool"), robot.frame_pose(q, "tool"), rtol=0, atol=0)
    locked = robot.locked({"j4": 0.3})
    assert locked.joint_names == ("j1", "j2", "j3", "fa")
    q4 = np.delete(q, robot.joint_names.index("j4"))
    q5 = q.copy()
    q5[robot.joint_names.index("j4")] = 0.3
    np.testing.assert_allclose(
        locked.frame_pose(q4, "tool"), robot.frame_pose(q5, "tool"), rtol=0, atol=1e-15
    )


def test_the_check_script_reports_every_model_of_a_folder(capsys):
    import importlib.util

    spec = importlib.util.spec_from_file_location("check_mjcf", DATA.parents[2] / "scripts" / "check_mjcf.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.main([str(DATA), "--samples", "3"]) == 0
    rows = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| ") and ".xml" in line]
    assert [r.split(" | ")[0] for r in rows] == [
        "| collision_arm.xml",
        "| features.xml",
        "| kinematics_only.xml",
        "| two_trees.xml",
    ]


def test_reference_positions_are_mujocos_qpos():
    """ref="20" (degrees) on j2: q is MuJoCo's qpos, so at q = ref the body sits where the file puts it."""
    robot = _load(FEATURES)
    model = mujoco.MjModel.from_xml_path(str(FEATURES))
    data = mujoco.MjData(model)  # qpos = qpos0 = the refs
    mujoco.mj_kinematics(model, data)
    q = robot.configuration({"j2": math.radians(20)}, base=np.zeros(robot.dof))
    np.testing.assert_allclose(robot.frame_pose(q, "link2")[:3, 3], data.body("link2").xpos, atol=1e-15)


def test_the_viewer_gets_the_visible_geoms_where_mujoco_draws_them():
    from kinengine.presentation.viewer_scene import read_visuals

    robot = _load(FEATURES)
    model = mujoco.MjModel.from_xml_path(str(FEATURES))
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    q = robot.configuration({"j2": math.radians(20)}, base=np.zeros(robot.dof))  # MuJoCo's qpos0
    visuals = read_visuals(robot.urdf_text, robot.source)
    assert visuals.failures == [] and visuals.error is None
    mesh = visuals.links["base"][0]
    T = robot.frame_pose(q, "base") @ mesh.origin
    placed = np.asarray(mesh.mesh.vertices) @ T[:3, :3].T + T[:3, 3]
    compiled = model.mesh_vert[: model.mesh_vertnum[0]] @ data.geom("base_mesh").xmat.reshape(3, 3).T
    np.testing.assert_allclose(placed, compiled + data.geom("base_mesh").xpos, rtol=0, atol=1e-6)  # float32
    kinds = [v.kind for v in visuals.links["link1"]]
    assert kinds == ["cylinder", "sphere", "sphere"]  # the capsule; the group-3 box is not drawn
    cylinder = robot.frame_pose(q, "link1") @ visuals.links["link1"][0].origin
    np.testing.assert_allclose(cylinder[:3, 3], data.geom("capsule").xpos, rtol=0, atol=1e-12)
    np.testing.assert_allclose(cylinder[:3, :3], data.geom("capsule").xmat.reshape(3, 3), rtol=0, atol=1e-12)
    assert visuals.links["link1"][0].size == (0.01, 0.1)


# -- trees, bases, warnings ---------------------------------------------------------------------------
def test_a_free_base_is_held_with_a_warning_and_root_picks_the_tree():
    with pytest.warns(UserWarning, match="free joint 'float'.*held at its pose in the file"):
        robot = kinengine.load(TWO_TREES)
    assert robot.joint_names == ("shoulder",)
    assert any("pass root= to load another" in n for n in robot.description.warnings)
    table = _load(TWO_TREES, root="table")
    assert table.joint_names == ("slide",) and "slider_tip" in table.frame_names
    assert table.upper_limits[0] == 1e16  # an unlimited slide gets the "no limit" of real URDF files
    with pytest.raises(
        MJCFError, match=r"root='nope' is not a child body of the world body; those are 'floating', 'table'"
    ):
        kinengine.load(TWO_TREES, root="nope")


def test_the_default_tree_is_the_one_with_the_most_joints(tmp_path):
    """A static table written before the arm: the arm is loaded, and the warning names the table."""
    path = _write(
        tmp_path,
        f'<body name="table" pos="0.5 0 0.4"><geom type="box" size="0.4 0.4 0.02"/></body>'
        f'<body name="top"><geom size=".05"/>{ARM}</body>',
    )
    with pytest.warns(
        UserWarning, match=r"2 trees: loaded the one with the most joints, of body 'top', not 'table'"
    ):
        robot = kinengine.load(path)
    assert robot.dof > 0 and "table" not in robot.frame_names


def test_a_ball_joint_on_the_top_body_is_held_like_a_free_one(tmp_path):
    body = f'<body name="top" euler="0.3 0 0"><joint name="s" type="ball"/><geom size=".05"/>{ARM}</body>'
    with pytest.warns(UserWarning, match="by a ball joint 's'.*held at its pose in the file"):
        robot = kinengine.load(_write(tmp_path, body))
    assert robot.joint_names == ("j",)
    assert cross_check(robot, samples=5).worst <= 1e-12


def test_root_is_only_for_mjcf_files():
    with pytest.raises(URDFError, match="root= is for MJCF"):
        kinengine.load("abb_irb120", root="base")


def test_a_urdf_named_xml_still_loads_as_urdf(tmp_path):
    path = tmp_path / "arm.xml"
    path.write_text('<?xml version="1.0"?>\n<!-- <mujoco> -->\n<robot name="r"><link name="a"/></robot>\n')
    assert kinengine.load(path).description.root == "a"


# -- refusals -----------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "body, extra, message",
    [
        (
            ARM.replace("</body>", '<body name="c"><joint name="k"/><geom size=".05"/></body></body>'),
            '<equality><joint joint1="k" joint2="j" polycoef="0 1 0.5 0 0"/></equality>',
            r"equality 0: polycoef 0 1 0.5 0 0 couples joint 'k' to 'j' by a nonlinear polynomial",
        ),
        (
            ARM.replace(
                "</body>", '<body name="c"><joint name="ball" type="ball"/><geom size=".05"/></body></body>'
            ),
            "",
            r"joint 'ball': a ball joint below the top body is not a kinematic joint kinengine models",
        ),
        (ARM, '<equality><joint joint1="j"/></equality>', r"holds joint 'j' at a constant"),
        (ARM.replace("range", "rnage"), "", r"robot.xml: MuJoCo's compiler refused the model: .*rnage"),
        ("", "", "the world body has no child body"),
    ],
)
def test_what_kinengine_or_mujoco_refuses_is_an_mjcf_error_naming_the_file(tmp_path, body, extra, message):
    path = _write(tmp_path, body, extra)
    with pytest.raises(MJCFError, match=message) as caught:
        kinengine.load(path)
    assert caught.value.source == str(path)


def test_untrusted_files_are_bounded_before_mujoco_reads_them(tmp_path):
    path = _write(tmp_path, ARM)
    with pytest.raises(URDFError, match="more than Limits.max_bytes"):
        kinengine.load(path, limits=Limits(max_bytes=100))
    with pytest.raises(MJCFError, match="more than Limits.max_movable_joints = 0"):
        kinengine.load(path, limits=Limits(max_movable_joints=0))
    entity = _write(tmp_path, ARM, name="entity.xml")
    entity.write_text('<!DOCTYPE m [<!ENTITY x "y">]>' + entity.read_text())
    with pytest.raises(MJCFError, match="DTD"):
        kinengine.load(entity)
    missing = _write(tmp_path, ARM, '<include file="nowhere.xml"/>', name="inc.xml")
    with pytest.raises(URDFError, match="nowhere.xml: no such file"):
        kinengine.load(missing)
    device = _write(tmp_path, ARM, '<asset><mesh name="m" file="/dev/zero"/></asset>', name="device.xml")
    with pytest.raises(MJCFError, match="<mesh file='/dev/zero'> is not a regular file"):
        kinengine.load(device)  # MuJoCo would read it forever
    big = _write(tmp_path, ARM, '<asset><mesh name="m" file="big.stl"/></asset>', name="big.xml")
    (tmp_path / "big.stl").write_bytes(b"\0" * 4096)
    with pytest.raises(
        MJCFError, match="<mesh file='big.stl'> is 4096 bytes, more than Limits.max_bytes = 2048"
    ):
        kinengine.load(big, limits=Limits(max_bytes=2048))
    not_mjcf = tmp_path / "other.xml"
    not_mjcf.write_text("<scene/>")
    with pytest.raises(MJCFError, match="the root element is <scene>, expected <mujoco>"):
        kinengine.load(not_mjcf)


def test_without_mujoco_the_error_names_the_extra(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "mujoco", None)
    with pytest.raises(MJCFError, match=r"pip install 'kinengine\[mjcf\]'"):
        kinengine.load(_write(tmp_path, ARM))
