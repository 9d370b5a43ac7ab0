"""The rows of ``kinengine bench``: what kinengine calls, and the raw-Pinocchio code a user would write instead.

Every :class:`Case` pairs a kinengine call with its floor: the plain inline code on raw Pinocchio
that gives the same output (same model ``robot.pinocchio_model()``, same configuration, the same 4x4
``.homogeneous`` or 6xdof array, no wrapper function in between), written as closures over local
names exactly as in a user's hot loop. ``floor`` holds that code as text for the table. Where both
return the same quantity, ``compare`` is set and the runner checks that they agree before timing.
For robots with mimic joints the floor is handed Pinocchio's configuration q_pin = M q + b ready made
(``robot.pinocchio_configuration(q)``); kinengine maps q itself, inside the timed call.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ...errors import RepresentationSingularityError

REFERENCES = ("local_world_aligned", "local", "world")
_PIN_REFERENCES = {"local_world_aligned": pin.LOCAL_WORLD_ALIGNED, "local": pin.LOCAL, "world": pin.WORLD}
_PIN_NAMES = {"local_world_aligned": "pin.LOCAL_WORLD_ALIGNED", "local": "pin.LOCAL", "world": "pin.WORLD"}
IK_TARGETS = 8
FLOOR_POSE = "pin.forwardKinematics(model, data, q); pin.updateFramePlacement(model, data, fid).homogeneous"
FLOOR_JACOBIAN = "pin.computeFrameJacobian(model, data, q, fid, {ref})"
FLOOR_KINEMATICS = (
    "J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED); "
    "T = pin.updateFramePlacement(model, data, fid).homogeneous"
)
FLOOR_ANALYTIC = {
    "euler_zyx": "J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED); "
    "J[3:] = pin.rpy.computeRpyJacobianInverse(pin.rpy.matrixToRpy(data.oMf[fid].rotation), "
    "pin.LOCAL_WORLD_ALIGNED)[::-1] @ J[3:]",
    "rotation_vector": "J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED); "
    "R = data.oMf[fid].rotation; J[3:] = pin.Jlog3(R) @ (R.T @ J[3:])",
    "quaternion": "J = pin.computeFrameJacobian(...); Q = pin.Quaternion(data.oMf[fid].rotation); "
    "E = ½[[-x,-y,-z],[w,z,-y],[-z,w,x],[y,-x,w]] (w >= 0); out[:3] = J[:3]; out[3:] = E @ J[3:]",
}
FLOOR_GEOMETRIC = (
    "pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED) (Pinocchio has no E(χ))"
)
FLOOR_LOOP = "for i, q in enumerate(Q): out[i] = <the single-q floor>"


@dataclass(frozen=True)
class Case:
    """One benchmark row; each call does ``n`` configurations (or IK solves)."""

    group: str  # "latency" or "throughput"
    name: str  # e.g. "jacobian[local]"
    n: int
    kinengine: Callable[[], object] | None  # None: the API does not exist (see note)
    pinocchio: Callable[[], object] | None  # None: no floor timed (see note)
    note: str = ""
    compare: bool = False  # both return the same array: check before timing
    q: np.ndarray | None = None  # the input: q (dof,) or Q (n, dof), for the peers
    floor: str = ""  # the floor's code, as a user would write it
    targets: np.ndarray | None = None  # IK rows: the target poses (n, 4, 4), for the peers
    robot: object = None  # IK rows: the robot and frame the targets are for
    frame: str = ""


def regular_configuration(robot, frame: str, rotations: list[str], seed: int = 0) -> np.ndarray:
    """A seeded q at which every rotation parameterization is at least 0.1 from its singular set."""
    rng = np.random.default_rng(seed)
    for _ in range(200):
        q = robot.random_configuration(rng)
        try:
            for name in rotations:
                robot.analytic_jacobian(
                    q, frame, position="cartesian", rotation=name, singularity_threshold=0.1
                )
        except RepresentationSingularityError:
            continue
        return q
    raise RuntimeError(f"no configuration of {robot.name} is regular for every parameterization")


def floors(robot, frame: str, q: np.ndarray) -> dict[str, Callable[[], object]]:
    """The inline raw-Pinocchio floors at one q, as closures over local names (see the module doc)."""
    model = robot.pinocchio_model()
    data = model.createData()
    fid = robot.frame_id(frame)
    qp = robot.pinocchio_configuration(q)
    fk, place, frame_jacobian = pin.forwardKinematics, pin.updateFramePlacement, pin.computeFrameJacobian
    LWA, oMf = pin.LOCAL_WORLD_ALIGNED, data.oMf
    rpy_inverse, matrix_to_rpy, jlog3, quaternion = (
        pin.rpy.computeRpyJacobianInverse,
        pin.rpy.matrixToRpy,
        pin.Jlog3,
        pin.Quaternion,
    )
    fold = robot.engine.coordinates.fold  # the identity without mimic joints

    def pose():
        fk(model, data, qp)
        return place(model, data, fid).homogeneous

    def jacobian(ref):
        def floor():
            return fold(frame_jacobian(model, data, qp, fid, ref))

        return floor

    def kinematics():
        J = fold(frame_jacobian(model, data, qp, fid, LWA))
        return place(model, data, fid).homogeneous, J

    def zyx():
        J = fold(frame_jacobian(model, data, qp, fid, LWA))
        J[3:] = rpy_inverse(matrix_to_rpy(oMf[fid].rotation), LWA)[::-1] @ J[3:]
        return J

    def rotation_vector():
        J = fold(frame_jacobian(model, data, qp, fid, LWA))
        R = oMf[fid].rotation
        J[3:] = jlog3(R) @ (R.T @ J[3:])
        return J

    def quat():
        J = fold(frame_jacobian(model, data, qp, fid, LWA))
        Q = quaternion(oMf[fid].rotation)
        w, x, y, z = Q.w, Q.x, Q.y, Q.z
        if w < 0:
            w, x, y, z = -w, -x, -y, -z
        E = np.array([[-x, -y, -z], [w, z, -y], [-z, w, x], [y, -x, w]])
        E *= 0.5
        out = np.empty((7, J.shape[1]))
        out[:3] = J[:3]
        out[3:] = E @ J[3:]
        return out

    def geometric():
        return fold(frame_jacobian(model, data, qp, fid, LWA))

    return {
        "frame_pose": pose,
        "kinematics": kinematics,
        **{f"jacobian[{r}]": jacobian(_PIN_REFERENCES[r]) for r in REFERENCES},
        "euler_zyx": zyx,
        "rotation_vector": rotation_vector,
        "quaternion": quat,
        "geometric": geometric,
    }


def latency_cases(robot, frame: str, rotations: list[str]) -> list[Case]:
    """Single-call rows at one configuration regular for every parameterization."""
    q = regular_configuration(robot, frame, rotations)
    floor = floors(robot, frame, q)
    fk, fast = robot.frame(frame), robot.frame(frame, check_inputs=False)
    cases = [
        Case(
            "latency",
            "frame_pose",
            1,
            lambda: robot.frame_pose(q, frame),
            floor["frame_pose"],
            compare=True,
            q=q,
            floor=FLOOR_POSE,
        )
    ]
    for ref in REFERENCES:
        cases.append(
            Case(
                "latency",
                f"jacobian[{ref}]",
                1,
                lambda ref=ref: robot.jacobian(q, frame, ref),
                floor[f"jacobian[{ref}]"],
                compare=True,
                q=q,
                floor=FLOOR_JACOBIAN.format(ref=_PIN_NAMES[ref]),
            )
        )
    cases.append(
        Case(
            "latency",
            "kinematics",
            1,
            lambda: robot.kinematics(q, frame),
            floor["kinematics"],
            compare=True,
            floor=FLOOR_KINEMATICS,
        )
    )
    for label, handle in (("", fk), (", check_inputs=False", fast)):
        cases += [
            Case(
                "latency",
                f"frame(){label}.pose",
                1,
                lambda h=handle: h.pose(q),
                floor["frame_pose"],
                compare=True,
                floor=FLOOR_POSE,
            ),
            Case(
                "latency",
                f"frame(){label}.jacobian",
                1,
                lambda h=handle: h.jacobian(q),
                floor["jacobian[local_world_aligned]"],
                compare=True,
                floor=FLOOR_JACOBIAN.format(ref="pin.LOCAL_WORLD_ALIGNED"),
            ),
            Case(
                "latency",
                f"frame(){label}.kinematics",
                1,
                lambda h=handle: h.kinematics(q),
                floor["kinematics"],
                compare=True,
                floor=FLOOR_KINEMATICS,
            ),
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
                "" if exact else "floor: geometric Jacobian only (Pinocchio has no E(χ) for it)",
                compare=exact,
                q=q,
                floor=FLOOR_ANALYTIC.get(rot, FLOOR_GEOMETRIC),
            )
        )
    cases += _task_cases(robot, frame, q, floor)
    return cases + [_ik_case(robot, frame)]


def _task_cases(robot, frame: str, q: np.ndarray, floor: dict) -> list[Case]:
    qdot = np.random.default_rng(1).uniform(-1.0, 1.0, robot.dof)
    model = robot.pinocchio_model()
    data = model.createData()
    fid = robot.frame_id(frame)
    qp, qdp = robot.pinocchio_configuration(q), robot.engine.coordinates.velocity_to_pinocchio(qdot)
    fold, zyx = robot.engine.coordinates.fold, floor["euler_zyx"]

    def floor_with_velocity():
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
            zyx,
            "euler_zyx; floor: J and the rpy conversion",
            floor=FLOOR_ANALYTIC["euler_zyx"],
        ),
        Case(
            "latency",
            "task.update(q)[euler_zyz]",
            1,
            lambda: zyz.update(q),
            floor["kinematics"],
            "floor: J and pose only (Pinocchio has no ZYZ angles)",
            floor=FLOOR_KINEMATICS,
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


def _ik_case(robot, frame: str) -> Case:
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

    def pinocchio():
        return [clik(T, s) for T, s in zip(pin_targets, pin_starts)]

    reached = sum(
        np.allclose(robot.frame_pose(coords.from_pinocchio(q), frame), T, rtol=0, atol=1e-8)
        for q, T in zip(pinocchio(), targets)
    )
    return Case(
        "latency",
        "inverse_kinematics",
        IK_TARGETS,
        lambda: [robot.inverse_kinematics(T, frame, q0=s) for T, s in zip(targets, starts)],
        pinocchio,
        f"from starts 0.2 away; floor reached {reached}/{IK_TARGETS}",
        floor="Pinocchio's CLIK example (log6 error, Jlog6, damping 1e-10, integrate) per target",
    )


def ik_cases(robot, frame: str, single: int, batch: int, seed: int = 2024) -> list[Case]:
    """Random reachable targets, no start given: ``single`` solves one by one, and ``batch`` solved as
    one (N, 4, 4) batch. No Pinocchio floor (Pinocchio has no IK solver); peers: Robotics Toolbox."""
    rng = np.random.default_rng(seed)
    cases = []
    for group, n, vectorized in (("latency", single, False), ("throughput", batch, True)):
        targets = robot.frame_pose(robot.random_configuration(rng, size=n), frame)
        if vectorized:

            def solve(targets=targets):
                return robot.inverse_kinematics(targets, frame, rng=0).q
        else:

            def solve(targets=targets):
                return np.array([robot.inverse_kinematics(T, frame, rng=i).q for i, T in enumerate(targets)])

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
    return cases


def throughput_cases(
    robot, frame: str, sizes: list[int], seed: int = 3, loop_max: int = 100_000
) -> list[Case]:
    """Batched rows for each N: poses, Jacobians, both in one call, and analytic Jacobians; the floor is
    a Python loop of the single-q floor (not timed above ``loop_max``)."""
    cases = []
    for n in sizes:
        Q = robot.random_configuration(np.random.default_rng(seed), size=n)
        QP = np.array([robot.pinocchio_configuration(q) for q in Q])
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

        def poses(QP=QP):
            out = np.empty((len(QP), 4, 4))
            for i, qp in enumerate(QP):
                fk(model, data, qp)
                out[i] = place(model, data, fid).homogeneous
            return out

        def jacobians(QP=QP):
            out = np.empty((len(QP), 6, dof))
            for i, qp in enumerate(QP):
                out[i] = fold(frame_jacobian(model, data, qp, fid, LWA))
            return out

        def both(QP=QP):
            T, J = np.empty((len(QP), 4, 4)), np.empty((len(QP), 6, dof))
            for i, qp in enumerate(QP):
                J[i] = fold(frame_jacobian(model, data, qp, fid, LWA))
                T[i] = place(model, data, fid).homogeneous
            return T, J

        timed = n <= loop_max
        out = (np.empty((n, 4, 4)), np.empty((n, 6, dof)))
        cases += [
            Case(
                "throughput",
                "frame_pose",
                n,
                lambda Q=Q: robot.frame_pose(Q, frame),
                poses if timed else None,
                "" if timed else f"floor not timed above N = {loop_max:,}",
                compare=timed,
                q=Q,
                floor=FLOOR_LOOP,
            ),
            Case(
                "throughput",
                "jacobian[local_world_aligned]",
                n,
                lambda Q=Q: robot.jacobian(Q, frame),
                jacobians if timed else None,
                "" if timed else f"floor not timed above N = {loop_max:,}",
                compare=timed,
                q=Q,
                floor=FLOOR_LOOP,
            ),
            Case(
                "throughput",
                "kinematics",
                n,
                lambda Q=Q: robot.kinematics(Q, frame),
                both if timed else None,
                "robot.kinematics(Q): pose and Jacobian in one call"
                + ("" if timed else f"; floor not timed above N = {loop_max:,}"),
                compare=timed,
                q=Q,
                floor=FLOOR_LOOP,
            ),
            Case(
                "throughput",
                "kinematics[out=]",
                n,
                lambda Q=Q, out=out: robot.kinematics(Q, frame, out=out),
                both if timed else None,
                "preallocated out=(T, J)",
                compare=timed,
                floor=FLOOR_LOOP,
            ),
        ]
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
                    _analytic_loop(robot, frame, Q, rot),
                    compare=True,
                    q=Q,
                    floor=FLOOR_LOOP,
                )
            )
    return cases


def _analytic_loop(robot, frame: str, Q: np.ndarray, rot: str) -> Callable[[], np.ndarray]:
    """The single-q analytic floor in a loop over Q (its closure reads the configuration from a cell)."""
    model = robot.pinocchio_model()
    data = model.createData()
    fid = robot.frame_id(frame)
    QP = np.array([robot.pinocchio_configuration(q) for q in Q])
    fold = robot.engine.coordinates.fold
    frame_jacobian, LWA, oMf = pin.computeFrameJacobian, pin.LOCAL_WORLD_ALIGNED, data.oMf
    rpy_inverse, matrix_to_rpy = pin.rpy.computeRpyJacobianInverse, pin.rpy.matrixToRpy
    rows = 7 if rot == "quaternion" else 6

    def loop():
        out = np.empty((len(QP), rows, robot.dof))
        for i, qp in enumerate(QP):
            J = fold(frame_jacobian(model, data, qp, fid, LWA))
            if rot == "euler_zyx":
                J[3:] = rpy_inverse(matrix_to_rpy(oMf[fid].rotation), LWA)[::-1] @ J[3:]
                out[i] = J
            else:
                Qn = pin.Quaternion(oMf[fid].rotation)
                w, x, y, z = Qn.w, Qn.x, Qn.y, Qn.z
                if w < 0:
                    w, x, y, z = -w, -x, -y, -z
                out[i, :3] = J[:3]
                out[i, 3:] = 0.5 * np.array([[-x, -y, -z], [w, z, -y], [-z, w, x], [y, -x, w]]) @ J[3:]
        return out

    return loop
