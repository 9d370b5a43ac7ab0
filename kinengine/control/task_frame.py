"""The per-frame work of a :class:`~kinengine.control.task.Task` update, all into preallocated arrays.

:class:`FrameKinematics` — one Pinocchio frame F: from the world-frame joint Jacobians J_w, J̇_w that one
``computeForwardKinematicsDerivatives`` left in the Task's Data, J_e0 = X(p)·J_w with
X = [[I, −[p]x], [0, I]] (the spatial velocity moved from I's origin to F's origin p), J̇_e0 = X·J̇_w + Ẋ·J_w
with Ẋ = [[0, −[ṗ]x], [0, 0]], and the twist J_e0·q̇ (rows [v; ω] in I, "local_world_aligned").

:class:`FrameBlock` — one :class:`~kinengine.FrameTask`: its pose (T_IA, or T_BA with ``relative_to`` B),
its Jacobian (J_e0 of A, or the relative Jacobian in B: see :mod:`kinengine.kinematics.relative`, with
J̇_rel = C_IBᵀ(d/dt inner − [ω_B]× inner), inner = [J_A,v − J_B,v + [p_A − p_B]× J_B,ω; J_A,ω − J_B,ω]),
χ (continuous if asked), E(χ) and J_A = E·J, Ė and J̇_A = Ė·J + E·J̇, χ̇ = J_A·q̇, each written into its
slice of the Task's stacked arrays. A parameterization within the threshold of its singular set gets NaN
entries in E (so NaN rows in J_A, J̇_A, χ̇); its χ rows keep the (finite) angles.
"""

from __future__ import annotations

import math
import struct

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..analytic.pose_map import PoseMap
from ..analytic.singular import singularity_error
from ..errors import RepresentationSingularityError
from ..model.coordinates import CoordinateMap
from ..parameterizations.base import (
    Parameterization,
    PositionParameterization,
    RotationParameterization,
)
from .continuity import Rule, continuity_rule
from .frame_task import FrameTask


def joint_jacobians(
    model: pin.Model, data: pin.Data, q: np.ndarray, v: np.ndarray | None, zero: np.ndarray
) -> None:
    """Pinocchio's world-frame joint Jacobians J_w into ``data.J`` at q (and the joint placements); with
    q̇ = ``v`` also J̇_w into ``data.dJ`` (computeForwardKinematicsDerivatives), without it
    computeJointJacobians, which fills the same J_w at about half the cost."""
    if v is None:
        pin.computeJointJacobians(model, data, q)
    else:
        pin.computeForwardKinematicsDerivatives(model, data, q, v, zero)


class FrameKinematics:
    """J_e0, J̇_e0, twist of one frame F (rows [v; ω] in I) from the Task's Pinocchio Data."""

    def __init__(self, model: pin.Model, data: pin.Data, fid: int, dof: int, coords: CoordinateMap) -> None:
        self.model, self.data, self.fid, self.coords = model, data, fid, coords
        placement = data.oMf[fid]  # a reference into data: these views follow every update
        self.R, self.p = placement.rotation, placement.translation
        mask = np.zeros(model.nv)  # Pinocchio's columns of the joints that move this frame
        for j in model.supports[model.frames[fid].parentJoint][1:]:
            joint = model.joints[j]
            mask[joint.idx_v : joint.idx_v + joint.nv] = 1.0
        self.mask = None if mask.all() else mask
        self.X = np.eye(6)
        self.Xdot_lin = np.zeros((3, 3))  # −[ṗ]x
        self.masked, self.masked_dot = np.empty((6, model.nv)), np.empty((6, model.nv))
        self.folded, self.folded_dot = np.empty((6, dof)), np.empty((6, dof))
        self.tmp = np.empty((3, dof))
        self.J, self.Jdot, self.twist = np.zeros((6, dof)), np.zeros((6, dof)), np.zeros(6)
        self.adopted = False
        self.Jw = self.folded  # J_w of this frame's joints, folded (set by update)

    def adopt(self, J: np.ndarray, Jdot: np.ndarray, twist: np.ndarray) -> None:
        """Write J, J̇ and the twist straight into these views (an absolute block's slices of the Task's
        arrays) instead of private buffers: that block then copies nothing."""
        self.J, self.Jdot, self.twist, self.adopted = J, Jdot, twist, True

    def update(self, Jw: np.ndarray, dJw: np.ndarray, qdot: np.ndarray | None) -> None:
        pin.updateFramePlacement(self.model, self.data, self.fid)
        self.C = self.R.tolist()
        self.pos = px, py, pz = self.p.tolist()
        X = self.X
        X[0, 4], X[0, 5], X[1, 3], X[1, 5], X[2, 3], X[2, 4] = pz, -py, -pz, px, py, -px
        if self.mask is not None:
            np.multiply(Jw, self.mask, out=self.masked)
            Jw = self.masked
        if not self.coords.identity:
            np.dot(Jw, self.coords.matrix, out=self.folded)
            Jw = self.folded
        self.Jw = Jw
        np.dot(X, Jw, out=self.J)
        if qdot is None:
            return
        np.dot(self.J, qdot, out=self.twist)
        if self.mask is not None:
            np.multiply(dJw, self.mask, out=self.masked_dot)
            dJw = self.masked_dot
        if not self.coords.identity:
            np.dot(dJw, self.coords.matrix, out=self.folded_dot)
            dJw = self.folded_dot
        Jdot = self.Jdot
        np.dot(X, dJw, out=Jdot)
        vx, vy, vz = self.twist[:3].tolist()
        S = self.Xdot_lin
        S[0, 1], S[0, 2], S[1, 0], S[1, 2], S[2, 0], S[2, 1] = vz, -vy, -vz, vx, vy, -vx
        np.dot(S, Jw[3:], out=self.tmp)
        np.add(Jdot[:3], self.tmp, out=Jdot[:3])


