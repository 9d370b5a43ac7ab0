"""The memory layout of E = blockdiag(E_P, E_R) for one pose map, and the row combination the batched
analytic Jacobian uses: where the computed entries go, so that one struct write fills them."""

from __future__ import annotations

import struct
from collections.abc import Callable, Sequence

import numpy as np
import numpy.typing as npt

from ..parameterizations.base import PositionParameterization, RotationParameterization


class Layout:
    """Where E's computed entries go in the (m, 6) matrix E = blockdiag(E_P, E_R) of one PoseMap.

    A template holds the constant entries (zeros, the identity of Cartesian rows); one struct writes the
    computed ones in native byte order (the template is a float64 ndarray of this process): E_P's entries
    in columns 0-2 of the position rows (unless Cartesian), then E_R's in columns 3-5 of the rotation rows.
    """

    def __init__(
        self, position: PositionParameterization | None, rotation: RotationParameterization | None
    ) -> None:
        cartesian = position is not None and position.name == "cartesian"
        m_P, m_R = (0 if part is None else part.size for part in (position, rotation))
        self.shape: tuple[int, int] = (m_P + m_R, 6)
        template = np.zeros(self.shape)
        if cartesian:
            template[:3, :3] = np.eye(3)
        self.template = template.tobytes()
        self.offset = 48 * m_P if cartesian else 0  # 48 bytes: one row of 6 float64
        rows = "24x3d" * m_R if cartesian else "3d24x" * m_P + "24x3d" * m_R
        self.pack_into: Callable[..., None] = struct.Struct("=" + rows).pack_into


def combine(
    entries: Sequence[npt.NDArray[np.float64] | float],
    block: npt.NDArray[np.float64],
    out: npt.NDArray[np.float64],
    scratch: npt.NDArray[np.float64],
) -> None:
    """out = Σ_k entries[k] · block[k]: a row of E (entries (n,) or constants) times J's rows (3, dof, n)."""
    terms = [(e, b) for e, b in zip(entries, block, strict=False) if not (isinstance(e, float) and e == 0.0)]
    if not terms:
        out[...] = 0.0
        return
    for k, (e, b) in enumerate(terms):
        if k == 0:
            np.multiply(b, e, out=out)
        else:
            np.multiply(b, e, out=scratch)
            np.add(out, scratch, out=out)
