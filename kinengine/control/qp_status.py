"""What one :meth:`kinengine.control.qp.DifferentialIK.solve` did: :class:`DiffIKStatus` (QP status, active
bounds, task residual, stall) and the :class:`StatusMonitor` that decides a stall over a window of steps."""

from __future__ import annotations

import math
import warnings
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ..errors import OptionError

_ACTIVE_TOL = 1e-12  # [rad | m] a step this close to a bound has it active


@dataclass
class DiffIKStatus:
    """What one :meth:`DifferentialIK.solve` did (``ik.status`` or ``solve(..., info=True)``).

    qp_status: "unconstrained" (no bound active: one linear solve), "optimal" (the QP solver with active
    bounds), "scaled" (``limits="scale"``: the whole step times ``scale``), "infeasible" (the QP solver
    found nothing; a zero step (or the bounds' nearest point to it) was returned).
    active_lower / active_upper: (dof,) bool, which coordinates' step sits on its lower / upper bound (the
    position, velocity or acceleration bound of that step). active_constraints: (m,) bool over the rows of
    the extra inequality blocks. residual: ‖e‖ of every PoseTarget's selected rows at q, before the step
    ([m] and [rad] mixed). stalled: the residual has not decreased by ``stall_decrease`` over the last
    ``stall_window`` steps, all of which had a bound active, and is above ``stall_residual``.
    outside_limits: the coordinates whose q was outside its position limits at the step; each is driven
    back toward its range as fast as its velocity (and acceleration) limit allows, whatever the tasks ask.
    """

    qp_status: str
    active_lower: npt.NDArray[np.bool_]
    active_upper: npt.NDArray[np.bool_]
    active_constraints: npt.NDArray[np.bool_]
    residual: float
    stalled: bool
    scale: float = 1.0
    step: int = 0
    active_joints: tuple[str, ...] = ()
    outside_limits: tuple[str, ...] = ()

    @property
    def bounds_active(self) -> bool:
        return bool(self.active_lower.any() or self.active_upper.any() or self.active_constraints.any())


def checked_window(value: object) -> int:
    """The stall window, a whole number of steps >= 1, else OptionError."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise OptionError(f"stall_window must be a whole number of steps >= 1, got {value!r}")
    return int(value)


class StallWarning(RuntimeWarning):
    """DifferentialIK's once-per-episode warning that the step stalled against its bounds."""


class StatusMonitor:
    """One DifferentialIK episode: each step's :class:`DiffIKStatus` (``reset`` makes a new one)."""

    def __init__(
        self, joint_names: Sequence[str], window: int, decrease: float, residual: float, warn: bool
    ) -> None:
        self.joint_names, self.stall_window, self.stall_decrease = joint_names, window, decrease
        self.stall_residual, self.warn_on_stall = residual, warn
        self._history: deque[float] = deque(maxlen=window + 1)
        self._active_run, self._warned, self._steps = 0, False, 0
        n = len(joint_names)
        self._no_active = np.zeros(n, dtype=bool)
        self._no_active.flags.writeable = False
        self._no_rows = np.zeros(0, dtype=bool)
        self._no_rows.flags.writeable = False
        self._status: DiffIKStatus | None = DiffIKStatus(
            "unconstrained", self._no_active, self._no_active, self._no_rows, math.nan, False
        )
        # the last step's values, made a DiffIKStatus only when read: (qp status, scale, active lower,
        # active upper, active rows (None: m rows, none active), m, residual, stalled)
        self._last: tuple = ()
        self._q = np.zeros(n)
        self.lower, self.upper = np.full(n, -np.inf), np.full(n, np.inf)
        """The position limits ``outside_limits`` is judged against (set by DifferentialIK)."""

    @property
    def status(self) -> DiffIKStatus:
        """The last step's :class:`DiffIKStatus`."""
        if self._status is None:
            status, scale, lower, upper, rows, m, residual, stalled = self._last
            if rows is None:
                rows = self._no_rows if not m else np.zeros(m, dtype=bool)
            outside = (self._q < self.lower) | (self._q > self.upper)
            self._status = DiffIKStatus(
                status,
                lower,
                upper,
                rows,
                residual,
                stalled,
                scale,
                self._steps,
                self._names(lower, upper),
                tuple(name for name, out in zip(self.joint_names, outside, strict=True) if out),
            )
        return self._status

    def _names(self, lower: np.ndarray, upper: np.ndarray) -> tuple[str, ...]:
        if lower is self._no_active:
            return ()
        return tuple(name for name, on in zip(self.joint_names, lower | upper, strict=True) if on)

    def record(
        self,
        status: str,
        scale: float,
        step: np.ndarray,
        lb: np.ndarray,
        ub: np.ndarray,
        G: np.ndarray,
        h: np.ndarray,
        residual: float,
        q: np.ndarray,
    ) -> None:
        """Record a step (Δq ``step`` from q within lb <= Δq <= ub, G Δq <= h): stall test and warning; the
        :class:`DiffIKStatus` is built when :attr:`status` is read."""
        self._steps += 1
        self._q[:] = q
        self._status = None
        history = self._history
        history.append(residual)
        if status == "unconstrained":  # no bound active: no stall, nothing to warn
            self._active_run = 0
            self._last = (status, scale, self._no_active, self._no_active, None, len(h), residual, False)
            return
        active_lower = step <= lb + _ACTIVE_TOL
        active_upper = step >= ub - _ACTIVE_TOL
        active_rows = G @ step >= h - _ACTIVE_TOL if len(h) else self._no_rows
        active = bool(active_lower.any() or active_upper.any() or (len(h) and active_rows.any()))
        self._active_run = self._active_run + 1 if active else 0
        stalled = (
            self._active_run >= self.stall_window
            and len(history) == self.stall_window + 1
            and residual > self.stall_residual
            and residual >= (1.0 - self.stall_decrease) * history[0]
        )
        self._last = (status, scale, active_lower, active_upper, active_rows, len(h), residual, stalled)
        if stalled and self.warn_on_stall and not self._warned:
            self._warned = True
            names = self._names(active_lower, active_upper)
            warnings.warn(
                f"DifferentialIK stalled at step {self._steps}: the task residual {residual:.3g} has not "
                f"decreased over {self.stall_window} steps while bounds were active "
                f"({', '.join(names) or 'extra constraints'}); check the target's reachability and the "
                "limits",
                StallWarning,
                stacklevel=4,
            )


__all__ = ["DiffIKStatus", "StallWarning", "StatusMonitor", "checked_window"]
