"""Pose parameters χ_e(q) and analytic Jacobians J_eA = E_e(χ_e)·J_e0 (Robot Dynamics lecture notes, ETH
Zurich, section 2.8, eqs. 2.180–2.181).

J_e0 is the geometric Jacobian in the inertial frame ("local_world_aligned": origin velocity and angular
velocity in I); E_e = blockdiag(E_P(χ_P), E_R(χ_R)) maps that twist to χ̇_e. A :class:`PoseMap` binds a
position and a rotation parameterization (either may be absent) and a selection of rows by label (the
operational-space coordinates of section 2.8.2). It evaluates the parameterizations' own formulas on
Python floats for one configuration and on numpy arrays for a batch (:meth:`PoseMap.fill_columns`).
"""

from __future__ import annotations

import math
import struct
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
import numpy.typing as npt

from ..errors import ParameterizationError
from ..parameterizations import get_position, get_rotation
from ..parameterizations.base import (
    Entries,
    Parameterization,
    PositionParameterization,
    RotationParameterization,
    is_singular,
    singular_where,
)
from .singular import singularity_error

DEFAULT_SINGULARITY_THRESHOLD = 1e-6
"""analytic_jacobian raises RepresentationSingularityError when the distance to the singular set
(e.g. |cos χ2| for Tait–Bryan angles, ρ for cylindrical) is below this; E's entries grow like
1/distance, so 1e-6 admits entries up to about 1e6."""


class Layout:
    """Where E's computed entries go in the (m, 6) matrix E = blockdiag(E_P, E_R) of one PoseMap.

    ``template`` holds the constant entries (zeros, the identity of Cartesian rows); ``pack_into`` writes the
    computed ones (float64, native byte order) from ``offset``: E_P's entries in columns 0-2 of the position
    rows (unless Cartesian), then E_R's in columns 3-5 of the rotation rows.
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


def _combine(entries: Entries, block: np.ndarray, out: np.ndarray, scratch: np.ndarray) -> None:
    """out = Σ_k entries[k]·block[k]: a row of E (entries (n,) or constants) times J's rows (3, dof, n)."""
    out[...] = 0.0
    for entry, row in zip(entries, block, strict=True):
        if not (isinstance(entry, float) and entry == 0.0):
            out += np.multiply(row, entry, out=scratch)


