"""The per-frame work of a :class:`~kinengine.control.task.Task` update, all into preallocated arrays.

:class:`FrameKinematics`: one frame F's J_e0 (rows [v; ω] in I, "local_world_aligned"), C_IF and p [m]; with
q̇ also J̇_e0 (Pinocchio's ``getFrameJacobianTimeVariation``) and the twist J_e0·q̇.
:class:`FrameBlock`: one :class:`~kinengine.FrameTask`'s pose, J (J_e0, or the relative Jacobian in B:
J_rel = C_IBᵀ inner, inner = [J_A,v − J_B,v + [p_A − p_B]× J_B,ω; J_A,ω − J_B,ω], and
J̇_rel = C_IBᵀ(d/dt inner − [ω_B]× inner)), χ, [J; J_A] = [I; E(χ)]·J by one product, J̇_A = Ė·J + E·J̇ and
χ̇ = J_A·q̇. A parameterization within the threshold of its singular set gets NaN entries in E (so NaN rows
in J_A, J̇_A, χ̇); its χ rows keep the (finite) angles.
"""

from __future__ import annotations

import math
import struct

import numpy as np
import pinocchio as pin

from ..analytic.pose_map import PoseMap
from ..analytic.singular import singularity_error
from ..errors import RepresentationSingularityError
from ..kinematics.engine import Kinematics
from ..kinematics.memory import create_data
from ..parameterizations.base import Entries, RotationParameterization, is_singular
from .continuity import continuity_rule
from .frame_task import FrameTask

_LWA = pin.LOCAL_WORLD_ALIGNED


def _skew(S: np.ndarray, x: float, y: float, z: float) -> np.ndarray:
    """S = [(x, y, z)]× in place (its zero diagonal stays as set)."""
    S[0, 1], S[0, 2], S[1, 0], S[1, 2], S[2, 0], S[2, 1] = -z, y, z, -x, -y, x
    return S


class FrameKinematics:
    """J_e0 (6, dof), C_IF (nested lists) and p [m] of one frame F, and with q̇ J̇_e0 and the twist.

    Without q̇ it takes the cheapest exact path of :meth:`Kinematics.frame_path` (for a frame that no mimic
    joint moves, a model whose coordinates are q's: no map), with q̇ the Task's model at q_pin."""

    def __init__(self, kin: Kinematics, data: pin.Data, fid: int) -> None:
        model, path = kin.model, kin.frame_path(fid)
        self.model, self.data, self.fid, self.nv, self.mapped = model, data, fid, model.nv, path.mapped
        path_data = data if path.model is model else create_data(path.model, "a Task")
        # references into the Data: they follow every update
        views = path_data.oMf[path.frame_id].rotation, path_data.oMf[path.frame_id].translation
        self.world_views = data.oMf[fid].rotation, data.oMf[fid].translation
        self.fold = None if kin.coordinates.identity else kin.coordinates.matrix
        plain = not path.mapped and path.model.nv > 1  # Pinocchio's frame Jacobian is J_e0 as it is
        self.path = pin.computeFrameJacobian, path.model, path_data, path.frame_id, path.mapped, plain, views
        self.path_nv = path.model.nv
        self.J = np.zeros((6, kin.dof))  # Pinocchio's fresh array (rebound every update) or self.buffer
        self.buffer, self.Jdot, self.twist = np.zeros((6, kin.dof)), np.zeros((6, kin.dof)), np.zeros(6)
        self.R = views[0]
        self.C: list[list[float]] = []
        self.pos: list[float] = []

    def update(self, q: np.ndarray, q_pin: np.ndarray, qdot: np.ndarray | None) -> None:
        """At q and Pinocchio's q_pin (with q̇: after ``computeJointJacobiansTimeVariation`` at q_pin)."""
        if qdot is None and self.path_nv:
            frame_jacobian, model, data, fid, mapped, plain, (R, p) = self.path
            J = frame_jacobian(model, data, q_pin if mapped else q, fid, _LWA)
            if not plain:  # eigenpy hands a (6, 1) matrix over as (6,)
                J = J.reshape(6, self.path_nv)
                J = np.dot(J, self.fold, out=self.buffer) if self.fold is not None and mapped else J
            self.J = J
        else:
            if not self.nv:  # Pinocchio 4.1 crashes on a frame Jacobian with nv = 0: J is (6, 0)
                pin.forwardKinematics(self.model, self.data, q_pin)
            pin.updateFramePlacement(self.model, self.data, self.fid)
            R, p = self.world_views
            if qdot is not None and self.nv:
                self._rates(qdot)
        self.R, self.C, self.pos = R, R.tolist(), p.tolist()

    def _rates(self, qdot: np.ndarray) -> None:
        model, data, fid, nv = self.model, self.data, self.fid, self.nv
        J = pin.getFrameJacobian(model, data, fid, _LWA).reshape(6, nv)
        dJ = pin.getFrameJacobianTimeVariation(model, data, fid, _LWA).reshape(6, nv)
        if self.fold is None:
            self.J = J
            np.copyto(self.Jdot, dJ)
        else:
            self.J = np.dot(J, self.fold, out=self.buffer)
            np.dot(dJ, self.fold, out=self.Jdot)
        np.dot(self.J, qdot, out=self.twist)


