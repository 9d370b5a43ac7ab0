"""The user's joint coordinates q and the constant affine map to Pinocchio's: q_pin = M q + b.

kinengine's q holds exactly one coordinate per independent movable joint, in ``names`` order
(Pinocchio's depth-first tree order, mimic joints left out): revolute and continuous joints in
[rad], prismatic joints in [m]. Pinocchio's model has one plain joint per movable URDF joint
(nq = nv = 1 each, continuous joints included), so its configuration is the vector of every
movable joint's value. Row i of (M, b) says which coordinate drives Pinocchio's joint i and how:
an independent joint is an identity row; a mimic joint θ = m·q_leader + o (a mimic of a mimic
composed down to its root leader). Velocities and Jacobians fold the same way: q̇_pin = M q̇,
J = J_pin · M. Without mimic joints M is the identity and q passes to Pinocchio untouched.
"""

from __future__ import annotations

import math
import numbers
import struct
from collections.abc import Callable, Mapping
from typing import TypeGuard

import numpy as np

from ..errors import ConfigurationError, FrameNotFoundError, OptionError
from ..urdf import RobotDescription
from . import accelerator
from .mimics import mimic_roots, narrow_by_mimics

_F64 = np.dtype(np.float64)
_SMALL_BATCH = 256
"""Up to this many entries, a ready batch is checked by one scalar hypot instead of two numpy reductions."""
MAX_MAGNITUDE = 1e9
"""[m or rad] the largest |q_i| accepted: beyond it a prismatic coordinate (or a mimic multiplier times
one) could overflow a pose; an angle of 1e9 rad is 1.6e8 turns. Limits beyond it are sampled within it."""
MAX_SAMPLES = 2**28
"""The most numbers one random_configuration call makes (2 GiB of float64)."""