@dataclass(frozen=True)
class PoseMap:
    """χ_e = (χ_P, χ_R)[rows]: which parameterizations, and which of their rows, make up χ."""

    position: PositionParameterization | None
    rotation: RotationParameterization | None
    labels: tuple[str, ...]  # labels of the selected rows
    rows: tuple[int, ...] | None  # indices into the full (χ_P, χ_R) stack; None: all rows
    layout: Layout = field(init=False, repr=False, compare=False)
    part_rows: tuple[tuple[int, ...], ...] = field(init=False, repr=False, compare=False)
    """Per part (in :attr:`parts` order), the indices of its rows among the selected rows."""
    formula_parts: tuple[Parameterization, ...] = field(init=False, repr=False, compare=False)
    """The parts whose E is computed (in :attr:`parts` order): all but Cartesian, whose E = I is constant."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "layout", Layout(self.position, self.rotation))
        selected = range(len(self.labels)) if self.rows is None else self.rows
        spans, start = [], 0
        for part in self.parts:
            spans.append(tuple(i for i, r in enumerate(selected) if start <= r < start + part.size))
            start += part.size
        object.__setattr__(self, "part_rows", tuple(spans))
        object.__setattr__(self, "formula_parts", tuple(p for p in self.parts if p.name != "cartesian"))

    @property
    def size(self) -> int:
        return len(self.labels)

    @property
    def parts(self) -> tuple[Parameterization, ...]:
        """The parameterizations in χ's order (position first), without the absent one."""
        return tuple(p for p in (self.position, self.rotation) if p is not None)

    def parameters(
        self,
        T: npt.NDArray[np.float64],
        threshold: float | None = None,
        nan: bool = False,
        J: Callable[[int | None], npt.NDArray[np.float64]] | None = None,
    ) -> npt.NDArray[np.float64]:
        """χ from poses T_IF, (4, 4) -> (m,) or (N, 4, 4) -> (N, m).

        ``threshold`` None: χ everywhere (a UserWarning at gimbal lock). Otherwise a pose within
        ``threshold`` of a part's singular set raises RepresentationSingularityError (``nan`` False;
        ``J(row)`` gives that pose's geometric Jacobian for the message) or gets NaN in that part's rows.
        """
        parts: list[npt.NDArray[np.float64]] = []
        with warnings.catch_warnings():
            if threshold is not None:
                warnings.simplefilter("ignore", UserWarning)
            if self.position is not None:
                parts.append(self.position.from_position(T[..., :3, 3]))
            if self.rotation is not None:
                parts.append(self.rotation.from_rotation(T[..., :3, :3]))
        chi = np.concatenate(parts, axis=-1)
        chi = chi if self.rows is None else chi[..., self.rows]
        if threshold is None:
            return chi
        distances = [param.singularity_distance(x) for param, x in zip(self.parts, parts, strict=True)]
        distance = np.stack(distances, axis=-1).reshape(-1, len(parts))  # (N, parts), N = 1 for one pose
        single, poses = T.ndim == 2, T.reshape(-1, 4, 4)
        jacobian = None if J is None else (lambda row: J(None if single else row))
        out = chi.reshape(-1, self.size)  # a view: NaN rows go into chi
        self.singular_rows(distance, threshold, out, nan, lambda row: poses[row], jacobian, single)
        return chi

    def jacobian(
        self,
        T: npt.NDArray[np.float64],
        J: npt.NDArray[np.float64],
        threshold: float,
        nan: bool = False,
    ) -> npt.NDArray[np.float64]:
        """J_A = E(χ)·J_e0 (m, dof) for one pose T_IF (4, 4) and J_e0 (6, dof) in "local_world_aligned": see
        :meth:`jacobian_single`."""
        rows = T.tolist()[:3]
        return self.jacobian_single([r[:3] for r in rows], [r[3] for r in rows], J, threshold, nan=nan)

    def jacobian_single(
        self,
        C: Sequence[Sequence[float]],
        p: Sequence[float],
        J: npt.NDArray[np.float64],
        threshold: float,
        row: int | None = None,
        nan: bool = False,
    ) -> npt.NDArray[np.float64]:
        """J_A = E·J_e0 for C_IF and p [m] given as Python floats, E's entries by scalar math into the layout.

        A part within ``threshold`` of its singular set raises RepresentationSingularityError (stating J_e0's
        rank; ``row``, a batch row, only goes into its message) or, with ``nan``, gets NaN rows."""
        layout = self.layout
        flat = (*C[0], *C[1], *C[2])
        entries: tuple[float, ...] = ()
        for param in self.formula_parts:
            try:
                chi = param._coordinates(math, p, flat)
                distance = param._distance(math, *chi)
                E = None if is_singular(distance, threshold) else param._E(math, *chi)
            except ZeroDivisionError:  # on the singular set with threshold 0 (the distance rounded above 0)
                distance, E = 0.0, None
            if E is None:
                if not nan:
                    T = np.eye(4)
                    T[:3, :3], T[:3, 3] = C, p
                    raise singularity_error(param, distance, threshold, T, row, J)
                E = (math.nan,) * (3 * param.size)
            entries += E
        buffer = bytearray(layout.template)
        layout.pack_into(buffer, layout.offset, *entries)
        JA = np.frombuffer(buffer).reshape(layout.shape).dot(J)
        return JA if self.rows is None else JA[self.rows, :]

    def fill_columns(
        self, p: Sequence[np.ndarray], C: Sequence[np.ndarray], J: np.ndarray, out: np.ndarray
    ) -> list[np.ndarray | float]:
        """The batch kernel on n configurations, sample-last: p, 3 arrays (n,) [m]; C, the 9 entries of C_IF
        row-major, arrays (n,); J, J_e0 (6, dof, n) in "local_world_aligned"; out (m, dof, n) receives J_A.
        Returns each part's distance to its singular set, (n,) or a float (see :meth:`singular_rows`)."""
        E_rows: list[tuple[Entries, npt.NDArray[np.float64]]] = []
        distances: list[npt.NDArray[np.float64] | float] = []
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            blocks = (J[:3], J[3:]) if self.position is not None else (J[3:],)
            for param, block in zip(self.parts, blocks, strict=False):  # no rotation: J[3:] unused
                chi = param._coordinates(np, p, C)
                distances.append(param._distance(np, *chi))
                E = param._E(np, *chi)
                E_rows += [(E[k : k + 3], block) for k in range(0, len(E), 3)]
            scratch = np.empty(out.shape[1:])
            for target, source in enumerate(range(len(E_rows)) if self.rows is None else self.rows):
                _combine(*E_rows[source], out[target], scratch)
        return distances

    def singular_rows(
        self,
        distances: np.ndarray,
        threshold: float,
        out: np.ndarray,
        nan: bool,
        pose: Callable[[int], np.ndarray],
        jacobian: Callable[[int], np.ndarray] | None = None,
        single: bool = False,
    ) -> None:
        """Batch rows closer than ``threshold`` to a part's singular set (distances: (N, len(parts))) get NaN
        in that part's rows of out (N, m, ...) (``nan``), or the first raises RepresentationSingularityError
        with pose(row) T_IF (4, 4) and jacobian(row) J_e0 (6, dof) (``single``: not named as a batch row)."""
        below = singular_where(distances, threshold)
        if nan:
            for k, rows in enumerate(self.part_rows):
                hit = np.flatnonzero(below[:, k])
                if hit.size and rows:
                    out[np.ix_(hit, np.array(rows, dtype=np.intp))] = np.nan
        elif below.any():
            row = int(np.argmax(below.any(axis=1)))
            part = int(np.argmax(below[row]))
            raise singularity_error(
                self.parts[part],
                float(distances[row, part]),
                threshold,
                pose(row),
                None if single else row,
                None if jacobian is None else jacobian(row),
            )


