"""Base classes of the end-effector parameterizations χ_P(p) and χ_R(C_IE) and of their rate maps E.

χ̇_P = E_P(χ_P)·v and χ̇_R = E_R(χ_R)·ω (Robot Dynamics lecture notes, ETH Zurich, section 2.8, eq. 2.180),
with v the velocity of the frame origin [m/s] and ω the angular velocity [rad/s], both expressed in the
inertial (root) frame I; J_A = E·J_e0.

Every method takes one sample (χ of shape (m,), p of shape (3,), C of shape (3, 3)) or a batch with any
leading axes ((..., m), (..., 3), (..., 3, 3)). Each family writes its formulas once, as functions of
scalar components over a namespace ``xp`` that is either :mod:`math` (one sample: Python floats, the result
built by one numpy call) or :mod:`numpy` (a batch: the same formulas on arrays, no loop over samples).
Both namespaces spell cos, sin, tan, atan2, hypot, sqrt alike; formulas that branch test ``xp is math``.
"""

from __future__ import annotations

import math
import os
import struct
import sys
import warnings
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from types import FrameType, ModuleType
from typing import Any, TypeAlias, TypeGuard

import numpy as np
import numpy.typing as npt

from ..errors import ParameterizationError, RepresentationSingularityError

SMALL_ANGLE_SQ = 1e-2
"""θ² below which coefficients with a division by a power of θ use their Taylor series (through θ⁸;
relative truncation error < 1e-14 there). Decided on θ², never on θ."""

Namespace: TypeAlias = ModuleType
"""The namespace the formulas run over: :mod:`math` (one sample) or :mod:`numpy` (a batch)."""
Component: TypeAlias = Any
"""One scalar component in a formula: a Python float when ``xp`` is math, a float64 array of the batch
shape when ``xp`` is numpy. ``Any`` because which of the two is decided at run time by ``xp`` (the
formulas branch on ``xp is math``), which a type checker cannot follow: a union would flag every
``math.*`` call on an array and every ``bool()`` of an array comparison."""
Entries: TypeAlias = tuple[Component, ...]
"""Row-major entries of a formula's result (a vector or matrix), each a Component."""
Values: TypeAlias = Sequence[Component]
"""The components of χ or of u given to a formula as one sequence (a tuple or list of Components)."""
FloatArray: TypeAlias = npt.NDArray[np.float64]

_ND = np.ndarray
_F8 = np.dtype(np.float64)
_PACK9 = struct.Struct("9d")
_KINENGINE_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + os.sep


def is_single(value: object, shape: tuple[int, ...]) -> TypeGuard[FloatArray]:
    """True for one float64 sample of exactly ``shape`` (the fast path: its .tolist() gives floats)."""
    return type(value) is _ND and value.dtype is _F8 and value.shape == shape


def as_float_array(value: npt.ArrayLike, tail: tuple[int, ...], what: str) -> FloatArray:
    """``value`` as a float64 array of shape tail or (..., *tail); ParameterizationError otherwise."""
    array = np.asarray(value, dtype=np.float64)
    n = len(tail)
    if array.ndim < n or array.shape[array.ndim - n :] != tail:
        expected = str(tail) if n > 1 else f"({tail[0]},)"
        batched = "(..., " + ", ".join(str(t) for t in tail) + ")"
        raise ParameterizationError(
            f"Expected `{what}` to have shape {expected} or {batched}, got {array.shape}"
        )
    return array


def columns(array: FloatArray, n: int) -> list[FloatArray]:
    """The n entries of the last axis of a batch (..., n), each of shape (...,)."""
    return [array[..., k] for k in range(n)]


def stack(entries: Entries, batch: tuple[int, ...], shape: tuple[int, ...]) -> FloatArray:
    """Assemble row-major ``entries`` (arrays of shape batch, or constants) into (*batch, *shape)."""
    out = np.empty(batch + (len(entries),))
    for k, entry in enumerate(entries):
        out[..., k] = entry
    return out.reshape(batch + shape)


def warn_where(xp: Namespace, condition: Component, message: str) -> None:
    """UserWarning if ``condition`` holds for any sample, attributed to the first caller outside kinengine."""
    if condition if xp is math else bool(np.any(condition)):
        frame: FrameType | None = sys._getframe(1)
        level = 2  # level 1 is this function, 2 its caller
        while frame is not None and frame.f_code.co_filename.startswith(_KINENGINE_DIR):
            frame, level = frame.f_back, level + 1
        warnings.warn(message, UserWarning, stacklevel=level)


