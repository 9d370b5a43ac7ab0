"""The controller's hot path: one ``update(q, qdot)`` computes everything, into preallocated arrays
(docs/controller.md lists every attribute with its shape).

>>> task = robot.task("tool0", position="cartesian", rotation="euler_zyz")
>>> task.update(q, qdot)                       # into preallocated read-only arrays
>>> task.chi, task.analytic_jacobian, task.jacobian_dot, task.analytic_jacobian_dot
>>> task = robot.task([kinengine.FrameTask("tool0", rotation="euler_zyz"),      # a stack, in this order
...                    kinengine.FrameTask("link_4", rotation=None, rows=("x", "y"))])

Frames, per entry: ``pose`` is T_IA in the root frame I (T_BA with ``relative_to`` B); ``jacobian`` is J_e0
in "local_world_aligned" (rows [v; ω] in I; with ``relative_to`` the relative Jacobian in B, see
:mod:`kinengine.kinematics.relative`); ``twist`` = J·q̇; ``analytic_jacobian`` = E(χ)·J;
``analytic_jacobian_dot`` = Ė·J + E·J̇; ``chi_dot`` = J_A·q̇. A stack concatenates its entries' rows
(``row_labels`` "frame:label"; ``weights`` each entry's weight over its rows).

Singularities: ``singularity_distances`` holds, per entry and parameterization (``singularity_labels``),
the distance of χ to that parameterization's singular set. Closer than ``singularity_threshold``: NaN in
its rows of ``analytic_jacobian``, ``analytic_jacobian_dot`` and ``chi_dot`` (χ keeps the finite angles),
and with ``on_singularity="raise"`` RepresentationSingularityError *after* every attribute is written (the
Task never holds a mix of old and new values).

How: per frame Pinocchio's frame Jacobian on the frame's cheapest exact model (``Kinematics.frame_path``);
with q̇ one ``computeJointJacobiansTimeVariation`` call; per entry :mod:`kinengine.control.task_frame`. With
mimic joints q_pin = M q + b and q̇_pin = M q̇ go to Pinocchio and the Jacobians are folded, J·M.
A Task owns its Pinocchio Data: use one Task per thread; copy the attributes you keep.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..analytic import as_rows, pose_map
from ..analytic.options import DEFAULTS, AnalyticOptions
from ..errors import OptionError
from ..kinematics.memory import create_data
from .frame_task import FrameTask, as_frame_tasks
from .task_frame import FrameBlock, FrameKinematics

if TYPE_CHECKING:  # named for the checker only
    from .robot_like import RobotLike


class Task:
    """Kinematics of one or several frames for a control loop. Build it with :meth:`Robot.task`.

    ``options``: the parameterizations, rows, ``singularity_threshold`` (below it: NaN rows, and with
    ``on_singularity="raise"`` the error after the update) as :meth:`Robot.analytic_jacobian` takes them
    (:class:`~kinengine.analytic.options.AnalyticOptions`). ``check_inputs=False`` skips the shape and
    finiteness checks of q and q̇ (for callers that validate upstream: then pass float64 arrays (dof,)).
    ``continuous=True`` keeps χ continuous between updates (no 2π jumps, no quaternion sign flips, rotation
    vectors across θ = π); :meth:`reset` returns to the canonical ranges. ``relative_to`` (for frames given
    by name): χ of T_BA and the relative Jacobian in B.
    """

    def __init__(
        self,
        robot: RobotLike,
        frames: str | FrameTask | Sequence[str | FrameTask],
        options: AnalyticOptions = DEFAULTS,
        *,
        check_inputs: bool = True,
        continuous: bool = True,
        relative_to: str | None = None,
    ) -> None:
        options = options.checked()
        specs = as_frame_tasks(frames, options.position, options.rotation, options.rows, relative_to)
        if not specs:
            raise OptionError("a task needs at least one frame: pass a frame name or a list of them")
        self.options, self.on_singularity = options, options.on_singularity
        self.singularity_threshold = options.singularity_threshold
        self.check_inputs, self.continuous = check_inputs, continuous
        self.frame_tasks, self.frames = specs, tuple(f.frame for f in specs)
        kin = robot.engine
        self._coords, self._model, self.dof = kin.coordinates, kin.model, robot.dof
        self._data = data = create_data(kin.model, "a Task")
        self._qp, self._vp = np.empty(kin.model.nq), np.empty(kin.model.nv)
        fids = {name: robot.frame_id(name) for f in specs for name in (f.frame, f.relative_to) if name}
        kinematics = {fid: FrameKinematics(kin, data, fid) for fid in dict.fromkeys(fids.values())}
        self._blocks = blocks = [
            FrameBlock(
                spec,
                pose_map(spec.position, spec.rotation, as_rows(spec.rows)),
                kinematics[fids[spec.frame]],
                None if spec.relative_to is None else kinematics[fids[spec.relative_to]],
            )
            for spec in specs
        ]
        self._kinematics = tuple(kinematics.values())
        self._mapped = not self._coords.identity and any(f.mapped or not f.path_nv for f in self._kinematics)
        single = isinstance(frames, (str, FrameTask))
        named = all(
            isinstance(f, str) for f in ((frames,) if isinstance(frames, (str, FrameTask)) else frames)
        )
        self.labels = blocks[0].pmap.labels if named else tuple(lab for b in blocks for lab in b.pmap.labels)
        self.row_labels = tuple(f"{b.spec.frame}:{lab}" for b in blocks for lab in b.pmap.labels)
        self.singularity_labels = tuple(f"{b.spec.frame}:{part.name}" for b in blocks for part in b.parts)
        # one block: the Task's arrays are the block's own; a stack: copies of the blocks' (see _gather)
        names = ("pose", "J", "JA", "chi", "distances", "Jdot", "JAdot", "twist", "chi_dot")
        if len(blocks) == 1:
            arrays, self._stack = [getattr(blocks[0], name) for name in names], []
        else:
            arrays = [np.concatenate([getattr(b, name) for b in blocks]) for name in names]
            self._stack = list(zip(names, arrays, strict=True))
        pose, J, JA, chi, distances, Jdot, JAdot, twist, chi_dot = arrays
        self.pose = _readonly(pose if single else pose.reshape(len(blocks), 4, 4))
        self.jacobian, self.jacobian_dot = _readonly(J), _readonly(Jdot)
        self.twist, self.chi = _readonly(twist), _readonly(chi)
        self.analytic_jacobian, self.analytic_jacobian_dot = _readonly(JA), _readonly(JAdot)
        self.chi_dot, self.singularity_distances = _readonly(chi_dot), _readonly(distances)
        self.weights = _readonly(np.concatenate([np.full(b.pmap.size, b.spec.weight) for b in blocks]))
        self._rates = (Jdot, JAdot, twist, chi_dot)
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
        coords = self._coords
        if self.check_inputs:
            if not coords.ready(q):
                q = coords.check(q, allow_batch=False)
            if qdot is not None and not coords.ready(qdot):
                qdot = coords.check(qdot, name="qdot", allow_batch=False)
        q_pin = q
        if qdot is not None:  # q_pin = M q + b and q̇_pin = M q̇ (in place) for the joint Jacobians
            v = qdot
            if not coords.identity:
                q_pin, v = self._to_pinocchio(q), np.dot(coords.matrix, qdot, out=self._vp)
            pin.computeJointJacobiansTimeVariation(self._model, self._data, q_pin, v)  # J, J̇ into the Data
            self._rates_valid = True
        elif self._mapped:  # a frame that needs q_pin
            q_pin = self._to_pinocchio(q)
        for frame in self._kinematics:
            frame.update(q, q_pin, qdot)
        error, threshold, continuous = None, self.singularity_threshold, self.continuous
        for block in self._blocks:
            found = block.update(qdot, threshold, continuous)
            error = error or found  # the first block's error
        if self._stack:
            self._gather(qdot is not None)
        if qdot is None and self._rates_valid:
            self._invalidate_rates()
        if error is not None and not self.options.nan:
            raise error

    def _to_pinocchio(self, q: np.ndarray) -> np.ndarray:
        """q_pin = M q + b into a preallocated array (``coordinates.to_pinocchio`` allocates)."""
        q_pin = np.dot(self._coords.matrix, q, out=self._qp)
        return np.add(q_pin, self._coords.offset, out=q_pin) if self._coords.has_offset else q_pin

    def _gather(self, rates: bool) -> None:
        """Copy each block's arrays into the stacked ones (rates only with q̇)."""
        for name, target in self._stack if rates else self._stack[:5]:
            np.concatenate([getattr(b, name) for b in self._blocks], out=target)

    def _invalidate_rates(self) -> None:
        """NaN in every rate attribute (until an update with q̇ fills them)."""
        for array in self._rates:
            array.fill(np.nan)
        self._rates_valid = False


def _readonly(array: np.ndarray) -> npt.NDArray[np.float64]:
    view = array.view()
    view.flags.writeable = False
    return view
