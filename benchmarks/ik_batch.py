"""Batched IK throughput: ``robot.inverse_kinematics(T)`` for T (N, 4, 4), in one process.

    python benchmarks/ik_batch.py [ROBOT ...]          # default: abb_irb120 ur5 panda_arm
    python benchmarks/ik_batch.py --rounds 5 --no-rtb  # more repeats, skip roboticstoolbox

Targets: T = robot.frame_pose(robot.random_configuration(np.random.default_rng(N), N)) (reachable, within
limits); tolerances 1e-6 m / 1e-6 rad (the defaults), rng=0. Per robot and N = 1,000 and
10,000: solves/s (N over the best of ``--rounds`` calls: a busy neighbour on the shared machine only slows
a call), the success count, mean iterations per target, and the worst pose error among the successes,
checked independently from ``robot.frame_pose`` at the returned q. Where roboticstoolbox-python is
installed, its C++ ``ets.ik_LM`` (one call per target, tol 1e-12 on ½eᵀe, joint limits on, as in
``kinengine bench --peers``) on the same targets, its successes checked the same way (errors within
1e-6 m / 1e-6 rad and q within the limits). A first batch of 64 targets per robot builds the batch seed
table (once per robot and frame); its time is printed and not counted.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import kinengine

TOL = 1e-6


def pose_errors(robot, q: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """|Δp| [m] and the rotation angle [rad] between frame_pose(q) and T, per row."""
    F = robot.frame_pose(q)
    ep = np.linalg.norm(F[:, :3, 3] - T[:, :3, 3], axis=1)
    R = np.einsum("nji,njk->nik", F[:, :3, :3], T[:, :3, :3])
    cos = np.clip((np.trace(R, axis1=1, axis2=2) - 1) / 2, -1, 1)
    sin = (
        np.linalg.norm(
            np.stack((R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]), 1), axis=1
        )
        / 2
    )
    return ep, np.arctan2(sin, cos)


def within(robot, q: np.ndarray) -> np.ndarray:
    return np.all((q >= robot.lower_limits - 1e-12) & (q <= robot.upper_limits + 1e-12), axis=1)


def kinengine_row(robot, T: np.ndarray, rounds: int) -> str:
    best, result = np.inf, None
    for _ in range(rounds):
        start = time.perf_counter()
        result = robot.inverse_kinematics(T, rng=0, method="numeric")
        best = min(best, time.perf_counter() - start)
    assert result is not None
    ep, er = pose_errors(robot, result.q, T)
    ok = result.success & within(robot, result.q)
    worst = max(ep[ok].max(initial=0.0), er[ok].max(initial=0.0))
    return (
        f"{len(T) / best:>10,.0f} solves/s  success {int(result.success.sum()):>6}/{len(T)} "
        f"({result.success.mean():.2%}, checked {int((ok & (ep <= TOL) & (er <= TOL + 2e-8)).sum())})  "
        f"iterations/target {result.iterations.mean():5.1f}  worst error {worst:.1e}"
    )


def rtb_row(robot, T: np.ndarray) -> str:
    from kinengine.cli.bench.peers import Peer

    peer = Peer("roboticstoolbox", robot, robot.end_effector)
    if not peer.loaded:
        return f"roboticstoolbox: {peer.note}"
    ets, unmap = peer._ets, peer._unmap()
    start = time.perf_counter()
    out = [ets.ik_LM(Ti, tol=1e-12, joint_limits=True)[0] for Ti in T]
    elapsed = time.perf_counter() - start
    q = np.array(out) @ unmap
    ep, er = pose_errors(robot, q, T)
    ok = (ep <= TOL) & (er <= TOL) & within(robot, q)
    return (
        f"{len(T) / elapsed:>10,.0f} solves/s  success {int(ok.sum()):>6}/{len(T)} ({ok.mean():.2%}, "
        f"checked: errors <= 1e-6 and within limits)  [roboticstoolbox {peer.version} ets.ik_LM, one call]"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("robots", nargs="*", default=["abb_irb120", "ur5", "panda_arm"])
    parser.add_argument("--sizes", type=int, nargs="*", default=[1_000, 10_000])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--no-rtb", action="store_true", help="skip roboticstoolbox's ik_LM")
    args = parser.parse_args()
    for name in args.robots:
        robot = kinengine.load(name)
        start = time.perf_counter()
        robot.inverse_kinematics(
            robot.frame_pose(robot.random_configuration(np.random.default_rng(0), 64)), method="numeric"
        )
        print(
            f"{name:<11} first call (64 targets, builds the seed table): {time.perf_counter() - start:.3f} s"
        )
        for n in args.sizes:
            T = robot.frame_pose(robot.random_configuration(np.random.default_rng(n), n))
            print(f"{name:<11} N={n:>6}  kinengine  {kinengine_row(robot, T, args.rounds)}", flush=True)
            if not args.no_rtb:
                print(f"{name:<11} N={n:>6}  rtb ik_LM  {rtb_row(robot, T)}", flush=True)


if __name__ == "__main__":
    main()