class FrameBlock:
    """One FrameTask's rows of a Task: see the module doc.

    ``values`` holds S = [I; E] ((6 + ms) × 6, E the selected rows of blockdiag(E_P, E_R)), then χ (ms,), one
    distance per parameterization and the pose (4, 4). The pose map's layout writes E's computed entries
    (as for :meth:`Robot.analytic_jacobian`); one struct write of doubles in native byte order writes the run
    [χ, distances, the pose's rows 0-2]; the constants (the identity rows, the pose's last row) stay as set.
    An absolute block shares its frame's J̇ and twist arrays."""

    def __init__(self, spec: FrameTask, pmap: PoseMap, a: FrameKinematics, b: FrameKinematics | None) -> None:
        self.spec, self.pmap, self.a, self.b, self.parts = spec, pmap, a, b, pmap.parts
        position, rotation = pmap.position, pmap.rotation
        m_P = 0 if position is None else position.size
        rule = continuity_rule("cartesian" if rotation is None else rotation.name)
        starts = np.cumsum([0] + [p.size for p in self.parts]).tolist()
        self.rate_parts = [  # (index, part, its rows of E, its columns of E: 0-2 for v, 3-5 for ω)
            (k, p, slice(first, first + p.size), slice(3, 6) if p.kind == "rotation" else slice(0, 3))
            for k, (p, first) in enumerate(zip(self.parts, starts, strict=False))
            if p.name != "cartesian"
        ]
        dof, m, ms, k = a.J.shape[1], starts[-1], pmap.size, len(self.parts)
        self.previous: list[float] | None = None
        self.selected = selected = None if pmap.rows is None else list(pmap.rows)
        self.values = values = np.zeros(6 * (6 + ms) + ms + k + 16)
        self.S = S = values[: 6 * (6 + ms)].reshape(6 + ms, 6)
        S[:6] = np.eye(6)
        self.E = S[6:]
        tail = values[S.size :]
        self.chi, self.distances, self.pose = tail[:ms], tail[ms : ms + k], tail[ms + k :].reshape(4, 4)
        self.pose[3, 3] = 1.0
        layout = pmap.layout  # E = blockdiag(E_P, E_R) (m, 6): all of it, its rows then selected into S
        self.write_E, self.E_offset = layout.pack_into, layout.offset
        self.E_all: np.ndarray = np.frombuffer(bytearray(layout.template)).reshape(layout.shape)
        run = f"{ms + k + 12}d"  # after S: χ, distances, the pose's rows 0-2
        write, at = struct.Struct("=" + run).pack_into, 8 * S.size
        if pmap.rows is None:  # no selection: E's entries and the run in one write, from S's E rows on
            self.E[:] = self.E_all
            write, at = struct.Struct(layout.format + run).pack_into, 8 * 36 + layout.offset
        self.out = out = np.zeros((6 + ms, dof))
        self.J, self.JA = out[:6], out[6:]
        self.Jdot, self.twist = (a.Jdot, a.twist) if b is None else (np.zeros((6, dof)), np.zeros(6))
        self.JAdot, self.chi_dot, self.tmp = np.zeros((ms, dof)), np.zeros(ms), np.zeros((ms, dof))
        self.Edot, self.Edot_selected, self.singular = np.zeros((m, 6)), np.zeros((ms, 6)), [False] * k
        cart = position is not None and position.name == "cartesian"  # update's constants, in one tuple:
        chart, dot = None if rotation is None else rotation.chart, S.dot
        self.bound = position, chart, m_P, cart, rule, self.singular, selected, write, values, at, dot, out
        if b is not None:  # relative: buffers for J_rel and its rate
            self.skew, self.t3 = np.zeros((3, 3)), np.zeros((3, dof))
            self.inner, self.dinner, self.Jrel = np.zeros((6, dof)), np.zeros((6, dof)), np.zeros((6, dof))

    def _relative(self, qdot: np.ndarray | None) -> tuple[list[list[float]], list[float]]:
        """(C_BA, B_p_BA [m]) and J_rel = blockdiag(C_IBᵀ, C_IBᵀ)·inner; with q̇ the twist and J̇_rel."""
        a, b = self.a, self.b
        assert b is not None
        (ax, ay, az), (bx, by, bz) = a.pos, b.pos
        d = dx, dy, dz = ax - bx, ay - by, az - bz
        CBt, S, inner, t3, dof = b.R.T, self.skew, self.inner, self.t3, self.Jrel.shape[1]
        np.subtract(a.J, b.J, out=inner)
        inner[:3] += np.dot(_skew(S, *d), b.J[3:], out=t3)
        np.matmul(CBt, inner.reshape(2, 3, dof), out=self.Jrel.reshape(2, 3, dof))
        if qdot is not None:
            np.dot(self.Jrel, qdot, out=self.twist)
            dinner = np.subtract(a.Jdot, b.Jdot, out=self.dinner)
            dd = (a.twist[:3] - b.twist[:3]).tolist()
            dinner[:3] += np.dot(_skew(S, *dd), b.J[3:], out=t3)  # [ḋ]× J_B,ω
            dinner[:3] += np.dot(_skew(S, *d), b.Jdot[3:], out=t3)  # [d]× J̇_B,ω
            _skew(S, *b.twist[3:].tolist())  # − [ω_B]× inner
            dinner.reshape(2, 3, dof)[...] -= np.matmul(S, inner.reshape(2, 3, dof))
            np.matmul(CBt, dinner.reshape(2, 3, dof), out=self.Jdot.reshape(2, 3, dof))
        return np.dot(CBt, a.R).tolist(), [x * dx + y * dy + z * dz for x, y, z in zip(*b.C, strict=True)]

    def _general(
        self, k: int, C: list[list[float]], p: list[float], before: list[float] | None, threshold: float
    ) -> tuple[list[float], float, Entries]:
        """(χ, distance, E's entries) of part k by its public methods, χ the representative closest to the
        previous χ ``before``; NaN entries within ``threshold`` of its singular set. For a position part, and
        for a rotation where the chart has no regular answer continuous with ``before``."""
        part = self.parts[k]
        if isinstance(part, RotationParameterization):
            chi = part.from_rotation(C, warn=False).tolist()
        else:
            chi = part.from_position(p).tolist()  # type: ignore[attr-defined]
        if before is not None:
            chi = continuity_rule(part.name)(chi, before)
        distance = float(part.singularity_distance(chi))
        self.singular[k] = singular = is_singular(distance, threshold)
        entries = (math.nan,) * (3 * part.size) if singular else tuple(part.E(chi).ravel().tolist())
        return chi, distance, entries

    def update(
        self, qdot: np.ndarray | None, threshold: float, continuous: bool
    ) -> RepresentationSingularityError | None:
        """Fill this block's arrays; returns the RepresentationSingularityError to raise (or None)."""
        position, chart, m_P, cartesian, rule, singular, selected, write, values, at, dot, out = self.bound
        if self.b is None:
            a = self.a
            C, p, J = a.C, a.pos, a.J
        else:
            (C, p), J = self._relative(qdot), self.Jrel
        (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = C
        previous = self.previous
        chi: list[float] = [*p] if cartesian else []  # χ_P = p and E_P = I: never singular
        distances: list[float] = [math.inf] if cartesian else []
        entries: Entries = ()
        if position is not None and not cartesian:
            chi, distance, entries = self._general(0, C, p, previous and previous[:m_P], threshold)
            distances.append(distance)
        if chart is not None:  # the rotation's chart gives χ, distance and E at once at a regular canonical χ
            found = chart(c00, c01, c02, c10, c11, c12, c20, c21, c22)
            if (
                found is None
                or not found[1] >= threshold
                or (previous is not None and rule(found[0], previous[m_P:]) != found[0])
            ):
                found = self._general(len(self.parts) - 1, C, p, previous and previous[m_P:], threshold)
            else:
                singular[-1] = False
            chi += found[0]
            distances.append(found[1])
            entries += found[2]
        selected_chi = chi
        if selected is not None:  # E's entries into the whole E, then its selected rows into S
            self.write_E(self.E_all, self.E_offset, *entries)
            np.take(self.E_all, selected, axis=0, out=self.E)
            entries, selected_chi = (), [chi[i] for i in selected]
        px, py, pz = p
        write(
            values, at, *entries, *selected_chi, *distances,  # type: ignore[arg-type]  # a buffer (numpy: 3.12+)
            c00, c01, c02, px, c10, c11, c12, py, c20, c21, c22, pz,
        )  # fmt: skip
        dot(J, out)  # [J; J_A] = [I; E]·J
        if continuous:
            self.previous = chi
        if qdot is not None:
            self._rates(qdot, chi)
        if True not in singular:
            return None
        k = self.singular.index(True)
        return singularity_error(
            self.parts[k], float(distances[k]), threshold, self.pose.copy(), None, self.J.copy()
        )

    def _rates(self, qdot: np.ndarray, chi: list[float]) -> None:
        """J̇_A = Ė·J + E·J̇ and χ̇ = J_A·q̇, Ė by the parameterizations' :meth:`~Parameterization.E_dot` along
        v or ω (NaN rows where E is NaN)."""
        Edot = self.Edot
        for k, part, rows, columns in self.rate_parts:
            Edot[rows, columns] = np.nan if self.singular[k] else part.E_dot(chi[rows], self.twist[columns])
        if self.selected is not None:
            Edot = np.take(Edot, self.selected, axis=0, out=self.Edot_selected)
        np.dot(self.E, self.Jdot, out=self.JAdot)
        self.JAdot += np.dot(Edot, self.J, out=self.tmp)
        np.dot(self.JA, qdot, out=self.chi_dot)


__all__ = ["FrameBlock", "FrameKinematics"]
