"""Targets for several frames at once: a mapping {frame name: T_IF (4, 4)}, each frame's target and
``rows``/``weights`` checked into a :class:`~.ik_target.FrameGoal`, all solved by the one attempt loop
(:func:`.ik_solver.solve`, errors and Jacobians stacked): success when EVERY frame is within the
tolerances; attempts ranked by Σ_F (|e_p| + 0.2 m/rad·|e_R|), seeds by :func:`.ik_seeds.frame_seeds`. The
:class:`MultiIKResult`'s position_error / rotation_error are the maxima over the frames, ``frame_errors``
each frame's (position error [m], rotation error [rad]).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import OptionError, ParameterizationError
from .ik_solver import MultiIKResult
from .ik_target import FrameGoal, Options, checked_problem, single_target

if TYPE_CHECKING:  # named for the checker only
    from .robot_like import RobotLike


def _per_frame(name: str, value: object, frames: Mapping[str, object]) -> dict[str, object]:
    """``rows``/``weights`` for each frame: one spec for all, or a mapping {frame: spec} (missing: None)."""
    if not isinstance(value, Mapping):
        return dict.fromkeys(frames, value)
    if not value:
        raise OptionError(
            f"`{name}` is an empty mapping; give {{frame: spec}} for some of the target's frames, "
            f"or None for all six rows of every frame"
        )
    unknown = [key for key in value if key not in frames]
    if unknown:
        raise OptionError(
            f"`{name}` names {unknown[0]!r}, which is not a frame of the target {list(frames)}; "
            f"name only frames of the target (the others keep all six rows, weight 1)"
        )
    return {frame: value.get(frame) for frame in frames}


def checked_goals(
    robot: RobotLike, target: Mapping[Any, Any], rows: object, weights: object, options: Options
) -> list[FrameGoal]:
    """Each frame's target and options checked (OptionError, FrameNotFoundError, ParameterizationError)."""
    if not target:
        raise OptionError(
            "`target` is an empty mapping; give {frame name: pose (4, 4)} for at least one frame"
        )
    for name in target:
        if not isinstance(name, str):
            raise OptionError(f"`target`'s keys must be frame names (str), got {name!r}")
    frames: dict[str, Any] = dict(target)
    frame_rows, frame_weights = _per_frame("rows", rows, frames), _per_frame("weights", weights, frames)
    goals = []
    for frame, pose in frames.items():
        problem = checked_problem(robot, frame, frame_rows[frame], frame_weights[frame], options)
        try:
            pose_shaped = not isinstance(pose, (str, bytes)) and np.shape(pose) == (4, 4)
        except ValueError:  # ragged nesting
            pose_shaped = False
        if not pose_shaped:
            raise ParameterizationError(
                f"`target[{frame!r}]` must be a pose (4, 4), got {pose!r:.60}; several frames take one "
                "pose T_IF each (for parameters χ or a batch, solve one frame at a time)"
            )
        try:
            p_d, C_d = single_target(pose, None, None)
        except ParameterizationError as error:
            raise ParameterizationError(f"`target[{frame!r}]`: {error}") from None
        assert p_d is not None and C_d is not None  # a (4, 4) pose fixes both
        goals.append(FrameGoal(problem, p_d, C_d))
    return goals


__all__ = ["MultiIKResult", "checked_goals"]
