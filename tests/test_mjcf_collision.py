"""MJCF robots collide the geoms MuJoCo collides: kinengine's distances against MuJoCo's own
``mj_geomDistance`` run directly on the same file, and which geoms become collision shapes."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import kinengine

mujoco = pytest.importorskip("mujoco")

ARM = Path(__file__).parent / "data" / "mjcf" / "collision_arm.xml"
COLLIDED = (2, 3, 5, 6, 7)  # mjtGeom: sphere, capsule, cylinder, box, mesh


def _load() -> kinengine.Robot:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return kinengine.load(ARM)


def test_collision_geoms_become_collision_shapes_and_the_rest_do_not():
    with pytest.warns(
        UserWarning, match=r"1 collision geom of a type .* left out: 'hand_ellipsoid' of body 'hand'"
    ):
        robot = kinengine.load(ARM)
    shapes = [
        (o.name.rsplit("_", 1)[0], type(o.geometry).__name__)
        for o in robot.collision_geometry().geometryObjects
    ]
    assert shapes == [  # no visual-only cylinder, no floor, no ellipsoid
        ("base", "Box"),
        ("upper", "Capsule"),
        ("fore", "Cylinder"),
        ("fore", "Convex"),
        ("hand", "Sphere"),
    ]
    assert robot.collision_pairs() == [("base", "fore"), ("base", "hand"), ("upper", "hand")]


def test_distances_match_mujocos_geom_distance():
    """The closest distance of each checked link pair equals MuJoCo's over the same geoms, penetration
    depths included (MuJoCo's convex solver is accurate to ~1e-6 m)."""
    robot = _load()
    model = mujoco.MjModel.from_xml_path(str(ARM))
    data = mujoco.MjData(model)
    geoms: dict[str, list[int]] = {}
    for g in range(model.ngeom):
        collides = model.geom_contype[g] or model.geom_conaffinity[g]
        if collides and model.geom_type[g] in COLLIDED and model.geom_bodyid[g] != 0:
            geoms.setdefault(model.body(model.geom_bodyid[g]).name, []).append(g)
    qpos_index = [robot.joint_names.index(model.joint(j).name) for j in range(model.njnt)]
    Q = np.random.default_rng(0).uniform(robot.lower_limits, robot.upper_limits, (200, robot.dof))
    ours, theirs = [], []
    for q in Q:
        data.qpos[:] = q[qpos_index]
        mujoco.mj_kinematics(model, data)
        D = robot.distances(q)
        for a, b in robot.collision_pairs():
            ours.append(min(d for pair, d in zip(D.links, D.distance, strict=True) if tuple(pair) == (a, b)))
            theirs.append(
                min(mujoco.mj_geomDistance(model, data, i, j, 10.0, None) for i in geoms[a] for j in geoms[b])
            )
    ours_a, theirs_a = np.array(ours), np.array(theirs)
    assert (theirs_a < 0).sum() > 10  # the sample has penetrations to compare
    np.testing.assert_allclose(ours_a, theirs_a, rtol=0, atol=5e-6)
    collided = [robot.in_collision(q) for q in Q]
    expected = (theirs_a.reshape(len(Q), -1) < 0).any(axis=1)
    assert collided == expected.tolist()


def test_an_mjcf_file_without_collision_geoms_still_refuses_collision_queries():
    path = Path(__file__).parent / "data" / "mjcf" / "kinematics_only.xml"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = kinengine.load(path)
    with pytest.raises(
        kinengine.URDFError, match="to an MJCF file: geoms with contype or conaffinity non-zero"
    ):
        robot.in_collision(np.zeros(robot.dof))


CAPSULES = """<robot name="capsules">
  <link name="base"><collision><geometry><capsule radius="0.05" length="0.4"/></geometry></collision></link>
  <link name="arm"><collision><origin xyz="0 0 0.2"/><geometry><capsule radius="0.03" length="0.2"/></geometry>
  </collision></link>
  <link name="tip"><collision><geometry>{tip}</geometry></collision></link>
  <joint name="j" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="0.3 0 0" rpy="1.2 0 0"/>
    <axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="k" type="fixed"><parent link="arm"/><child link="tip"/><origin xyz="0 0 0.4"/></joint>
</robot>"""


def _segment_distance(p0, p1, q0, q1):
    """Closest distance between segments [p0, p1] and [q0, q1], by dense sampling refined by scipy."""
    from scipy.optimize import minimize

    def f(st):
        s, t = np.clip(st, 0.0, 1.0)
        return np.linalg.norm(p0 + s * (p1 - p0) - q0 - t * (q1 - q0))

    starts = [(s, t) for s in np.linspace(0, 1, 5) for t in np.linspace(0, 1, 5)]
    return min(
        minimize(f, x0, method="Nelder-Mead", options={"xatol": 1e-12, "fatol": 1e-14}).fun for x0 in starts
    )


def test_urdf_capsules_are_capsules():
    """Two capsules' distance is their axes' segment distance minus both radii (a closed form): the arm's
    URDF capsule against an obstacle capsule where the base's is."""
    plain = kinengine.load_urdf_string(CAPSULES.format(tip='<sphere radius="0.01"/>'))
    robot = plain.with_obstacles([kinengine.Capsule(0.05, 0.4, name="post")])
    shapes = {o.name: type(o.geometry).__name__ for o in robot.collision_geometry().geometryObjects}
    assert shapes == {"base_0": "Capsule", "arm_0": "Capsule", "tip_0": "Sphere", "post": "Capsule"}
    penetrating = 0
    for q in np.linspace(-3, 3, 13):
        Q = np.array([q])
        T = robot.frame_pose(Q, "arm")
        a0, a1 = np.array([0, 0, -0.2]), np.array([0, 0, 0.2])
        b0, b1 = (T @ [0, 0, 0.1, 1])[:3], (T @ [0, 0, 0.3, 1])[:3]
        D = robot.distances(Q)
        (k,) = [i for i, pair in enumerate(D.links) if set(pair) == {"arm", "post"}]
        expected = _segment_distance(a0, a1, b0, b1) - 0.08
        tolerance = 1e-12 if expected > 0 else 1e-5  # a penetration depth comes from coal's EPA
        assert D.distance[k] == pytest.approx(expected, abs=tolerance)
        penetrating += expected < 0
    assert penetrating > 0


def test_a_geometry_pinocchio_cannot_read_is_refused_naming_the_link():
    robot = kinengine.load_urdf_string(CAPSULES.format(tip='<cone radius="0.01" length="0.1"/>'))
    with pytest.raises(
        kinengine.URDFError, match=r"a <collision> of link 'tip' holds \['cone'\].*one of box"
    ):
        robot.collision_geometry()
    bad = kinengine.load_urdf_string(CAPSULES.format(tip='<capsule radius="-1" length="0.1"/>'))
    with pytest.raises(kinengine.URDFError, match=r"the <capsule> of link 'tip' needs radius > 0"):
        bad.collision_geometry()