_POSE_ROWS = struct.Struct("12d")
"""The first three rows of a (4, 4) pose (C-contiguous float64): 12 doubles in one call."""


def _skew(S: np.ndarray, x: float, y: float, z: float) -> None:
    """S = [(x, y, z)]x in place."""
    S[0, 1], S[0, 2], S[1, 0], S[1, 2], S[2, 0], S[2, 1] = -z, y, z, -x, -y, x


class FrameBlock:
    """One FrameTask's rows of a Task: see the module doc. ``out`` holds the views it writes into."""

    def __init__(
        self,
        spec: FrameTask,
        pmap: PoseMap,
        a: FrameKinematics,
        b: FrameKinematics | None,
        dof: int,
        out: dict[str, np.ndarray],
        chi_offset: int,
        distance_offset: int,
    ) -> None:
        self.spec, self.pmap, self.a, self.b = spec, pmap, a, b
        # views into the Task's stacked arrays: pose (4, 4), J, Jdot (6, dof), twist (6,),
        # JA, JAdot (ms, dof), chi_dot (ms,)
        self.pose, self.J, self.Jdot, self.twist = out["pose"], out["J"], out["Jdot"], out["twist"]
        self.JA, self.JAdot, self.chi_dot = out["JA"], out["JAdot"], out["chi_dot"]
        self.chi_offset, self.distance_offset = chi_offset, distance_offset
        layout = pmap.layout
        self.template, self.pack_into, self.offset = layout.template, layout.pack_into, layout.offset
        self.E: npt.NDArray[np.float64] = np.frombuffer(bytearray(layout.template)).reshape(layout.shape)
        self.Edot: npt.NDArray[np.float64] = np.zeros(layout.shape)
        self.rows = None if pmap.rows is None else np.asarray(pmap.rows, dtype=np.intp)
        ms = pmap.size
        self.Esel, self.Edot_sel = np.zeros((ms, 6)), np.zeros((ms, 6))
        self.tmpA = np.zeros((ms, dof))
        self.write_chi = struct.Struct(f"{ms}d").pack_into
        # per part: (param, param if a position one else None, param if a rotation one else None,
        # constant E (cartesian), continuity rule, its rows in χ)
        self.parts: list[
            tuple[
                Parameterization,
                PositionParameterization | None,
                RotationParameterization | None,
                bool,
                Rule,
                slice,
            ]
        ] = []
        start = 0
        for param in pmap.parts:
            self.parts.append(
                (
                    param,
                    param if isinstance(param, PositionParameterization) else None,
                    param if isinstance(param, RotationParameterization) else None,
                    param.name == "cartesian",
                    continuity_rule(param.name),
                    slice(start, start + param.size),
                )
            )
            start += param.size
        self.previous: list[float] | None = None
        if b is not None:  # relative: buffers for J_rel and its rate
            self.CBt, self.CBA = np.zeros((3, 3)), np.zeros((3, 3))
            self.S = np.zeros((3, 3))
            self.inner = np.zeros((6, dof))
            self.dinner = np.zeros((6, dof))
            self.t3 = np.zeros((3, dof))

    # -- pose and Jacobian ------------------------------------------------------------------------
    def _relative(self, qdot: np.ndarray | None) -> tuple[list, list]:
        a, b = self.a, self.b
        assert b is not None
        (ax, ay, az), (bx, by, bz) = a.pos, b.pos
        dx, dy, dz = ax - bx, ay - by, az - bz
        CBt, S, inner, t3 = self.CBt, self.S, self.inner, self.t3
        np.copyto(CBt, b.R.T)
        np.dot(CBt, a.R, out=self.CBA)
        C = self.CBA.tolist()
        (r0, r1, r2), (r3, r4, r5), (r6, r7, r8) = CBt.tolist()
        p = [r0 * dx + r1 * dy + r2 * dz, r3 * dx + r4 * dy + r5 * dz, r6 * dx + r7 * dy + r8 * dz]
        JA, JB = a.J, b.J
        _skew(S, dx, dy, dz)
        np.subtract(JA, JB, out=inner)
        np.dot(S, JB[3:], out=t3)
        np.add(inner[:3], t3, out=inner[:3])
        J = self.J
        np.dot(CBt, inner[:3], out=J[:3])
        np.dot(CBt, inner[3:], out=J[3:])
        if qdot is not None:
            np.dot(J, qdot, out=self.twist)
            dinner = self.dinner
            np.subtract(a.Jdot, b.Jdot, out=dinner)
            va, vb = a.twist[:3].tolist(), b.twist[:3].tolist()
            _skew(S, va[0] - vb[0], va[1] - vb[1], va[2] - vb[2])  # [ḋ]x J_B,ω
            np.dot(S, JB[3:], out=t3)
            np.add(dinner[:3], t3, out=dinner[:3])
            _skew(S, dx, dy, dz)  # [d]x J̇_B,ω
            np.dot(S, b.Jdot[3:], out=t3)
            np.add(dinner[:3], t3, out=dinner[:3])
            wx, wy, wz = b.twist[3:].tolist()  # − [ω_B]x inner
            _skew(S, wx, wy, wz)
            for half in (slice(0, 3), slice(3, 6)):
                np.dot(S, inner[half], out=t3)
                np.subtract(dinner[half], t3, out=dinner[half])
                np.dot(CBt, dinner[half], out=self.Jdot[half])
        return C, p

    def update(
        self,
        qdot: np.ndarray | None,
        threshold: float,
        continuous: bool,
        chi_out: np.ndarray,
        distances: np.ndarray,
        distance_offset: int,
    ) -> RepresentationSingularityError | None:
        """Fill this block's views; returns the RepresentationSingularityError to raise (or None)."""
        if self.b is None:
            a = self.a
            C, p = a.C, a.pos
            if a.J is not self.J:  # another block adopted this frame's kinematics
                np.copyto(self.J, a.J)
                if qdot is not None:
                    np.copyto(self.Jdot, a.Jdot)
                    np.copyto(self.twist, a.twist)
        else:
            C, p = self._relative(qdot)
        (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = C
        px, py, pz = p
        _POSE_ROWS.pack_into(
            self.pose,  # type: ignore[arg-type]  # a buffer; numpy declares __buffer__ for Python >= 3.12 only
            0,
            c00,
            c01,
            c02,
            px,
            c10,
            c11,
            c12,
            py,
            c20,
            c21,
            c22,
            pz,
        )
        values: list[float] = []
        entries: tuple[float, ...] = ()
        previous = self.previous
        error: tuple[Parameterization, float] | None = None
        flags: list[bool] = []
        for k, (param, position, rotation, constant, rule, rows) in enumerate(self.parts):
            if position is not None:
                chi = list(position._from_position(math, px, py, pz))
            elif rotation is not None:
                chi = list(rotation._from_rotation(math, False, c00, c01, c02, c10, c11, c12, c20, c21, c22))
            if previous is not None:
                chi = rule(chi, previous[rows])
            distance = param._distance(math, *chi)
            distances[distance_offset + k] = distance
            singular = not distance >= threshold or distance == 0.0
            if singular and error is None:
                error = (param, distance)
            values += chi
            flags += (singular,) * param.size
            if not constant:
                entries += (math.nan,) * (3 * param.size) if singular else param._E(math, *chi)
        self.pack_into(self.E, self.offset, *entries)
        E = self.E
        if self.rows is not None:
            np.take(E, self.rows, axis=0, out=self.Esel)
            E = self.Esel
        np.dot(E, self.J, out=self.JA)
        self.write_chi(
            chi_out,  # type: ignore[arg-type]  # a buffer; numpy declares __buffer__ for Python >= 3.12 only
            8 * self.chi_offset,
            *(values if self.pmap.rows is None else [values[i] for i in self.pmap.rows]),
        )
        if continuous:
            self.previous = values
        if qdot is not None:
            self._rates(qdot, values, E, flags)
        if error is None:
            return None
        return singularity_error(error[0], float(error[1]), threshold, self.pose.copy(), None, self.J.copy())

    def _rates(self, qdot: np.ndarray, values: list[float], E: np.ndarray, singular: list[bool]) -> None:
        """J̇_A = Ė·J + E·J̇ and χ̇ = J_A·q̇ (NaN rows where E is NaN)."""
        vx, vy, vz, wx, wy, wz = self.twist.tolist()
        entries: tuple[float, ...] = ()
        for param, position, _rotation, constant, _rule, rows in self.parts:
            if constant:
                continue
            chi = values[rows]
            if singular[rows.start]:
                entries += (math.nan,) * (3 * param.size)
            else:
                entries += param._E_dot(math, chi, (vx, vy, vz) if position is not None else (wx, wy, wz))
        self.pack_into(self.Edot, self.offset, *entries)  # Ė's constant entries are all zero
        Edot = self.Edot
        if self.rows is not None:
            np.take(Edot, self.rows, axis=0, out=self.Edot_sel)
            Edot = self.Edot_sel
        np.dot(Edot, self.J, out=self.tmpA)
        np.dot(E, self.Jdot, out=self.JAdot)
        np.add(self.JAdot, self.tmpA, out=self.JAdot)
        np.dot(self.JA, qdot, out=self.chi_dot)


__all__ = ["FrameBlock", "FrameKinematics", "joint_jacobians"]
