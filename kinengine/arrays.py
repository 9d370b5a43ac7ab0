"""Array and option types of the public API (numpy typing), shared by every layer.

Shapes are given in the names where numpy can carry them: a :data:`Vector` is (n,), a :data:`Matrix`
(m, n), a :data:`Stack` (N, m, n). Inputs take anything array-like (lists, tuples, any numeric dtype);
outputs are float64 arrays.
"""

from __future__ import annotations

from typing import Literal, TypeAlias

import numpy as np
import numpy.typing as npt
import pinocchio as pin

FloatArray: TypeAlias = npt.NDArray[np.float64]
"""A float64 array of any shape (returned)."""
Vector: TypeAlias = np.ndarray[tuple[int], np.dtype[np.float64]]
"""A float64 array of shape (n,), e.g. one configuration q (dof,)."""
Matrix: TypeAlias = np.ndarray[tuple[int, int], np.dtype[np.float64]]
"""A float64 array of shape (m, n), e.g. a pose (4, 4), a Jacobian (6, dof) or a batch Q (N, dof)."""
Stack: TypeAlias = np.ndarray[tuple[int, int, int], np.dtype[np.float64]]
"""A float64 array of shape (N, m, n), e.g. N poses (N, 4, 4) or N Jacobians (N, 6, dof)."""
ArrayLike: TypeAlias = npt.ArrayLike
"""Anything numpy turns into an array: a configuration (dof,), a batch (N, dof), a pose (4, 4), ..."""
ReferenceName: TypeAlias = Literal["local_world_aligned", "local", "world"]
Reference: TypeAlias = "ReferenceName | pin.ReferenceFrame"
"""A Jacobian's reference: "local_world_aligned" (J_e0), "local", "world", or Pinocchio's enum."""

__all__ = ["ArrayLike", "FloatArray", "Matrix", "Reference", "ReferenceName", "Stack", "Vector"]
