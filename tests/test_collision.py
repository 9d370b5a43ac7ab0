"""Collision geometry, pairs, distances and the CollisionAvoidance constraint (kinengine.collision), checked
against closed forms for primitives, coal's own distance query run directly on shapes placed by kinengine's
frame poses, finite differences of the distance, and raw Pinocchio + coal on Pinocchio's own URDF model."""

from __future__ import annotations

import importlib.util
import pickle
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
import pytest
from example_modules import example_module

import kinengine
from kinengine import Box, Capsule, DifferentialIK, Mesh, PoseTarget, Sphere
from kinengine.errors import OptionError, URDFError

R_BALL = 0.05
BALL_AT = np.array([0.3, 0.0, 0.1])  # the ball's centre in link_2 [m]

ARM = f"""<robot name="ball_arm">
  <link name="base"/>
  <link name="link_1"><collision><origin xyz="0 0 0.05"/><geometry><cylinder radius="0.03" length="0.1"/></geometry></collision></link>
  <link name="link_2"><collision><origin xyz="{BALL_AT[0]} {BALL_AT[1]} {BALL_AT[2]}"/><geometry><sphere radius="{R_BALL}"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="link_1"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="link_1"/><child link="link_2"/><origin xyz="0 0 0.1"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>"""


@pytest.fixture(scope="module")
def arm():
    return kinengine.load_urdf_string(ARM)


@pytest.fixture(scope="module")
def panda():
    return kinengine.load("panda")


def ball_centre(robot, q):
    return (robot.frame_pose(q, "link_2") @ np.append(BALL_AT, 1.0))[:3]


def _transform(T):
    return coal.Transform3s(np.ascontiguousarray(T[:3, :3]), np.ascontiguousarray(T[:3, 3]))


def random_q(robot, n, seed=0):
    return robot.random_configuration(rng=seed, size=n)


# -- closed forms --------------------------------------------------------------------------------------
def test_sphere_sphere_distance_and_witness_points_match_the_closed_form(arm):
    c2, r2 = np.array([0.2, 0.25, 0.3]), 0.07
    robot = arm.with_obstacles([Sphere(r2, c2)])
    for q in random_q(robot, 50):
        D = robot.distances(q)
        k = D.links.index(("link_2", "obstacle_0"))
        c1 = ball_centre(robot, q)
        gap = np.linalg.norm(c2 - c1)
        u = (c2 - c1) / gap
        assert D.distance[k] == pytest.approx(gap - R_BALL - r2, abs=1e-9)
        np.testing.assert_allclose(D.p1[k], c1 + R_BALL * u, rtol=0, atol=1e-9)
        np.testing.assert_allclose(D.p2[k], c2 - r2 * u, rtol=0, atol=1e-9)


def test_box_sphere_distance_matches_the_closed_form_and_witnesses_lie_on_the_surfaces(arm):
    T = np.eye(4)
    T[:3, :3] = pin.rpy.rpyToMatrix(0.3, -0.2, 0.5)
    T[:3, 3] = [0.25, -0.2, 0.15]
    half = np.array([0.05, 0.08, 0.04])
    robot = arm.with_obstacles([Box(2 * half, T)])
    checked = 0
    for q in random_q(robot, 100, seed=1):
        D = robot.distances(q)
        k = D.links.index(("link_2", "obstacle_0"))
        local = T[:3, :3].T @ (ball_centre(robot, q) - T[:3, 3])
        if np.all(np.abs(local) <= half):
            continue  # centre inside the box: no simple closed form
        closest = np.clip(local, -half, half)
        expected = np.linalg.norm(local - closest) - R_BALL
        assert D.distance[k] == pytest.approx(expected, abs=1e-9)
        p2_local = T[:3, :3].T @ (D.p2[k] - T[:3, 3])
        if expected > 0:
            np.testing.assert_allclose(p2_local, closest, rtol=0, atol=1e-9)  # on the box's surface
            assert np.linalg.norm(D.p1[k] - ball_centre(robot, q)) == pytest.approx(R_BALL, abs=1e-9)
        checked += 1
    assert checked > 50


