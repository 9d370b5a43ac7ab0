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
import sys
import warnings
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from types import FrameType, ModuleType
from typing import Any, TypeAlias

import numpy as np
import numpy.typing as npt

from ..errors import ParameterizationError, RepresentationSingularityError

SMALL_ANGLE_SQ = 1e-2
"""θ² below which coefficients with a division by a power of θ use their Taylor series (through θ⁸;
relative truncation error < 1e-14 there). Decided on θ², never on θ."""

Namespace: TypeAlias = ModuleType
"""The namespace the formulas run over: :mod:`math` (one sample) or :mod:`numpy` (a batch)."""
Component: TypeAlias = Any
"""One scalar component in a formula: a Python float (xp = math) or a float64 array of the batch shape
(xp = numpy). ``Any``: which one is decided at run time by ``xp``, which a type checker cannot follow."""
Entries: TypeAlias = tuple[Component, ...]
"""Row-major entries of a formula's result (a vector or matrix), each a Component."""
Values: TypeAlias = Sequence[Component]
"""The components of χ or of u given to a formula as one sequence (a tuple or list of Components)."""
FloatArray: TypeAlias = npt.NDArray[np.float64]

_KINENGINE_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + os.sep


def as_float_array(value: npt.ArrayLike, tail: tuple[int, ...], what: str) -> FloatArray:
    """``value`` as a float64 array of shape tail or (..., *tail); ParameterizationError otherwise (complex
    values, dates and None too: numpy would drop the imaginary parts, keep the dates' counts, make NaN)."""
    try:
        array = np.asarray(value)
        if array.dtype.kind == "O":  # float() of each entry: refuses None, complex and other objects
            array = np.array([float(x) for x in array.ravel()]).reshape(array.shape)
        if array.dtype.kind in "biufUS":  # numbers, or text numpy reads as numbers
            array = array.astype(np.float64, copy=False)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ParameterizationError(f"Expected `{what}` to be an array of real numbers: {exc}") from None
    if array.dtype != np.float64:  # complex, dates, durations, structured
        raise ParameterizationError(f"Expected `{what}` to be real numbers, got {array.dtype} values")
    if array.shape[max(0, array.ndim - len(tail)) :] != tail:
        batched = ", ".join(map(str, tail))
        raise ParameterizationError(
            f"Expected `{what}` to have shape {tail} or (..., {batched}), got {array.shape}"
        )
    return array


def apply(formula: Callable[..., Entries], values: FloatArray, shape: tuple[int, ...]) -> FloatArray:
    """A formula of the components of the last axis of ``values``: one sample (n,) -> ``shape`` (on Python
    floats, ``xp`` = math), a batch (..., n) -> (..., *shape) (on arrays, ``xp`` = numpy)."""
    if values.ndim == 1:
        return np.array(formula(math, *values.tolist())).reshape(shape)
    batch = values.shape[:-1]
    entries = formula(np, *np.moveaxis(values, -1, 0))
    out = np.empty(batch + (len(entries),))
    for k, entry in enumerate(entries):
        out[..., k] = entry
    return out.reshape(batch + shape)


def where(xp: Namespace, condition: Component, a: Component, b: Component) -> Component:
    """``a`` where ``condition`` holds, else ``b``: one sample (``xp`` = math) or each entry of a batch."""
    return (a if condition else b) if xp is math else np.where(condition, a, b)


def is_singular(distance: float, threshold: float) -> bool:
    """True where a distance to a singular set counts as singular: below ``threshold``, NaN, or exactly 0
    (E has no finite value there, whatever the threshold)."""
    return not distance >= threshold or distance == 0.0


