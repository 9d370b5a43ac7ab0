"""The per-frame work of a :class:`~kinengine.control.task.Task` update, all into preallocated arrays.

:class:`FrameKinematics` — one Pinocchio frame F: J_e0 (rows [v; ω] in I, "local_world_aligned") and the
pose C_IF, p [m]. Without q̇ J_e0 is Pinocchio's frame Jacobian (which also places the frame); with q̇
J_e0 and J̇_e0 (d/dt of that same Jacobian) are Pinocchio's ``getFrameJacobian`` and
``getFrameJacobianTimeVariation`` in LOCAL_WORLD_ALIGNED from the joint Jacobians and their rates that
``computeJointJacobiansTimeVariation`` left in the Task's Data, and the twist is J_e0·q̇. Mimic joints fold
every Jacobian, J·M (see :mod:`kinengine.model.coordinates`).

:class:`FrameBlock` — one :class:`~kinengine.FrameTask`: its pose (T_IA, or T_BA with ``relative_to`` B),
its Jacobian J (J_e0 of A, or the relative Jacobian in B: see :mod:`kinengine.kinematics.relative`, with
J̇_rel = C_IBᵀ(d/dt inner − [ω_B]× inner), inner = [J_A,v − J_B,v + [p_A − p_B]× J_B,ω; J_A,ω − J_B,ω]),
χ (continuous if asked), E(χ) from the parameterizations (:meth:`RotationParameterization.chart` at a
canonical χ), [J; J_A] = [I; E]·J by one product, Ė and J̇_A = Ė·J + E·J̇, χ̇ = J_A·q̇. A parameterization
within the threshold of its singular set gets NaN entries in E (so NaN rows in J_A, J̇_A, χ̇); its χ
rows keep the (finite) angles.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ..analytic.pose_map import PoseMap
from ..analytic.singular import singularity_error
from ..errors import RepresentationSingularityError
from ..kinematics.engine import Kinematics
from ..kinematics.memory import create_data
from ..parameterizations.base import Parameterization, RotationParameterization
from .continuity import continuity_rule
from .frame_task import FrameTask

_INF = math.inf


def _skew(S: np.ndarray, x: float, y: float, z: float) -> None:
    """S = [(x, y, z)]x in place."""
    S[0, 1], S[0, 2], S[1, 0], S[1, 2], S[2, 0], S[2, 1] = -z, y, z, -x, -y, x


class FrameKinematics:
    """J_e0 (6, dof), the pose C_IF (row lists) and p [m] of one frame F, and with q̇ J̇_e0 and the twist.

    Without q̇ it takes the cheapest exact path of :meth:`Kinematics.frame_path` (for a frame that no mimic
    joint moves, a model whose coordinates are q's: no map), with q̇ the Task's model at q_pin."""

    def __init__(self, kin: Kinematics, data: pin.Data, fid: int) -> None:
        model, coords, path = kin.model, kin.coordinates, kin.frame_path(fid)
        self.model, self.data, self.fid, self.nv, self.mapped = model, data, fid, model.nv, path.mapped
        own = path.model is model
        self.path = (path.model, data if own else create_data(path.model, "a Task"), path.frame_id)
        self.path_nv = path.model.nv
        placement = self.path[1].oMf[path.frame_id]  # references into the Data: they follow every update
        self.views = self.R, self.p = placement.rotation, placement.translation
        placement = data.oMf[fid]
        self.world_views = placement.rotation, placement.translation
        self.fold = None if coords.identity else coords.matrix
        self.plain = not path.mapped and path.model.nv > 1  # Pinocchio's frame Jacobian is J_e0 as it is
        dof = kin.dof
        self.J: np.ndarray = np.zeros((6, dof))  # Pinocchio's array (rebound) or self.buffer
        self.buffer, self.Jdot, self.twist = np.zeros((6, dof)), np.zeros((6, dof)), np.zeros(6)
        self.adopted = False  # Jdot and twist are an absolute block's own arrays (see FrameBlock)
        self.C: list[list[float]] = []
        self.pos: list[float] = []

    def update(self, q: np.ndarray, q_pin: np.ndarray, qdot: np.ndarray | None) -> None:
        """At q and Pinocchio's q_pin (with q̇: after ``computeJointJacobiansTimeVariation`` at q_pin)."""
        if qdot is None and self.path_nv:  # LOCAL_WORLD_ALIGNED: J_e0 itself, the frame placed on the way
            model, data, fid = self.path
            J = pin.computeFrameJacobian(
                model, data, q_pin if self.mapped else q, fid, pin.LOCAL_WORLD_ALIGNED
            )
            if not self.plain:  # eigenpy hands a (6, 1) matrix over as (6,); zero columns need no mask
                J = J.reshape(6, self.path_nv)
                J = np.dot(J, self.fold, out=self.buffer) if self.fold is not None and self.mapped else J
            self.J = J
            self.R, self.p = R, p = self.views
            self.C, self.pos = R.tolist(), p.tolist()
            return
        if not self.nv:  # Pinocchio 4.1 crashes on a frame Jacobian with nv = 0: J is (6, 0)
            pin.forwardKinematics(self.model, self.data, q_pin)
        pin.updateFramePlacement(self.model, self.data, self.fid)
        self.R, self.p = R, p = self.world_views
        self.C, self.pos = R.tolist(), p.tolist()
        if qdot is None or not self.nv:  # without q̇, or J and J̇ (6, 0): nothing more to fill
            return
        model, data, fid = self.model, self.data, self.fid
        J = pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED).reshape(6, self.nv)
        dJ = pin.getFrameJacobianTimeVariation(model, data, fid, pin.LOCAL_WORLD_ALIGNED).reshape(6, self.nv)
        if self.fold is None:
            np.copyto(self.buffer, J)
            np.copyto(self.Jdot, dJ)
        else:
            np.dot(J, self.fold, out=self.buffer)
            np.dot(dJ, self.fold, out=self.Jdot)
        self.J = self.buffer
        np.dot(self.buffer, qdot, out=self.twist)