class Parameterization(ABC):
    """χ ∈ R^m and its rate map E(χ): χ̇ = E(χ)·u with u = v (position) or ω (rotation) in I.

    One sample is built as ndarray(shape, float64, bytearray(struct.pack(*floats))): measured about half
    the cost of np.array(floats).reshape(shape) for 9 to 27 entries.
    """

    name: str
    kind: str
    labels: tuple[str, ...]
    singular_set: str
    alternatives: tuple[str, ...]
    """Parameterizations regular wherever this one is singular (for error messages)."""

    def __init__(self) -> None:
        m = len(self.labels)
        self._one, self._E_shape, self._E_inverse_shape = (m,), (m, 3), (3, m)
        self._pack = struct.Struct(f"{3 * m}d").pack  # E, E_inverse and E_dot all have 3m entries

    @property
    def size(self) -> int:
        """m, the number of coordinates."""
        return len(self.labels)

    def __repr__(self) -> str:
        return f"<{self.kind} parameterization {self.name!r} {self.labels}>"

    def E(self, chi: npt.ArrayLike) -> FloatArray:
        """E(χ), (m,) -> (m, 3) or (..., m) -> (..., m, 3): χ̇ = E(χ)·u, u = v [m/s] or ω [rad/s] in I.

        Raises RepresentationSingularityError where E has no finite value (distance exactly 0).
        """
        if type(chi) is _ND and chi.dtype is _F8 and chi.shape == self._one:
            try:
                return _ND(self._E_shape, _F8, bytearray(self._pack(*self._E(math, *chi.tolist()))))
            except ZeroDivisionError:
                raise self._singular_error() from None
        return self._general(self._E, chi, self._E_shape)

    def E_inverse(self, chi: npt.ArrayLike) -> FloatArray:
        """(m,) -> (3, m), batched (..., 3, m): u = E_inverse(χ)·χ̇, with E_inverse(χ)·E(χ) = I_3."""
        if type(chi) is _ND and chi.dtype is _F8 and chi.shape == self._one:
            entries = self._E_inverse(math, *chi.tolist())
            return _ND(self._E_inverse_shape, _F8, bytearray(self._pack(*entries)))
        return self._general(self._E_inverse, chi, self._E_inverse_shape)

    def E_dot(self, chi: npt.ArrayLike, velocity: npt.ArrayLike) -> FloatArray:
        """dE/dt along the motion with u = velocity (v [m/s] or ω [rad/s] in I): (m,), (3,) -> (m, 3).

        Batched: (..., m) and (..., 3) broadcast to (..., m, 3). J̇_A = Ė·J_e0 + E·J̇_e0.
        """
        m = len(self.labels)
        chi = as_float_array(chi, (m,), "chi")
        u = as_float_array(velocity, (3,), "velocity")
        if chi.ndim == 1 and u.ndim == 1:
            try:
                entries = self._E_dot(math, chi.tolist(), u.tolist())
                return _ND(self._E_shape, _F8, bytearray(self._pack(*entries)))
            except ZeroDivisionError:
                raise self._singular_error() from None
        batch = np.broadcast_shapes(chi.shape[:-1], u.shape[:-1])
        chi = np.broadcast_to(chi, batch + (m,))
        u = np.broadcast_to(u, batch + (3,))
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            entries = self._E_dot(np, columns(chi, m), columns(u, 3))
        return self._finite(stack(entries, batch, (m, 3)))

    def singularity_distance(self, chi: npt.ArrayLike) -> float | FloatArray:
        """(m,) -> float, (..., m) -> (...,): >= 0, zero exactly on the singular set, ~ the vanishing
        sine/cosine/radius there (E's entries grow like 1/distance); ``inf`` if never singular."""
        if type(chi) is _ND and chi.dtype is _F8 and chi.shape == self._one:
            return float(self._distance(math, *chi.tolist()))
        chi = as_float_array(chi, self._one, "chi")
        if chi.ndim == 1:
            return float(self._distance(math, *chi.tolist()))
        return np.broadcast_to(self._distance(np, *columns(chi, chi.shape[-1])), chi.shape[:-1]).copy()

    def _general(
        self, formula: Callable[..., Entries], chi: npt.ArrayLike, shape: tuple[int, int]
    ) -> FloatArray:
        """formula for any input: a single sample of another type, or a batch (..., m) -> (..., *shape)."""
        m = len(self.labels)
        chi = as_float_array(chi, (m,), "chi")
        if chi.ndim == 1:
            try:
                return np.array(formula(math, *chi.tolist())).reshape(shape)
            except ZeroDivisionError:
                raise self._singular_error() from None
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            entries = formula(np, *columns(chi, m))
        return self._finite(stack(entries, chi.shape[:-1], shape))

    def _finite(self, out: np.ndarray) -> FloatArray:
        if not np.isfinite(out).all():
            raise self._singular_error()
        return out

    def _singular_error(self) -> RepresentationSingularityError:
        return RepresentationSingularityError(self.name, 0.0, 0.0, self.alternatives, self.singular_set)

    @abstractmethod
    def _E(self, xp: Namespace, *chi: Component) -> Entries: ...

    @abstractmethod
    def _E_inverse(self, xp: Namespace, *chi: Component) -> Entries: ...

    @abstractmethod
    def _E_dot(self, xp: Namespace, chi: Values, u: Values) -> Entries: ...

    @abstractmethod
    def _distance(self, xp: Namespace, *chi: Component) -> Component: ...


