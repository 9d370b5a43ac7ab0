"""Closed-form IK (``robot.ik_solutions``) next to the library call it wraps and to numeric IK.

ABB IRB 120, frame tool0, targets = poses of random in-limit configurations (rng 2024). Rows:

* ``ik_solutions(T)``, every solution of one pose per call, against EAIK's own ``calculate_IK(T)`` (the
  floor: what a user calling the library directly pays; kinengine adds the forward-kinematics check of
  each answer, deduplication, wrapping into the ranges, the limit filter and the result object);
* ``ik_solutions(T)`` for a batch (N, 4, 4) [poses/s], against EAIK's ``calculate_IK_batched`` (its
  worker threads; the floor returns raw answers, no wrapping or limit filter);
* one solution per target at equal achieved accuracy: ``inverse_kinematics(T, method="closed_form")``
  (nearest the middle of the ranges), kinengine's numeric ``inverse_kinematics(T, method="numeric")`` and,
  with the [peers] extra, Robotics Toolbox's ``ets.ik_LM(T, tol=1e-12, joint_limits=True)`` (its default
  tol leaves a median error of 1.6e-4 m): solves/s, success and the achieved position/rotation error.

Each timed pair runs interleaved, ``--rounds`` times; the best round counts (a busy neighbour on the shared
machine only slows a round). ``python benchmarks/closed_form_ik.py [--json PATH]``.
"""

from __future__ import annotations

import argparse
import json
import platform
import time

import numpy as np

import kinengine


def best(fn, rounds: int) -> float:
    """The shortest wall time [s] of ``rounds`` calls of fn."""
    times = []
    for _ in range(rounds):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def errors(robot: kinengine.Robot, q: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Position [m] and rotation [rad] errors of the frame at q (N, dof) against T (N, 4, 4)."""
    from scipy.spatial.transform import Rotation

    F = robot.frame_pose(q)
    dp = np.linalg.norm(F[:, :3, 3] - T[:, :3, 3], axis=1)
    dr = Rotation.from_matrix(np.swapaxes(T[:, :3, :3], 1, 2) @ F[:, :3, :3]).magnitude()
    return dp, dr


def accuracy_row(name: str, robot, q: np.ndarray, T: np.ndarray, seconds: float) -> dict:
    dp, dr = errors(robot, q, T)
    inside = ((q >= robot.lower_limits - 1e-12) & (q <= robot.upper_limits + 1e-12)).all(axis=1)
    reached = (dp <= 1e-6) & (dr <= 1e-6) & inside
    return {
        "name": name,
        "solves_per_s": len(T) / seconds,
        "reached": float(reached.mean()),
        "median_position_error_m": float(np.median(dp)),
        "max_position_error_m": float(dp.max()),
        "median_rotation_error_rad": float(np.median(dr)),
        "max_rotation_error_rad": float(dr.max()),
    }


def rtb_solver(robot: kinengine.Robot):
    """Robotics Toolbox's ik_LM on the robot's own URDF, or None (not installed / joint order differs)."""
    try:
        import roboticstoolbox as rtb
    except ImportError:
        return None
    ets = rtb.Robot.URDF(str(robot.source)).ets(end=robot.end_effector)
    q = robot.random_configuration(rng=0)
    if not np.allclose(ets.fkine(q).A, robot.frame_pose(q), rtol=0, atol=1e-9):
        return None
    return lambda T: ets.ik_LM(T, tol=1e-12, joint_limits=True)[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="abb_irb120")
    parser.add_argument("--batch", type=int, default=10_000)
    parser.add_argument("--single", type=int, default=1_000)
    parser.add_argument("--solves", type=int, default=300, help="targets of the one-solution rows")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--json", default=None, help="also write the rows to this JSON file")
    args = parser.parse_args()

    from eaik.pybindings import EAIK  # the [ik] extra

    from kinengine.control.closed_form import THREADS, chain_geometry

    robot = kinengine.load(args.robot)
    Q = robot.random_configuration(rng=2024, size=args.batch)
    T = robot.frame_pose(Q)
    g = chain_geometry(robot, robot.end_effector)
    raw = EAIK.Robot(g.H.T, g.P.T, g.C_tool, [], True)
    poses = list(T)
    robot.ik_solutions(T[:100])  # build the solver outside the timing
    rows: list[dict] = []

    single = T[: args.single]
    t_kin, t_raw = [], []
    for _ in range(args.rounds):  # interleaved
        t_kin.append(best(lambda: [robot.ik_solutions(x) for x in single], 1))
        t_raw.append(best(lambda: [raw.calculate_IK(x) for x in single], 1))
    us, floor = min(t_kin) / len(single) * 1e6, min(t_raw) / len(single) * 1e6
    rows.append({"name": "ik_solutions(T), one pose", "us_per_call": us, "eaik_us_per_call": floor})
    t_kin, t_raw = [], []
    for _ in range(args.rounds):
        t_kin.append(best(lambda: robot.ik_solutions(T), 1))
        t_raw.append(best(lambda: raw.calculate_IK_batched(poses, THREADS), 1))
    rate, floor = len(T) / min(t_kin), len(T) / min(t_raw)
    found = robot.ik_solutions(T)
    rows.append(
        {
            "name": f"ik_solutions(T), batch of {len(T)}",
            "poses_per_s": rate,
            "eaik_poses_per_s": floor,
            "solutions_per_pose": float(found.count.mean()),
        }
    )

    targets = T[: args.solves]
    seconds = best(lambda: [robot.inverse_kinematics(x, method="closed_form") for x in targets], args.rounds)
    q = np.array([robot.inverse_kinematics(x, method="closed_form").q for x in targets])
    rows.append(accuracy_row("inverse_kinematics(T, method='closed_form')", robot, q, targets, seconds))
    robot.inverse_kinematics(targets[0], method="numeric")  # the seed table, outside the timing
    solve = robot.inverse_kinematics

    def numeric() -> list:
        return [solve(x, rng=i, method="numeric") for i, x in enumerate(targets)]

    seconds = best(numeric, args.rounds)
    q = np.array([r.q for r in numeric()])
    rows.append(accuracy_row("inverse_kinematics(T, method='numeric')", robot, q, targets, seconds))
    ik_lm = rtb_solver(robot)
    if ik_lm is not None:
        seconds = best(lambda: [ik_lm(x) for x in targets], args.rounds)
        q = np.array([ik_lm(x) for x in targets])
        rows.append(accuracy_row("roboticstoolbox ets.ik_LM(T, tol=1e-12)", robot, q, targets, seconds))

    report = {
        "robot": robot.name,
        "machine": f"{platform.processor() or platform.machine()}, {platform.python_version()}",
        "eaik_threads": THREADS,
        "rounds": args.rounds,
        "rows": rows,
    }
    for row in rows:
        print(json.dumps(row))
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(report, f, indent=2)


if __name__ == "__main__":
    main()
