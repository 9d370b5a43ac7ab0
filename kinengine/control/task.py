"""The controller's hot path: one ``update(q, qdot)`` computes everything, into preallocated arrays.

>>> task = robot.task("tool0", position="cartesian", rotation="euler_zyz")
>>> task.update(q, qdot)                       # one pass over the chain, no numpy allocation
>>> task.chi, task.analytic_jacobian, task.jacobian_dot, task.analytic_jacobian_dot

Frames: ``pose`` is T_IF in the root frame I; ``jacobian`` is J_e0 in "local_world_aligned"
(origin velocity and angular velocity in I, rows [linear; angular]); ``twist`` = J_e0·q̇;
``jacobian_dot`` = dJ_e0/dt; ``analytic_jacobian`` = E(χ)·J_e0 and
``analytic_jacobian_dot`` = Ė·J_e0 + E·J̇_e0 with Ė = dE/dt along (v, ω); ``chi_dot`` = J_A·q̇.
With several frames the per-frame blocks are stacked: ``chi`` (k·m,), ``jacobian`` (6k, dof),
``analytic_jacobian`` (k·m, dof), ``pose`` (k, 4, 4).

How: one ``computeForwardKinematicsDerivatives`` fills Pinocchio's world-frame joint Jacobians
J_w and J̇_w (no array is returned, so nothing is allocated; ``computeJointJacobians`` would be
0.38 µs faster without q̇ on the ABB IRB 120 but returns a copy of J_w). Pinocchio's model has plain
joints only; with mimic joints q_pin = M q + b and q̇_pin = M q̇ are written into preallocated arrays
and J_w, J̇_w are folded, J_w·M, in place (see :mod:`kinengine.model.coordinates`); per frame,
J_e0 = X(p)·J_w with X = [[I, −[p]x], [0, I]] (the spatial velocity moved from I's origin to the
frame origin p) and J̇_e0 = X·J̇_w + Ẋ·J_w with Ẋ = [[0, −[ṗ]x], [0, 0]], ṗ = v.

A Task owns its own Pinocchio Data: use one Task per thread. The attributes are read-only
views that the next update overwrites; copy what you keep.
"""

from __future__ import annotations

from collections.abc import Sequence
import math
import struct

import numpy as np
import pinocchio as pin

from ..analytic import DEFAULT_SINGULARITY_THRESHOLD, as_rows, pose_map
from ..errors import OptionError, RepresentationSingularityError
from .continuity import continuity_rule


class _Part:
    """One parameterization (position or rotation) of one frame: its rows in χ."""

    def __init__(self, param, rows: slice) -> None:
        self.param = param
        self.position = param.kind == "position"
        self.constant = param.name == "cartesian"   # E_P = I (in E's template), Ė_P = 0
        self.rule = continuity_rule(param.name)
        self.rows = rows


class _Frame:
    """Pinocchio views and buffers of one frame of a task."""

    def __init__(self, model: pin.Model, data: pin.Data, fid: int, dof: int) -> None:
        self.fid = fid
        placement = data.oMf[fid]  # a reference into data: these views follow every update
        self.R, self.p = placement.rotation, placement.translation
        mask = np.zeros(model.nv)  # Pinocchio's columns of the joints that move this frame
        for j in model.supports[model.frames[fid].parentJoint][1:]:
            joint = model.joints[j]
            mask[joint.idx_v:joint.idx_v + joint.nv] = 1.0
        self.mask = None if mask.all() else mask
        self.X = np.eye(6)
        self.Xdot_lin = np.zeros((3, 3))   # −[ṗ]x
        self.masked, self.masked_dot = np.empty((6, model.nv)), np.empty((6, model.nv))
        self.folded, self.folded_dot = np.empty((6, dof)), np.empty((6, dof))
        self.tmp = np.empty((3, dof))
        self.previous: list[float] | None = None


def _pose_writer(frame_index: int):
    """Writes C_IF row by row with p into rows 0-2 of pose[frame_index] (k, 4, 4): 12 doubles, one call."""
    pack_into, offset = struct.Struct("12d").pack_into, 128 * frame_index
    return lambda pose, *entries: pack_into(pose, offset, *entries)


