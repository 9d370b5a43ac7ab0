"""The independent reference (kinengine.reference) against closed forms, finite differences,
yourdfpy's own forward kinematics and raw Pinocchio.

Frames: I = root link frame; T = T_IF (4, 4); Jacobians rows [linear; angular], columns in
the reference's ``joint_names`` order. Pinocchio is only ever used here as a second opinion:
raw ``pinocchio.buildModelFromXML(text)`` on the very same text, continuous joints entered as
(cos q, sin q), mimic joints as ordinary joints set to multiplier · leader + offset (recursively,
for mimics of mimics) by this file's own code, their Jacobian columns summed by the chain rule.

Typo in the printed course text corrected below: eq. 2.175, entry (3, 1) reads
-l1 s1 - l2 s12 - l3 c123; with n = e_y and r_1E = (x, 0, z - l0), n × r = (z - l0, 0, -x), so
the entry is -(l1 s1 + l2 s12 + l3 s123).
"""

from __future__ import annotations

import importlib.metadata
import io
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yourdfpy
from hypothesis import given, settings
from hypothesis import strategies as st
from lxml import etree
from scipy.spatial.transform import Rotation
from urdf_strategies import random_urdfs

from kinengine.errors import ConfigurationError, FrameNotFoundError, KinematicsError, URDFError
from kinengine.reference import REFERENCES, ReferenceKinematics, read_urdf

ERD_ROBOTS = Path(
    importlib.metadata.distribution("example-robot-data").locate_file(
        "cmeel.prefix/share/example-robot-data/robots"
    )
)
ERD = {  # revolute arms, continuous joints (kinova), prismatic + mimic fingers (panda, baxter)
    "ur5": ERD_ROBOTS / "ur_description/urdf/ur5_robot.urdf",
    "panda": ERD_ROBOTS / "panda_description/urdf/panda.urdf",
    "kinova": ERD_ROBOTS / "kinova_description/robots/kinova.urdf",
    "baxter": ERD_ROBOTS / "baxter_description/urdf/baxter.urdf",
}

L0, L1, L2, L3 = 0.4, 0.5, 0.35, 0.2  # planar arm of examples 2.8.5 / 2.8.7 [m]
LIMIT = '<limit lower="-3" upper="3" effort="1" velocity="1"/>'


def _joint(name: str, kind: str, parent: str, child: str, inner: str = "") -> str:
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>{inner}</joint>'
    )


def _robot(links: str, *joints: str) -> str:
    return (
        '<?xml version="1.0"?>\n<robot name="t">'
        + "".join(f'<link name="{n}"/>' for n in links.split())
        + "".join(joints)
        + "</robot>"
    )


PLANAR = _robot(
    "base l1 l2 l3 ee",
    _joint("q1", "revolute", "base", "l1", f'<origin xyz="0 0 {L0}"/><axis xyz="0 1 0"/>{LIMIT}'),
    _joint("q2", "revolute", "l1", "l2", f'<origin xyz="0 0 {L1}"/><axis xyz="0 1 0"/>{LIMIT}'),
    _joint("q3", "revolute", "l2", "l3", f'<origin xyz="0 0 {L2}"/><axis xyz="0 1 0"/>{LIMIT}'),
    _joint("ee_joint", "fixed", "l3", "ee", f'<origin xyz="0 0 {L3}"/>'),
)

