"""Multi-frame IK rate: ``robot.inverse_kinematics({frame: T, ...})`` one target set at a time.

    python benchmarks/ik_multi.py               # the four rows of docs/controller.md's multi-frame table
    python benchmarks/ik_multi.py --rounds 5    # best of 5 rounds (default 3)

Targets: every frame's pose at the same random configuration, uniform within the joint limits (rng 2024),
200 target sets per row; default options, rng=0. A solve counts when ``success`` is True and every frame's
position at the returned q, from ``robot.frame_pose``, is within 1e-6 m of its target in the kept rows
(rows given in the target frame). solves/s is 200 over the best round's wall time (a busy neighbour on the
shared machine only slows a round).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import kinengine

ROWS = [  # (robot, {frame: rows or None (the full pose)})
    ("panda_arm", {"panda_hand": None, "panda_link4": None}),
    ("panda_arm", {"panda_hand": None, "panda_link4": ("x", "y")}),
    ("abb_irb120", {"tool0": None, "link_4": None}),
    ("abb_irb120", {"tool0": None, "link_4": ("x", "y", "z")}),
]
TARGETS = 200


def reached(robot: kinengine.Robot, q: np.ndarray, goals: dict, rows: dict) -> bool:
    """Every frame's position at q within 1e-6 m of its goal in its kept rows (in the goal's axes)."""
    for frame, T_d in goals.items():
        kept = [axis for axis in "xyz" if rows.get(frame) is None or axis in rows[frame]]
        offset = T_d[:3, :3].T @ (robot.frame_pose(q, frame)[:3, 3] - T_d[:3, 3])
        if np.abs(offset[["xyz".index(axis) for axis in kept]]).max() > 1e-6:
            return False
    return True


def run(name: str, frames: dict, rounds: int) -> str:
    robot = kinengine.load(name)
    Q = robot.random_configuration(np.random.default_rng(2024), size=TARGETS)
    sets = [{frame: robot.frame_pose(q, frame) for frame in frames} for q in Q]
    rows = {frame: kept for frame, kept in frames.items() if kept is not None}
    options = {"rows": rows} if rows else {}
    best, results = float("inf"), []
    for _ in range(rounds):
        start = time.perf_counter()
        results = [robot.inverse_kinematics(goals, rng=0, **options) for goals in sets]
        best = min(best, time.perf_counter() - start)
    pairs = zip(results, sets, strict=True)
    solved = sum(r.success and reached(robot, r.q, goals, rows) for r, goals in pairs)
    label = " + ".join(f"{f} ({', '.join(kept)})" if kept else f"{f} (pose)" for f, kept in frames.items())
    return f"| {name}, {label} | {solved}/{TARGETS} | {TARGETS / best:,.0f} |"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    print("| robot, frames | solved | solves/s |\n|---|---|---|")
    for name, frames in ROWS:
        print(run(name, frames, args.rounds))


if __name__ == "__main__":
    main()
