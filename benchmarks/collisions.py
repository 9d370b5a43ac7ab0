"""Collision queries next to raw Pinocchio + coal on the same geometry and pairs, the batched collision test,
and a DifferentialIK step with CollisionAvoidance.

Robot: example-robot-data's Panda (8 dof with the finger; meshes as convex hulls, as kinengine builds them),
its default pairs (adjacent links left out: 42 link pairs, 99 shape pairs), 1,000 random configurations
within the limits
(seeded). "Raw" is the code a user writes inline on Pinocchio on the same GeometryModel (its own
GeometryData with Pinocchio's defaults): ``pin.computeDistances(model, data, geom, gdata, q)``, then reading
the results out (the smallest distance, or every distance and both witness points), and
``pin.computeCollisions(..., True)``. kinengine's call includes its input check and q -> Pinocchio's q map.
Times are interleaved (kinengine and raw alternate, round by round, over the same 1,000 configurations,
7 rounds); the table gives each side's median per call over the rounds and the ratio of the medians.

    python benchmarks/collisions.py
"""

from __future__ import annotations

import platform
import time

import numpy as np
import pinocchio as pin

import kinengine
from kinengine import Box, CollisionAvoidance, DifferentialIK, PoseTarget, PostureTarget


def per_call(fn, Q) -> float:
    t = time.perf_counter()
    for q in Q:
        fn(q)
    return (time.perf_counter() - t) / len(Q)


def main() -> None:
    robot = kinengine.load("panda")
    geometry = robot.collision_geometry()
    model = robot.engine.model
    data, gdata = model.createData(), pin.GeometryData(geometry)
    Q = robot.random_configuration(rng=0, size=1000)
    Q_pin = [robot.engine.coordinates.to_pinocchio(q) for q in Q]  # raw code gets Pinocchio's q ready-made
    pairs = len(geometry.collisionPairs)

    def raw_min(q):
        k = pin.computeDistances(model, data, geometry, gdata, q)
        return gdata.distanceResults[k].min_distance

    def raw_all(q):
        pin.computeDistances(model, data, geometry, gdata, q)
        res = gdata.distanceResults
        d = np.array([r.min_distance for r in res])
        p1 = np.array([r.getNearestPoint1() for r in res])
        p2 = np.array([r.getNearestPoint2() for r in res])
        return d, p1, p2

    def raw_collide(q):
        return pin.computeCollisions(model, data, geometry, gdata, q, True)

    rows = []
    for name, ours, raw in (
        ("min_distance(q)", robot.min_distance, raw_min),
        ("distances(q) (+ witness points)", robot.distances, raw_all),
        ("in_collision(q)", robot.in_collision, raw_collide),
    ):
        ours(Q[0])
        raw(Q_pin[0])
        # both sides loop over their own inputs: kinengine's q and Pinocchio's q (equal here: no mimic map
        # cost hidden, the Panda's finger mimic is mapped by kinengine inside its call)
        t_ours, t_raw = [], []
        for _ in range(7):
            t_ours.append(per_call(ours, Q))
            t_raw.append(per_call(raw, Q_pin))
        a, b = float(np.median(t_ours)), float(np.median(t_raw))
        rows.append((name, a * 1e6, b * 1e6, a / b))

    N = 10_000
    QN = robot.random_configuration(rng=1, size=N)
    rates = []
    for _ in range(3):
        t = time.perf_counter()
        hit = robot.in_collision(QN)
        rates.append(N / (time.perf_counter() - t))
    batch_rate = float(np.median(rates))

    arm = kinengine.load("panda_arm")
    q0 = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
    T0 = arm.frame_pose(q0, "panda_hand")
    scene = arm.with_obstacles([Box((0.1, 0.1, 0.1), T0[:3, 3] + [0.0, 0.2, -0.1])])
    target = PoseTarget("panda_hand", T0.copy(), rows=("x", "y", "z"))
    steps = {}
    for label, constraints in (
        ("without constraints", []),
        ("with CollisionAvoidance", [CollisionAvoidance(0.01, 0.05)]),
    ):
        ik = DifferentialIK(scene, [target, PostureTarget(q0, 1e-3)], constraints=constraints)
        q, dt, times = q0.copy(), 0.002, []
        for k in range(1500):
            target.T_target = T0.copy()
            target.T_target[1, 3] += 0.4 * min(k / 1000, 1.0)
            t = time.perf_counter()
            qdot = ik.solve(q, dt)
            times.append(time.perf_counter() - t)
            q = q + qdot * dt
        steps[label] = (float(np.median(times)) * 1e6, ik.qp_calls)

    print(
        f"kinengine collisions benchmark: {platform.processor() or platform.machine()}, Python "
        f"{platform.python_version()}, pin {pin.__version__}, numpy {np.__version__}, "
        f"ACCELERATED={kinengine.ACCELERATED}"
    )
    print(f"Panda, {pairs} shape pairs, 1,000 random q, 7 interleaved rounds (median per call)")
    print("| call | kinengine | raw Pinocchio + coal | ratio |\n|---|--:|--:|--:|")
    for name, a, b, r in rows:
        print(f"| `{name}` | {a:.1f} µs | {b:.1f} µs | {r:.2f} |")
    print(f"in_collision(Q), N = {N:,}: {batch_rate:,.0f} configurations/s ({hit.mean():.1%} colliding)")
    for label, (us, calls) in steps.items():
        print(f"DifferentialIK step, panda_arm + box, {label}: {us:.0f} µs median ({calls} of 1500 steps QP)")


if __name__ == "__main__":
    main()