def singular_where(distance: npt.ArrayLike, threshold: float) -> npt.NDArray[np.bool_]:
    """:func:`is_singular` of every entry of an array of distances."""
    distance = np.asarray(distance)
    return ~(distance >= threshold) | (distance == 0.0)


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

    A family writes five formulas over ``xp`` (:meth:`_E`, :meth:`_E_inverse`, :meth:`_E_dot`,
    :meth:`_distance` and χ from the pose); this class gives them their checks, batches and errors.
    """

    name: str
    kind: str
    labels: tuple[str, ...]
    singular_set: str
    alternatives: tuple[str, ...]
    """Parameterizations regular wherever this one is singular (for error messages)."""

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
        return self._evaluate(self._E, (self.size, 3), as_float_array(chi, (self.size,), "chi"))

    def E_inverse(self, chi: npt.ArrayLike) -> FloatArray:
        """(m,) -> (3, m), batched (..., 3, m): u = E_inverse(χ)·χ̇, with E_inverse(χ)·E(χ) = I_3."""
        return self._evaluate(self._E_inverse, (3, self.size), as_float_array(chi, (self.size,), "chi"))

    def E_dot(self, chi: npt.ArrayLike, velocity: npt.ArrayLike) -> FloatArray:
        """dE/dt along the motion with u = velocity (v [m/s] or ω [rad/s] in I): (m,), (3,) -> (m, 3).

        Batched: (..., m) and (..., 3) broadcast to (..., m, 3). J̇_A = Ė·J_e0 + E·J̇_e0.
        """
        m = self.size
        chi, u = as_float_array(chi, (m,), "chi"), as_float_array(velocity, (3,), "velocity")
        if chi.ndim == 1 and u.ndim == 1:  # one sample (a controller's step): the formula on Python floats
            try:
                return np.array(self._E_dot(math, chi.tolist(), u.tolist())).reshape(m, 3)
            except ZeroDivisionError:
                raise self._singular_error() from None
        batch = np.broadcast_shapes(chi.shape[:-1], u.shape[:-1])
        both = np.concatenate((np.broadcast_to(chi, batch + (m,)), np.broadcast_to(u, batch + (3,))), axis=-1)
        return self._evaluate(lambda xp, *c: self._E_dot(xp, c[:m], c[m:]), (m, 3), both)

    def singularity_distance(self, chi: npt.ArrayLike) -> float | FloatArray:
        """(m,) -> float, (..., m) -> (...,): >= 0, zero exactly on the singular set, ~ the vanishing
        sine/cosine/radius there (E's entries grow like 1/distance); ``inf`` if never singular."""
        distance = apply(
            lambda xp, *c: (self._distance(xp, *c),), as_float_array(chi, (self.size,), "chi"), ()
        )
        return float(distance) if distance.ndim == 0 else distance

    def _evaluate(
        self, formula: Callable[..., Entries], shape: tuple[int, int], values: FloatArray
    ) -> FloatArray:
        """:func:`apply` of a rate formula; RepresentationSingularityError where an entry has no finite value
        (the sample is on the singular set)."""
        if values.ndim == 1:  # Python floats: no errstate to set up; a division by zero raises
            try:
                return apply(formula, values, shape)
            except ZeroDivisionError:
                raise self._singular_error() from None
        with np.errstate(all="ignore"):
            out = apply(formula, values, shape)
        if not np.isfinite(out).all():
            raise self._singular_error()
        return out

    def _singular_error(self) -> RepresentationSingularityError:
        return RepresentationSingularityError(self.name, 0.0, 0.0, self.alternatives, self.singular_set)

    @abstractmethod
    def _coordinates(self, xp: Namespace, p: Values, C: Values) -> Entries:
        """χ at the pose with origin p (3 components) and C_IE (9, row-major), without warnings."""

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
        return apply(self._from_position, as_float_array(pos, (3,), "pos"), (self.size,))

    def to_position(self, chi: npt.ArrayLike) -> FloatArray:
        """p [m] in I from χ_P: (m,) -> (3,), (..., m) -> (..., 3)."""
        return apply(self._to_position, as_float_array(chi, (self.size,), "chi"), (3,))

    def _coordinates(self, xp: Namespace, p: Values, C: Values) -> Entries:
        return self._from_position(xp, *p)

    def _azimuth(self, xp: Namespace, x: Component, y: Component) -> tuple[Component, Component]:
        """(ρ, θ) = (√(x² + y²), atan2(y, x)) [m, rad] of a point; a UserWarning on the z axis (ρ = 0), where
        the azimuth θ is undefined (atan2(0, 0) = 0)."""
        rho = xp.sqrt(x * x + y * y)
        warn_where(xp, rho == 0.0, f"{self.name}: point on the z axis (ρ = 0); azimuth θ undefined, set to 0")
        return rho, xp.atan2(y, x)

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
        C = as_float_array(C, (3, 3), "C")
        rows = C.reshape(C.shape[:-2] + (9,))
        return apply(lambda xp, *c: self._from_rotation(xp, warn, *c), rows, (self.size,))

    def to_rotation(self, chi: npt.ArrayLike) -> FloatArray:
        """C_IE from χ_R: (m,) -> (3, 3), (..., m) -> (..., 3, 3)."""
        return apply(self._to_rotation, as_float_array(chi, (self.size,), "chi"), (3, 3))

    def chart(self, *C: float) -> tuple[list[float], float, Entries] | None:
        """(χ in the ranges of :meth:`from_rotation`, its distance to the singular set, E(χ)'s row-major
        entries) at one pose C_IE given by its 9 row-major entries (Python floats): the single-pose rate map
        of the analytic Jacobian and the Task. None where χ is not unique (gimbal lock) or E is not finite:
        the caller's general path then decides. A family may override it to share intermediate values."""
        chi = list(self._from_rotation(math, False, *C))
        try:
            distance = self._distance(math, *chi)
            return (chi, distance, self._E(math, *chi)) if distance != 0.0 else None
        except ZeroDivisionError:
            return None

    def _coordinates(self, xp: Namespace, p: Values, C: Values) -> Entries:
        return self._from_rotation(xp, False, *C)

    @abstractmethod
    def _from_rotation(self, xp: Namespace, warn: bool, *c: Component) -> Entries: ...
    @abstractmethod
    def _to_rotation(self, xp: Namespace, *chi: Component) -> Entries: ...