# -- coal directly ------------------------------------------------------------------------------------
def test_panda_distances_equal_coal_on_shapes_placed_by_kinengine(panda):
    robot = panda.with_obstacles(
        [Box((0.2, 0.3, 0.1), [0.4, 0.1, 0.3]), Capsule(0.05, 0.3, [0.3, -0.3, 0.5])]
    )
    geometry = robot.collision_geometry()
    objects = geometry.geometryObjects
    for q in random_q(robot, 20, seed=2):
        D = robot.distances(q)

        def placement(obj):
            if obj.parentJoint == 0:  # the base link and the obstacles: placed in the root link frame
                return obj.placement.homogeneous
            joint = robot.engine.model.names[obj.parentJoint]  # a shape is placed on its joint's frame
            return robot.frame_pose(q, joint) @ obj.placement.homogeneous

        _, gdata = robot.collision_checker().data()  # the placements of this thread's last query (at q)
        for i, obj in enumerate(objects):  # placed by kinengine's own frame poses: the same, to rounding
            np.testing.assert_allclose(gdata.oMg[i].homogeneous, placement(obj), rtol=0, atol=1e-12)
        for k, cp in enumerate(geometry.collisionPairs):
            a, b = objects[cp.first], objects[cp.second]
            result = coal.DistanceResult()
            Ta, Tb = gdata.oMg[cp.first].homogeneous, gdata.oMg[cp.second].homogeneous
            d = coal.distance(
                a.geometry, _transform(Ta), b.geometry, _transform(Tb), coal.DistanceRequest(), result
            )
            assert D.distance[k] == pytest.approx(d, abs=1e-9), D.pairs[k]
            if d > 0:
                np.testing.assert_allclose(D.p1[k], result.getNearestPoint1(), rtol=0, atol=1e-9)
                np.testing.assert_allclose(D.p2[k], result.getNearestPoint2(), rtol=0, atol=1e-9)
                assert np.linalg.norm(D.p2[k] - D.p1[k]) == pytest.approx(d, abs=1e-9)
        assert robot.min_distance(q) == pytest.approx(D.distance.min(), abs=0)


# -- gradients ----------------------------------------------------------------------------------------
def test_distance_gradient_matches_finite_differences(arm):
    T = np.eye(4)
    T[:3, :3] = pin.rpy.rpyToMatrix(0.1, 0.4, -0.3)
    T[:3, 3] = [0.1, 0.3, 0.2]
    robot = arm.with_obstacles([Sphere(0.06, [0.2, 0.25, 0.3]), Box((0.1, 0.12, 0.08), T)])
    checker = robot.collision_checker()
    h = 1e-6
    for q in random_q(robot, 30, seed=3):
        rows, _d, G = checker.gradients(q)
        assert G.shape == (len(rows), robot.dof)
        ball = [r for r in range(len(rows)) if checker.links[rows[r]][0] == "link_2"]  # closed forms in coal
        rows, G = rows[ball], G[ball]
        assert len(rows) == 2
        for i in range(robot.dof):
            e = np.zeros(robot.dof)
            e[i] = h
            fd = (checker.distances(q + e).distance[rows] - checker.distances(q - e).distance[rows]) / (2 * h)
            np.testing.assert_allclose(G[:, i], fd, rtol=0, atol=1e-6)


def test_panda_gradients_match_finite_differences_for_separated_pairs(panda):
    robot = panda.with_obstacles([Sphere(0.05, [0.45, 0.1, 0.45])])
    checker = robot.collision_checker()
    h = 1e-5
    q = np.array([0.1, -0.6, 0.1, -2.2, 0.1, 1.7, 0.7, 0.02])
    rows, _d, G = checker.gradients(q, 0.1)
    obstacle_rows = [r for r in range(len(rows)) if checker.links[rows[r]][1] == "obstacle_0"]
    assert obstacle_rows  # the hand and fingers are near the ball
    for i in range(robot.dof):
        e = np.zeros(robot.dof)
        e[i] = h
        fd = (checker.distances(q + e).distance[rows] - checker.distances(q - e).distance[rows]) / (2 * h)
        # sphere-to-convex distances come from GJK (tolerance ~1e-6 m): the difference quotient is that noisy
        np.testing.assert_allclose(G[obstacle_rows, i], fd[obstacle_rows], rtol=0, atol=2e-3)


