"""The rows of ``kinengine bench``: what kinengine calls, and what raw Pinocchio does for the same work.

Every :class:`Case` pairs a kinengine call with its floor, the least a Python caller of Pinocchio
can do to get the same numbers (e.g. ``forwardKinematics`` + ``updateFramePlacement`` for a pose;
a Python loop over Pinocchio for a batch). Where the floor returns the same quantity, ``compare``
is set and the runner checks that both agree before timing. A kinengine API that does not exist
yet gives a row with ``kinengine=None`` and a note; its floor is still timed.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ...errors import RepresentationSingularityError

REFERENCES = ("local_world_aligned", "local", "world")
_PIN_REFERENCES = {"local_world_aligned": pin.LOCAL_WORLD_ALIGNED, "local": pin.LOCAL, "world": pin.WORLD}
IK_TARGETS = 8


@dataclass(frozen=True)
class Case:
    """One benchmark row; each call does ``n`` configurations (or IK solves)."""

    group: str                                  # "latency" or "throughput"
    name: str                                   # e.g. "jacobian[local]"
    n: int
    kinengine: Callable[[], object] | None      # None: the API does not exist yet (see note)
    pinocchio: Callable[[], object] | None
    note: str = ""
    compare: bool = False                       # both return the same array: check before timing
    q: np.ndarray | None = None                 # the input: q (dof,) or Q (n, dof), for the peers


def regular_configuration(robot, frame: str, rotations: list[str], seed: int = 0) -> np.ndarray:
    """A seeded q at which every rotation parameterization is at least 0.1 from its singular set."""
    rng = np.random.default_rng(seed)
    analytic = getattr(robot, "analytic_jacobian", None)
    for _ in range(200):
        q = robot.random_configuration(rng)
        try:
            for name in rotations if analytic is not None else ():
                analytic(q, frame, position="cartesian", rotation=name, singularity_threshold=0.1)
        except RepresentationSingularityError:
            continue
        return q
    raise RuntimeError(f"no configuration of {robot.name} is regular for every parameterization")


class _Floor:
    """Raw Pinocchio on the robot's model, with its own Data."""

    def __init__(self, robot, frame: str) -> None:
        self.model = robot.pinocchio_model()
        self.data = self.model.createData()
        self.fid = robot.frame_id(frame)
        coords = robot.engine.coordinates
        self.to_pin = coords.to_pinocchio
        self.from_pin = coords.from_pinocchio

    def pose(self, qp: np.ndarray) -> np.ndarray:
        pin.forwardKinematics(self.model, self.data, qp)
        return pin.updateFramePlacement(self.model, self.data, self.fid).homogeneous

    def jacobian(self, qp: np.ndarray, reference: pin.ReferenceFrame) -> np.ndarray:
        J = pin.computeFrameJacobian(self.model, self.data, qp, self.fid, reference)
        return J if J.ndim == 2 else J.reshape(6, 1)  # eigenpy returns (6, 1) as (6,)

    def analytic(self, qp: np.ndarray, rotation: str) -> np.ndarray:
        """[J_v; E_R·J_ω] with Pinocchio's own conversions where it has them."""
        J = self.jacobian(qp, pin.LOCAL_WORLD_ALIGNED)
        R = pin.updateFramePlacement(self.model, self.data, self.fid).rotation
        if rotation == "euler_zyx":  # χ = (yaw, pitch, roll): Pinocchio's rpy reversed
            E = pin.rpy.computeRpyJacobianInverse(pin.rpy.matrixToRpy(R), pin.LOCAL_WORLD_ALIGNED)[::-1]
        elif rotation == "rotation_vector":  # d log(C)/dt = Jlog3(C)·C^T·ω
            E = pin.Jlog3(R) @ R.T
        elif rotation == "quaternion":  # scalar first, w >= 0; q̇ = ½ [−v^T; w I − [v]x]·ω
            quat = pin.Quaternion(R)
            w, x, y, z = np.copysign(0.5, quat.w) * np.array([quat.w, quat.x, quat.y, quat.z])
            E = np.array([[-x, -y, -z], [w, z, -y], [-z, w, x], [y, -x, w]])
        else:  # no Pinocchio routine: the floor is the geometric part alone
            return J
        return np.vstack([J[:3], E @ J[3:]])

    def ik(self, target: pin.SE3, q0: np.ndarray, iterations: int = 200, tol: float = 1e-10) -> np.ndarray:
        """Pinocchio's CLIK example, Gauss–Newton with damping 1e-10, in the frame (LOCAL)."""
        q = q0.copy()
        for _ in range(iterations):
            pin.forwardKinematics(self.model, self.data, q)
            fMd = pin.updateFramePlacement(self.model, self.data, self.fid).actInv(target)  # target in F
            err = pin.log6(fMd).vector
            if err @ err < tol * tol:
                break
            J = -pin.Jlog6(fMd.inverse()) @ self.jacobian(q, pin.LOCAL)
            v = -J.T @ np.linalg.solve(J @ J.T + 1e-10 * np.eye(6), err)
            q = pin.integrate(self.model, q, v)
        return q


