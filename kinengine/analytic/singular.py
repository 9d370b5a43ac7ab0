"""Representation singularities met by the analytic layer: the RepresentationSingularityError, with the
parameterizations regular at the same pose and whether the robot itself is kinematically singular there
(from the singular values of the geometric Jacobian that E(χ) multiplies: J_e0, or a relative Jacobian)."""

from __future__ import annotations

import math
import warnings

import numpy as np

from ..errors import OptionError, RepresentationSingularityError
from ..parameterizations import POSITION_PARAMETERIZATIONS, ROTATION_PARAMETERIZATIONS
from ..parameterizations.base import Parameterization

ON_SINGULARITY = ("raise", "nan")
"""Within the threshold of a singular set: RepresentationSingularityError ("raise", the default) or NaN in
the rows of the singular parameterization ("nan"; the other rows stay exact)."""

RANK_TOLERANCE = 1e-6
"""Relative tolerance of :func:`robot_rank`: σ_i > RANK_TOLERANCE·σ_max counts (the value of
kinengine.control.manipulability.DEFAULT_TOLERANCE, taken relative to the largest singular value)."""


def check_on_singularity(on_singularity: object) -> bool:
    """True for "nan", False for "raise"; OptionError otherwise."""
    if isinstance(on_singularity, str) and on_singularity in ON_SINGULARITY:
        return on_singularity == "nan"
    raise OptionError(f"on_singularity must be 'raise' or 'nan', got {on_singularity!r}")


def robot_rank(J: np.ndarray) -> tuple[int, int]:
    """(rank, generic rank) of a geometric Jacobian J (6, dof): rank counts σ_i > RANK_TOLERANCE·σ_max, the
    generic rank is min(6, number of nonzero columns: a relative Jacobian's vanish for joints that move both
    frames alike). The robot is kinematically singular when rank < generic rank."""
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


__all__ = ["ON_SINGULARITY", "RANK_TOLERANCE", "check_on_singularity", "robot_rank", "singularity_error"]