# -- self-collision against raw Pinocchio + coal ----------------------------------------------------------
def test_10000_panda_configurations_classified_like_raw_pinocchio_and_coal(panda):
    checker = panda.collision_checker()
    model = pin.buildModelFromUrdf(str(panda.source))
    geometry = pin.buildGeomFromUrdf(
        model,
        str(panda.source),
        pin.GeometryType.COLLISION,
        package_dirs=[str(panda.source).split("/robots/")[0] + "/.."],
    )
    for obj in geometry.geometryObjects:
        if isinstance(obj.geometry, coal.BVHModelBase):
            obj.geometry.buildConvexHull(True, "Qt")
            obj.geometry = obj.geometry.convex
    names = [o.name for o in geometry.geometryObjects]
    for a, b in checker.pairs:
        geometry.addCollisionPair(pin.CollisionPair(names.index(a), names.index(b)))
    data, gdata = model.createData(), pin.GeometryData(geometry)
    Q = random_q(panda, 10_000, seed=4)
    # kinengine's q -> Pinocchio's q of its own URDF model, joint by joint (the finger mimic copies its leader)
    coords = panda.engine.coordinates
    Q_pin = np.zeros((len(Q), model.nq))
    for k, name in enumerate(coords.pinocchio_names):
        j = model.joints[model.getJointId(name)]
        Q_pin[:, j.idx_q] = Q[:, coords.leader[k]] * coords.multiplier[k] + coords.offset[k]
    raw = np.array([pin.computeCollisions(model, data, geometry, gdata, q, True) for q in Q_pin])
    ours = panda.in_collision(Q)
    assert ours.dtype == bool and ours.shape == (10_000,)
    assert 0.02 < raw.mean() < 0.98  # both classes are sampled
    np.testing.assert_array_equal(ours, raw)
    assert [panda.in_collision(q) for q in Q[:200]] == list(raw[:200])


# -- control ------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def example():
    """examples/collision_avoidance.py, whose sweep the test below runs."""
    yield from example_module("collision_avoidance")


def test_panda_hand_past_a_box_collides_without_avoidance_and_keeps_clear_with_it(example, tmp_path):
    """The example's 500 Hz sweep: 0.4 m in 2 s past a 10 cm box 0.1 m below the hand, then 1 s hold."""
    robot, T0 = example.scene()
    free = example.sweep(robot, T0, avoid=False)
    assert free.min_distance.min() < 0.0  # the fingers go through the box
    avoided = example.sweep(robot, T0, avoid=True)
    assert avoided.min_distance.min() >= 0.01 - 1e-4
    assert avoided.error.max() < 0.03 and avoided.error[-1] < 0.005  # over the box, then on target
    assert abs(avoided.error[-1] - free.error[-1]) < 1e-4  # the same end point (the posture term's offset)
    example.plot(free, avoided, str(tmp_path / "sweep.png"))
    assert (tmp_path / "sweep.png").stat().st_size > 10_000


def test_differential_ik_respects_a_constraint_row():
    robot = kinengine.load("abb_irb120")
    q = np.array([0.3, 0.2, -0.4, 0.5, 0.7, 1.0])

    class Cap:
        def inequalities(self, robot, q, dt):
            return np.eye(robot.dof)[:1], np.array([0.05])  # q̇_1 <= 0.05 rad/s

    target = PoseTarget("tool0", robot.frame_pose(q + 0.3))
    free = DifferentialIK(robot, [target]).solve(q, 0.01)
    capped = DifferentialIK(robot, [target], constraints=[Cap()]).solve(q, 0.01)
    assert free[0] > 0.05 and capped[0] == pytest.approx(0.05, abs=1e-9)
    with pytest.raises(OptionError, match="inequalities"):
        DifferentialIK(robot, [target], constraints=[object()])


