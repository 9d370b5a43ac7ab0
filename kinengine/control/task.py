"""The controller's hot path: one ``update(q, qdot)`` computes everything, into preallocated arrays.

>>> task = robot.task("tool0", position="cartesian", rotation="euler_zyz")
>>> task.update(q, qdot)                       # one pass over the chain, no numpy allocation
>>> task.chi, task.analytic_jacobian, task.jacobian_dot, task.analytic_jacobian_dot

A task stack: several :class:`~kinengine.FrameTask` entries, each with its own parameterizations,
rows, reference frame and weight, stacked in the given order:

>>> task = robot.task([kinengine.FrameTask("tool0", rotation="euler_zyz"),
...                    kinengine.FrameTask("link_4", rotation=None, rows=("x", "y"))])

Frames: per entry, ``pose`` is T_IA in the root frame I (T_BA with ``relative_to`` B); ``jacobian`` is J_e0
in "local_world_aligned" (origin velocity and angular velocity in I, rows [linear; angular]; with
``relative_to`` the relative Jacobian expressed in B, see :mod:`kinengine.kinematics.relative`);
``twist`` = J·q̇; ``jacobian_dot`` = dJ/dt; ``analytic_jacobian`` = E(χ)·J and
``analytic_jacobian_dot`` = Ė·J + E·J̇ with Ė = dE/dt along (v, ω); ``chi_dot`` = J_A·q̇. Stacked over
the k entries: ``chi`` (M,), ``analytic_jacobian`` (M, dof) with M the total of the entries' selected
rows, ``jacobian`` (6k, dof), ``pose`` (k, 4, 4) ((4, 4) for a single frame given as a name or a FrameTask),
``weights`` (M,) each entry's weight repeated over its rows, ``row_labels`` ("frame:label", ...).

Singularities: ``singularity_distances`` (P,) is, per entry and per parameterization in
``singularity_labels`` order ("frame:parameterization"), the distance of the current χ to that
parameterization's singular set (|cos χ2| for Tait–Bryan angles, ρ for cylindrical, inf if never
singular), updated every update, so a controller can switch parameterization before reaching it. A
parameterization closer than ``singularity_threshold`` gets NaN in its rows of ``analytic_jacobian``,
``analytic_jacobian_dot`` and ``chi_dot`` (its χ rows keep the finite angles; every other row is exact);
with ``on_singularity="raise"`` (default) the update then raises RepresentationSingularityError *after*
writing every attribute: a failed update leaves the Task consistent, holding all the new configuration's
values (so the next update continues from it), never a mix of old and new.

How: one Pinocchio call fills its world-frame joint Jacobians J_w and, with q̇, J̇_w
(:func:`~kinengine.control.task_frame.joint_jacobians`); per frame :mod:`kinengine.control.task_frame` does
the rest. Pinocchio's model has plain joints only; with mimic joints q_pin = M q + b and q̇_pin = M q̇
are written into preallocated arrays and J_w, J̇_w are folded, J_w·M (see :mod:`kinengine.model.coordinates`).
A task of one absolute frame with all rows, Cartesian position and a rotation takes the fast path of
:mod:`kinengine.control.task_fast` (the same χ, J and J_A to rounding by one product) wherever χ is regular.

A Task owns its own Pinocchio Data: use one Task per thread. The attributes are read-only
views that the next update overwrites; copy what you keep.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from ..analytic import as_rows, pose_map
from ..analytic.options import DEFAULTS, AnalyticOptions
from ..errors import OptionError
from ..kinematics.memory import create_data
from .frame_task import FrameTask, as_frame_tasks
from .task_fast import fast_update
from .task_frame import FrameBlock, FrameKinematics, joint_jacobians

if TYPE_CHECKING:  # named for the checker only
    from .robot_like import RobotLike


class Task:
    """Kinematics of one or several frames for a control loop. Build it with :meth:`Robot.task`.

    ``check_inputs=False`` skips the shape and finiteness checks of q and q̇ (for callers that
    validate upstream: then pass float64 arrays of shape (dof,)). ``continuous=True`` keeps χ
    continuous between updates (no 2π jumps, no quaternion sign flips, rotation vectors across
    θ = π); :meth:`reset` returns to the canonical ranges. ``singularity_threshold``: as in
    :meth:`Robot.analytic_jacobian` (below it: NaN rows, and with ``on_singularity="raise"`` the error
    after the update). ``relative_to`` (for frames given by name): χ of T_BA and the relative Jacobian in B.
    """

    def __init__(
        self,
        robot: RobotLike,
        frames: str | FrameTask | Sequence[str | FrameTask],
        position: str | None = DEFAULTS.position,
        rotation: str | None = DEFAULTS.rotation,
        *,
        rows: Sequence[str | int] | None = DEFAULTS.rows,
        check_inputs: bool = True,
        continuous: bool = True,
        singularity_threshold: float = DEFAULTS.singularity_threshold,
        relative_to: str | None = None,
        on_singularity: str = DEFAULTS.on_singularity,
    ) -> None:
        options = AnalyticOptions(position, rotation, rows, singularity_threshold, on_singularity).checked()
        specs = as_frame_tasks(frames, options.position, options.rotation, options.rows, relative_to)
        if not specs:
            raise OptionError("a task needs at least one frame: pass a frame name or a list of them")
        self.options = options
        self._nan, self.on_singularity = options.nan, on_singularity
        pmaps = [pose_map(f.position, f.rotation, as_rows(f.rows)) for f in specs]
        self.frame_tasks, self.frames = specs, tuple(f.frame for f in specs)
        uniform = all(
            not isinstance(f, FrameTask)
            for f in ((frames,) if isinstance(frames, (str, FrameTask)) else frames)
        )
        self.labels = pmaps[0].labels if uniform else tuple(lab for pm in pmaps for lab in pm.labels)
        self.row_labels = tuple(
            f"{f.frame}:{lab}" for f, pm in zip(specs, pmaps, strict=False) for lab in pm.labels
        )
        self.singularity_labels = tuple(
            f"{f.frame}:{part.name}" for f, pm in zip(specs, pmaps, strict=False) for part in pm.parts
        )
        self.check_inputs, self.continuous = check_inputs, continuous
        self.singularity_threshold = options.singularity_threshold
        kin = robot.engine
        self._coords = coords = kin.coordinates
        self._model = model = kin.model
        self._data = data = create_data(model, "a Task")
        self.dof = n = robot.dof
        k, M = len(specs), sum(pm.size for pm in pmaps)
        # views of Pinocchio's world-frame joint Jacobians (eigenpy hands a (6, 1) matrix over as (6,))
        self._Jw, self._dJw = data.J.reshape(6, model.nv), data.dJ.reshape(6, model.nv)
        self._zero = np.zeros(model.nv)
        self._qp, self._vp = np.empty(model.nq), np.empty(model.nv)
        spec0, pm0 = specs[0], pmaps[0]
        fast = (
            k == 1
            and spec0.relative_to is None
            and pm0.rows is None
            and pm0.position is not None
            and pm0.position.name == "cartesian"
            and pm0.rotation is not None
        )
        # J_e0 and J_A in one buffer: the fast path writes both with one product (see task_fast)
        stacked = np.zeros((6 * k + M, n))
        self._J, self._JA = stacked[: 6 * k].reshape(k, 6, n), stacked[6 * k :]
        stacked_dot, rates = np.zeros((6 * k + M, n)), np.zeros(6 * k + M)  # [J̇; J̇_A], [twist; χ̇] alike
        self._Jdot, self._JAdot = stacked_dot[: 6 * k].reshape(k, 6, n), stacked_dot[6 * k :]
        self._twist, self._chi_dot = rates[: 6 * k].reshape(k, 6), rates[6 * k :]
        # ([X; E·X] of the fast path,) χ, the distances and the poses in one buffer: one struct call fills it
        P, lead = len(self.singularity_labels), 6 * (6 + M) if fast else 0
        flat = np.zeros(lead + M + P + 16 * k)
        self._chi, self._distances = flat[lead : lead + M], flat[lead + M : lead + M + P]
        self._distances.fill(np.inf)
        self._pose = flat[lead + M + P :].reshape(k, 4, 4)
        self._pose[:, 3, 3] = 1.0
        self._weights = np.concatenate(
            [np.full(pm.size, f.weight) for f, pm in zip(specs, pmaps, strict=False)]
        )
        kinematics: dict[int, FrameKinematics] = {}

        def frame_kinematics(name: str) -> FrameKinematics:
            fid = robot.frame_id(name)
            if fid not in kinematics:
                kinematics[fid] = FrameKinematics(model, data, fid, n, coords)
            return kinematics[fid]

        self._blocks: list[FrameBlock] = []
        row, part = 0, 0
        for i, (spec, pm) in enumerate(zip(specs, pmaps, strict=False)):
            a = frame_kinematics(spec.frame)
            b = None if spec.relative_to is None else frame_kinematics(spec.relative_to)
            rows_i = slice(row, row + pm.size)
            out = {
                "pose": self._pose[i],
                "J": self._J[i],
                "Jdot": self._Jdot[i],
                "twist": self._twist[i],
                "JA": self._JA[rows_i],
                "JAdot": self._JAdot[rows_i],
                "chi_dot": self._chi_dot[rows_i],
            }
            if b is None and not a.adopted:
                a.adopt(out["J"], out["Jdot"], out["twist"])
            block = FrameBlock(spec, pm, a, b, n, out, row, part)
            self._blocks.append(block)
            row, part = row + pm.size, part + len(pm.parts)
        self._kinematics = tuple(kinematics.values())
        self._fast = (
            fast_update(self._kinematics[0], self._blocks[0], stacked, stacked_dot, rates, flat)
            if fast
            else None
        )
        single = isinstance(frames, (str, FrameTask))
        self.pose = _readonly(self._pose[0] if single else self._pose)
        self.jacobian = _readonly(self._J.reshape(6 * k, n))
        self.jacobian_dot = _readonly(self._Jdot.reshape(6 * k, n))
        self.twist = _readonly(self._twist.reshape(6 * k))
        self.chi = _readonly(self._chi)
        self.analytic_jacobian = _readonly(self._JA)
        self.analytic_jacobian_dot = _readonly(self._JAdot)
        self.chi_dot = _readonly(self._chi_dot)
        self.weights = _readonly(self._weights)
        self.singularity_distances = _readonly(self._distances)
        self._rates = (self._twist, self._Jdot, self._JAdot, self._chi_dot)
        self._rates_valid: bool = False
        self._invalidate_rates()

    def __repr__(self) -> str:
        return f"<Task {self.frames} {self.labels}>"

    def reset(self) -> None:
        """Forget the previous χ: the next update returns χ in the canonical ranges."""
        for block in self._blocks:
            block.previous = None

    def update(self, q: np.ndarray, qdot: np.ndarray | None = None) -> None:
        """Evaluate at q [rad | m] (and q̇ [rad/s | m/s]); overwrites every attribute in place.

        Without q̇, ``twist``, ``chi_dot``, ``jacobian_dot`` and ``analytic_jacobian_dot`` are NaN
        (never the rates of an earlier q). Within ``singularity_threshold`` of a parameterization's singular
        set: NaN rows (``on_singularity="nan"``) or, after every attribute is written,
        RepresentationSingularityError (see the module doc).
        """
        fast = self._fast
        if fast is not None and fast(q, qdot, self.check_inputs, self.singularity_threshold, self.continuous):
            if qdot is not None:
                self._rates_valid = True
            elif self._rates_valid:
                self._invalidate_rates()
            return
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
        joint_jacobians(self._model, self._data, qp, vp, self._zero)
        if qdot is None:
            if self._rates_valid:
                self._invalidate_rates()
        else:
            self._rates_valid = True
        Jw, dJw = self._Jw, self._dJw
        for frame in self._kinematics:
            frame.update(Jw, dJw, qdot)
        error = None
        threshold, continuous, chi, distances = (
            self.singularity_threshold,
            self.continuous,
            self._chi,
            self._distances,
        )
        for block in self._blocks:
            found = block.update(qdot, threshold, continuous, chi, distances, block.distance_offset)
            if found is not None and error is None:
                error = found
        if error is not None and not self._nan:
            raise error

    def _invalidate_rates(self) -> None:
        """NaN in every rate attribute (until an update with q̇ fills them)."""
        for array in self._rates:
            array.fill(np.nan)
        self._rates_valid = False


def _readonly(array: np.ndarray) -> npt.NDArray[np.float64]:
    view = array.view()
    view.flags.writeable = False
    return view