# Every joint type and a mimic joint following a prismatic leader (and one following a revolute one).
MIXED = _robot(
    "base a b c d tip f1 f2",
    _joint(
        "spin", "continuous", "base", "a", '<origin xyz="0 0 0.3" rpy="0.1 -0.2 0.3"/><axis xyz="0 0 1"/>'
    ),
    _joint(
        "lift", "prismatic", "a", "b", f'<origin xyz="0.2 0.05 0.1" rpy="0 0.4 0"/><axis xyz="0 3 4"/>{LIMIT}'
    ),
    _joint(
        "elbow", "revolute", "b", "c", f'<origin xyz="0.1 0 0.25" rpy="0.3 0 0"/><axis xyz="1 1 0"/>{LIMIT}'
    ),
    _joint("wrist_fixed", "fixed", "c", "tip", '<origin xyz="0.05 0 0.12" rpy="0.2 0.1 -0.3"/>'),
    _joint(
        "follow_lift",
        "prismatic",
        "tip",
        "f1",
        f'<origin xyz="0 0.03 0.04"/><axis xyz="0 1 0"/>{LIMIT}'
        '<mimic joint="lift" multiplier="-1.5" offset="0.2"/>',
    ),
    _joint(
        "follow_elbow",
        "revolute",
        "f1",
        "f2",
        f'<origin xyz="0 0.1 0"/><axis xyz="0 0 1"/>{LIMIT}'
        '<mimic joint="elbow" multiplier="0.7" offset="-0.4"/>',
    ),
    _joint("side", "revolute", "a", "d", f'<origin xyz="0 0.2 0" rpy="0 0 1"/><axis xyz="0 1 0"/>{LIMIT}'),
)


# -- helpers --------------------------------------------------------------------------------------
def _pinocchio(text: str) -> tuple[pin.Model, list[str]]:
    """Raw Pinocchio's model of ``text`` (mimic joints built as ordinary joints, continuous joints with
    nq = 2) and the independent joints in its own order."""
    model = pin.buildModelFromXML(text)
    mimics = _mimics(text)
    return model, [model.names[i] for i in range(1, model.njoints) if model.names[i] not in mimics]


def _mimics(text: str) -> dict[str, tuple[str, float, float]]:
    """Movable joint name -> (leader, multiplier, offset), read straight from the XML."""
    out = {}
    for joint in etree.fromstring(text.encode()).iter("joint"):
        mimic = joint.find("mimic")
        if joint.get("type") != "fixed" and mimic is not None:
            out[joint.get("name")] = (
                mimic.get("joint"),
                float(mimic.get("multiplier", 1)),
                float(mimic.get("offset", 0)),
            )
    return out


def _pin_q(model: pin.Model, names: list[str], q: np.ndarray, text: str) -> tuple[np.ndarray, np.ndarray]:
    """Pinocchio's configuration (nq,) for q in ``names`` order (continuous joints as (cos, sin), each
    mimic joint at multiplier · its leader's value + offset, recursively) and dθ/dq (nv, dof)."""
    mimics = _mimics(text)
    column = {n: k for k, n in enumerate(names)}

    def theta(name: str) -> tuple[float, np.ndarray]:
        if name not in mimics:
            grad = np.zeros(len(names))
            grad[column[name]] = 1.0
            return float(q[column[name]]), grad
        leader, multiplier, offset = mimics[name]
        value, grad = theta(leader)
        return multiplier * value + offset, multiplier * grad

    qp, A = np.zeros(model.nq), np.zeros((model.nv, len(names)))
    for i in range(1, model.njoints):
        joint = model.joints[i]
        value, A[joint.idx_v] = theta(model.names[i])
        qp[joint.idx_q : joint.idx_q + joint.nq] = (np.cos(value), np.sin(value)) if joint.nq == 2 else value
    return qp, A


def _fd_jacobian(
    ref: ReferenceKinematics, q: np.ndarray, frame: str, reference: str, h: float = 1e-6
) -> np.ndarray:
    """(6, dof) Jacobian by central differences of T(q), each reference taken from its definition.

    local_world_aligned: [(p+ - p-) / 2h; log(C+ C-^T) / 2h]; local: T^-1 dT/dq = [[ω]x, v] in F;
    world: dT/dq T^-1 = [[ω]x, v_O] in I (v_O: velocity of the body point at I's origin).
    """
    T = ref.frame_pose(q, frame)
    J = np.empty((6, ref.dof))
    for k in range(ref.dof):
        dq = np.zeros(ref.dof)
        dq[k] = h
        Tp, Tm = ref.frame_pose(q + dq, frame), ref.frame_pose(q - dq, frame)
        if reference == "local_world_aligned":
            v = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
            w = Rotation.from_matrix(Tp[:3, :3] @ Tm[:3, :3].T).as_rotvec() / (2 * h)
        else:
            dT = (Tp - Tm) / (2 * h)
            twist = np.linalg.solve(T, dT) if reference == "local" else dT @ np.linalg.inv(T)
            v, w = twist[:3, 3], np.array([twist[2, 1], twist[0, 2], twist[1, 0]])
        J[:, k] = np.concatenate([v, w])
    return J


