"""The rows of ``kinengine bench``: what kinengine calls, and the raw-Pinocchio code a user would write
instead (the floors themselves: :mod:`.floors`; the IK rows: :mod:`.ik_cases`).

Every :class:`Case` pairs a kinengine call with its floor: the plain inline code on raw Pinocchio
that gives the same output (same model ``robot.pinocchio_model()``, same configuration, the same 4x4
``.homogeneous`` or 6xdof array, no wrapper function in between), written as closures over local
names exactly as in a user's hot loop. ``floor`` holds that code as text for the table. Where both
return the same quantity, ``compare`` is set and the runner checks that they agree before timing.
For robots with mimic joints the floor is handed Pinocchio's configuration q_pin = M q + b ready made
(``robot.pinocchio_configuration(q)``); kinengine maps q itself, inside the timed call.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable

import numpy as np
import pinocchio as pin

from ...errors import ConfigurationError, RepresentationSingularityError
from ...robot import Robot
from .floors import (
    FLOOR_ANALYTIC,
    FLOOR_GEOMETRIC,
    FLOOR_JACOBIAN,
    FLOOR_KINEMATICS,
    FLOOR_LOOP,
    FLOOR_POSE,
    FLOOR_TASK,
    PIN_NAMES,
    REFERENCES,
    analytic_loop,
    floors,
)
from .ik_cases import ik_case
from .row import Case


def regular_configuration(
    robot: Robot, frame: str, rotations: list[str], seed: int = 0
) -> tuple[np.ndarray, list[str]]:
    """(q, the parameterizations regular there): a seeded q at which the most rotation parameterizations
    (all, when one of 200 samples has them all) are at least 0.1 from their singular sets."""
    rng = np.random.default_rng(seed)
    best: tuple[np.ndarray, list[str]] | None = None
    for _ in range(200):
        q = robot.random_configuration(rng)
        regular = []
        for name in rotations:
            try:
                robot.analytic_jacobian(
                    q, frame, position="cartesian", rotation=name, singularity_threshold=0.1
                )
            except RepresentationSingularityError:
                continue
            regular.append(name)
        if best is None or len(regular) > len(best[1]):
            best = (q, regular)
        if len(regular) == len(rotations):
            break
    assert best is not None
    q, regular = best
    skipped = [name for name in rotations if name not in regular]
    if skipped:
        warnings.warn(
            f"bench: the analytic rows of {', '.join(skipped)} are not timed: no configuration of "
            f"{robot.name} among 200 samples keeps frame {frame!r} 0.1 from their singular sets along with "
            "the others",
            UserWarning,
            stacklevel=2,
        )
    return q, regular


def latency_cases(robot: Robot, frame: str, rotations: list[str]) -> list[Case]:
    """Single-call rows at one configuration regular for every parameterization timed (those singular
    there are left out, with a warning)."""
    if robot.dof < 2:
        raise ConfigurationError(
            f"{robot.name} has {robot.dof} movable joint(s); kinengine bench times robots with 2 or more"
        )
    q, rotations = regular_configuration(robot, frame, rotations)
    floor = floors(robot, frame, q)
    fk, fast = robot.frame(frame), robot.frame(frame, check_inputs=False)
    # (row, kinengine call, floor key, floor code, q for the peers)
    rows: list[tuple[str, Callable[[], object], str, str, np.ndarray | None]] = [
        ("frame_pose", lambda: robot.frame_pose(q, frame), "frame_pose", FLOOR_POSE, q)
    ]
    for ref in REFERENCES:
        code = FLOOR_JACOBIAN.format(ref=PIN_NAMES[ref])
        rows.append(
            (f"jacobian[{ref}]", lambda ref=ref: robot.jacobian(q, frame, ref), f"jacobian[{ref}]", code, q)
        )
    rows.append(("kinematics", lambda: robot.kinematics(q, frame), "kinematics", FLOOR_KINEMATICS, None))
    lwa_key, lwa_code = (
        "jacobian[local_world_aligned]",
        FLOOR_JACOBIAN.format(ref=PIN_NAMES["local_world_aligned"]),
    )
    for label, h in (("", fk), (", check_inputs=False", fast)):
        rows += [
            (f"frame(){label}.pose", lambda h=h: h.pose(q), "frame_pose", FLOOR_POSE, None),
            (f"frame(){label}.jacobian", lambda h=h: h.jacobian(q), lwa_key, lwa_code, None),
            (f"frame(){label}.kinematics", lambda h=h: h.kinematics(q), "kinematics", FLOOR_KINEMATICS, None),
        ]
    cases = [
        Case("latency", name, 1, call, floor[key], compare=True, q=q_in, floor=code)
        for name, call, key, code, q_in in rows
    ]
    for rot in rotations:
        exact = rot in FLOOR_ANALYTIC
        cases.append(
            Case(
                "latency",
                f"analytic_jacobian[{rot}]",
                1,
                lambda rot=rot: robot.analytic_jacobian(q, frame, rotation=rot),
                floor[rot] if exact else floor["geometric"],
                "" if exact else "floor: geometric Jacobian only",
                compare=exact,
                q=q,
                floor=FLOOR_ANALYTIC.get(rot, FLOOR_GEOMETRIC),
            )
        )
    if {"euler_zyx", "euler_zyz"} <= set(rotations):
        cases += _task_cases(robot, frame, q, floor)
    return cases + [ik_case(robot, frame)]


def _task_cases(
    robot: Robot, frame: str, q: np.ndarray, floor: dict[str, Callable[[], object]]
) -> list[Case]:
    qdot = np.random.default_rng(1).uniform(-1.0, 1.0, robot.dof)
    model = robot.pinocchio_model()
    data = model.createData()
    fid = robot.frame_id(frame)
    qp, qdp = robot.pinocchio_configuration(q), robot.engine.coordinates.velocity_to_pinocchio(qdot)
    fold, zyx = robot.engine.coordinates.fold, floor["euler_zyx"]

    def floor_with_velocity() -> object:
        pin.computeJointJacobiansTimeVariation(model, data, qp, qdp)
        pin.updateFramePlacement(model, data, fid)
        fold(pin.getFrameJacobianTimeVariation(model, data, fid, pin.LOCAL_WORLD_ALIGNED))
        return zyx()

    task = robot.task(frame, position="cartesian", rotation="euler_zyx")
    zyz = robot.task(frame, position="cartesian", rotation="euler_zyz")
    return [
        Case(
            "latency",
            "task.update(q)",
            1,
            lambda: task.update(q),
            floor["task"],
            "euler_zyx; floor: J, χ and the rpy conversion",
            floor=FLOOR_TASK,
        ),
        Case(
            "latency",
            "task.update(q)[euler_zyz]",
            1,
            lambda: zyz.update(q),
            floor["euler_zyz"],
            "floor: the euler_zyz analytic Jacobian floor",
            floor=FLOOR_ANALYTIC["euler_zyz"],
        ),
        Case(
            "latency",
            "task.update(q, qdot)",
            1,
            lambda: task.update(q, qdot),
            floor_with_velocity,
            "euler_zyx; floor: J̇ (TimeVariation), J, rpy conversion, no Ė",
            floor="pin.computeJointJacobiansTimeVariation(...); getFrameJacobianTimeVariation(...); "
            "then the euler_zyx floor",
        ),
    ]


def throughput_cases(
    robot: Robot, frame: str, sizes: list[int], seed: int = 3, loop_max: int = 100_000
) -> list[Case]:
    """Batched rows for each N: poses, Jacobians, both in one call, and analytic Jacobians; the floor is
    a Python loop of the single-q floor (not timed above ``loop_max``)."""
    cases = []
    # loop-invariant: the floor closures below share one model and data (the rows are timed one by one)
    model = robot.pinocchio_model()
    data = model.createData()
    fid, dof = robot.frame_id(frame), robot.dof
    fold = robot.engine.coordinates.fold
    fk, place, frame_jacobian, LWA = (
        pin.forwardKinematics,
        pin.updateFramePlacement,
        pin.computeFrameJacobian,
        pin.LOCAL_WORLD_ALIGNED,
    )
    for n in sizes:
        Q = robot.random_configuration(np.random.default_rng(seed), size=n)
        QP = np.array([robot.pinocchio_configuration(q) for q in Q])

        def poses(QP: np.ndarray = QP) -> np.ndarray:
            out = np.empty((len(QP), 4, 4))
            for i, qp in enumerate(QP):
                fk(model, data, qp)
                out[i] = place(model, data, fid).homogeneous
            return out

        def jacobians(QP: np.ndarray = QP) -> np.ndarray:
            out = np.empty((len(QP), 6, dof))
            for i, qp in enumerate(QP):
                out[i] = fold(frame_jacobian(model, data, qp, fid, LWA))
            return out

        def both(QP: np.ndarray = QP) -> tuple[np.ndarray, np.ndarray]:
            T, J = np.empty((len(QP), 4, 4)), np.empty((len(QP), 6, dof))
            for i, qp in enumerate(QP):
                J[i] = fold(frame_jacobian(model, data, qp, fid, LWA))
                T[i] = place(model, data, fid).homogeneous
            return T, J

        timed = n <= loop_max
        untimed = "" if timed else f"floor not timed above N = {loop_max:,}"
        out = (np.empty((n, 4, 4)), np.empty((n, 6, dof)))
        for name, call, loop, note in (
            ("frame_pose", robot.frame_pose, poses, ""),
            ("jacobian[local_world_aligned]", robot.jacobian, jacobians, ""),
            ("kinematics", robot.kinematics, both, "robot.kinematics(Q): pose and Jacobian in one call"),
        ):
            cases.append(
                Case(
                    "throughput",
                    name,
                    n,
                    lambda Q=Q, call=call: call(Q, frame),
                    loop if timed else None,
                    "; ".join(text for text in (note, untimed) if text),
                    compare=timed,
                    q=Q,
                    floor=FLOOR_LOOP,
                )
            )
        cases.append(
            Case(
                "throughput",
                "kinematics[out=]",
                n,
                lambda Q=Q, out=out: robot.kinematics(Q, frame, out=out),
                both if timed else None,
                "preallocated out=(T, J)",
                compare=timed,
                floor=FLOOR_LOOP,
            )
        )
        if n > loop_max:
            continue
        for rot in ("euler_zyx", "quaternion"):
            cases.append(
                Case(
                    "throughput",
                    f"analytic_jacobian[{rot}]",
                    n,
                    lambda Q=Q, rot=rot: robot.analytic_jacobian(
                        Q, frame, position="cartesian", rotation=rot, singularity_threshold=0.0
                    ),
                    analytic_loop(robot, frame, Q, rot),
                    compare=True,
                    q=Q,
                    floor=FLOOR_LOOP,
                )
            )
    return cases


__all__ = ["Case", "latency_cases", "regular_configuration", "throughput_cases"]
