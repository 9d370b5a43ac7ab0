"""FrameTask: what one frame of a task stack contributes — its parameterizations, rows, reference frame
and weight. A plain frozen (hashable) description; :class:`kinengine.control.task.Task` turns a list of
them into preallocated arrays.

>>> kinengine.FrameTask("tool0", rotation="euler_zyz")                       # χ = (x, y, z, χ1, χ2, χ3)
>>> kinengine.FrameTask("link_4", rotation=None, rows=("x", "y"))          # two rows: x and y of link_4
>>> kinengine.FrameTask("left_tool", relative_to="right_tool")              # χ of T_BA (A in B)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from ..analytic.pose_map import as_rows
from ..errors import OptionError
from ..kinematics.options import checked_nonnegative


@dataclass(frozen=True)
class FrameTask:
    """One frame of a task stack.

    frame: the frame name A. position / rotation: parameterization names (None leaves those rows out),
    as in :meth:`kinengine.Robot.analytic_jacobian`. rows: labels or indices of the rows kept (None: all).
    relative_to: a frame name B; χ then parameterizes T_BA (A's pose in B) and the frame's Jacobian is the
    relative Jacobian expressed in B (None: the root frame I). weight: a non-negative scalar the Task repeats
    over this frame's rows in ``task.weights`` (for a weighted least-squares or QP controller; the Task's
    Jacobians are not scaled by it).
    """

    frame: str
    position: str | None = "cartesian"
    rotation: str | None = "euler_zyx"
    rows: tuple[str | int, ...] | None = None
    relative_to: str | None = None
    weight: float = 1.0

    def __post_init__(self) -> None:
        if not isinstance(self.frame, str):
            raise OptionError(f"FrameTask.frame must be a frame name (str), got {self.frame!r}")
        object.__setattr__(self, "rows", as_rows(self.rows))
        object.__setattr__(self, "weight", checked_nonnegative(self.weight, "FrameTask.weight"))


def as_frame_tasks(
    frames: str | FrameTask | Sequence[str | FrameTask],
    position: str | None,
    rotation: str | None,
    rows: Sequence[str | int] | None,
    relative_to: str | None,
) -> tuple[FrameTask, ...]:
    """FrameTask entries for each item of ``frames`` (names take the other arguments)."""
    items, selected = (frames,) if isinstance(frames, (str, FrameTask)) else tuple(frames), as_rows(rows)
    for item in items:
        if not isinstance(item, (str, FrameTask)):
            raise OptionError(f"a task's frames are frame names or kinengine.FrameTask entries, got {item!r}")
    return tuple(
        item if isinstance(item, FrameTask) else FrameTask(item, position, rotation, selected, relative_to)
        for item in items
    )


__all__ = ["FrameTask", "as_frame_tasks"]
