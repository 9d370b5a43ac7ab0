"""The memory layout of E = blockdiag(E_P, E_R) for one pose map, and the row combination the batched
analytic Jacobian uses: where the computed entries go, so that one struct write fills them."""

from __future__ import annotations

import struct
from collections.abc import Callable, Sequence

import numpy as np
import numpy.typing as npt

from ..parameterizations.base import PositionParameterization, RotationParameterization

Fast = tuple[
    bool,
    PositionParameterization | None,
    RotationParameterization | None,
    bytes,
    Callable[..., None],
    int,
    tuple[int, int],
]
"""Layout.fast: (position_formula, position, rotation, template, pack_into, offset, shape)."""


class Layout:
    """Where E's computed entries go in the (m, 6) matrix E = blockdiag(E_P, E_R) of one PoseMap.

    A template holds the constant entries (zeros, the identity of Cartesian rows); one struct writes
    the computed ones: E_P entries in columns 0-2 of the position rows, E_R in columns 3-5.
    """

    def __init__(
        self, position: PositionParameterization | None, rotation: RotationParameterization | None
    ) -> None:
        self.position_formula = position is not None and position.name != "cartesian"
        rows = (position.size if position is not None else 0) + (rotation.size if rotation is not None else 0)
        self.shape: tuple[int, int] = (rows, 6)
        template = np.zeros(self.shape)
        if position is not None and not self.position_formula:
            template[:3, :3] = np.eye(3)
        self.template = template.tobytes()
        self.offset = 0 if self.position_formula else 48 * (rows - (rotation.size if rotation else 0))
        self.pack_into: Callable[..., None] = struct.Struct(
            "="  # native byte order: the template is a float64 ndarray of this process
            + "3d24x" * (position.size if position is not None and self.position_formula else 0)
            + "24x3d" * (rotation.size if rotation is not None else 0)
        ).pack_into
        self.fast: Fast = (
            self.position_formula,
            position,
            rotation,
            self.template,
            self.pack_into,
            self.offset,
            self.shape,
        )  # what jacobian_single reads, in one attribute lookup


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