def _v(values: np.ndarray) -> str:
    return " ".join(repr(float(v)) for v in values)


def _samples(dof: int, n: int, seed: int) -> np.ndarray:
    """(n + 1, dof): zero and n uniform samples in [-2, 2] (rad or m)."""
    return np.vstack([np.zeros(dof), np.random.default_rng(seed).uniform(-2, 2, (n, dof))])


def _assert_matches_pinocchio(text: str, q: np.ndarray, atol: float) -> None:
    model, names = _pinocchio(text)
    data = model.createData()
    ref = ReferenceKinematics.from_urdf_string(text, joint_names=names)
    poses = {f: ref.frame_pose(q, f) for f in ref.frame_names}
    jacobians = {(f, r): ref.jacobian(q, f, r) for f in ref.frame_names for r in REFERENCES}
    pin_refs = {"local_world_aligned": pin.LOCAL_WORLD_ALIGNED, "local": pin.LOCAL, "world": pin.WORLD}
    for i, qi in enumerate(q):
        qp, A = _pin_q(model, names, qi, text)
        pin.forwardKinematics(model, data, qp)
        for frame in ref.frame_names:
            fid = model.getFrameId(frame)
            np.testing.assert_allclose(
                pin.updateFramePlacement(model, data, fid).homogeneous,
                poses[frame][i],
                rtol=0,
                atol=atol,
                err_msg=frame,
            )
            for r in REFERENCES:
                # eigenpy hands a (6, 1) matrix back as a (6,) array: restore the column.
                J_pin = pin.computeFrameJacobian(model, data, qp, fid, pin_refs[r]).reshape(6, model.nv) @ A
                np.testing.assert_allclose(
                    J_pin, jacobians[frame, r][i], rtol=0, atol=atol, err_msg=f"{frame} {r}"
                )