@lru_cache(maxsize=256)
def pose_map(
    position: str | None, rotation: str | None, rows: tuple[str | int, ...] | None = None
) -> PoseMap:
    """Resolve parameterization names (and an optional row selection by label or index) once."""
    if position is None and rotation is None:
        raise ParameterizationError(
            "position and rotation are both None: choose at least one, e.g. "
            "position='cartesian' or rotation='quaternion'"
        )
    p = None if position is None else get_position(position)
    r = None if rotation is None else get_rotation(rotation)
    labels = (tuple(p.labels) if p else ()) + (tuple(r.labels) if r else ())
    if rows is None:
        return PoseMap(p, r, labels, None)
    index = []
    for row in rows:
        if isinstance(row, (int, np.integer)) and not isinstance(row, bool):
            if not -len(labels) <= row < len(labels):
                raise ParameterizationError(f"row {row} out of range for the {len(labels)} rows {labels}")
            index.append(int(row) % len(labels))
        elif row in labels:
            index.append(labels.index(row))
        else:
            raise ParameterizationError(
                f"unknown row {row!r}; rows of this parameterization: {', '.join(labels)}"
            )
    if len(set(index)) != len(index):
        raise ParameterizationError(f"rows {rows} select a row twice")
    return PoseMap(p, r, tuple(labels[i] for i in index), tuple(index))


def as_rows(rows: Sequence[str | int] | str | None) -> tuple[str | int, ...] | None:
    """A hashable row selection (a single label is accepted as a one-row selection)."""
    if isinstance(rows, str):
        return (rows,)
    return None if rows is None else tuple(rows)
