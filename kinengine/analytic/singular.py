"""Representation singularities met by the analytic layer: what to do there (``on_singularity``), the
robot's own rank for the message, and the RepresentationSingularityError with the parameterizations that are
regular at the same pose.

A configuration closer than the threshold to a parameterization's singular set gives either the error
("raise", the default) or NaN in that parameterization's rows ("nan"; the other rows stay exact). The error
says whether the robot itself is also kinematically singular there, from the singular values of the
geometric Jacobian that E(χ) multiplies (J_e0, or a relative Jacobian).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from ..errors import OptionError, RepresentationSingularityError
from ..parameterizations import POSITION_PARAMETERIZATIONS, ROTATION_PARAMETERIZATIONS
from ..parameterizations.base import Parameterization

ON_SINGULARITY = ("raise", "nan")
"""What a configuration closer than the threshold to a singular set gives: RepresentationSingularityError
("raise", the default) or NaN in the rows of the singular parameterization ("nan"; other rows stay exact)."""

RANK_TOLERANCE = 1e-6
"""Relative tolerance of :func:`robot_rank`: σ_i > RANK_TOLERANCE·σ_max counts (the value of
kinengine.control.manipulability.DEFAULT_TOLERANCE, taken relative to the largest singular value)."""


def check_on_singularity(on_singularity: object) -> bool:
    """True for "nan", False for "raise"; OptionError otherwise."""
    if isinstance(on_singularity, str) and on_singularity in ON_SINGULARITY:
        return on_singularity == "nan"
    raise OptionError(f"on_singularity must be 'raise' or 'nan', got {on_singularity!r}")


def robot_rank(J: np.ndarray) -> tuple[int, int]:
    """(rank, generic rank) of a geometric Jacobian J (6, dof): rank counts σ_i > RANK_TOLERANCE·σ_max,
    the generic rank is min(6, number of columns that are not zero). The robot is kinematically singular
    when rank < generic rank. (Columns of a relative Jacobian vanish identically for the joints that move
    both frames alike; an absolute J_e0 has no zero column: a joint always moves its frame.)"""
    J = np.asarray(J, dtype=float)
    if J.size == 0 or not np.isfinite(J).all():
        return 0, min(J.shape)
    norms = np.linalg.norm(J, axis=0)
    full = min(J.shape[0], int(np.count_nonzero(norms > 1e-12 * norms.max())))
    if full == 0:
        return 0, 0
    s = np.linalg.svd(J, compute_uv=False)
    return int(np.count_nonzero(s > RANK_TOLERANCE * s[0])) if s[0] > 0 else 0, full


def singularity_error(
    param: Parameterization,
    distance: float,
    threshold: float,
    T: np.ndarray,
    row: int | None = None,
    J: np.ndarray | None = None,
) -> RepresentationSingularityError:
    """The error at pose T (4, 4), with the parameterizations that are regular at the same pose and
    (given the geometric Jacobian J (6, dof)) whether the robot itself is singular there."""
    family = POSITION_PARAMETERIZATIONS if param.kind == "position" else ROTATION_PARAMETERIZATIONS
    p, C = T[:3, 3].tolist(), T[:3, :3].ravel().tolist()
    with warnings.catch_warnings():  # "on the z axis" from the other position parameterizations
        warnings.simplefilter("ignore", UserWarning)
        regular = [
            n for n, other in family.items() if other._distance(math, *other._coordinates(math, p, C)) > 0.1
        ]
    preferred = [
        n for n in ("quaternion", "rotation_matrix", "euler_zyz", "euler_xyz", "cartesian") if n in regular
    ]
    alternatives = preferred + [n for n in regular if n not in preferred]
    where = "" if row is None else f"row {row} of the batch: "
    rank, full = (None, None) if J is None else robot_rank(J)
    return RepresentationSingularityError(
        param.name, float(distance), threshold, alternatives[:4], where + param.singular_set, rank, full
    )


def pose_of(C: Sequence[Sequence[float]], p: Sequence[float]) -> npt.NDArray[np.float64]:
    """T (4, 4) from C (3x3 nested floats) and p (3 floats)."""
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = C, p
    return T


__all__ = [
    "ON_SINGULARITY",
    "RANK_TOLERANCE",
    "check_on_singularity",
    "pose_of",
    "robot_rank",
    "singularity_error",
]
