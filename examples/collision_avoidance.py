"""A Panda's hand sweeps 0.4 m sideways past a box: without collision avoidance its fingers go through the
box; with ``CollisionAvoidance`` in the QP they pass over it, at least ``min_distance`` away.

The arm (``panda_arm``: fingers locked, their collision boxes kept) starts at the ready pose; a position
target on ``panda_hand`` moves 0.4 m along y in 2 s and then holds for 1 s. A 10 cm box stands in the way,
0.1 m below the hand. Each 500 Hz control step is one ``DifferentialIK.solve`` (DAQP): the position target,
a small posture term, joint limits, and, in the second run, ``CollisionAvoidance(min_distance=0.01,
influence_distance=0.05)``: d + ∇d·q̇ dt ≥ d_min for every shape pair closer than 5 cm.

It saves a PNG of the smallest distance and of the hand's position error over time, and a 3-D picture.

    python examples/collision_avoidance.py --output docs/images/collision_avoidance.png
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

import kinengine
from kinengine import Box, CollisionAvoidance, DifferentialIK, PoseTarget, PostureTarget

Q_READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
DT, SWEEP, HOLD = 0.002, 2.0, 1.0  # [s]


@dataclass
class Run:
    t: np.ndarray  # (n,) [s]
    min_distance: np.ndarray  # (n,) [m], over every checked pair
    error: np.ndarray  # (n,) [m], ‖p_target − p_hand‖
    q: np.ndarray  # (n, 7)


def scene() -> tuple[kinengine.Robot, np.ndarray]:
    """The arm with the box, and the hand's start pose T_I,hand (4, 4)."""
    arm = kinengine.load("panda_arm")
    T0 = arm.frame_pose(Q_READY, "panda_hand")
    return arm.with_obstacles([Box((0.1, 0.1, 0.1), T0[:3, 3] + [0.0, 0.2, -0.1], name="box")]), T0


def sweep(robot: kinengine.Robot, T0: np.ndarray, avoid: bool) -> Run:
    constraints = [CollisionAvoidance(min_distance=0.01, influence_distance=0.05)] if avoid else []
    target = PoseTarget("panda_hand", T0.copy(), rows=("x", "y", "z"))
    ik = DifferentialIK(robot, [target, PostureTarget(Q_READY, 1e-3)], constraints=constraints)
    n_sweep, n = int(SWEEP / DT), int((SWEEP + HOLD) / DT)
    q, out_d, out_e, out_q = Q_READY.copy(), np.empty(n), np.empty(n), np.empty((n, 7))
    for k in range(n):
        target.T_target = T0.copy()
        target.T_target[1, 3] += 0.4 * min(k / n_sweep, 1.0)
        q = q + ik.solve(q, DT) * DT
        out_d[k] = robot.min_distance(q)
        out_e[k] = np.linalg.norm(robot.frame_pose(q, "panda_hand")[:3, 3] - target.T_target[:3, 3])
        out_q[k] = q
    return Run(np.arange(1, n + 1) * DT, out_d, out_e, out_q)


def plot(free: Run, avoided: Run, path: str) -> None:
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.6))
    a.plot(free.t, 1e3 * free.min_distance, label="without avoidance")
    a.plot(avoided.t, 1e3 * avoided.min_distance, label="CollisionAvoidance")
    a.axhline(10.0, color="k", lw=0.8, ls="--", label="min_distance 10 mm")
    a.set(xlabel="t [s]", ylabel="smallest distance [mm]", title="Panda hand past a box")
    a.legend(fontsize=8)
    b.plot(free.t, 1e3 * free.error, label="without avoidance")
    b.plot(avoided.t, 1e3 * avoided.error, label="CollisionAvoidance")
    b.set(xlabel="t [s]", ylabel="hand position error [mm]", title="Task error")
    b.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def main(argv: Sequence[str] | None = None) -> tuple[Run, Run]:
    parser = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    parser.add_argument("--output", help="write the PNG here")
    args = parser.parse_args(argv)
    robot, T0 = scene()
    free, avoided = sweep(robot, T0, avoid=False), sweep(robot, T0, avoid=True)
    for name, run in (("without avoidance", free), ("with CollisionAvoidance", avoided)):
        print(
            f"{name}: smallest distance {1e3 * run.min_distance.min():.2f} mm, "
            f"largest position error {1e3 * run.error.max():.1f} mm, final {1e3 * run.error[-1]:.1f} mm"
        )
    if args.output:
        plot(free, avoided, args.output)
    return free, avoided


if __name__ == "__main__":
    main()
