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
    """The Panda with its mimic finger against the same URDF without the <mimic> tag: extra µs per call, for
    the hand (no mimic joint moves it: Pinocchio's model with the mimic joint locked), the leading finger,
    and the mimicking finger (the only frame that takes q_pin = M q + b and J_pin · M)."""
    panda = kinengine.load("panda")
    plain = kinengine.load_urdf_string(re.sub(r"<mimic[^>]*/>", "", panda.urdf_text))
    qm = panda.random_configuration(0)
    qp = plain.pinocchio_configuration(plain.random_configuration(0))  # same values, finger 2 = finger 1
    qp[-1] = qp[-2]
    print(f"mimic map (Panda: {panda.dof} coordinates with the mimic, {plain.dof} without):")
    for frame in ("panda_hand", "panda_leftfinger", "panda_rightfinger"):
        hm, hp = panda.frame(frame), plain.frame(frame)
        um, up = panda.frame(frame, check_inputs=False), plain.frame(frame, check_inputs=False)
        best = best_times(
            {
                "mimic pose": lambda hm=hm: hm.pose(qm),
                "plain pose": lambda hp=hp: hp.pose(qp),
                "mimic jacobian": lambda hm=hm: hm.jacobian(qm),
                "plain jacobian": lambda hp=hp: hp.jacobian(qp),
                "mimic pose unchecked": lambda um=um: um.pose(qm),
                "plain pose unchecked": lambda up=up: up.pose(qp),
                "mimic jacobian unchecked": lambda um=um: um.jacobian(qm),
                "plain jacobian unchecked": lambda up=up: up.jacobian(qp),
            },
            rounds=ROUNDS // 2,
        )
        path = panda.engine.frame_path(panda.frame_id(frame))
        moved = frame == "panda_rightfinger"  # panda_finger_joint2, the mimic joint, moves it alone
        how = (
            "moved by the mimic joint: "
            + ("mapped" if path.mapped else "a model of its own joints, q untouched")
            if moved
            else "not moved by a mimic joint"
        )
        print(f"  {frame} ({how}):")
        for what in ("pose", "jacobian", "pose unchecked", "jacobian unchecked"):
            print(
                f"    {what:18s} {best['mimic ' + what] - best['plain ' + what]:+.2f} µs "
                f"({best['mimic ' + what]:.2f} against {best['plain ' + what]:.2f})"
            )


if __name__ == "__main__":
    for robot_name in sys.argv[1:] or ("abb_irb120", "ur5", "panda", "kinova"):
        ratios(robot_name)
    mimic_overhead()