# -- closed forms ---------------------------------------------------------------------------------
def test_planar_arm_matches_closed_forms_of_examples_2_8_5_and_2_8_7():
    ref = ReferenceKinematics.from_urdf_string(PLANAR)
    q = _samples(3, 64, seed=1)
    phi = np.cumsum(q, axis=1)  # φ_i = q1 + ... + qi
    lengths = np.array([L1, L2, L3])
    s, c = lengths * np.sin(phi), lengths * np.cos(phi)
    T = ref.frame_pose(q, "ee")
    # eq. 2.130 and C_IE = C_y(q1 + q2 + q3) (eqs. 2.158-2.160)
    np.testing.assert_allclose(
        T[:, :3, 3], np.stack([s.sum(1), 0 * phi[:, 0], L0 + c.sum(1)], 1), rtol=0, atol=1e-15
    )
    c3, s3, o = np.cos(phi[:, 2]), np.sin(phi[:, 2]), np.zeros(len(q))
    C_y = np.stack([c3, o, s3, o, o + 1, o, -s3, o, c3], axis=1).reshape(-1, 3, 3)
    np.testing.assert_allclose(T[:, :3, :3], C_y, rtol=0, atol=1e-15)

    tail_c, tail_s = np.cumsum(c[:, ::-1], 1)[:, ::-1], np.cumsum(s[:, ::-1], 1)[:, ::-1]  # Σ_{i>=k}
    zero, one = np.zeros_like(tail_c), np.ones_like(tail_c)
    # eq. 2.175 (corrected) and 2.177
    expected = np.stack([tail_c, zero, -tail_s, zero, one, zero], axis=1)
    np.testing.assert_allclose(ref.jacobian(q, "ee"), expected, rtol=0, atol=1e-15)
    # local: C_IE^T = C_y(-φ3), column k = [Σ_{i>=k} l_i cos(φ3 - φ_i), 0, Σ l_i sin(φ3 - φ_i); e_y]
    rel = phi[:, 2:3] - phi
    loc_c = np.cumsum((lengths * np.cos(rel))[:, ::-1], 1)[:, ::-1]
    loc_s = np.cumsum((lengths * np.sin(rel))[:, ::-1], 1)[:, ::-1]
    expected = np.stack([loc_c, zero, loc_s, zero, one, zero], axis=1)
    np.testing.assert_allclose(ref.jacobian(q, "ee", "local"), expected, rtol=0, atol=1e-15)
    # world: column k is p_k × e_y = (-z_k, 0, x_k), p_k the position of joint k
    x_k = np.concatenate([np.zeros((len(q), 1)), np.cumsum(s, 1)[:, :2]], 1)
    z_k = L0 + np.concatenate([np.zeros((len(q), 1)), np.cumsum(c, 1)[:, :2]], 1)
    expected = np.stack([-z_k, zero, x_k, zero, one, zero], axis=1)
    np.testing.assert_allclose(ref.jacobian(q, "ee", "world"), expected, rtol=0, atol=1e-15)


def test_origin_is_translation_then_rz_ry_rx():
    rng = np.random.default_rng(2)
    rpys = np.vstack([rng.uniform(-np.pi, np.pi, (20, 3)), [[0.3, np.pi / 2, -0.2], [0.1, -np.pi / 2, 1.0]]])
    for rpy in rpys:
        xyz = rng.uniform(-1, 1, 3)
        text = _robot("a b", _joint("j", "fixed", "a", "b", f'<origin xyz="{_v(xyz)}" rpy="{_v(rpy)}"/>'))
        T = ReferenceKinematics.from_urdf_string(text).frame_pose(np.zeros(0), "b")
        rz, ry, rx = (Rotation.from_euler(a, v).as_matrix() for a, v in zip("zyx", rpy[::-1], strict=False))
        np.testing.assert_allclose(T[:3, :3], rz @ ry @ rx, rtol=0, atol=1e-15)
        np.testing.assert_allclose(T[:3, 3], xyz, rtol=0, atol=0)


@pytest.mark.parametrize("theta", [0.0, 1e-12, 1e-9, 1e-7, 1e-5, 1e-3, 1.0, np.pi - 1e-6, np.pi, -2.5, 7.0])
def test_revolute_joint_rotates_about_its_unit_axis(theta):
    text = _robot("a b", _joint("j", "continuous", "a", "b", '<axis xyz="1 -2 2"/>'))
    T = ReferenceKinematics.from_urdf_string(text).frame_pose([theta], "b")
    n = np.array([1.0, -2.0, 2.0]) / 3.0
    np.testing.assert_allclose(T[:3, :3], Rotation.from_rotvec(theta * n).as_matrix(), rtol=0, atol=1e-15)
    np.testing.assert_allclose(T[:3, 3], 0.0, rtol=0, atol=0)


def test_prismatic_joint_translates_along_its_unit_axis():
    text = _robot(
        "a b",
        _joint(
            "j", "prismatic", "a", "b", f'<origin rpy="0 0 1.5707963267948966"/><axis xyz="0 3 4"/>{LIMIT}'
        ),
    )
    T = ReferenceKinematics.from_urdf_string(text).frame_pose([0.5], "b")
    # the axis is expressed in the joint frame, rotated by +90° about z: (0, .6, .8) -> (-.6, 0, .8)
    np.testing.assert_allclose(T[:3, 3], [-0.3, 0.0, 0.4], rtol=0, atol=1e-15)


