"""The floors of ``kinengine bench``: the raw-Pinocchio code a user would write instead of each kinengine
call, as closures over local names (:func:`floors` for one q, :func:`analytic_loop` for a batch Q (n, dof)),
and as text (the ``FLOOR_*`` strings shown in the table). Floors return T_IF (4, 4) [m] and Jacobians
(6, dof) (or (7, dof) for the quaternion) exactly as kinengine does.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pinocchio as pin

from ...robot import Robot

REFERENCES = ("local_world_aligned", "local", "world")
PIN_REFERENCES = {"local_world_aligned": pin.LOCAL_WORLD_ALIGNED, "local": pin.LOCAL, "world": pin.WORLD}
PIN_NAMES = {"local_world_aligned": "pin.LOCAL_WORLD_ALIGNED", "local": "pin.LOCAL", "world": "pin.WORLD"}
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


def floors(robot: Robot, frame: str, q: np.ndarray) -> dict[str, Callable[[], object]]:
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

    def pose() -> np.ndarray:
        fk(model, data, qp)
        return place(model, data, fid).homogeneous

    def jacobian(ref: pin.ReferenceFrame) -> Callable[[], np.ndarray]:
        def floor() -> np.ndarray:
            return fold(frame_jacobian(model, data, qp, fid, ref))

        return floor

    def kinematics() -> tuple[np.ndarray, np.ndarray]:
        J = fold(frame_jacobian(model, data, qp, fid, LWA))
        return place(model, data, fid).homogeneous, J

    def zyx() -> np.ndarray:
        J = fold(frame_jacobian(model, data, qp, fid, LWA))
        J[3:] = rpy_inverse(matrix_to_rpy(oMf[fid].rotation), LWA)[::-1] @ J[3:]
        return J

    def rotation_vector() -> np.ndarray:
        J = fold(frame_jacobian(model, data, qp, fid, LWA))
        R = oMf[fid].rotation
        J[3:] = jlog3(R) @ (R.T @ J[3:])
        return J

    def quat() -> np.ndarray:
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

    def geometric() -> np.ndarray:
        return fold(frame_jacobian(model, data, qp, fid, LWA))

    return {
        "frame_pose": pose,
        "kinematics": kinematics,
        **{f"jacobian[{r}]": jacobian(PIN_REFERENCES[r]) for r in REFERENCES},
        "euler_zyx": zyx,
        "rotation_vector": rotation_vector,
        "quaternion": quat,
        "geometric": geometric,
    }


def analytic_loop(robot: Robot, frame: str, Q: np.ndarray, rot: str) -> Callable[[], np.ndarray]:
    """The single-q analytic floor in a loop over Q (its closure reads the configuration from a cell)."""
    model = robot.pinocchio_model()
    data = model.createData()
    fid = robot.frame_id(frame)
    QP = np.array([robot.pinocchio_configuration(q) for q in Q])
    fold = robot.engine.coordinates.fold
    frame_jacobian, LWA, oMf = pin.computeFrameJacobian, pin.LOCAL_WORLD_ALIGNED, data.oMf
    rpy_inverse, matrix_to_rpy = pin.rpy.computeRpyJacobianInverse, pin.rpy.matrixToRpy
    rows = 7 if rot == "quaternion" else 6

    def loop() -> np.ndarray:
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


__all__ = [
    "FLOOR_ANALYTIC",
    "FLOOR_GEOMETRIC",
    "FLOOR_JACOBIAN",
    "FLOOR_KINEMATICS",
    "FLOOR_LOOP",
    "FLOOR_POSE",
    "PIN_NAMES",
    "PIN_REFERENCES",
    "REFERENCES",
    "analytic_loop",
    "floors",
]