class Task:
    """Kinematics of one or several frames for a control loop. Build it with :meth:`Robot.task`.

    ``check_inputs=False`` skips the shape and finiteness checks of q and q̇ (for callers that
    validate upstream: then pass float64 arrays of shape (dof,)). ``continuous=True`` keeps χ
    continuous between updates (no 2π jumps, no quaternion sign flips, rotation vectors across
    θ = π); :meth:`reset` returns to the canonical ranges. ``singularity_threshold``: as in
    :meth:`Robot.analytic_jacobian` (RepresentationSingularityError below it).
    """

    def __init__(self, robot, frames: str | Sequence[str], position: str | None = "cartesian",
                 rotation: str | None = "euler_zyx", *, rows: Sequence[str | int] | None = None,
                 check_inputs: bool = True, continuous: bool = True,
                 singularity_threshold: float = DEFAULT_SINGULARITY_THRESHOLD) -> None:
        names = (frames,) if isinstance(frames, str) else tuple(frames)
        if not names:
            raise OptionError("a task needs at least one frame: pass a frame name or a list of them")
        fids = [robot.frame_id(f) for f in names]
        pmap = pose_map(position, rotation, as_rows(rows))
        self.frames, self.labels = names, pmap.labels
        self.check_inputs, self.continuous = check_inputs, continuous
        self.singularity_threshold = singularity_threshold
        kin = robot.engine
        self._coords = coords = kin.coordinates
        self._model = model = kin.model
        self._data = data = model.createData()
        self.dof = n = robot.dof
        k = len(fids)
        params = [p for p in (pmap.position, pmap.rotation) if p is not None]
        m = sum(p.size for p in params)
        self._m = m
        # views of Pinocchio's world-frame joint Jacobians (eigenpy hands a (6, 1) matrix over as (6,))
        self._Jw, self._dJw = data.J.reshape(6, model.nv), data.dJ.reshape(6, model.nv)
        self._zero = np.zeros(model.nv)
        self._qp, self._vp = np.empty(model.nq), np.empty(model.nv)
        self._pose = np.zeros((k, 4, 4))
        self._pose[:, 3, 3] = 1.0
        self._J, self._Jdot = np.zeros((k, 6, n)), np.zeros((k, 6, n))
        self._twist = np.zeros((k, 6))
        self._chi, self._chi_dot = np.zeros((k, m)), np.zeros((k, m))
        self._JA, self._JAdot = np.zeros((k, m, n)), np.zeros((k, m, n))
        self._frames = []
        layout = pmap.layout  # E = blockdiag(E_P, E_R) as one (m, 6) matrix: J_A = E·J_e0 in one product
        self._write_E = layout.pack_into, layout.offset
        for f, fid in enumerate(fids):
            frame = _Frame(model, data, fid, n)
            frame.write_pose = _pose_writer(f)
            frame.J, frame.Jdot, frame.twist = self._J[f], self._Jdot[f], self._twist[f]
            frame.chi, frame.JA, frame.JAdot, frame.chi_dot = self._chi[f], self._JA[f], self._JAdot[f], self._chi_dot[f]
            frame.E = np.frombuffer(bytearray(layout.template)).reshape(layout.shape)
            frame.Edot = np.zeros(layout.shape)
            frame.tmpA = np.zeros((m, n))
            frame.parts, start = [], 0
            for param in params:
                frame.parts.append(_Part(param, slice(start, start + param.size)))
                start += param.size
            frame.write_chi = struct.Struct(f"{m}d").pack_into
            self._frames.append(frame)
        # Public read-only views: selected rows, stacked over frames.
        self._rows = None if pmap.rows is None else np.asarray(pmap.rows, dtype=np.intp)
        if self._rows is None:
            sel = (self._chi, self._JA, self._JAdot, self._chi_dot)
        else:
            ms = len(self._rows)
            sel = (np.zeros((k, ms)), np.zeros((k, ms, n)), np.zeros((k, ms, n)), np.zeros((k, ms)))
        self._sel = sel
        ms = sel[0].shape[1]
        self.pose = _readonly(self._pose[0] if isinstance(frames, str) else self._pose)
        self.jacobian = _readonly(self._J.reshape(6 * k, n))
        self.jacobian_dot = _readonly(self._Jdot.reshape(6 * k, n))
        self.twist = _readonly(self._twist.reshape(6 * k))
        self.chi = _readonly(sel[0].reshape(k * ms))
        self.analytic_jacobian = _readonly(sel[1].reshape(k * ms, n))
        self.analytic_jacobian_dot = _readonly(sel[2].reshape(k * ms, n))
        self.chi_dot = _readonly(sel[3].reshape(k * ms))
        self._rates = (self._twist, self._Jdot, self._JAdot, self._chi_dot) + (sel[2], sel[3])
        self._invalidate_rates()

    def __repr__(self) -> str:
        return f"<Task {self.frames} {self.labels}>"

    def reset(self) -> None:
        """Forget the previous χ: the next update returns χ in the canonical ranges."""
        for frame in self._frames:
            frame.previous = None

    def update(self, q: np.ndarray, qdot: np.ndarray | None = None) -> None:
        """Evaluate at q [rad | m] (and q̇ [rad/s | m/s]); overwrites every attribute in place.

        Without q̇, ``twist``, ``chi_dot``, ``jacobian_dot`` and ``analytic_jacobian_dot`` are NaN
        (never the rates of an earlier q).
        """
        coords = self._coords
        if self.check_inputs:
            q = coords.check(q, allow_batch=False)
            if qdot is not None:
                qdot = coords.check(qdot, name="qdot", allow_batch=False)
        qp, vp = q, qdot
        if not coords.identity:  # mimic joints: q_pin = M q + b, q̇_pin = M q̇, written in place
            qp = self._qp
            np.dot(coords.matrix, q, out=qp)
            if coords.has_offset:
                np.add(qp, coords.offset, out=qp)
            if qdot is not None:
                vp = self._vp
                np.dot(coords.matrix, qdot, out=vp)
        # returns nothing: no allocation
        pin.computeForwardKinematicsDerivatives(self._model, self._data, qp, self._zero if vp is None else vp,
                                                self._zero)
        if qdot is None:
            if self._rates_valid:
                self._invalidate_rates()
        else:
            self._rates_valid = True
        for frame in self._frames:
            self._update_frame(frame, qdot)
        if self._rows is not None:
            chi, JA, JAdot, chi_dot = self._sel
            np.take(self._chi, self._rows, axis=1, out=chi)
            np.take(self._JA, self._rows, axis=1, out=JA)
            if qdot is not None:
                np.take(self._JAdot, self._rows, axis=1, out=JAdot)
                np.take(self._chi_dot, self._rows, axis=1, out=chi_dot)

    def _invalidate_rates(self) -> None:
        """NaN in every rate attribute (until an update with q̇ fills them)."""
        for array in self._rates:
            array.fill(np.nan)
        self._rates_valid = False

    def _update_frame(self, frame: _Frame, qdot: np.ndarray | None) -> None:
        model, data = self._model, self._data
        pin.updateFramePlacement(model, data, frame.fid)
        (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = frame.R.tolist()
        px, py, pz = frame.p.tolist()
        frame.write_pose(self._pose, c00, c01, c02, px, c10, c11, c12, py, c20, c21, c22, pz)
        X = frame.X
        X[0, 4], X[0, 5], X[1, 3], X[1, 5], X[2, 3], X[2, 4] = pz, -py, -pz, px, py, -px
        J = frame.J
        Jw = self._Jw
        if frame.mask is not None:
            np.multiply(Jw, frame.mask, out=frame.masked)
            Jw = frame.masked
        if not self._coords.identity:
            np.dot(Jw, self._coords.matrix, out=frame.folded)
            Jw = frame.folded
        np.dot(X, Jw, out=J)
        values: list[float] = []
        entries: tuple[float, ...] = ()
        previous = frame.previous
        for part in frame.parts:
            param = part.param
            if part.position:
                chi = list(param._from_position(math, px, py, pz))
            else:
                chi = list(param._from_rotation(math, False, c00, c01, c02, c10, c11, c12, c20, c21, c22))
            if previous is not None:
                chi = part.rule(chi, previous[part.rows])
            distance = param._distance(math, *chi)
            if distance < self.singularity_threshold:
                raise RepresentationSingularityError(param.name, float(distance), self.singularity_threshold,
                                                     param.alternatives, param.singular_set)
            values += chi
            if not part.constant:
                entries += param._E(math, *chi)
        pack_into, offset = self._write_E
        pack_into(frame.E, offset, *entries)
        np.dot(frame.E, J, out=frame.JA)
        frame.write_chi(frame.chi, 0, *values)
        if self.continuous:
            frame.previous = values
        if qdot is not None:
            self._update_rates(frame, qdot, values, Jw)

    def _update_rates(self, frame: _Frame, qdot: np.ndarray, values: list[float], Jw: np.ndarray) -> None:
        """twist, J̇_e0 = X·J̇w + Ẋ·Jw, J̇_A = Ė·J_e0 + E·J̇_e0, χ̇ = J_A·q̇."""
        twist, J, Jdot = frame.twist, frame.J, frame.Jdot
        np.dot(J, qdot, out=twist)
        dJw = self._dJw
        if frame.mask is not None:
            np.multiply(dJw, frame.mask, out=frame.masked_dot)
            dJw = frame.masked_dot
        if not self._coords.identity:
            np.dot(dJw, self._coords.matrix, out=frame.folded_dot)
            dJw = frame.folded_dot
        np.dot(frame.X, dJw, out=Jdot)
        vx, vy, vz, wx, wy, wz = twist.tolist()
        S = frame.Xdot_lin
        S[0, 1], S[0, 2], S[1, 0], S[1, 2], S[2, 0], S[2, 1] = vz, -vy, -vz, vx, vy, -vx
        np.dot(S, Jw[3:], out=frame.tmp)
        np.add(Jdot[:3], frame.tmp, out=Jdot[:3])
        entries: tuple[float, ...] = ()
        for part in frame.parts:
            if not part.constant:
                u = (vx, vy, vz) if part.position else (wx, wy, wz)
                entries += part.param._E_dot(math, values[part.rows], u)
        pack_into, offset = self._write_E  # Ė's constant entries are all zero
        pack_into(frame.Edot, offset, *entries)
        np.dot(frame.Edot, J, out=frame.tmpA)
        np.dot(frame.E, Jdot, out=frame.JAdot)
        np.add(frame.JAdot, frame.tmpA, out=frame.JAdot)
        np.dot(frame.JA, qdot, out=frame.chi_dot)


def _readonly(array: np.ndarray) -> np.ndarray:
    view = array.view()
    view.flags.writeable = False
    return view
