"""The shipped descriptions robots/<name>/<name>.urdf against closed forms derived by hand.

Frames: I = the root link frame; p = origin of the end-effector frame in I [m]; C = C_IE.
Jacobians are (N, 6, dof), rows [linear; angular] (kinengine's "local_world_aligned",
"local" and "world", see kinengine/robot.py). For a revolute joint k with axis n_k through
the point p_k (both in I), the definitions give the columns
    local_world_aligned: [n_k x (p - p_k); n_k]        (eq. 2.155)
    local:               [C^T n_k x C^T (p - p_k); C^T n_k]
    world:               [p_k x n_k; n_k]                (v_O = v - w x p: independent of p)
and for a prismatic joint [n_k; 0] ("local_world_aligned", "world") or [C^T n_k; 0] ("local").

Typos in the printed course text (/work/shared/seed), corrected below:
  * eq. 2.175, entry (3, 1): printed -l1 s1 - l2 s12 - l3 c123; the z velocity is
    -(l1 s1 + l2 s12 + l3 s123): s123, not c123 (the entries (3, 2), (3, 3) have it right).
  * eq. 2.138, columns 2 and 3: printed c213 / s213, a symbol the text never defines;
    c123 / s123 is meant (the entries are d/dq2, d/dq3 of eq. 2.130).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yourdfpy
from scipy.spatial.transform import Rotation

import kinengine

ROBOTS_DIR = Path(__file__).resolve().parent.parent / "robots"
SHIPPED = sorted(p.name for p in ROBOTS_DIR.iterdir() if p.is_dir())
REFERENCES = ("local_world_aligned", "local", "world")
N_SAMPLES = 128

# Design values, stated in robots/planar_3dof/README.md and robots/scara/README.md [m].
L0, L1, L2, L3 = 0.4, 0.5, 0.35, 0.2  # planar_3dof: base height, link lengths
H0, A1, A2, D = 0.45, 0.325, 0.275, 0.1  # scara: arm plane height, inner/outer arm, quill to tip


def _samples(robot: kinengine.Robot, seed: int) -> np.ndarray:
    """(N_SAMPLES + 1, dof): q = 0 plus uniform samples within the joint limits."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(robot.lower_limits, robot.upper_limits, size=(N_SAMPLES, robot.dof))
    return np.vstack([np.zeros(robot.dof), q])


def _rot(axis: str, angle: np.ndarray) -> np.ndarray:
    """(N, 3, 3) elementary rotations about x, y or z by angle [rad]."""
    return Rotation.from_euler(axis, np.asarray(angle)[:, None]).as_matrix()


def _pose(C: np.ndarray, p: np.ndarray) -> np.ndarray:
    """(N, 4, 4) homogeneous transforms from rotations C (N, 3, 3) and translations p (N, 3) [m]."""
    T = np.zeros((len(p), 4, 4))
    T[:, :3, :3], T[:, :3, 3], T[:, 3, 3] = C, p, 1.0
    return T


def _columns(*cols: list) -> np.ndarray:
    """(N, 6, k) from k columns, each a list of six (N,) arrays or scalars."""
    n = max(np.size(e) for c in cols for e in c)
    return np.stack([np.stack([np.broadcast_to(e, (n,)) for e in c], -1) for c in cols], -1)


# -- planar 3-DOF arm, examples 2.8.5-2.8.7 -------------------------------------------------------
def planar_pose(q: np.ndarray) -> np.ndarray:
    """T_IE, eq. 2.130/2.131: rotation about y by q1 + q2 + q3."""
    t1, t12, t123 = np.cumsum(q, axis=1).T
    x = L1 * np.sin(t1) + L2 * np.sin(t12) + L3 * np.sin(t123)
    z = L0 + L1 * np.cos(t1) + L2 * np.cos(t12) + L3 * np.cos(t123)
    return _pose(_rot("y", t123), np.stack([x, 0 * x, z], -1))


