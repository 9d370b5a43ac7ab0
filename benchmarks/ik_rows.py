"""The IK rows of ``kinengine bench --peers`` alone, as Markdown: kinengine and Robotics Toolbox's ``ik_LM``
at equal asked accuracy (1e-6; ``ik_LM`` at tol 5e-13 on ½eᵀe), each with its achieved error.

    python benchmarks/ik_rows.py [ROBOT ...]      # default: abb_irb120 ur5 panda_arm

The same cases, timing and counting as the full benchmark (:func:`kinengine.cli.bench.ik_cases.ik_cases`,
200 random targets one by one and 10,000 as one batch; min and median of the repeats), without its other
rows, for refreshing the IK rows of README.md and docs/benchmarks.md.
"""

from __future__ import annotations

import argparse

import kinengine
from kinengine.cli.bench.command import _achieved, _peer_cell, _us
from kinengine.cli.bench.ik_cases import ik_cases
from kinengine.cli.bench.peers import Peer
from kinengine.cli.bench.run import FULL, run_case


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("robots", nargs="*", default=["abb_irb120", "ur5", "panda_arm"])
    args = parser.parse_args()
    print(
        "| robot | case | N | kinengine per s | min µs | reached, achieved error "
        "| ik_LM min µs [reached, error] |"
    )
    print("|---|---|--:|--:|--:|---|---|")
    for name in args.robots:
        robot = kinengine.load(name)
        peer = Peer("roboticstoolbox", robot, robot.end_effector)
        for case in ik_cases(robot, robot.end_effector, *FULL.ik):
            row = run_case(case, FULL, [peer] if peer.loaded else None)
            k = row["kinengine"]
            rtb = _peer_cell(row["peers"]["roboticstoolbox"], k["min_us"]) if "peers" in row else peer.note
            label = "batch" if case.group == "throughput" else "one by one"
            print(
                f"| {name} | {label} | {case.n:,} | {k['per_second']:,.0f} | {_us(k['min_us'])} | "
                f"{row['success']:.1%}, {_achieved(row)} | {rtb} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