# -- model, pairs, obstacles -----------------------------------------------------------------------------
def test_abb_ships_its_collision_meshes(abb):
    geometry = abb.collision_geometry()
    assert geometry.ngeoms == 7
    assert all(isinstance(o.geometry, coal.ConvexBase) for o in geometry.geometryObjects)
    assert ("link_1", "link_2") not in abb.collision_pairs()  # adjacent
    assert ("base_link", "link_2") in abb.collision_pairs()
    assert abb.min_distance(abb.neutral()) > 0
    assert abb.collision_geometry() is geometry  # built once


def test_srdf_disables_pairs_and_pickling_keeps_obstacles_and_srdf(arm, tmp_path):
    robot = arm.with_obstacles([Sphere(0.05, [0.5, 0.5, 0.5], name="ball")])
    assert ("link_2", "ball") in robot.collision_pairs()
    assert ("link_1", "ball") in robot.collision_pairs()
    srdf = tmp_path / "arm.srdf"
    srdf.write_text(
        '<robot name="ball_arm"><disable_collisions link1="ball" link2="link_1" reason="x"/></robot>'
    )
    assert ("link_1", "ball") not in robot.collision_pairs(srdf=srdf)
    limited = robot.with_srdf(srdf)
    copy = pickle.loads(pickle.dumps(limited))
    assert copy.collision_pairs() == limited.collision_pairs() == [("link_2", "ball")]
    q = np.array([0.2, 0.3])
    assert copy.min_distance(q) == limited.min_distance(q)
    assert (
        pickle.loads(pickle.dumps(arm)).collision_pairs() == []
    )  # base-fixed cylinder vs ball arm: adjacent


def test_missing_meshes_and_bad_obstacles_are_clear_errors(arm, tmp_path):
    text = ARM.replace('<sphere radius="0.05"/>', '<mesh filename="meshes/ball.stl"/>').replace(
        '<cylinder radius="0.03" length="0.1"/>', '<mesh filename="package://nowhere_pkg/c.stl"/>'
    )
    path = tmp_path / "arm.urdf"
    path.write_text(text)
    robot = kinengine.load(str(path))
    with pytest.raises(URDFError, match=r"2 collision mesh files not found: .*nowhere_pkg") as caught:
        robot.distances(robot.neutral())
    assert "'meshes/ball.stl' of link 'link_2'" in str(caught.value)
    with pytest.raises(OptionError, match="radius"):
        Sphere(-1.0)
    with pytest.raises(OptionError, match="pose"):
        Box((0.1, 0.1, 0.1), np.ones((4, 4)))
    with pytest.raises(OptionError, match="obstacles are"):
        arm.with_obstacles(["box"])


def test_collision_pairs_command_writes_an_srdf_the_robot_reads(tmp_path, capsys):
    from kinengine.cli import main

    srdf = tmp_path / "abb.srdf"
    assert main(["collision-pairs", "abb_irb120", "--samples", "300", "--write", str(srdf)]) == 0
    out = capsys.readouterr().out
    assert "6 pairs adjacent or rigidly joined" in out and "15 pairs sampled in 300" in out
    abb = kinengine.load("abb_irb120")
    limited = abb.with_srdf(srdf)
    text = srdf.read_text()
    never = text.count('reason="Never"')
    assert len(limited.collision_pairs()) == 15 - never - text.count('reason="Always"')
    # every pair left out as "Never" is free in every one of 300 fresh configurations
    free = set(abb.collision_pairs()) - set(limited.collision_pairs())
    checker = abb.collision_checker()
    for q in abb.random_configuration(rng=7, size=300):
        hit = checker.colliding_pairs(q)
        assert not any(h and checker.links[k] in free for k, h in enumerate(hit))
    with pytest.raises(SystemExit, match="2"):
        main(["collision-pairs", "abb_irb120", "--samples", "0"])