class CoordinateMap:
    """Joint names, limits, the checked input q and its constant map to Pinocchio's coordinates."""

    def __init__(self, description: RobotDescription) -> None:
        movable = [j for j in description.joints if j.movable]
        roots = mimic_roots(description)
        names = [j.name for j in movable if j.name not in roots]
        index = {n: i for i, n in enumerate(names)}
        self.names: tuple[str, ...] = tuple(names)
        self.dof = len(names)
        self.nq = len(movable)
        self.pinocchio_names: tuple[str, ...] = tuple(j.name for j in movable)
        leader = np.empty(self.nq, dtype=np.intp)
        multiplier, offset = np.ones(self.nq), np.zeros(self.nq)
        for k, joint in enumerate(movable):
            root, m, o = roots.get(joint.name, (joint.name, 1.0, 0.0))
            leader[k], multiplier[k], offset[k] = index[root], m, o
        self.leader, self.multiplier, self.offset = leader, multiplier, offset
        self.identity = not roots
        M = np.zeros((self.nq, self.dof))
        M[np.arange(self.nq), leader] = multiplier
        self.matrix, self.has_offset = M, bool(offset.any())
        self.independent = np.array([k for k, j in enumerate(movable) if j.name not in roots], dtype=np.intp)
        joints = {j.name: j for j in movable}
        lower = np.array([_or(joints[n].lower, -np.inf) for n in names])
        upper = np.array([_or(joints[n].upper, np.inf) for n in names])
        self._narrowed_by = narrow_by_mimics(description, roots, index, self.names, lower, upper)
        lower.flags.writeable = upper.flags.writeable = False
        self.lower, self.upper = lower, upper
        self.continuous = np.array([joints[n].type == "continuous" for n in names], dtype=bool)
        self._index = index
        self.ready: Callable[[object], TypeGuard[np.ndarray]] = _ready_vector(self.dof)
        """``ready(q)``: True only if q is already a C-contiguous float64 ndarray of shape (dof,) with every
        |q_i| <= MAX_MAGNITUDE (finite): :meth:`check` returns it as it is. The one check's fast path (in C
        when :mod:`kinengine.model.accelerator` runs; a q it passes by goes through the full check)."""
        self._mimics = {name: root[0] for name, root in roots.items()}

    # -- the map ------------------------------------------------------------------------------
    def to_pinocchio(self, q: np.ndarray) -> np.ndarray:
        """Pinocchio's configuration for a checked q: (dof,) -> (nq,), (N, dof) -> (N, nq); q itself
        if M = I."""
        if self.identity:
            return q
        out = q[..., self.leader] * self.multiplier
        if self.has_offset:
            out += self.offset
        return out

    def from_pinocchio(self, q_pin: np.ndarray) -> np.ndarray:
        """The user's q from a Pinocchio configuration (the independent joints' entries), a fresh array."""
        return np.array(np.asarray(q_pin, dtype=float)[..., self.independent])

    def velocity_to_pinocchio(self, qdot: np.ndarray) -> np.ndarray:
        """q̇_pin = M q̇ (q̇ itself if M = I)."""
        return qdot if self.identity else self.matrix @ qdot

    def fold(self, J_pin: np.ndarray) -> np.ndarray:
        """J = J_pin · M for arrays whose last axis is over Pinocchio's nv (or J_pin itself if M = I)."""
        return J_pin if self.identity else J_pin @ self.matrix

    # -- checking -----------------------------------------------------------------------------
    def check(
        self, q: object, *, name: str = "q", check_limits: bool = False, allow_batch: bool = True
    ) -> np.ndarray:
        """q as a C-contiguous float64 array of shape (dof,) or (N >= 1, dof); ConfigurationError otherwise.

        ints, float32, lists, tuples, strided, Fortran-ordered and read-only arrays are
        accepted and converted (a new array when conversion is needed; the input is never
        modified). NaN/inf, strings, None, booleans, complex, masked entries, empty batches
        and wrongly shaped input are refused with the expected shape in the message. A q that is
        :attr:`ready` is returned unchanged.
        """
        if self.ready(q):  # a float64 vector of the right length and magnitude: returned as it is
            pass
        elif (
            allow_batch
            and type(q) is np.ndarray
            and q.dtype is _F64
            and q.ndim == 2
            and q.shape[0]
            and q.shape[1] == self.dof
            and q.flags.c_contiguous
        ):  # a ready batch: one hypot (small) or max/min (large) bounds every entry; NaN fails both
            if not (
                math.hypot(*q.ravel().tolist()) <= MAX_MAGNITUDE
                if q.size <= _SMALL_BATCH
                else q.min() >= -MAX_MAGNITUDE and q.max() <= MAX_MAGNITUDE
            ):
                self._check_values(q, name)
        else:
            q = self._convert(q, name, allow_batch)
        if check_limits is not False:  # the default costs one identity test
            if check_limits is not True and not isinstance(check_limits, np.bool_):
                raise OptionError(f"check_limits must be True or False, got {type(check_limits).__name__}")
            if check_limits:
                self.check_limits(q, name=name)
        return q

    def _convert(self, q: object, name: str, allow_batch: bool) -> np.ndarray:
        expected = f"({self.dof},)" + (f" or (N, {self.dof})" if allow_batch else "")
        if q is None:
            raise ConfigurationError(f"Expected `{name}` to be an array of shape {expected}, got None")
        if isinstance(q, (str, bytes)):
            raise ConfigurationError(f"Expected `{name}` to be numeric with shape {expected}, got a string")
        if np.ma.is_masked(q):
            raise ConfigurationError(
                f"Expected `{name}` to have a value for every joint, got a masked array "
                "with masked entries; fill them (q.filled(...)) first"
            )
        try:
            arr = np.asarray(q)
        except Exception as exc:  # ragged sequences and the like
            raise ConfigurationError(
                f"Expected `{name}` to be numeric with shape {expected}: {exc}"
            ) from None
        if arr.dtype.kind == "O":
            arr = self._from_objects(arr, q, name, expected)
        elif arr.dtype.kind not in "iuf":
            raise ConfigurationError(
                f"Expected `{name}` to hold real numbers with shape {expected}, got dtype {arr.dtype}"
            )
        if arr.ndim == 0 or arr.shape[-1] != self.dof or arr.ndim > (2 if allow_batch else 1):
            hint = (
                "; this function takes one configuration: call it once per row"
                if not allow_batch and arr.ndim == 2 and arr.shape[-1] == self.dof
                else ""
            )
            raise ConfigurationError(f"Expected `{name}` to have shape {expected}, got {arr.shape}{hint}")
        if arr.ndim == 2 and arr.shape[0] == 0:
            raise ConfigurationError(
                f"Expected `{name}` to hold at least one configuration, got an empty batch {arr.shape}"
            )
        arr = np.ascontiguousarray(arr, dtype=np.float64)
        self._check_values(arr, name)
        return arr

    @staticmethod
    def _from_objects(arr: np.ndarray, q: object, name: str, expected: str) -> np.ndarray:
        """An object array (e.g. Python numbers) as float64; ConfigurationError if an entry is not one."""
        what = f"a {type(q).__name__}" if arr.ndim == 0 else "an object array"
        if any(v is None for v in arr.flat):
            raise ConfigurationError(
                f"Expected `{name}` to hold real numbers with shape {expected}, got {what} with None entries"
            )
        try:
            return arr.astype(np.float64)
        except OverflowError:
            raise ConfigurationError(
                f"Expected `{name}` to hold real numbers with shape {expected}, "
                f"got {what} with a number too large for a float64"
            ) from None
        except (TypeError, ValueError):
            raise ConfigurationError(
                f"Expected `{name}` to hold real numbers with shape {expected}, "
                f"got {what} with non-numeric entries"
            ) from None

    def _check_values(self, q: np.ndarray, name: str) -> None:
        """ConfigurationError for a NaN/inf entry or one beyond ±MAX_MAGNITUDE (the slow path of check)."""
        if not np.isfinite(q).all():
            self._raise_nonfinite(q, name)
        if (np.abs(q) > MAX_MAGNITUDE).any():
            bad = np.argwhere(np.abs(q) > MAX_MAGNITUDE)[0]
            where = f"[{', '.join(map(str, bad))}]"
            raise ConfigurationError(
                f"`{name}`{where} (joint {self.names[bad[-1]]!r}) is {float(q[tuple(bad)])!r}: "
                f"coordinates beyond ±{MAX_MAGNITUDE:g} (m or rad) are refused, so that poses and "
                "Jacobians cannot overflow; wrap angles into [-π, π)"
            )

    def _raise_nonfinite(self, q: np.ndarray, name: str) -> None:
        bad = np.argwhere(~np.isfinite(q))[0]
        joint = self.names[bad[-1]]
        where = f"[{', '.join(map(str, bad))}]"
        raise ConfigurationError(
            f"`{name}`{where} (joint {joint!r}) is {float(q[tuple(bad)])}: "
            "every coordinate must be a finite number"
        )

    def check_limits(self, q: np.ndarray, *, name: str = "q") -> None:
        """ConfigurationError naming the first joint outside [lower, upper] (and its row in a batch)."""
        outside = (q < self.lower) | (q > self.upper)
        if outside.any():
            bad = np.argwhere(outside)[0]
            i = bad[-1]
            row = f"[{bad[0]}]" if q.ndim == 2 else ""
            why = (
                f" (narrowed so that mimic joint {', '.join(self._narrowed_by[i])})"
                if i in self._narrowed_by
                else ""
            )
            raise ConfigurationError(
                f"`{name}`{row} puts joint {self.names[i]!r} at {float(q[tuple(bad)])!r}, outside its limits "
                f"[{float(self.lower[i])!r}, {float(self.upper[i])!r}]{why}; "
                "clip q or pass check_limits=False"
            )

    # -- construction -------------------------------------------------------------------------
    def from_mapping(
        self, values: Mapping[str, float], base: np.ndarray, *, strict: bool = True
    ) -> np.ndarray:
        """q from joint name -> value (e.g. a ROS JointState); joints not named keep ``base``."""
        if not isinstance(values, Mapping):
            raise ConfigurationError(
                f"Expected a mapping of joint name to value, got {type(values).__name__}"
            )
        q = base.copy()
        for joint, value in values.items():
            i = self._index.get(joint)
            if i is None:
                if not strict:
                    continue
                if joint in self._mimics:
                    raise ConfigurationError(
                        f"joint {joint!r} is a mimic joint that follows {self._mimics[joint]!r} and takes no "
                        "coordinate; set the leader instead (or pass strict=False to ignore it)"
                    )
                raise FrameNotFoundError(joint, self.names, kind="joint")
            if isinstance(value, (bool, np.bool_)) or not isinstance(
                value, (numbers.Real, np.floating, np.integer)
            ):
                raise ConfigurationError(
                    f"joint {joint!r}: expected a real number, got {type(value).__name__} {_short(value)}"
                )
            try:
                v = float(value)
            except (TypeError, ValueError, OverflowError):
                raise ConfigurationError(
                    f"joint {joint!r}: expected a number that fits a float64, got {_short(value)}"
                ) from None
            if not math.isfinite(v) or abs(v) > MAX_MAGNITUDE:
                raise ConfigurationError(
                    f"joint {joint!r}: expected a finite number within ±{MAX_MAGNITUDE:g}, got {v}"
                )
            q[i] = v
        return q

    def sample(self, rng: np.random.Generator, size: int | None) -> np.ndarray:
        """Uniform samples within limits; unbounded (continuous) joints in [-π, π)."""
        if size is not None and (
            isinstance(size, bool) or not isinstance(size, (int, np.integer)) or size < 0
        ):
            raise OptionError(f"`size` must be None or a number of configurations >= 0, got {size!r}")
        lo = np.clip(np.where(np.isfinite(self.lower), self.lower, -np.pi), -MAX_MAGNITUDE, MAX_MAGNITUDE)
        hi = np.clip(np.where(np.isfinite(self.upper), self.upper, np.pi), -MAX_MAGNITUDE, MAX_MAGNITUDE)
        if size is not None and size * max(self.dof, 1) > MAX_SAMPLES:
            raise OptionError(
                f"`size` = {size} asks for {size * self.dof} numbers, more than {MAX_SAMPLES:g}; "
                "sample in smaller batches"
            )
        shape = (self.dof,) if size is None else (size, self.dof)
        return rng.uniform(lo, hi, size=shape)


