"""Pose parameters χ_e(q) and analytic Jacobians J_eA = E_e(χ_e) · J_e0 (seed eq. 2.180–2.181).

J_e0 is the geometric Jacobian in the inertial frame ("local_world_aligned": origin velocity
and angular velocity in I) and E_e = blockdiag(E_P(χ_P), E_R(χ_R)) maps that twist to χ̇_e.
A :class:`PoseMap` binds one position and one rotation parameterization (either may be
absent) and, optionally, a selection of rows by label (the operational-space coordinates of
seed 2.8.2). It is resolved once per (position, rotation, rows) and cached.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
import math
import struct

import numpy as np

from .errors import ParameterizationError, RepresentationSingularityError
from .parameterizations import (
    POSITION_PARAMETERIZATIONS,
    ROTATION_PARAMETERIZATIONS,
    get_position,
    get_rotation,
)

DEFAULT_SINGULARITY_THRESHOLD = 1e-6
"""analytic_jacobian raises RepresentationSingularityError when the distance to the singular set
(e.g. |cos χ2| for Tait–Bryan angles, ρ for cylindrical) is below this; E's entries grow like
1/distance, so 1e-6 admits entries up to about 1e6."""


@dataclass(frozen=True)
class PoseMap:
    """χ_e = (χ_P, χ_R)[rows]: which parameterizations, and which of their rows, make up χ."""

    position: object | None
    rotation: object | None
    labels: tuple[str, ...]          # labels of the selected rows
    rows: tuple[int, ...] | None     # indices into the full (χ_P, χ_R) stack; None: all rows

    @property
    def size(self) -> int:
        return len(self.labels)

    def parameters(self, T: np.ndarray) -> np.ndarray:
        """χ from poses T_IF, (4, 4) -> (m,) or (N, 4, 4) -> (N, m)."""
        parts = []
        if self.position is not None:
            parts.append(self.position.from_position(T[..., :3, 3]))
        if self.rotation is not None:
            parts.append(self.rotation.from_rotation(T[..., :3, :3]))
        chi = parts[0] if len(parts) == 1 else np.concatenate(parts, axis=-1)
        return chi if self.rows is None else chi[..., self.rows]

    def jacobian_single(self, C: list[list[float]], p: list[float], J: np.ndarray, threshold: float) -> np.ndarray:
        """The single-sample fast path of :meth:`jacobian`: C_IF and p as Python floats.

        Scalar math builds E = blockdiag(E_P, E_R) as one (m, 6) array; J_A = E·J_e0 is one product.
        """
        entries: tuple[float, ...] = ()
        if self.position is not None:
            P = self.position
            if P.name == "cartesian":
                entries = _IDENTITY_ROWS
            else:
                chi = P._from_position(math, *p)
                distance = P._distance(math, *chi)
                if distance < threshold:
                    raise _singularity_error(P, float(distance), threshold, _pose(C, p))
                entries = _rows_with_zeros(P._E(math, *chi), left=True)
        if self.rotation is not None:
            R = self.rotation
            (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = C
            chi = R._from_rotation(math, False, c00, c01, c02, c10, c11, c12, c20, c21, c22)
            distance = R._distance(math, *chi)
            if distance < threshold:
                raise _singularity_error(R, float(distance), threshold, _pose(C, p))
            entries += _rows_with_zeros(R._E(math, *chi), left=False)
        E = np.ndarray((len(entries) // 6, 6), _F64, _packer(len(entries)).pack(*entries))
        JA = E.dot(J)
        return JA if self.rows is None else JA[self.rows, :]

    def jacobian(self, T: np.ndarray, J: np.ndarray, threshold: float) -> np.ndarray:
        """J_A = E(χ) · J_e0 for J_e0 in "local_world_aligned", (6, dof) -> (m, dof), batched too.

        Raises RepresentationSingularityError when χ is within ``threshold`` of its singular set.
        """
        out = []
        if self.position is not None:
            chi_p = self.position.from_position(T[..., :3, 3])
            self._check(self.position, chi_p, threshold, T)
            out.append(self.position.E(chi_p) @ J[..., :3, :])
        if self.rotation is not None:
            chi_r = self.rotation.from_rotation(T[..., :3, :3], warn=False)  # we raise instead
            self._check(self.rotation, chi_r, threshold, T)
            out.append(self.rotation.E(chi_r) @ J[..., 3:, :])
        JA = out[0] if len(out) == 1 else np.concatenate(out, axis=-2)
        return JA if self.rows is None else JA[..., self.rows, :]

    @staticmethod
    def _check(param: object, chi: np.ndarray, threshold: float, T: np.ndarray) -> None:
        distance = np.min(param.singularity_distance(chi))
        if distance < threshold:
            raise _singularity_error(param, float(distance), threshold, T)


def _singularity_error(param: object, distance: float, threshold: float,
                       T: np.ndarray) -> RepresentationSingularityError:
    """The error, with the parameterizations that are regular at the same pose."""
    if T.ndim == 3:
        sample = int(np.argmin(param.singularity_distance(
            param.from_position(T[:, :3, 3]) if param.kind == "position" else _quiet_rotation(param, T))))
        T = T[sample]
        detail_prefix = f"sample {sample}: "
    else:
        detail_prefix = ""
    if param.kind == "position":
        family, value = POSITION_PARAMETERIZATIONS, T[:3, 3]
        convert = "from_position"
    else:
        family, value = ROTATION_PARAMETERIZATIONS, T[:3, :3]
        convert = "from_rotation"
    regular = []
    for name, other in family.items():
        chi = other.from_position(value) if convert == "from_position" else other.from_rotation(value, warn=False)
        if float(np.min(other.singularity_distance(chi))) > 0.1:
            regular.append(name)
    preferred = [n for n in ("quaternion", "rotation_matrix", "euler_zyz", "euler_xyz", "cartesian") if n in regular]
    alternatives = preferred + [n for n in regular if n not in preferred]
    return RepresentationSingularityError(param.name, distance, threshold, alternatives[:4],
                                          detail_prefix + param.singular_set)


_PACKERS: dict[int, struct.Struct] = {}
_F64 = np.dtype(np.float64)
_IDENTITY_ROWS = (1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
_ZEROS = (0.0, 0.0, 0.0)


def _packer(n: int) -> struct.Struct:
    """struct for n doubles: packs Python floats into bytes numpy can wrap without a copy."""
    packer = _PACKERS.get(n)
    if packer is None:
        packer = _PACKERS[n] = struct.Struct(f"{n}d")
    return packer


def _rows_with_zeros(E: Sequence[float], *, left: bool) -> tuple[float, ...]:
    """Row-major (m, 3) entries widened to (m, 6): [E, 0] (position) or [0, E] (rotation)."""
    out: tuple[float, ...] = ()
    for i in range(0, len(E), 3):
        out += (E[i], E[i + 1], E[i + 2]) + _ZEROS if left else _ZEROS + (E[i], E[i + 1], E[i + 2])
    return out


def _quiet_rotation(param: object, T: np.ndarray) -> np.ndarray:
    return param.from_rotation(T[..., :3, :3], warn=False)


def _pose(C: list[list[float]], p: list[float]) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = C, p
    return T


@lru_cache(maxsize=256)
def pose_map(position: str | None, rotation: str | None, rows: tuple[str | int, ...] | None = None) -> PoseMap:
    """Resolve parameterization names (and an optional row selection by label or index) once."""
    if position is None and rotation is None:
        raise ParameterizationError("position and rotation are both None: choose at least one, e.g. "
                                    "position='cartesian' or rotation='quaternion'")
    p = None if position is None else _lookup(get_position, position)
    r = None if rotation is None else _lookup(get_rotation, rotation)
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
            raise ParameterizationError(f"unknown row {row!r}; rows of this parameterization: {', '.join(labels)}")
    if len(set(index)) != len(index):
        raise ParameterizationError(f"rows {rows} select a row twice")
    return PoseMap(p, r, tuple(labels[i] for i in index), tuple(index))


def _lookup(getter, name: object):
    if not isinstance(name, str):
        raise ParameterizationError(f"parameterization names are strings, got {name!r}")
    return getter(name)


def as_rows(rows: Sequence[str | int] | str | None) -> tuple[str | int, ...] | None:
    """A hashable row selection (a single label is accepted as a one-row selection)."""
    if rows is None:
        return None
    if isinstance(rows, str):
        return (rows,)
    return tuple(rows)