@pytest.mark.skipif(importlib.util.find_spec("viser") is None, reason="needs the [view] extra (viser)")
def test_viewer_shows_collision_shapes_and_colours_the_colliding_ones(panda):
    q_free = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785, 0.02])
    q_hit = panda.neutral()  # joint 4 at 0: link 5 folds into the hand (outside the limits, but allowed)
    checker = panda.collision_checker()
    with panda.view(q_free, port=0, frames=[]) as viewer:
        assert viewer.show_collisions() == []
        layer = viewer._collisions
        assert len(layer.nodes) == panda.collision_geometry().ngeoms
        viewer.update(q_hit)
        expected = [checker.links[k] for k in np.flatnonzero(checker.colliding_pairs(q_hit))]
        assert layer.colliding == expected and ("panda_link5", "panda_hand") in expected
        _, gdata = checker.data()
        shown = {i for i, (free, hit) in layer.nodes.items() if hit.visible}
        assert shown == {
            i for k in np.flatnonzero(checker.colliding_pairs(q_hit)) for i in checker.index_pairs[k]
        }
        for i, (_free, hit) in layer.nodes.items():
            np.testing.assert_allclose(hit.position, gdata.oMg[i].translation, rtol=0, atol=1e-6)
        assert viewer.show_collisions(False) == [] and viewer._collisions is None


def test_inverse_kinematics_avoid_collisions_repairs_a_colliding_solution():
    arm = kinengine.load("panda_arm")
    q_star = np.array([0.3, -0.4, 0.2, -2.0, 0.1, 1.8, 0.5])
    T = arm.frame_pose(q_star, "panda_hand")
    plain = arm.inverse_kinematics(T, "panda_hand", rng=1)
    elbow = arm.frame_pose(plain.q, "panda_link4")[:3, 3]
    scene = arm.with_obstacles([Sphere(0.06, elbow)])  # right where that solution puts its elbow
    assert plain.success and scene.in_collision(plain.q)
    assert scene.inverse_kinematics(T, "panda_hand", rng=1).q == pytest.approx(plain.q, abs=1e-12)
    repaired = scene.inverse_kinematics(T, "panda_hand", rng=1, restarts=10, avoid_collisions=True)
    assert repaired.success and not scene.in_collision(repaired.q)
    np.testing.assert_allclose(scene.frame_pose(repaired.q, "panda_hand"), T, rtol=0, atol=1e-5)
    batch = scene.inverse_kinematics(np.stack([T, T]), "panda_hand", avoid_collisions=True)
    assert not (batch.success & scene.in_collision(batch.q)).any()  # colliding rows are not successes


def test_a_mesh_obstacle_is_its_convex_hull(arm):
    stl = Path(kinengine.load("abb_irb120").source).parent / "meshes" / "collision" / "link_1.stl"
    far = arm.with_obstacles([Mesh(stl, [2.0, 0.0, 0.0])])
    near = arm.with_obstacles([Mesh(stl, ball_centre(arm, np.zeros(2)) - [0.0, 0.0, 0.2])])
    hull = far.collision_geometry().geometryObjects[-1].geometry
    assert isinstance(hull, coal.ConvexBase)
    points = np.asarray(hull.points()) + [2.0, 0.0, 0.0]
    centre = ball_centre(far, np.zeros(2))
    expected = np.linalg.norm(points - centre, axis=1).min() - R_BALL  # a vertex is closest, seen from afar
    assert far.distances(np.zeros(2)).distance[-1] == pytest.approx(expected, abs=2e-3)
    assert far.distances(np.zeros(2)).distance[-1] <= expected + 1e-9  # a face or edge may be closer
    assert near.in_collision(np.zeros(2))