def latency_cases(robot, frame: str, rotations: list[str]) -> list[Case]:
    """Single-call rows at one configuration regular for every parameterization."""
    floor = _Floor(robot, frame)
    q = regular_configuration(robot, frame, rotations)
    qp = np.array(floor.to_pin(q))
    cases = [Case("latency", "frame_pose", 1, lambda: robot.frame_pose(q, frame), lambda: floor.pose(qp),
                  compare=True, q=q)]
    for ref in REFERENCES:
        cases.append(Case("latency", f"jacobian[{ref}]", 1, lambda ref=ref: robot.jacobian(q, frame, ref),
                          lambda ref=ref: floor.jacobian(qp, _PIN_REFERENCES[ref]), compare=True, q=q))
    analytic = getattr(robot, "analytic_jacobian", None)
    for rot in rotations:
        exact = rot in ("euler_zyx", "rotation_vector", "quaternion")
        cases.append(Case(
            "latency", f"analytic_jacobian[{rot}]", 1,
            None if analytic is None else lambda rot=rot: analytic(q, frame, rotation=rot),
            lambda rot=rot: floor.analytic(qp, rot),
            "" if exact else "floor: geometric Jacobian only (Pinocchio has no E(χ) for it)", compare=exact,
            q=q))
    cases += _task_cases(robot, frame, q, qp, floor)
    return cases + [_ik_case(robot, frame, floor)]


def _task_cases(robot, frame: str, q: np.ndarray, qp: np.ndarray, floor: _Floor) -> list[Case]:
    qdot = np.random.default_rng(1).uniform(-1.0, 1.0, robot.dof)
    model, data, fid = floor.model, floor.data, floor.fid

    def floor_with_velocity():
        pin.computeJointJacobiansTimeVariation(model, data, qp, qdot)
        pin.updateFramePlacement(model, data, fid)
        pin.getFrameJacobianTimeVariation(model, data, fid, pin.LOCAL_WORLD_ALIGNED)
        return floor.analytic(qp, "euler_zyx")

    if getattr(robot, "task", None) is None:
        return [Case("latency", name, 1, None, fn, "robot.task() not available yet")
                for name, fn in (("task.update(q)", lambda: floor.analytic(qp, "euler_zyx")),
                                 ("task.update(q, qdot)", floor_with_velocity))]
    def pose_and_jacobian():
        J = floor.jacobian(qp, pin.LOCAL_WORLD_ALIGNED)
        return pin.updateFramePlacement(model, data, fid).homogeneous, J

    task = robot.task(frame, position="cartesian", rotation="euler_zyx")
    zyz = robot.task(frame, position="cartesian", rotation="euler_zyz")
    return [Case("latency", "task.update(q)", 1, lambda: task.update(q),
                 lambda: floor.analytic(qp, "euler_zyx"), "euler_zyx; floor: J, pose and rpy conversion"),
            Case("latency", "task.update(q)[euler_zyz]", 1, lambda: zyz.update(q), pose_and_jacobian,
                 "floor: J and pose only (Pinocchio has no ZYZ angles)"),
            Case("latency", "task.update(q, qdot)", 1, lambda: task.update(q, qdot), floor_with_velocity,
                 "euler_zyx; floor: J, J̇ (TimeVariation), rpy conversion, no Ė")]