def test_mimic_joint_equals_its_expanded_model():
    ref = ReferenceKinematics.from_urdf_string(MIXED)
    free = MIXED.replace('<mimic joint="lift" multiplier="-1.5" offset="0.2"/>', "").replace(
        '<mimic joint="elbow" multiplier="0.7" offset="-0.4"/>', ""
    )
    names = list(ref.joint_names)
    expanded = ReferenceKinematics.from_urdf_string(free, joint_names=names + ["follow_lift", "follow_elbow"])
    q = _samples(ref.dof, 8, seed=3)
    iq = {n: i for i, n in enumerate(names)}
    q_exp = np.hstack([q, -1.5 * q[:, [iq["lift"]]] + 0.2, 0.7 * q[:, [iq["elbow"]]] - 0.4])
    for frame in ref.frame_names:
        np.testing.assert_allclose(
            ref.frame_pose(q, frame), expanded.frame_pose(q_exp, frame), rtol=0, atol=1e-15
        )
        for r in REFERENCES:
            J, J_exp = ref.jacobian(q, frame, r), expanded.jacobian(q_exp, frame, r)
            expected = J_exp[..., : ref.dof].copy()
            expected[..., iq["lift"]] += -1.5 * J_exp[..., ref.dof]  # chain rule dq_m/dq_L = multiplier
            expected[..., iq["elbow"]] += 0.7 * J_exp[..., ref.dof + 1]
            np.testing.assert_allclose(J, expected, rtol=0, atol=1e-14, err_msg=f"{frame} {r}")


# A chain of mimics of every type, the first one sorted before the independent joint that drives it:
# cont = -1.5·lead + 0.2 (continuous follows revolute), slide = 0.5·cont - 0.1 (prismatic follows continuous).
CHAIN = _robot(
    "base a b c",
    _joint("z_lead", "revolute", "base", "a", f'<origin xyz="0 0 0.3"/><axis xyz="0 1 0"/>{LIMIT}'),
    _joint(
        "a_cont",
        "continuous",
        "base",
        "b",
        '<origin xyz="0.1 0 0.2" rpy="0.3 0 0"/><axis xyz="0 0 1"/>'
        '<mimic joint="z_lead" multiplier="-1.5" offset="0.2"/>',
    ),
    _joint(
        "slide",
        "prismatic",
        "b",
        "c",
        f'<origin xyz="0 0.1 0"/><axis xyz="1 0 0"/>{LIMIT}'
        '<mimic joint="a_cont" multiplier="0.5" offset="-0.1"/>',
    ),
)


def test_mimic_chain_equals_its_expanded_model():
    ref = ReferenceKinematics.from_urdf_string(CHAIN)
    assert ref.joint_names == ("z_lead",)
    free = CHAIN.replace('<mimic joint="z_lead" multiplier="-1.5" offset="0.2"/>', "").replace(
        '<mimic joint="a_cont" multiplier="0.5" offset="-0.1"/>', ""
    )
    expanded = ReferenceKinematics.from_urdf_string(free, joint_names=["z_lead", "a_cont", "slide"])
    q = _samples(1, 6, seed=9)
    cont = -1.5 * q + 0.2
    q_exp = np.hstack([q, cont, 0.5 * cont - 0.1])
    for frame in ref.frame_names:
        np.testing.assert_allclose(
            ref.frame_pose(q, frame), expanded.frame_pose(q_exp, frame), rtol=0, atol=1e-15
        )
        for r in REFERENCES:
            J_exp = expanded.jacobian(q_exp, frame, r)  # chain rule: d(cont)/dq = -1.5, d(slide)/dq = -0.75
            expected = J_exp[..., [0]] - 1.5 * J_exp[..., [1]] - 0.75 * J_exp[..., [2]]
            np.testing.assert_allclose(
                ref.jacobian(q, frame, r), expected, rtol=0, atol=1e-14, err_msg=f"{frame} {r}"
            )