def planar_jacobians(q: np.ndarray) -> dict[str, np.ndarray]:
    """(N, 6, 3) Jacobians of "ee" per reference."""
    t1, t12, t123 = np.cumsum(q, axis=1).T
    s1, s12, s123 = np.sin(t1), np.sin(t12), np.sin(t123)
    c1, c12, c123 = np.cos(t1), np.cos(t12), np.cos(t123)
    s3, c3, s23, c23 = np.sin(q[:, 2]), np.cos(q[:, 2]), np.sin(q[:, 1] + q[:, 2]), np.cos(q[:, 1] + q[:, 2])
    ey = [0, 1, 0]
    # Rows x, z: eq. 2.138 and 2.175 (corrected); angular rows: eq. 2.177.
    lwa = _columns(
        [L1 * c1 + L2 * c12 + L3 * c123, 0, -(L1 * s1 + L2 * s12 + L3 * s123), *ey],
        [L2 * c12 + L3 * c123, 0, -(L2 * s12 + L3 * s123), *ey],
        [L3 * c123, 0, -L3 * s123, *ey],
    )
    # In E, r_kE = sum_{j>=k} l_j (sin(t_j - t123), 0, cos(t_j - t123)) and v = e_y x r_kE.
    local = _columns(
        [L1 * c23 + L2 * c3 + L3, 0, L1 * s23 + L2 * s3, *ey],
        [L2 * c3 + L3, 0, L2 * s3, *ey],
        [L3, 0, 0, *ey],
    )
    # p_k x e_y = (-z_k, 0, x_k) for the joint positions p_k = (x_k, 0, z_k).
    world = _columns(
        [-L0, 0, 0, *ey],
        [-(L0 + L1 * c1), 0, L1 * s1, *ey],
        [-(L0 + L1 * c1 + L2 * c12), 0, L1 * s1 + L2 * s12, *ey],
    )
    return {"local_world_aligned": lwa, "local": local, "world": world}


# -- SCARA, examples 2.8.1 and 2.8.4: q = (alpha, beta, gamma, zeta), zeta positive downwards ------
def scara_pose(q: np.ndarray) -> np.ndarray:
    """T_IE: rotation about z by phi = alpha + beta + gamma, tip at (x, y, h0 - d - zeta)."""
    a, b, g, z = q.T
    p = np.stack([A1 * np.cos(a) + A2 * np.cos(a + b), A1 * np.sin(a) + A2 * np.sin(a + b), H0 - D - z], -1)
    return _pose(_rot("z", a + b + g), p)


def scara_jacobians(q: np.ndarray) -> dict[str, np.ndarray]:
    """(N, 6, 4) Jacobians of "ee" per reference."""
    a, b, g, _ = q.T
    sa, ca, sab, cab = np.sin(a), np.cos(a), np.sin(a + b), np.cos(a + b)
    x, y = A1 * ca + A2 * cab, A1 * sa + A2 * sab
    ez, zeta_col = [0, 0, 1], [0, 0, -1, 0, 0, 0]
    lwa = _columns([-y, x, 0, *ez], [-A2 * sab, A2 * cab, 0, *ez], [0, 0, 0, *ez], zeta_col)
    # C^T = rotation about z by -phi; the planar vectors turn by -(alpha + beta + gamma).
    local = _columns(
        [A1 * np.sin(b + g) + A2 * np.sin(g), A1 * np.cos(b + g) + A2 * np.cos(g), 0, *ez],
        [A2 * np.sin(g), A2 * np.cos(g), 0, *ez],
        [0, 0, 0, *ez],
        zeta_col,
    )
    # p_k x e_z = (y_k, -x_k, 0); joint alpha's axis passes through the origin.
    world = _columns([0, 0, 0, *ez], [A1 * sa, -A1 * ca, 0, *ez], [y, -x, 0, *ez], zeta_col)
    return {"local_world_aligned": lwa, "local": local, "world": world}


CLOSED_FORMS = {"planar_3dof": (planar_pose, planar_jacobians), "scara": (scara_pose, scara_jacobians)}