class FrameBlock:
    """One FrameTask's rows of a Task: see the module doc.

    ``values`` holds S = [I; E] ((6 + ms) × 6, E the selected rows of blockdiag(E_P, E_R)), then χ (ms,), one
    distance per parameterization and the pose (4, 4): the pose map's layout writes E's computed entries
    (as for :meth:`Robot.analytic_jacobian`), one write of doubles in native byte order the run
    [χ, distances, the pose's rows 0-2]; constants (the identity rows, the pose's last row) stay as set."""

    def __init__(self, spec: FrameTask, pmap: PoseMap, a: FrameKinematics, b: FrameKinematics | None) -> None:
        self.spec, self.pmap, self.a, self.b = spec, pmap, a, b
        self.parts: Sequence[Parameterization] = pmap.parts
        self.position, self.rotation = pmap.position, pmap.rotation
        self.cartesian = pmap.position is not None and pmap.position.name == "cartesian"
        self.m_P = 0 if pmap.position is None else pmap.position.size
        self.rule = continuity_rule("cartesian" if pmap.rotation is None else pmap.rotation.name)
        self.pose_map = (self.position, self.rotation, self.m_P, self.cartesian)
        starts = np.cumsum([0] + [p.size for p in self.parts]).tolist()
        self.rate_parts = [  # (index, part, its rows of E, its columns of E: 0-2 for v, 3-5 for ω)
            (k, p, slice(first, first + p.size), slice(3, 6) if p.kind == "rotation" else slice(0, 3))
            for k, (p, first) in enumerate(zip(self.parts, starts, strict=False))
            if p.name != "cartesian"
        ]
        dof, m, ms, k = a.J.shape[1], sum(p.size for p in self.parts), pmap.size, len(self.parts)
        self.rows = list(range(m)) if pmap.rows is None else list(pmap.rows)
        self.previous: list[float] | None = None
        self.selected = None if pmap.rows is None else self.rows
        self.values = np.zeros(6 * (6 + ms) + ms + k + 16)
        S = self.values[: 6 * (6 + ms)].reshape(6 + ms, 6)
        S[:6] = np.eye(6)
        self.S, self.E = S, S[6:]
        run = self.values[S.size :]
        self.chi, self.distances = run[:ms], run[ms : ms + k]
        self.pose: np.ndarray = run[ms + k :].reshape(4, 4)
        self.pose[3, 3] = 1.0
        self.write_run, self.run_at = struct.Struct(f"={ms + k + 12}d").pack_into, 8 * S.size
        layout = pmap.layout  # E = blockdiag(E_P, E_R) (m, 6): all of it, its rows then selected into S
        self.E_all: np.ndarray = np.frombuffer(bytearray(layout.template)).reshape(layout.shape)
        self.write_E, self.E_offset = layout.pack_into, layout.offset
        if pmap.rows is None:  # no selection: the layout writes straight into S's E rows
            self.E_all, self.E_offset = S, 8 * 36 + layout.offset
            self.E[:] = np.frombuffer(layout.template).reshape(layout.shape)
        self.out, self.Jdot, self.twist = np.zeros((6 + ms, dof)), np.zeros((6, dof)), np.zeros(6)
        self.J, self.JA = self.out[:6], self.out[6:]
        self.JAdot, self.chi_dot, self.tmp = np.zeros((ms, dof)), np.zeros(ms), np.zeros((ms, dof))
        self.Edot, self.Edot_selected, self.singular = np.zeros((m, 6)), np.zeros((ms, 6)), [False] * k
        if b is None and not a.adopted:  # the frame writes its rates straight into this block's arrays
            a.Jdot, a.twist, a.adopted = self.Jdot, self.twist, True
        if b is not None:  # relative: buffers for J_rel and its rate
            self.CBt, self.CBA, self.skew = np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3))
            self.inner, self.dinner, self.t3 = np.zeros((6, dof)), np.zeros((6, dof)), np.zeros((3, dof))
            self.Jrel = np.zeros((6, dof))

    # -- pose and Jacobian ------------------------------------------------------------------------
    def _relative(self, qdot: np.ndarray | None) -> tuple[list[list[float]], list[float]]:
        a, b = self.a, self.b
        assert b is not None
        (ax, ay, az), (bx, by, bz) = a.pos, b.pos
        dx, dy, dz = ax - bx, ay - by, az - bz
        CBt, S, inner, t3 = self.CBt, self.skew, self.inner, self.t3
        np.copyto(CBt, b.R.T)
        np.dot(CBt, a.R, out=self.CBA)
        (r0, r1, r2), (r3, r4, r5), (r6, r7, r8) = CBt.tolist()
        p = [r0 * dx + r1 * dy + r2 * dz, r3 * dx + r4 * dy + r5 * dz, r6 * dx + r7 * dy + r8 * dz]
        JA, JB = a.J, b.J
        _skew(S, dx, dy, dz)
        np.subtract(JA, JB, out=inner)
        np.dot(S, JB[3:], out=t3)
        np.add(inner[:3], t3, out=inner[:3])
        np.dot(CBt, inner[:3], out=self.Jrel[:3])
        np.dot(CBt, inner[3:], out=self.Jrel[3:])
        if qdot is not None:
            np.dot(self.Jrel, qdot, out=self.twist)
            dinner = self.dinner
            np.subtract(a.Jdot, b.Jdot, out=dinner)
            va, vb = a.twist[:3].tolist(), b.twist[:3].tolist()
            _skew(S, va[0] - vb[0], va[1] - vb[1], va[2] - vb[2])  # [ḋ]x J_B,ω
            np.dot(S, JB[3:], out=t3)
            np.add(dinner[:3], t3, out=dinner[:3])
            _skew(S, dx, dy, dz)  # [d]x J̇_B,ω
            np.dot(S, b.Jdot[3:], out=t3)
            np.add(dinner[:3], t3, out=dinner[:3])
            _skew(S, *b.twist[3:].tolist())  # − [ω_B]x inner
            for half in (slice(0, 3), slice(3, 6)):
                np.dot(S, inner[half], out=t3)
                np.subtract(dinner[half], t3, out=dinner[half])
                np.dot(CBt, dinner[half], out=self.Jdot[half])
        return self.CBA.tolist(), p

    def _coordinates(
        self, part: Parameterization, C: list[float], p: list[float], previous: list[float] | None
    ) -> tuple[list[float], float, tuple[float, ...] | None]:
        """(χ, its distance, None) of one parameterization by its public methods (continuous w.r.t. the
        previous χ if given): where the rotation's chart has no answer, or for a position formula."""
        if isinstance(part, RotationParameterization):
            chi = part.from_rotation(np.reshape(C, (3, 3)), warn=False).tolist()
        else:
            chi = part.from_position(np.array(p)).tolist()  # type: ignore[attr-defined]
        if previous is not None:
            chi = continuity_rule(part.name)(chi, previous)
        return chi, float(part.singularity_distance(np.array(chi))), None

    @staticmethod
    def _entries(part: Parameterization, chi: list[float], singular: bool) -> tuple[float, ...]:
        """E's computed entries of ``part`` at χ by its :meth:`~Parameterization.E` (NaN if singular)."""
        return (math.nan,) * (3 * part.size) if singular else tuple(part.E(np.array(chi)).ravel().tolist())

    def update(
        self, qdot: np.ndarray | None, threshold: float, continuous: bool
    ) -> RepresentationSingularityError | None:
        """Fill this block's arrays; returns the RepresentationSingularityError to raise (or None)."""
        if self.b is None:
            a = self.a
            C, p, J = a.C, a.pos, a.J
            if qdot is not None and a.Jdot is not self.Jdot:  # another block adopted the frame's rates
                np.copyto(self.Jdot, a.Jdot)
                np.copyto(self.twist, a.twist)
        else:
            (C, p), J = self._relative(qdot), self.Jrel
        (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = C
        previous, (position, rotation, m_P, cartesian) = self.previous, self.pose_map
        chi: list[float]
        distances: list[float]
        entries: tuple[float, ...]
        found: tuple[list[float], float, tuple[float, ...] | None] | None
        if position is None:
            chi, distances, entries = [], [], ()
        elif cartesian:  # χ_P = p, E_P = I: never singular
            chi, distances, entries = [*p], [_INF], ()
        else:
            chi, distance, _ = self._coordinates(
                position, [], p, None if previous is None else previous[:m_P]
            )
            self.singular[0] = off = not distance >= threshold or distance == 0.0
            distances, entries = [distance], self._entries(position, chi, off)
        if rotation is not None:  # the chart gives χ, distance and E at once at a regular canonical χ
            before = None if previous is None else previous[m_P:]
            found = rotation.chart(c00, c01, c02, c10, c11, c12, c20, c21, c22)
            if found is None or (before is not None and self.rule(found[0], before) != found[0]):
                flat = [c00, c01, c02, c10, c11, c12, c20, c21, c22]
                found = self._coordinates(rotation, flat, p, before)  # another representative, or none
            self.singular[-1] = off = not found[1] >= threshold or found[1] == 0.0
            entries += (
                found[2] if found[2] is not None and not off else self._entries(rotation, found[0], off)
            )
            chi += found[0]
            distances.append(found[1])
        self.write_E(self.E_all, self.E_offset, *entries)
        selected = chi
        if self.selected is not None:
            np.take(self.E_all, self.selected, axis=0, out=self.E)
            selected = [chi[i] for i in self.selected]
        px, py, pz = p
        self.write_run(
            self.values,  # type: ignore[arg-type]  # a buffer; numpy declares __buffer__ for Python >= 3.12 only
            self.run_at,
            *selected, *distances, c00, c01, c02, px, c10, c11, c12, py, c20, c21, c22, pz,
        )  # fmt: skip
        self.S.dot(J, self.out)  # [J; J_A] = [I; E]·J
        if continuous:
            self.previous = chi
        if qdot is not None:
            self._rates(qdot, chi)
        if True not in self.singular:
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
        np.dot(Edot, self.J, out=self.tmp)
        np.dot(self.E, self.Jdot, out=self.JAdot)
        np.add(self.JAdot, self.tmp, out=self.JAdot)
        np.dot(self.JA, qdot, out=self.chi_dot)


__all__ = ["FrameBlock", "FrameKinematics"]