def test_the_reference_reads_non_urdf_namespaces_as_urdfdom_does():
    extras = (
        '<gazebo reference="a"><sensor:camera name="c"><sensor:image w="1"/></sensor:camera>'
        '<plugin gz:rate="1" name="p"/></gazebo>'
    )
    decorated = MIXED.replace('<robot name="t">', '<robot name="t" xmlns="http://www.ros.org">').replace(
        "</robot>", extras + "</robot>"
    )
    q = _samples(4, 2, seed=10)
    plain, read = ReferenceKinematics.from_urdf_string(MIXED), ReferenceKinematics.from_urdf_string(decorated)
    for frame in plain.frame_names:
        np.testing.assert_array_equal(read.frame_pose(q, frame), plain.frame_pose(q, frame))
    with pytest.raises(URDFError, match="DOCTYPE"):
        ReferenceKinematics.from_urdf_string('<!DOCTYPE robot [<!ENTITY x "1">]>' + MIXED.split("?>", 1)[1])


# -- finite differences ---------------------------------------------------------------------------
@pytest.mark.parametrize("reference", REFERENCES)
@pytest.mark.parametrize("robot", ["planar", "mixed", "chain", *ERD])
def test_jacobian_matches_finite_differences(robot, reference):
    text = {"planar": PLANAR, "mixed": MIXED, "chain": CHAIN}.get(robot) or ERD[robot].read_text()
    ref = ReferenceKinematics.from_urdf_string(text)
    frames = ref.frame_names[-12:]  # the deepest frames of the first branches stay covered below
    for q in _samples(ref.dof, 2, seed=4):
        for frame in (*frames, *ref.frame_names[:: max(1, len(ref.frame_names) // 8)]):
            J, J_fd = ref.jacobian(q, frame, reference), _fd_jacobian(ref, q, frame, reference)
            assert np.max(np.abs(J - J_fd)) <= 1e-7 * max(1.0, np.max(np.abs(J))), (frame, reference)


@settings(max_examples=30, deadline=None)
@given(random_urdfs(max_links=6), st.integers(0, 2**32 - 1))
def test_jacobian_matches_finite_differences_on_random_urdfs(text, seed):
    ref = ReferenceKinematics.from_urdf_string(text)
    q = np.random.default_rng(seed).uniform(-2, 2, ref.dof)
    for frame in ref.frame_names:
        for reference in REFERENCES:
            J, J_fd = ref.jacobian(q, frame, reference), _fd_jacobian(ref, q, frame, reference)
            assert np.max(np.abs(J - J_fd), initial=0.0) <= 1e-7 * max(1.0, np.max(np.abs(J), initial=0.0))


# -- other implementations ------------------------------------------------------------------------
@pytest.mark.parametrize("robot", list(ERD))
def test_poses_match_yourdfpy_forward_kinematics(robot):
    text = ERD[robot].read_text()
    urdf = read_urdf(text, scene_graph=True)
    ref = ReferenceKinematics.from_urdf_string(text, joint_names=urdf.actuated_joint_names)
    for q in _samples(ref.dof, 4, seed=5):
        urdf.update_cfg(q)
        for link in urdf.link_map:
            np.testing.assert_allclose(
                ref.frame_pose(q, link),
                urdf.get_transform(link, urdf.base_link),
                rtol=0,
                atol=1e-12,
                err_msg=link,
            )


@pytest.mark.parametrize("robot", list(ERD))
def test_poses_and_jacobians_match_pinocchio(robot):
    text = ERD[robot].read_text()
    _assert_matches_pinocchio(text, _samples(len(_pinocchio(text)[1]), 3, seed=6), atol=1e-10)


def test_mimic_chain_matches_raw_pinocchio():
    _assert_matches_pinocchio(CHAIN, _samples(1, 4, seed=11), atol=1e-12)


def test_pinocchio_visits_sibling_joints_in_name_order_not_file_order():
    text = _robot(
        "base x y z",
        *(
            _joint(n, "revolute", "base", c, LIMIT)
            for n, c in (("b_joint", "x"), ("a_joint", "y"), ("c_joint", "z"))
        ),
    )
    assert ReferenceKinematics.from_urdf_string(text).joint_names == ("b_joint", "a_joint", "c_joint")
    assert _pinocchio(text)[1] == ["a_joint", "b_joint", "c_joint"]
    _assert_matches_pinocchio(text, _samples(3, 2, seed=7), atol=1e-12)


@pytest.mark.slow
@settings(max_examples=60, deadline=None)
@given(random_urdfs(max_links=8), st.integers(0, 2**32 - 1))
def test_random_urdfs_match_pinocchio(text, seed):
    _assert_matches_pinocchio(text, _samples(len(_pinocchio(text)[1]), 2, seed=seed), atol=1e-10)


# -- API ------------------------------------------------------------------------------------------
def test_batched_results_equal_single_results():
    ref = ReferenceKinematics.from_urdf_string(MIXED)
    q = _samples(ref.dof, 5, seed=8)
    assert ref.frame_pose(q, "f2").shape == (6, 4, 4) and ref.jacobian(q, "f2").shape == (6, 6, ref.dof)
    for i, qi in enumerate(q):
        assert ref.frame_pose(qi, "f2").shape == (4, 4)
        np.testing.assert_array_equal(ref.frame_pose(qi, "f2"), ref.frame_pose(q, "f2")[i])
        for r in REFERENCES:
            np.testing.assert_array_equal(ref.jacobian(qi, "f2", r), ref.jacobian(q, "f2", r)[i])


def test_default_order_is_depth_first_with_children_in_file_order_and_frames_cover_links_and_joints():
    ref = ReferenceKinematics.from_urdf_string(MIXED)
    assert ref.joint_names == ("spin", "lift", "elbow", "side")
    assert ref.root == "base" and ref.dof == 4 and ref.name == "t"
    assert set(ref.frame_names) == {"base", "a", "b", "c", "d", "tip", "f1", "f2"} | {
        "spin",
        "lift",
        "elbow",
        "wrist_fixed",
        "follow_lift",
        "follow_elbow",
        "side",
    }
    q = _samples(4, 1, seed=9)[1]
    np.testing.assert_array_equal(ref.frame_pose(q, "follow_elbow"), ref.frame_pose(q, "f2"))


def test_joint_names_reorder_the_columns_of_q_and_the_jacobian():
    ref = ReferenceKinematics.from_urdf_string(MIXED)
    perm = [2, 0, 3, 1]
    other = ReferenceKinematics.from_urdf_string(MIXED, joint_names=[ref.joint_names[i] for i in perm])
    q = _samples(4, 1, seed=10)[1]
    np.testing.assert_array_equal(other.frame_pose(q[perm], "f2"), ref.frame_pose(q, "f2"))
    np.testing.assert_array_equal(
        other.jacobian(q[perm], "f2", "world"), ref.jacobian(q, "f2", "world")[:, perm]
    )


def test_robot_without_joints_has_empty_jacobians():
    ref = ReferenceKinematics.from_urdf_string(_robot("only"))
    np.testing.assert_array_equal(ref.frame_pose([], "only"), np.eye(4))
    assert ref.jacobian(np.zeros((3, 0)), "only", "local").shape == (3, 6, 0)


def test_from_file_reads_the_same_robot():
    ref = ReferenceKinematics.from_file(ERD["ur5"])
    assert ref.dof == 6 and "tool0" in ref.frame_names


@pytest.mark.parametrize(
    "joint_names, error",
    [
        (["spin", "lift", "elbow"], ConfigurationError),
        (["spin", "lift", "elbow", "elbow"], ConfigurationError),
        (["spin", "lift", "elbow", "follow_lift"], FrameNotFoundError),
        (["spin", "lift", "elbow", "sied"], FrameNotFoundError),
    ],
)
def test_joint_names_must_be_a_permutation_of_the_independent_joints(joint_names, error):
    with pytest.raises(error):
        ReferenceKinematics.from_urdf_string(MIXED, joint_names=joint_names)


def test_bad_inputs_raise_kinengine_errors_naming_the_problem():
    ref = ReferenceKinematics.from_urdf_string(MIXED)
    with pytest.raises(ConfigurationError, match=r"shape \(4,\) or \(N, 4\), got \(5,\)"):
        ref.frame_pose(np.zeros(5), "f2")
    with pytest.raises(ConfigurationError, match="non-finite"):
        ref.jacobian([0, np.nan, 0, 0], "f2")
    with pytest.raises(FrameNotFoundError, match="'f2'"):
        ref.frame_pose(np.zeros(4), "f3")
    with pytest.raises(KinematicsError, match="local_world_aligned"):
        ref.jacobian(np.zeros(4), "f2", reference="global")


# -- strict parsing -------------------------------------------------------------------------------
def test_malformed_xml_is_refused_although_yourdfpy_alone_would_recover_it():
    text = ERD["ur5"].read_text()
    truncated = text[: text.index("</joint>", len(text) // 2) + len("</joint>")]  # no </robot>
    recovered = yourdfpy.URDF.load(io.BytesIO(truncated.encode()), build_scene_graph=False, load_meshes=False)
    assert 0 < len(recovered.robot.joints) < 10  # yourdfpy kept a silently truncated robot
    with pytest.raises(URDFError, match="not well-formed") as info:
        ReferenceKinematics.from_urdf_string(truncated, source="ur5_half.urdf")
    assert info.value.source == "ur5_half.urdf" and info.value.line is not None


@pytest.mark.parametrize(
    "text, message",
    [
        ("<robot name='r'><link name='a'></robot>", "not well-formed"),
        ("<robt name='r'><link name='a'/></robt>", "expected <robot>"),
        ("<robot name='r'><link name='a'/><link name='a'/></robot>", "two links"),
        (_robot("a b", _joint("j", "floating", "a", "b")), "not supported"),
        (_robot("a b", _joint("j", "fixed", "a", "c")), "'c' is not defined"),
        (_robot("a b c", _joint("j", "fixed", "a", "c"), _joint("k", "fixed", "b", "c")), "child of both"),
        (_robot("a b c", _joint("j", "fixed", "a", "b")), "exactly one root"),
        (_robot("a b c", _joint("j", "fixed", "a", "b"), _joint("k", "fixed", "c", "c")), "not connected"),
        (_robot("a b", _joint("j", "revolute", "a", "b", f'<axis xyz="0 0 0"/>{LIMIT}')), "non-zero"),
        (_robot("a b", _joint("j", "revolute", "a", "b", f'<axis xyz="0 1"/>{LIMIT}')), "3-vector"),
        (_robot("a b", _joint("j", "fixed", "a", "b", '<origin xyz="0 zero 0"/>')), "yourdfpy could not"),
        (_robot("a b", _joint("j", "revolute", "a", "b", f'{LIMIT}<mimic joint="nope"/>')), "does not exist"),
        (
            _robot(
                "a b c",
                _joint("j", "fixed", "a", "b"),
                _joint("k", "revolute", "b", "c", f'{LIMIT}<mimic joint="j"/>'),
            ),
            "is fixed",
        ),
        (
            _robot(
                "a b c",
                _joint("j", "revolute", "a", "b", f'{LIMIT}<mimic joint="k"/>'),
                _joint("k", "revolute", "b", "c", f'{LIMIT}<mimic joint="j"/>'),
            ),
            "form a cycle",
        ),
    ],
)
def test_invalid_urdfs_raise_urdf_error(text, message):
    with pytest.raises(URDFError, match=message):
        ReferenceKinematics.from_urdf_string(text)
