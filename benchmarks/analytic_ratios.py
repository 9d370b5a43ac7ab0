"""analytic_jacobian and task.update(q) against their inline raw-Pinocchio floors (the ``kinengine bench``
floors of kinengine.cli.bench.floors: J from computeFrameJacobian, χ by closed form, E(χ) by np.array, one @),
measured interleaved in one process (min of many short rounds in shuffled order, see latency_ratios.py).

    python benchmarks/analytic_ratios.py [ROBOT ...]        # default: abb_irb120 ur5 panda kinova
"""

from __future__ import annotations

import sys

from latency_ratios import best_times

import kinengine
from kinengine.cli.bench.cases import regular_configuration
from kinengine.cli.bench.floors import floors
from kinengine.parameterizations import ROTATION_PARAMETERIZATIONS

ROUNDS, CALLS = 150, 50


def ratios(name: str) -> None:
    robot = kinengine.load(name)
    frame = robot.end_effector
    rotations = list(ROTATION_PARAMETERIZATIONS)
    q, _ = regular_configuration(robot, frame, rotations)
    floor = floors(robot, frame, q)
    task = robot.task(frame, position="cartesian", rotation="euler_zyx")
    fns = {}
    for rot in rotations:
        fns[f"floor {rot}"] = floor[rot]
        fns[rot] = lambda rot=rot: robot.analytic_jacobian(q, frame, rotation=rot)
    fns["floor task"] = floor["task"]
    fns["task"] = lambda: task.update(q)
    best = best_times(fns, ROUNDS, CALLS)
    print(f"{name} ({frame}):")
    print(f"  {'row':18s} {'kinengine':>10s} {'floor':>8s} {'ratio':>6s}")
    for key in [*rotations, "task"]:
        label = "task.update(q)" if key == "task" else key
        value, base = best[key], best["floor " + key]
        print(f"  {label:18s} {value:8.2f}µs {base:6.2f}µs {value / base:5.2f}×")


if __name__ == "__main__":
    for robot_name in sys.argv[1:] or ("abb_irb120", "ur5", "panda", "kinova"):
        ratios(robot_name)
