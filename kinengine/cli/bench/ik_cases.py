"""The inverse-kinematics rows of ``kinengine bench``: IK_TARGETS solves from nearby starts against
Pinocchio's CLIK example (:func:`ik_case`), and random reachable targets one by one and as one batch
(:func:`ik_cases`, no Pinocchio floor: Pinocchio has no IK solver; the peers time theirs).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ...errors import KinematicsError
from ...robot import Robot
from .row import Case

IK_TARGETS = 8
SOLUTIONS = "ik_solutions[all, closed form]"
"""The rows of ``robot.ik_solutions``: every solution of each target (the others give one)."""
NEAREST = "inverse_kinematics[random targets, closed form]"


def ik_case(robot: Robot, frame: str) -> Case:
    """IK_TARGETS solves per call, each from a start 0.2 rad (or m) away from a reachable target."""
    rng = np.random.default_rng(2)
    solutions = robot.random_configuration(rng, size=IK_TARGETS)
    starts = np.clip(
        solutions + rng.normal(0.0, 0.2, solutions.shape), robot.lower_limits, robot.upper_limits
    )
    targets = [robot.frame_pose(s, frame) for s in solutions]
    model = robot.pinocchio_model()
    data = model.createData()
    fid = robot.frame_id(frame)
    coords = robot.engine.coordinates

    def clik(target: pin.SE3, q: np.ndarray) -> np.ndarray:
        """Pinocchio's CLIK example, Gauss–Newton with damping 1e-10, in the frame (LOCAL)."""
        for _ in range(200):
            pin.forwardKinematics(model, data, q)
            fMd = pin.updateFramePlacement(model, data, fid).actInv(target)
            err = pin.log6(fMd).vector
            if err @ err < 1e-20:
                break
            J = -pin.Jlog6(fMd.inverse()) @ pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL)
            v = -J.T @ np.linalg.solve(J @ J.T + 1e-10 * np.eye(6), err)
            q = pin.integrate(model, q, v)
        return q

    pin_targets = [pin.SE3(T) for T in targets]
    pin_starts = [robot.pinocchio_configuration(s) for s in starts]

    def pinocchio() -> list[np.ndarray]:
        return [clik(T, s) for T, s in zip(pin_targets, pin_starts, strict=True)]

    reached = sum(
        np.allclose(robot.frame_pose(coords.from_pinocchio(q), frame), T, rtol=0, atol=1e-8)
        for q, T in zip(pinocchio(), targets, strict=True)
    )
    return Case(
        "latency",
        "inverse_kinematics",
        IK_TARGETS,
        lambda: [
            robot.inverse_kinematics(T, frame, q0=s, method="numeric")
            for T, s in zip(targets, starts, strict=True)
        ],
        pinocchio,
        f"from starts 0.2 away; floor reached {reached}/{IK_TARGETS}",
        floor="Pinocchio's CLIK example (log6 error, Jlog6, damping 1e-10, integrate) per target",
    )


def ik_cases(robot: Robot, frame: str, single: int, batch: int, seed: int = 2024) -> list[Case]:
    """Random reachable targets, no start given: ``single`` solves one by one, and ``batch`` solved as
    one (N, 4, 4) batch. No Pinocchio floor (Pinocchio has no IK solver); peers: Robotics Toolbox."""
    rng = np.random.default_rng(seed)
    cases = []
    for group, n, vectorized in (("latency", single, False), ("throughput", batch, True)):
        targets = robot.frame_pose(robot.random_configuration(rng, size=n), frame)
        if vectorized:

            def solve(targets: np.ndarray = targets) -> np.ndarray:
                return robot.inverse_kinematics(targets, frame, rng=0, method="numeric").q
        else:

            def solve(targets: np.ndarray = targets) -> np.ndarray:
                return np.array(
                    [
                        robot.inverse_kinematics(T, frame, rng=i, method="numeric").q
                        for i, T in enumerate(targets)
                    ]
                )

        cases.append(
            Case(
                group,
                "inverse_kinematics[random targets]",
                n,
                solve,
                None,
                "1e-6 m, 1e-6 rad, within limits; no floor (Pinocchio has no IK solver)",
                targets=targets,
                robot=robot,
                frame=frame,
            )
        )
    return cases + closed_form_cases(robot, frame, single, batch, seed)


def closed_form_cases(robot: Robot, frame: str, single: int, batch: int, seed: int = 2024) -> list[Case]:
    """The closed form on the targets of :func:`ik_cases` (the same seed: the same targets), one by one and
    as one batch: ``robot.ik_solutions`` (every solution; wrapping into the ranges and the limit filter
    included) and ``inverse_kinematics(T, method="closed_form")`` (the solution nearest the middle of the
    ranges), each with its achieved error. None where the frame's chain has no closed form or the ``ik``
    extra is missing. The peers are not timed again on these targets (their rows are :func:`ik_cases`')."""
    rng = np.random.default_rng(seed)
    try:
        robot.ik_solutions(robot.frame_pose(robot.neutral(), frame), frame)
    except KinematicsError:
        return []
    cases = []
    for group, n in (("latency", single), ("throughput", batch)):
        targets = robot.frame_pose(robot.random_configuration(rng, size=n), frame)
        if group == "throughput":

            def every(targets: np.ndarray = targets) -> object:
                return robot.ik_solutions(targets, frame).q

            def nearest(targets: np.ndarray = targets) -> object:
                return robot.inverse_kinematics(targets, frame, method="closed_form").q
        else:

            def every(targets: np.ndarray = targets) -> object:
                return [robot.ik_solutions(T, frame).q for T in targets]

            def nearest(targets: np.ndarray = targets) -> object:
                return np.array([robot.inverse_kinematics(T, frame, method="closed_form").q for T in targets])

        for name, solve, note in (
            (SOLUTIONS, every, "every solution within the limits"),
            (NEAREST, nearest, "method='closed_form': the solution nearest the middle of the ranges"),
        ):
            cases.append(
                Case(
                    group, name, n, solve, None, note, targets=targets, robot=robot, frame=frame, peers=False
                )
            )
    return cases


__all__ = ["IK_TARGETS", "NEAREST", "SOLUTIONS", "closed_form_cases", "ik_case", "ik_cases"]
