"""The analytic options, declared once: every method that takes ``position``, ``rotation``, ``rows``,
``singularity_threshold`` or ``on_singularity`` (``Robot.pose_parameters``, ``analytic_jacobian``,
``analytic_hessian``, ``task`` and :class:`~kinengine.control.task.Task`) takes its defaults from
:data:`DEFAULTS` and checks its values by :meth:`AnalyticOptions.checked`, so none can drift apart."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from ..kinematics.options import checked_parameterization, checked_threshold
from .pose_map import DEFAULT_SINGULARITY_THRESHOLD, PoseMap, pose_map
from .singular import check_on_singularity


@dataclass(frozen=True)
class AnalyticOptions:
    """position / rotation: parameterization names (None leaves those rows out); rows: labels or indices of
    the rows kept (None: all); singularity_threshold: distance to a parameterization's singular set below
    which a configuration counts as singular [≥ 0]; on_singularity: "raise" (RepresentationSingularityError
    there) or "nan" (NaN in that parameterization's rows) (``Robot.pose_parameters`` also takes None: χ
    without the check, a UserWarning at gimbal lock)."""

    position: str | None = "cartesian"
    rotation: str | None = "euler_zyx"
    rows: Sequence[str | int] | None = None
    singularity_threshold: float = DEFAULT_SINGULARITY_THRESHOLD
    on_singularity: str = "raise"

    def checked(self) -> AnalyticOptions:
        """These options with every value checked (ParameterizationError for names and rows, OptionError
        for the rest), rows as a tuple."""
        position, rotation, rows = checked_parameterization(self.position, self.rotation, self.rows)
        threshold = checked_threshold(self.singularity_threshold)
        check_on_singularity(self.on_singularity)
        return AnalyticOptions(position, rotation, rows, threshold, self.on_singularity)

    @property
    def nan(self) -> bool:
        """True for on_singularity "nan" (NaN rows), False for "raise" (the error)."""
        return self.on_singularity == "nan"

    def pose_map(self) -> PoseMap:
        """The :class:`~kinengine.analytic.pose_map.PoseMap` of position, rotation and rows."""
        return pose_map(self.position, self.rotation, self.rows)


DEFAULTS = AnalyticOptions()
"""The defaults of every method and of the Task."""

__all__ = ["DEFAULTS", "AnalyticOptions"]