def _ready_vector(dof: int) -> Callable[[object], TypeGuard[np.ndarray]]:
    """The predicate :attr:`CoordinateMap.ready` for ``dof`` coordinates, in one pass over q's bytes:
    ``Struct("<dof>d").unpack`` reads exactly dof float64 from a C-contiguous buffer (a strided view or a
    wrong size raises, and Eigen's vectorized loops would round a strided vector's products differently);
    ``hypot`` of the entries is NaN for a NaN, inf for an inf and at least max |q_i| otherwise, so
    ``hypot <= MAX_MAGNITUDE`` bounds every entry with one scalar call (a plain sum would let +1e300 and
    -1e300 cancel). The dtype test keeps other 8-byte types out; ndim keeps (dof, 1) out. The C accelerator,
    when it runs, tests the same things entry by entry."""
    native = accelerator.ready_check(dof, MAX_MAGNITUDE)
    if native is not None:
        return native  # type: ignore[return-value]  # the same predicate
    ndarray, f64, hypot, limit = np.ndarray, _F64, math.hypot, MAX_MAGNITUDE
    unpack = struct.Struct(f"={dof}d").unpack

    def ready(q: object) -> TypeGuard[np.ndarray]:
        if type(q) is not ndarray or q.dtype is not f64 or q.ndim != 1:
            return False
        try:
            return hypot(*unpack(q)) <= limit  # type: ignore[arg-type]  # an ndarray is a buffer
        except (ValueError, struct.error):  # not C-contiguous, or not dof entries
            return False

    return ready


def _short(value: object) -> str:
    text = " ".join(repr(value).split())  # one line, e.g. for a numpy array
    return text if len(text) <= 40 else text[:37] + "..."


def _or(value: float | None, default: float) -> float:
    return default if value is None else value


__all__ = ["CoordinateMap"]
