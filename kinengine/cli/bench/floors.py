"""The floors of ``kinengine bench``: the raw-Pinocchio code a user would write instead of each kinengine
call, as closures over local names (:func:`floors` for one q, :func:`analytic_loop` for a batch Q (n, dof)),
and as text (the ``FLOOR_*`` strings shown in the table). Floors return T_IF (4, 4) [m] and Jacobians
(6, dof) (or (7, dof) for the quaternion) exactly as kinengine does.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from operator import itemgetter

import numpy as np
import pinocchio as pin

from ...parameterizations import EULER_SEQUENCES
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
    "pin.LOCAL_WORLD_ALIGNED)[::-1].dot(J[3:])",
    "rotation_vector": "J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED); "
    "R = data.oMf[fid].rotation; J[3:] = pin.Jlog3(R).dot(R.T.dot(J[3:]))",
    "quaternion": "J = pin.computeFrameJacobian(...); (w, x, y, z) from R.tolist() by Shepperd's method "
    "(w >= 0); E = ½[[-x,-y,-z],[w,z,-y],[-z,w,x],[y,-x,w]]; out[:3] = J[:3]; out[3:] = E.dot(J[3:])",
    "angle_axis": "J = pin.computeFrameJacobian(...); φ = pin.log3(R); θ = |φ|; n = φ/θ; "
    "E = [n^T; −½([n]x + cot(θ/2)(n n^T − I))]; out[:3] = J[:3]; out[3:] = E.dot(J[3:])",
    "rotation_matrix": "J = pin.computeFrameJacobian(...); c_j = R[:, j]; "
    "E = [row i of −[c_j]x for (i, j) row-major] (9x3); out[:3] = J[:3]; out[3:] = E.dot(J[3:])",
    **{
        f"euler_{seq}": "J = pin.computeFrameJacobian(...); R = data.oMf[fid].rotation.tolist(); "
        f"χ1, χ2 = math.atan2(...) ({seq}); E = np.array(E_{seq}(χ1, χ2)).reshape(3, 3); J[3:] = E.dot(J[3:])"
        for seq in EULER_SEQUENCES
        if seq != "zyx"
    },
}
FLOOR_TASK = (
    "J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED); M = data.oMf[fid]; "
    "rpy = pin.rpy.matrixToRpy(M.rotation); χ = (M.translation, rpy[::-1]); "
    "J[3:] = pin.rpy.computeRpyJacobianInverse(rpy, pin.LOCAL_WORLD_ALIGNED)[::-1].dot(J[3:])"
)
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
    rpy_inverse, matrix_to_rpy, jlog3 = pin.rpy.computeRpyJacobianInverse, pin.rpy.matrixToRpy, pin.Jlog3
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
        J[3:] = rpy_inverse(matrix_to_rpy(oMf[fid].rotation), LWA)[::-1].dot(J[3:])
        return J

    def rotation_vector() -> np.ndarray:
        J = fold(frame_jacobian(model, data, qp, fid, LWA))
        R = oMf[fid].rotation
        J[3:] = jlog3(R).dot(R.T.dot(J[3:]))
        return J

    log3, sqrt, tan, array = pin.log3, math.sqrt, math.tan, np.array

    def quat() -> np.ndarray:
        J = fold(frame_jacobian(model, data, qp, fid, LWA))
        (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = oMf[fid].rotation.tolist()
        trace = c00 + c11 + c22  # Shepperd: the largest of 4w², 4x², 4y², 4z² (all scaled by 4·(that one))
        best = max(c00, c11, c22, trace)
        if best == trace:
            x, y, z, w = c21 - c12, c02 - c20, c10 - c01, 1.0 + trace
        elif best == c00:
            x, y, z, w = 1.0 - trace + 2.0 * c00, c10 + c01, c20 + c02, c21 - c12
        elif best == c11:
            x, y, z, w = c10 + c01, 1.0 - trace + 2.0 * c11, c21 + c12, c02 - c20
        else:
            x, y, z, w = c20 + c02, c21 + c12, 1.0 - trace + 2.0 * c22, c10 - c01
        h = 0.5 / sqrt(x * x + y * y + z * z + w * w)  # ½ of the normalization: E = ½[...]
        if w < 0.0:
            h = -h
        x, y, z, w = x * h, y * h, z * h, w * h
        E = array((-x, -y, -z, w, z, -y, -z, w, x, y, -x, w)).reshape(4, 3)
        out = np.empty((7, J.shape[1]))
        out[:3] = J[:3]
        out[3:] = E.dot(J[3:])
        return out

    def geometric() -> np.ndarray:
        return fold(frame_jacobian(model, data, qp, fid, LWA))

    def angle_axis() -> np.ndarray:
        J = fold(frame_jacobian(model, data, qp, fid, LWA))
        x, y, z = log3(oMf[fid].rotation).tolist()
        theta = sqrt(x * x + y * y + z * z)
        x, y, z = x / theta, y / theta, z / theta
        k = 0.5 / tan(0.5 * theta)  # E[1:] = −½[n]x − ½ cot(θ/2)(n nᵀ − I)
        E = array(
            (
                x, y, z,
                k - k * x * x, 0.5 * z - k * x * y, -0.5 * y - k * x * z,
                -0.5 * z - k * x * y, k - k * y * y, 0.5 * x - k * y * z,
                0.5 * y - k * x * z, -0.5 * x - k * y * z, k - k * z * z,
            )
        ).reshape(4, 3)  # fmt: skip
        out = np.empty((7, J.shape[1]))
        out[:3] = J[:3]
        out[3:] = E.dot(J[3:])
        return out

    def rotation_matrix() -> np.ndarray:
        J = fold(frame_jacobian(model, data, qp, fid, LWA))
        (a, b, c), (d, e, f), (g, h, i) = oMf[fid].rotation.tolist()
        # Ċ = [ω]x C: row 3i + j of E is row i of −[C[:, j]]x,
        # −[v]x = [[0, vz, −vy], [−vz, 0, vx], [vy, −vx, 0]]
        E = array(
            (
                0.0, g, -d, 0.0, h, -e, 0.0, i, -f,
                -g, 0.0, a, -h, 0.0, b, -i, 0.0, c,
                d, -a, 0.0, e, -b, 0.0, f, -c, 0.0,
            )
        ).reshape(9, 3)  # fmt: skip
        out = np.empty((12, J.shape[1]))
        out[:3] = J[:3]
        out[3:] = E.dot(J[3:])
        return out

    rpy = pin.rpy.matrixToRpy
    translation = data.oMf[fid].translation

    def task() -> tuple[np.ndarray, np.ndarray]:
        J = fold(frame_jacobian(model, data, qp, fid, LWA))
        angles = rpy(oMf[fid].rotation)
        chi = np.concatenate((translation, angles[::-1]))
        J[3:] = rpy_inverse(angles, LWA)[::-1].dot(J[3:])
        return chi, J

    return {
        **{f"euler_{seq}": euler_floor(seq, model, data, qp, fid, fold) for seq in EULER_SEQUENCES},
        "angle_axis": angle_axis,
        "rotation_matrix": rotation_matrix,
        "task": task,
        "frame_pose": pose,
        "kinematics": kinematics,
        **{f"jacobian[{r}]": jacobian(PIN_REFERENCES[r]) for r in REFERENCES},
        "euler_zyx": zyx,
        "rotation_vector": rotation_vector,
        "quaternion": quat,
        "geometric": geometric,
    }


def euler_floor(
    seq: str,
    model: pin.Model,
    data: pin.Data,
    qp: np.ndarray,
    fid: int,
    fold: Callable[[np.ndarray], np.ndarray],
) -> Callable[[], np.ndarray]:
    """The floor of intrinsic Euler angles ``seq`` = "abc" (C = R_a(χ1) R_b(χ2) R_c(χ3)), as a user writes
    it for one sequence: χ1, χ2 by math.atan2 off C's entries (E does not depend on χ3), E(χ1, χ2) by
    np.array, one .dot (measured faster than @ for these sizes).

    In the axes (a, b, t), t the remaining axis, ε = ε_abt, c_k = cos χk, s_k = sin χk, ω = B(χ)·χ̇ with
    Tait–Bryan (c = t): B = [[1, 0, ε s2], [0, c1, −ε s1 c2], [0, ε s1, c1 c2]], E = B⁻¹ =
    [[1, s1 s2/c2, −ε c1 s2/c2], [0, c1, ε s1], [0, −ε s1/c2, c1/c2]];
    proper (c = a): B = [[1, 0, c2], [0, c1, s1 s2], [0, ε s1, −ε c1 s2]], E = B⁻¹ =
    [[1, −s1 c2/s2, ε c1 c2/s2], [0, c1, ε s1], [0, s1/s2, −ε c1/s2]]; columns placed on axes a, b, t.
    """
    a, b, c = ("xyz".index(axis) for axis in seq)
    t = 3 - a - b
    e = float((a - b) * (b - t) * (t - a) // 2)
    # E's entry (r, k) is the (a, b, t)-column entry (r, (a, b, t).index(k)), row-major
    place = itemgetter(*(3 * r + (a, b, t).index(k) for r in range(3) for k in range(3)))
    frame_jacobian, LWA, oMf, atan2, hypot = (
        pin.computeFrameJacobian,
        pin.LOCAL_WORLD_ALIGNED,
        data.oMf,
        math.atan2,
        math.hypot,
    )
    cos, sin, array = math.cos, math.sin, np.array

    def proper() -> np.ndarray:
        J = fold(frame_jacobian(model, data, qp, fid, LWA))
        C = oMf[fid].rotation.tolist()
        chi2 = atan2(hypot(C[a][b], C[a][t]), C[a][a])
        chi1 = atan2(C[b][a], -e * C[t][a])
        c1, s1, c2, s2 = cos(chi1), sin(chi1), cos(chi2), sin(chi2)
        u = 1.0 / s2
        k = c2 * u
        E = array(place((1.0, -s1 * k, e * c1 * k, 0.0, c1, e * s1, 0.0, s1 * u, -e * c1 * u)))
        J[3:] = E.reshape(3, 3).dot(J[3:])
        return J

    def tait_bryan() -> np.ndarray:
        J = fold(frame_jacobian(model, data, qp, fid, LWA))
        C = oMf[fid].rotation.tolist()
        bt, tt = C[b][t], C[t][t]
        chi2 = atan2(e * C[a][t], hypot(bt, tt))
        chi1 = atan2(-e * bt, tt)
        c1, s1, c2, s2 = cos(chi1), sin(chi1), cos(chi2), sin(chi2)
        u = 1.0 / c2
        k = s2 * u
        E = array(place((1.0, s1 * k, -e * c1 * k, 0.0, c1, e * s1, 0.0, -e * s1 * u, c1 * u)))
        J[3:] = E.reshape(3, 3).dot(J[3:])
        return J

    return proper if a == c else tait_bryan


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
    "FLOOR_TASK",
    "PIN_NAMES",
    "PIN_REFERENCES",
    "REFERENCES",
    "analytic_loop",
    "euler_floor",
    "floors",
]