def test_edited_robots_keep_their_obstacles_and_lock_through_the_geometry(panda):
    scene = panda.with_obstacles([Sphere(0.05, [0.4, 0.0, 0.4], name="ball")])
    arm = scene.locked({"panda_finger_joint1": 0.02})
    assert ("panda_hand", "ball") in arm.collision_pairs()
    q = np.array([0.1, -0.6, 0.1, -2.2, 0.1, 1.7, 0.7])
    # the locked robot's shapes sit where the full robot's do at the locked value; its fingers are now rigid
    # with the hand, so the pairs among them are gone
    locked, full = arm.distances(q), scene.distances(np.append(q, 0.02))
    by_name = dict(zip(full.pairs, full.distance, strict=True))
    assert len(locked.pairs) < len(full.pairs) and set(locked.pairs) <= set(full.pairs)
    assert ("panda_leftfinger_0", "panda_rightfinger_0") in set(full.pairs) - set(locked.pairs)
    for name, d in zip(locked.pairs, locked.distance, strict=True):
        assert d == pytest.approx(by_name[name], abs=1e-9), name


def test_edited_robots_keep_their_srdf_pairs(arm, tmp_path):
    srdf = '<robot name="ball_arm"><disable_collisions link1="link_1" link2="ball" reason="x"/></robot>'
    robot = arm.with_obstacles([Sphere(0.05, [0.5, 0.5, 0.5], name="ball")]).with_srdf(srdf)
    tooled = robot.with_frame("tip", "link_2", ([0.35, 0.0, 0.1], [0.0, 0.0, 0.0]))
    assert tooled.obstacles == robot.obstacles
    assert (
        tooled.disabled_collision_pairs == robot.disabled_collision_pairs == {frozenset(("link_1", "ball"))}
    )
    assert tooled.collision_pairs() == robot.collision_pairs() == [("link_2", "ball")]


def test_ik_solutions_avoid_collisions_drops_exactly_the_colliding_solutions():
    pytest.importorskip("eaik", reason="the closed-form solver needs the ik extra")
    abb = kinengine.load("abb_irb120")
    # a wall beside the arm: some of a pose's elbow/shoulder branches pass through it, others do not
    wall = abb.with_obstacles([Box((0.05, 1.0, 1.0), [-0.25, 0.0, 0.5])])
    T = abb.frame_pose(abb.random_configuration(rng=3, size=60))
    every = wall.ik_solutions(T)
    free = wall.ik_solutions(T, avoid_collisions=True)
    dropped = 0
    for i in range(len(T)):
        q_all = every.q[i][: every.count[i]]
        hit = np.asarray(wall.in_collision(q_all)) if len(q_all) else np.zeros(0, bool)
        expected = q_all[~hit]
        assert free.count[i] == len(expected)
        np.testing.assert_array_equal(free.q[i][: free.count[i]], expected)  # same order, colliding ones gone
        assert np.all(np.isnan(free.q[i][free.count[i] :]))
        dropped += int(hit.sum())
    assert dropped > 0 and int(np.sum(free.count)) > 0
    single = wall.ik_solutions(T[0], avoid_collisions=True)
    np.testing.assert_array_equal(single.q, free.q[0][: free.count[0]])
    with pytest.raises(OptionError, match="avoid_collisions"):
        wall.ik_solutions(T[0], avoid_collisions="yes")


# -- review fixes: robots without shapes, 1-DOF gradients, option checks, SRDF names, the command -----------
ONE_DOF = f"""<robot name="one_arm">
  <link name="base"/>
  <link name="link_1"><collision><origin xyz="{BALL_AT[0]} {BALL_AT[1]} {BALL_AT[2]}"/><geometry><sphere radius="{R_BALL}"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="link_1"/><axis xyz="0 0.6 0.8"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>"""


def test_a_robot_without_collision_shapes_is_an_error_not_collision_free():
    robot = kinengine.load("planar_3dof").with_obstacles([Sphere(5.0)])  # engulfs the whole arm
    q = np.zeros(robot.dof)
    for query in (
        lambda: robot.in_collision(q),
        lambda: robot.min_distance(q),
        robot.collision_pairs,
        robot.collision_geometry,
    ):
        with pytest.raises(
            URDFError, match=r"robot 'planar_3dof' has no <collision> elements.*add <collision>"
        ):
            query()
    target = PoseTarget(robot.end_effector, robot.frame_pose(q + 0.1))
    ik = DifferentialIK(robot, [target], constraints=[kinengine.CollisionAvoidance()])
    with pytest.raises(URDFError, match="to an MJCF file: geoms with contype or conaffinity"):
        ik.solve(q, 0.01)