@pytest.fixture(scope="module", params=SHIPPED)
def shipped(request):
    return kinengine.load(request.param)


@pytest.mark.parametrize("name", sorted(CLOSED_FORMS))
def test_pose_equals_closed_form(name):
    robot = kinengine.load(name)
    q = _samples(robot, seed=1)
    np.testing.assert_allclose(robot.frame_pose(q, "ee"), CLOSED_FORMS[name][0](q), rtol=0, atol=1e-12)


@pytest.mark.parametrize("reference", REFERENCES)
@pytest.mark.parametrize("name", sorted(CLOSED_FORMS))
def test_jacobian_equals_closed_form(name, reference):
    robot = kinengine.load(name)
    q = _samples(robot, seed=2)
    expected = CLOSED_FORMS[name][1](q)[reference]
    np.testing.assert_allclose(robot.jacobian(q, "ee", reference=reference), expected, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", sorted(CLOSED_FORMS))
def test_closed_form_references_follow_from_their_definitions(name):
    """local = blockdiag(C^T, C^T) J_lwa and world = [[I, [p]x], [0, I]] J_lwa, on the closed forms alone."""
    q = _samples(kinengine.load(name), seed=3)
    T, J = CLOSED_FORMS[name][0](q), CLOSED_FORMS[name][1](q)
    Ct, p, lwa = np.swapaxes(T[:, :3, :3], 1, 2), T[:, :3, 3], J["local_world_aligned"]
    np.testing.assert_allclose(
        J["local"], np.concatenate([Ct @ lwa[:, :3], Ct @ lwa[:, 3:]], 1), rtol=0, atol=1e-12
    )
    world_lin = lwa[:, :3] + np.cross(p[:, :, None], lwa[:, 3:], axis=1)
    np.testing.assert_allclose(J["world"], np.concatenate([world_lin, lwa[:, 3:]], 1), rtol=0, atol=1e-12)


def test_scara_operational_space_and_singularity():
    """chi_o = (x, y, z, phi) of example 2.8.4; its analytic Jacobian has det = l1 l2 sin(beta)."""
    robot = kinengine.load("scara")
    q = np.vstack([_samples(robot, seed=4), [[0.3, 0.0, -1.0, 0.05]]])  # last: stretched arm, beta = 0
    a, b, g, _z = q.T
    T = robot.frame_pose(q, "ee")
    np.testing.assert_allclose(T[:, 2, :3], np.broadcast_to([0, 0, 1], (len(q), 3)), rtol=0, atol=1e-12)
    phi = np.arctan2(T[:, 1, 0], T[:, 0, 0])
    np.testing.assert_allclose(np.angle(np.exp(1j * (phi - (a + b + g)))), 0, rtol=0, atol=1e-12)
    J_A = robot.jacobian(q, "ee")[:, [0, 1, 2, 5]]  # E = identity for (x, y, z, phi)
    expected = _columns(
        [-A1 * np.sin(a) - A2 * np.sin(a + b), A1 * np.cos(a) + A2 * np.cos(a + b), 0, 1],
        [-A2 * np.sin(a + b), A2 * np.cos(a + b), 0, 1],
        [0, 0, 0, 1],
        [0, 0, -1, 0],
    )
    np.testing.assert_allclose(J_A, expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(J_A), A1 * A2 * np.sin(b), rtol=0, atol=1e-12)
    assert np.linalg.matrix_rank(J_A[-1]) == 3


# -- ABB IRB 120: /work/shared/facts/abb_irb120.md ------------------------------------------------
# joint: (origin xyz [m], axis, lower, upper [rad], velocity [rad/s]) from the facts table, and the
# product specification's axis ranges [deg] and speeds [deg/s].
ABB_JOINTS = {
    "joint_1": ((0, 0, 0), (0, 0, 1), -2.87979, 2.87979, 4.36332, (-165, 165), 250),
    "joint_2": ((0, 0, 0.29), (0, 1, 0), -1.91986, 1.91986, 4.36332, (-110, 110), 250),
    "joint_3": ((0, 0, 0.27), (0, 1, 0), -1.91986, 1.22173, 4.36332, (-110, 70), 250),
    "joint_4": ((0, 0, 0.07), (1, 0, 0), -2.79253, 2.79253, 5.58505, (-160, 160), 320),
    "joint_5": ((0.302, 0, 0), (0, 1, 0), -2.094395, 2.094395, 5.58505, (-120, 120), 320),
    "joint_6": ((0.072, 0, 0), (1, 0, 0), -6.98132, 6.98132, 7.33038, (-400, 400), 420),
}
ABB_MASSES = {
    "base_link": 6.215,
    "link_1": 3.067,
    "link_2": 3.909,
    "link_3": 2.944,
    "link_4": 1.328,
    "link_5": 0.546,
    "link_6": 0.137,
}
ABB_LINK_4 = (
    (0.2247, 0.00015, 0.00041),
    (0.00284661, -2.12765e-05, -1.6435e-05, 0.00401346, 1.31336e-05, 0.0052535),
)


def abb_chain(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Independent FK from the facts table: T_I,tool0 (N, 4, 4) and I J_e0 of tool0 (N, 6, 6)."""
    T = np.broadcast_to(np.eye(4), (len(q), 4, 4)).copy()
    axes, points = [], []
    for k, (origin, axis, *_) in enumerate(ABB_JOINTS.values()):
        T[:, :3, 3] += T[:, :3, :3] @ np.asarray(origin, float)
        axes.append(T[:, :3, :3] @ np.asarray(axis, float))
        points.append(T[:, :3, 3].copy())
        T[:, :3, :3] = T[:, :3, :3] @ Rotation.from_rotvec(np.outer(q[:, k], axis)).as_matrix()
    T[:, :3, :3] = T[:, :3, :3] @ _rot("y", np.full(len(q), np.pi / 2))  # flange -> tool0
    J = np.stack(
        [np.concatenate([np.cross(n, T[:, :3, 3] - p), n], -1) for n, p in zip(axes, points, strict=False)],
        -1,
    )
    return T, J


def test_abb_check_figure_at_zero(abb):
    T = abb.frame_pose(abb.neutral(), "tool0")
    np.testing.assert_allclose(T[:3, 3], [0.374, 0.0, 0.630], rtol=0, atol=1e-12)
    np.testing.assert_allclose(T[:3, 2], [1.0, 0.0, 0.0], rtol=0, atol=1e-12)  # tool0 z along base +x
    np.testing.assert_allclose(T[:3, :3], [[0, 0, 1], [0, 1, 0], [-1, 0, 0]], rtol=0, atol=1e-12)
    flange = abb.frame_pose(abb.neutral(), "flange")
    np.testing.assert_allclose(
        flange, [[1, 0, 0, 0.374], [0, 1, 0, 0], [0, 0, 1, 0.63], [0, 0, 0, 1]], rtol=0, atol=1e-12
    )
    np.testing.assert_allclose(abb.frame_pose(abb.neutral(), "base"), np.eye(4), rtol=0, atol=0)


def test_abb_reach_is_the_product_specification_figure(abb):
    """Wrist centre (link_5) to joint-2 axis: at most 0.27 + |(0.302, 0.07)|, ABB's reach 0.580 m."""
    reach = 0.27 + np.hypot(0.302, 0.07)
    stretched = np.array([[0.4, -0.3, -np.arctan2(0.302, 0.07), 0.5, 0.2, 0.1]])
    q = np.vstack([stretched, _samples(abb, seed=7)])
    arm = abb.frame_pose(q, "link_5")[:, :3, 3] - abb.frame_pose(q, "link_2")[:, :3, 3]
    distance = np.linalg.norm(arm, axis=1)
    np.testing.assert_allclose(distance[0], reach, rtol=0, atol=1e-12)
    assert np.all(distance <= reach + 1e-12)
    assert abs(reach - 0.580) < 5e-4


def test_abb_joints_and_limits_match_the_facts(abb):
    assert abb.joint_names == tuple(ABB_JOINTS)
    facts = np.array([row[2:5] for row in ABB_JOINTS.values()])
    np.testing.assert_array_equal(abb.lower_limits, facts[:, 0])
    np.testing.assert_array_equal(abb.upper_limits, facts[:, 1])
    velocity = np.array([abb.description.joint(name).velocity for name in ABB_JOINTS])
    np.testing.assert_array_equal(velocity, facts[:, 2])
    spec_range = np.deg2rad([row[5] for row in ABB_JOINTS.values()])
    spec_speed = np.deg2rad([row[6] for row in ABB_JOINTS.values()])
    np.testing.assert_allclose(facts[:, :2], spec_range, rtol=0, atol=5e-6)  # 5 decimals in the facts
    np.testing.assert_allclose(facts[:, 2], spec_speed, rtol=0, atol=5e-6)


def test_abb_inertials_match_the_facts(abb):
    links = {link.name: link for link in abb.description.links}
    assert {name: links[name].inertial.mass for name in ABB_MASSES} == ABB_MASSES
    assert links["link_4"].inertial.xyz == ABB_LINK_4[0]
    assert links["link_4"].inertial.inertia == ABB_LINK_4[1]
    assert all(links[name].inertial is None for name in ("base", "flange", "tool0"))


def test_abb_pose_and_jacobian_equal_an_independent_chain(abb):
    q = _samples(abb, seed=5)
    T, J = abb_chain(q)
    np.testing.assert_allclose(abb.frame_pose(q, "tool0"), T, rtol=0, atol=1e-12)
    np.testing.assert_allclose(abb.jacobian(q, "tool0"), J, rtol=0, atol=1e-12)


# -- every shipped robot (menagerie style: a new folder is a new test case) ---------------------
README_MUST_NAME = {
    "abb_irb120": ("ABB", "product specification", "abb_irb120_support"),
    "planar_3dof": ("Robot Dynamics", "2.8.5", "2.8.7"),
    "scara": ("Robot Dynamics", "2.8.1", "2.8.4"),
}


@pytest.mark.parametrize("name", SHIPPED)
def test_folder_layout_and_readme_sources(name):
    folder = ROBOTS_DIR / name
    assert sorted(p.name for p in folder.glob("*.urdf")) == [f"{name}.urdf"]
    readme = (folder / "README.md").read_text(encoding="utf-8")
    sources = readme.split("## Sources", 1)[1].split("\n## ", 1)[0]
    assert any(line.startswith("- ") for line in sources.splitlines())
    for phrase in README_MUST_NAME.get(name, ()):
        assert phrase.lower() in readme.lower()


def test_loaded_name_and_end_effector(shipped):
    assert shipped.name == shipped.description.name == Path(shipped.source).parent.name
    assert shipped.end_effector == ("tool0" if shipped.name == "abb_irb120" else "ee")


def test_inertials_are_physical(shipped):
    for link in shipped.description.links:
        if link.inertial is None:
            continue
        ixx, ixy, ixz, iyy, iyz, izz = link.inertial.inertia
        principal = np.linalg.eigvalsh([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
        assert link.inertial.mass > 0 and principal[0] > 0, link.name
        assert principal[0] + principal[1] >= principal[2], link.name  # triangle inequality


def test_every_link_pose_equals_yourdfpy(shipped):
    """A second, independent URDF reader (yourdfpy) agrees on every link frame."""
    urdf = yourdfpy.URDF.load(shipped.source, load_meshes=False, build_collision_scene_graph=False)
    order = [shipped.joint_names.index(n) for n in urdf.actuated_joint_names]
    for q in _samples(shipped, seed=6)[:20]:
        urdf.update_cfg(q[order])
        for link in urdf.link_map:
            np.testing.assert_allclose(
                shipped.frame_pose(q, link), urdf.get_transform(link), rtol=0, atol=1e-12, err_msg=link
            )
