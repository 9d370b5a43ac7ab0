"""Single-call ratios to the inline raw-Pinocchio floor, measured interleaved in one process (min of many
short rounds in shuffled order, so a busy neighbour on a shared machine slows every side alike).

    python benchmarks/latency_ratios.py [ROBOT ...]        # default: abb_irb120 ur5 panda kinova

Rows: robot.frame_pose / robot.jacobian / robot.kinematics (input checks on), the frame handle
robot.frame(f) (checks on) and robot.frame(f, check_inputs=False); floors as in `kinengine bench`.
Also the cost of the mimic map q_pin = M q + b: the Panda (a mimic finger joint) against the same URDF
with the <mimic> tag removed (the finger then takes its own coordinate).
"""

from __future__ import annotations

import random
import re
import sys
import time

import numpy as np
import pinocchio as pin

import kinengine

ROUNDS, CALLS = 400, 100


def best_times(fns: dict, rounds: int = ROUNDS, calls: int = CALLS) -> dict[str, float]:
    """min over ``rounds`` shuffled rounds of the mean time per call [µs] of each fn."""
    best = {k: float("inf") for k in fns}
    items = list(fns.items())
    for _ in range(rounds):
        random.shuffle(items)
        for key, fn in items:
            start = time.perf_counter()
            for _ in range(calls):
                fn()
            best[key] = min(best[key], (time.perf_counter() - start) / calls * 1e6)
    return best


def calls(robot, frame: str, q: np.ndarray) -> dict:
    model = robot.pinocchio_model()
    data = model.createData()
    fid = robot.frame_id(frame)
    qp = robot.pinocchio_configuration(q)
    fk, place, frame_jacobian, LWA = (
        pin.forwardKinematics,
        pin.updateFramePlacement,
        pin.computeFrameJacobian,
        pin.LOCAL_WORLD_ALIGNED,
    )
    fold = robot.engine.coordinates.fold
    checked, unchecked = robot.frame(frame), robot.frame(frame, check_inputs=False)

    def floor_pose():
        fk(model, data, qp)
        return place(model, data, fid).homogeneous

    def floor_jacobian():
        return fold(frame_jacobian(model, data, qp, fid, LWA))

    def floor_kinematics():
        J = fold(frame_jacobian(model, data, qp, fid, LWA))
        return place(model, data, fid).homogeneous, J

    return {
        "floor pose": floor_pose,
        "floor jacobian": floor_jacobian,
        "floor kinematics": floor_kinematics,
        "frame_pose": lambda: robot.frame_pose(q, frame),
        "jacobian": lambda: robot.jacobian(q, frame),
        "kinematics": lambda: robot.kinematics(q, frame),
        "fk.pose": lambda: checked.pose(q),
        "fk.jacobian": lambda: checked.jacobian(q),
        "fk.kinematics": lambda: checked.kinematics(q),
        "fk.pose unchecked": lambda: unchecked.pose(q),
        "fk.jacobian unchecked": lambda: unchecked.jacobian(q),
        "fk.kinematics unchecked": lambda: unchecked.kinematics(q),
    }


def ratios(name: str) -> None:
    robot = kinengine.load(name)
    frame = robot.end_effector
    best = best_times(calls(robot, frame, robot.random_configuration(0)))
    print(
        f"{name} ({frame}): floors pose {best['floor pose']:.2f} µs, "
        f"jacobian {best['floor jacobian']:.2f} µs, "
        f"kinematics {best['floor kinematics']:.2f} µs"
    )
    for key, value in best.items():
        if key.startswith("floor"):
            continue
        base = "floor " + ("pose" if "pose" in key else "jacobian" if "jacobian" in key else "kinematics")
        print(f"  {key:26s} {value:7.2f} µs  {value / best[base]:5.2f}×")


def mimic_overhead() -> None:
    """The Panda with its mimic finger against the same URDF without the <mimic> tag: extra µs per call."""
    panda = kinengine.load("panda")
    plain = kinengine.load_urdf_string(re.sub(r"<mimic[^>]*/>", "", panda.urdf_text))
    frame = "panda_leftfinger" if "panda_leftfinger" in panda.frame_names else panda.end_effector
    qm = panda.random_configuration(0)
    qp = plain.random_configuration(0)
    hm, hp = panda.frame(frame), plain.frame(frame)
    um, up = panda.frame(frame, check_inputs=False), plain.frame(frame, check_inputs=False)
    best = best_times(
        {
            "mimic pose": lambda: hm.pose(qm),
            "plain pose": lambda: hp.pose(qp),
            "mimic jacobian": lambda: hm.jacobian(qm),
            "plain jacobian": lambda: hp.jacobian(qp),
            "mimic pose unchecked": lambda: um.pose(qm),
            "plain pose unchecked": lambda: up.pose(qp),
            "mimic frame_pose": lambda: panda.frame_pose(qm, frame),
            "plain frame_pose": lambda: plain.frame_pose(qp, frame),
        }
    )
    print(f"mimic map (Panda, {frame}: {panda.dof} coordinates with the mimic, {plain.dof} without):")
    for what in ("pose", "jacobian", "pose unchecked", "frame_pose"):
        print(
            f"  {what:16s} +{best['mimic ' + what] - best['plain ' + what]:.2f} µs "
            f"({best['mimic ' + what]:.2f} against {best['plain ' + what]:.2f})"
        )


if __name__ == "__main__":
    for robot_name in sys.argv[1:] or ("abb_irb120", "ur5", "panda", "kinova"):
        ratios(robot_name)
    mimic_overhead()