def _ik_case(robot, frame: str, floor: _Floor) -> Case:
    """IK_TARGETS solves per call, each from a start 0.2 rad (or m) away from a reachable target."""
    rng = np.random.default_rng(2)
    solutions = robot.random_configuration(rng, size=IK_TARGETS)
    starts = np.clip(solutions + rng.normal(0.0, 0.2, solutions.shape),
                     robot.lower_limits, robot.upper_limits)
    targets = [robot.frame_pose(s, frame) for s in solutions]
    pin_targets = [pin.SE3(T) for T in targets]
    pin_starts = [np.array(floor.to_pin(s)) for s in starts]

    def pinocchio():
        return [floor.ik(T, s) for T, s in zip(pin_targets, pin_starts)]

    reached = sum(np.allclose(robot.frame_pose(floor.from_pin(q), frame), T, rtol=0, atol=1e-8)
                  for q, T in zip(pinocchio(), targets))
    note = f"floor: Pinocchio CLIK (Gauss–Newton), {reached}/{IK_TARGETS} targets reached"
    solve = getattr(robot, "inverse_kinematics", None)
    if solve is None:
        return Case("latency", "inverse_kinematics", IK_TARGETS, None, pinocchio,
                    "robot.inverse_kinematics() not available yet; " + note)
    return Case("latency", "inverse_kinematics", IK_TARGETS,
                lambda: [solve(T, frame, q0=s) for T, s in zip(targets, starts)], pinocchio, note)


def throughput_cases(robot, frame: str, sizes: list[int], seed: int = 3) -> list[Case]:
    """Batched rows for each N: poses, Jacobians, both in one pass, and analytic Jacobians."""
    floor = _Floor(robot, frame)
    analytic = getattr(robot, "analytic_jacobian", None)
    cases = []
    for n in sizes:
        Q = robot.random_configuration(np.random.default_rng(seed), size=n)
        QP = np.array(floor.to_pin(Q))

        def loop(fn, shape, QP=QP):
            out = np.empty((len(QP),) + shape)
            for i, qp in enumerate(QP):
                out[i] = fn(qp)
            return out

        def both(QP=QP):
            return loop(floor.pose, (4, 4), QP), loop(lambda qp: floor.jacobian(qp, pin.LOCAL_WORLD_ALIGNED),
                                                      (6, robot.dof), QP)

        cases += [
            Case("throughput", "frame_pose", n, lambda Q=Q: robot.frame_pose(Q, frame),
                 lambda loop=loop: loop(floor.pose, (4, 4)), compare=True, q=Q),
            Case("throughput", "jacobian[local_world_aligned]", n,
                 lambda Q=Q: robot.jacobian(Q, frame),
                 lambda loop=loop: loop(lambda qp: floor.jacobian(qp, pin.LOCAL_WORLD_ALIGNED),
                                        (6, robot.dof)),
                 compare=True, q=Q),
            Case("throughput", "pose+jacobian", n, lambda Q=Q: robot.kinematics(Q, frame),
                 both, "robot.kinematics(Q); floor: two loops", compare=True)]
        for rot in ("euler_zyx", "quaternion"):
            cases.append(Case(
                "throughput", f"analytic_jacobian[{rot}]", n,
                None if analytic is None else lambda Q=Q, rot=rot: analytic(
                    Q, frame, position="cartesian", rotation=rot, singularity_threshold=0.0),
                lambda loop=loop, rot=rot: loop(lambda qp: floor.analytic(qp, rot),
                                                (7 if rot == "quaternion" else 6, robot.dof)),
                "" if analytic is not None else "robot.analytic_jacobian() not available yet", compare=True,
                q=Q))
    return cases