class PositionParameterization(Parameterization):
    """χ_P(p) for the frame origin p [m] in the inertial frame I; E_P maps v (in I) to χ̇_P."""

    kind = "position"
    alternatives: tuple[str, ...] = ("cartesian",)

    def from_position(self, pos: npt.ArrayLike) -> FloatArray:
        """χ_P from p [m] in I: (3,) -> (m,), (..., 3) -> (..., m)."""
        if not is_single(pos, (3,)):
            pos = as_float_array(pos, (3,), "pos")
            if pos.ndim > 1:
                return stack(self._from_position(np, *columns(pos, 3)), pos.shape[:-1], self._one)
        return np.array(self._from_position(math, *pos.tolist()))

    def to_position(self, chi: npt.ArrayLike) -> FloatArray:
        """p [m] in I from χ_P: (m,) -> (3,), (..., m) -> (..., 3)."""
        chi = as_float_array(chi, self._one, "chi")
        if chi.ndim == 1:
            return np.array(self._to_position(math, *chi.tolist()))
        return stack(self._to_position(np, *columns(chi, self.size)), chi.shape[:-1], (3,))

    @abstractmethod
    def _from_position(self, xp: Namespace, x: Component, y: Component, z: Component) -> Entries: ...

    @abstractmethod
    def _to_position(self, xp: Namespace, *chi: Component) -> Entries: ...


class RotationParameterization(Parameterization):
    """χ_R(C) for C = C_IE, the rotation of the frame E in the inertial frame I; E_R maps ω (in I) to χ̇_R."""

    kind = "rotation"
    alternatives: tuple[str, ...] = ("quaternion", "rotation_matrix")

    def from_rotation(self, C: npt.ArrayLike, *, warn: bool = True) -> FloatArray:
        """χ_R from C_IE: (3, 3) -> (m,), (..., 3, 3) -> (..., m).

        Where χ_R is not unique (a singular set) a documented choice is returned and, if ``warn``,
        a UserWarning is issued.
        """
        if not (type(C) is _ND and C.dtype is _F8 and C.shape == (3, 3)):
            C = as_float_array(C, (3, 3), "C")
            if C.ndim > 2:
                entries = self._from_rotation(np, warn, *columns(C.reshape(C.shape[:-2] + (9,)), 9))
                return stack(entries, C.shape[:-2], self._one)
        (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = C.tolist()
        return np.array(self._from_rotation(math, warn, c00, c01, c02, c10, c11, c12, c20, c21, c22))

    def chart(self, *C: float) -> tuple[list[float], float, Entries] | None:
        """(χ, its distance to the singular set, E(χ)'s row-major entries) at one pose C_IE given by its 9
        row-major entries (Python floats), χ in the canonical ranges of :meth:`from_rotation`. None where
        χ is not unique (gimbal lock) or E has no finite value: the caller's general path then decides.

        The single-pose rate map that the analytic Jacobian and the Task call: :meth:`_from_rotation`,
        :meth:`_distance` and :meth:`_E` (a family may share their intermediate values, as Euler angles do).
        """
        chi = list(self._from_rotation(math, False, *C))
        try:
            distance = self._distance(math, *chi)
            return (chi, distance, self._E(math, *chi)) if distance != 0.0 else None
        except ZeroDivisionError:
            return None

    def pose_rate(self, C: FloatArray) -> tuple[float, FloatArray | Entries] | None:
        """(distance to the singular set, E_R) at one pose C_IE (3, 3) float64: χ̇_R = E_R·ω with ω [rad/s]
        in I. E_R is :meth:`chart`'s row-major entries (Python floats), or an (m, 3) array where Pinocchio
        computes it (euler_zyx; rotation_vector below JLOG3_MAX_ANGLE). None as for :meth:`chart`."""
        (c00, c01, c02), (c10, c11, c12), (c20, c21, c22) = C.tolist()
        found = self.chart(c00, c01, c02, c10, c11, c12, c20, c21, c22)
        return None if found is None else (found[1], found[2])

    def to_rotation(self, chi: npt.ArrayLike) -> FloatArray:
        """C_IE from χ_R: (m,) -> (3, 3), (..., m) -> (..., 3, 3)."""
        chi = as_float_array(chi, self._one, "chi")
        if chi.ndim == 1:
            return _ND((3, 3), _F8, bytearray(_PACK9.pack(*self._to_rotation(math, *chi.tolist()))))
        return stack(self._to_rotation(np, *columns(chi, self.size)), chi.shape[:-1], (3, 3))

    @abstractmethod
    def _from_rotation(self, xp: Namespace, warn: bool, *c: Component) -> Entries: ...

    @abstractmethod
    def _to_rotation(self, xp: Namespace, *chi: Component) -> Entries: ...