def test_distance_gradient_of_a_one_dof_arm_matches_finite_differences():
    robot = kinengine.load_urdf_string(ONE_DOF).with_obstacles([Sphere(0.06, [0.1, 0.3, 0.2])])
    checker = robot.collision_checker()
    h, slopes = 1e-6, []
    for q in random_q(robot, 20, seed=5):
        rows, d, G = checker.gradients(q)
        assert G.shape == (1, 1) and rows.tolist() == [0]
        c1 = (robot.frame_pose(q, "link_1") @ np.append(BALL_AT, 1.0))[:3]
        assert d[0] == pytest.approx(np.linalg.norm(c1 - [0.1, 0.3, 0.2]) - R_BALL - 0.06, abs=1e-9)
        fd = (checker.min_distance(q + h) - checker.min_distance(q - h)) / (2 * h)
        assert G[0, 0] == pytest.approx(fd, abs=1e-6)
        slopes.append(abs(fd))
    assert max(slopes) > 0.05  # the sample sees the distance change with q, not a flat zero
    q = np.array([0.4])
    T = robot.frame_pose(q + 0.2)
    step = DifferentialIK(
        robot,
        [PoseTarget(robot.end_effector, T, rows=("x", "y", "z"))],
        constraints=[kinengine.CollisionAvoidance()],
    ).solve(q, 0.01)
    assert step.shape == (1,) and np.isfinite(step).all()


def test_collision_avoidance_options_are_checked():
    with pytest.raises(OptionError, match="min_distance .*number >= 0, got str 'a'"):
        kinengine.CollisionAvoidance(min_distance="a")
    with pytest.raises(OptionError, match="min_distance .*>= 0, got -1"):
        kinengine.CollisionAvoidance(min_distance=-1)
    with pytest.raises(OptionError, match="influence_distance"):
        kinengine.CollisionAvoidance(influence_distance=None)
    with pytest.raises(OptionError, match=r"gain must be in \(0, 1\]"):
        kinengine.CollisionAvoidance(gain=0)
    zero = kinengine.CollisionAvoidance(min_distance=0)
    assert zero.min_distance == 0.0 and type(zero.min_distance) is float


def test_an_srdf_naming_unknown_links_warns_once(arm):
    srdf = (
        '<robot name="other"><disable_collisions link1="link_1" link2="elbow" reason="x"/>'
        '<disable_collisions link1="wrist" link2="elbow" reason="x"/></robot>'
    )
    with pytest.warns(UserWarning, match=r"2 links this robot does not have: 'elbow', 'wrist'") as caught:
        robot = arm.with_srdf(srdf)
    assert len(caught) == 1 and caught[0].filename == __file__
    assert robot.disabled_collision_pairs == {frozenset(("link_1", "elbow")), frozenset(("wrist", "elbow"))}
    with pytest.warns(UserWarning, match="'elbow'"):
        arm.collision_pairs(srdf=srdf)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # known names (links and obstacles): no warning
        arm.with_obstacles([Sphere(0.05, [0.5, 0.5, 0.5], name="ball")]).with_srdf(
            '<robot name="ball_arm"><disable_collisions link1="link_1" link2="ball" reason="x"/></robot>'
        )


def test_collision_pairs_command_fails_at_once_without_shapes_or_a_writable_srdf(
    tmp_path, capsys, monkeypatch
):
    from kinengine.cli import main

    sampled = []
    monkeypatch.setattr("kinengine.cli.collisions.sample_pairs", lambda *a: sampled.append(a) or ([], []))
    assert main(["collision-pairs", "planar_3dof"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "robot 'planar_3dof' has no <collision> elements" in err
    with pytest.raises(SystemExit, match="2"):
        main(["collision-pairs", "abb_irb120", "--write", str(tmp_path / "missing" / "abb.srdf")])
    assert "folder" in capsys.readouterr().err and sampled == []
