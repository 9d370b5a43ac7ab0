"""The user's joint coordinates q and their map to Pinocchio's configuration vector.

kinengine's q holds exactly one coordinate per independent movable joint, in
``joint_names`` order (Pinocchio's depth-first tree order): revolute and continuous
joints in [rad], prismatic joints in [m]. Mimic joints take no coordinate. Pinocchio
stores a continuous joint as (cos q, sin q); that mapping lives here and nowhere else.
Velocities need no map: Pinocchio's nv equals ``dof`` in the same order.
"""

from __future__ import annotations

from collections.abc import Mapping
import math
import warnings

import numpy as np
import pinocchio as pin

from .errors import ConfigurationError, FrameNotFoundError, OptionError
from .urdf import RobotDescription

_F64 = np.dtype(np.float64)
_STRIDES = (_F64.itemsize,)  # a C-contiguous float64 vector
_SMALL_BATCH = 8  # rows up to which to_pinocchio converts row by row in Python (measured on kinova)


class JointSpace:
    """Joint names, limits and the checked conversion of q to Pinocchio's q."""

    def __init__(self, model: pin.Model, description: RobotDescription) -> None:
        joints = {j.name: j for j in description.joints}
        names, idx_q, continuous = [], [], []
        for jid in range(1, model.njoints):
            name = model.names[jid]
            jmodel = model.joints[jid]
            if jmodel.nv == 0:  # a mimic joint: follows its leader, owns no coordinate
                continue
            names.append(name)
            idx_q.append(jmodel.idx_q)
            continuous.append(joints[name].type == "continuous")
        self.names: tuple[str, ...] = tuple(names)
        self.dof = len(names)
        if self.dof != model.nv:
            raise AssertionError(f"joint map mismatch: {self.dof} coordinates, Pinocchio nv = {model.nv}")
        self.nq = model.nq
        lower = np.array([joints[n].lower if joints[n].lower is not None else -np.inf for n in names])
        upper = np.array([joints[n].upper if joints[n].upper is not None else np.inf for n in names])
        self._narrowed_by: dict[int, list[str]] = {}
        self._narrow_by_mimics(description, names, lower, upper)
        lower.flags.writeable = upper.flags.writeable = False
        self.lower, self.upper = lower, upper
        self.continuous = np.array(continuous, dtype=bool)
        self.identity = not any(continuous)
        cont = np.flatnonzero(self.continuous)
        lin = np.flatnonzero(~self.continuous)
        idx = np.asarray(idx_q, dtype=np.intp)
        self._lin_user, self._lin_pin = lin, idx[lin]
        self._cont_user, self._cos_pin, self._sin_pin = cont, idx[cont], idx[cont] + 1
        self._linear = tuple(zip(lin.tolist(), idx[lin].tolist()))      # (user index, Pinocchio index)
        self._circular = tuple(zip(cont.tolist(), idx[cont].tolist()))  # (user index, index of cos)
        self._index = {n: i for i, n in enumerate(names)}
        self._shape = (self.dof,)
        self._mimics = {j.name: j.mimic.joint for j in description.joints if j.mimic is not None}

    def _narrow_by_mimics(self, description: RobotDescription, names: list[str], lower: np.ndarray,
                          upper: np.ndarray) -> None:
        """A coordinate's limits also keep each mimic joint that follows it within that joint's own limits:
        lower ≤ m·q + o ≤ upper of the follower, i.e. q within [(lower − o)/m, (upper − o)/m] (swapped if m < 0).
        Limits that no value meets (sloppy gripper URDFs) are warned about and not enforced."""
        index = {n: i for i, n in enumerate(names)}
        for joint in description.joints:
            mimic = joint.mimic
            if mimic is None or joint.lower is None or mimic.multiplier == 0.0:
                continue
            i = index[mimic.joint]
            a = (joint.lower - mimic.offset) / mimic.multiplier
            b = (joint.upper - mimic.offset) / mimic.multiplier
            lo, hi = max(lower[i], min(a, b)), min(upper[i], max(a, b))
            follows = (f"{joint.name!r} = {mimic.multiplier:g}·q + {mimic.offset:g} within "
                       f"[{joint.lower:g}, {joint.upper:g}]")
            if lo > hi:
                warnings.warn(f"{description.source}: no value of joint {mimic.joint!r} keeps it within its limits "
                              f"and mimic joint {follows}; the mimic joint's limits are not enforced", stacklevel=2)
            elif lo > lower[i] or hi < upper[i]:
                lower[i], upper[i] = lo, hi
                self._narrowed_by.setdefault(i, []).append(follows)

    # -- conversion -------------------------------------------------------------------------
    def to_pinocchio(self, q: np.ndarray) -> np.ndarray:
        """Pinocchio's configuration for a checked q of shape (dof,) (or (N, dof) -> (N, nq))."""
        if self.identity:
            return q
        if q.ndim == 1:  # scalar Python is ~4x faster than numpy fancy indexing for one vector
            out = np.empty(self.nq)
            self.write_pinocchio(q.tolist(), out)
            return out
        if len(q) <= _SMALL_BATCH:  # ... and for a few
            out = np.empty((len(q), self.nq))
            for row, values in zip(out, q.tolist()):
                self.write_pinocchio(values, row)
            return out
        out = np.empty(q.shape[:-1] + (self.nq,))
        out[..., self._lin_pin] = q[..., self._lin_user]
        qc = q[..., self._cont_user]
        out[..., self._cos_pin] = np.cos(qc)
        out[..., self._sin_pin] = np.sin(qc)
        return out

    def write_pinocchio(self, values: list[float], out: np.ndarray) -> None:
        """Write one checked q, given as a list, into Pinocchio's configuration ``out`` (nq,) in place."""
        for user, index in self._linear:
            out[index] = values[user]
        for user, index in self._circular:
            out[index], out[index + 1] = math.cos(values[user]), math.sin(values[user])

    def from_pinocchio(self, q_pin: np.ndarray) -> np.ndarray:
        """The user's q from Pinocchio's configuration (continuous angles in (-π, π])."""
        q_pin = np.asarray(q_pin, dtype=float)
        if self.identity:
            return q_pin.copy()
        out = np.empty(q_pin.shape[:-1] + (self.dof,))
        out[..., self._lin_user] = q_pin[..., self._lin_pin]
        out[..., self._cont_user] = np.arctan2(q_pin[..., self._sin_pin], q_pin[..., self._cos_pin])
        return out

    # -- checking ---------------------------------------------------------------------------
    def check(self, q: object, *, name: str = "q", check_limits: bool = False,
              allow_batch: bool = True) -> np.ndarray:
        """q as a C-contiguous float64 array of shape (dof,) or (N >= 1, dof); ConfigurationError otherwise.

        ints, float32, lists, tuples, strided, Fortran-ordered and read-only arrays are
        accepted and converted (a new array when conversion is needed; the input is never
        modified). NaN/inf, strings, None, booleans, complex, masked entries, empty batches
        and wrongly shaped input are refused with the expected shape in the message.
        """
        # Hot path: a contiguous float64 vector of the right shape costs one float sum (~0.15 µs)
        # to check; a non-finite sum (NaN, inf or overflow) is confirmed element-wise.
        if type(q) is np.ndarray and q.dtype is _F64 and q.shape == self._shape and q.strides == _STRIDES:
            if not math.isfinite(sum(q.tolist())) and not np.isfinite(q).all():
                self._raise_nonfinite(q, name)
        elif (allow_batch and type(q) is np.ndarray and q.dtype is _F64 and q.ndim == 2 and q.shape[0]
              and q.shape[1] == self.dof and q.flags.c_contiguous):  # a ready batch: one sum as well
            total = sum(q.ravel().tolist()) if q.size <= 256 else float(q.sum())
            if not math.isfinite(total) and not np.isfinite(q).all():
                self._raise_nonfinite(q, name)
        else:
            q = self._convert(q, name, allow_batch)
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
            raise ConfigurationError(f"Expected `{name}` to have a value for every joint, got a masked array "
                                     "with masked entries; fill them (q.filled(...)) first")
        try:
            arr = np.asarray(q)
        except Exception as exc:  # ragged sequences and the like
            raise ConfigurationError(f"Expected `{name}` to be numeric with shape {expected}: {exc}") from None
        if arr.dtype.kind == "O":
            arr = self._from_objects(arr, q, name, expected)
        elif arr.dtype.kind not in "iuf":
            raise ConfigurationError(
                f"Expected `{name}` to hold real numbers with shape {expected}, got dtype {arr.dtype}")
        if arr.ndim == 0 or arr.shape[-1] != self.dof or arr.ndim > (2 if allow_batch else 1):
            hint = ("; this function takes one configuration: call it once per row"
                    if not allow_batch and arr.ndim == 2 and arr.shape[-1] == self.dof else "")
            raise ConfigurationError(f"Expected `{name}` to have shape {expected}, got {arr.shape}{hint}")
        if arr.ndim == 2 and arr.shape[0] == 0:
            raise ConfigurationError(f"Expected `{name}` to hold at least one configuration, "
                                     f"got an empty batch {arr.shape}")
        arr = np.ascontiguousarray(arr, dtype=np.float64)
        if not np.isfinite(arr).all():
            self._raise_nonfinite(arr, name)
        return arr

    @staticmethod
    def _from_objects(arr: np.ndarray, q: object, name: str, expected: str) -> np.ndarray:
        """An object array (e.g. Python numbers) as float64; ConfigurationError if an entry is not one."""
        what = f"a {type(q).__name__}" if arr.ndim == 0 else "an object array"
        if any(v is None for v in arr.flat):
            raise ConfigurationError(f"Expected `{name}` to hold real numbers with shape {expected}, "
                                     f"got {what} with None entries")
        try:
            return arr.astype(np.float64)
        except OverflowError:
            raise ConfigurationError(f"Expected `{name}` to hold real numbers with shape {expected}, "
                                     f"got {what} with a number too large for a float64") from None
        except (TypeError, ValueError):
            raise ConfigurationError(f"Expected `{name}` to hold real numbers with shape {expected}, "
                                     f"got {what} with non-numeric entries") from None

    def _raise_nonfinite(self, q: np.ndarray, name: str) -> None:
        bad = np.argwhere(~np.isfinite(q))[0]
        joint = self.names[bad[-1]]
        where = f"[{', '.join(map(str, bad))}]"
        raise ConfigurationError(f"`{name}`{where} (joint {joint!r}) is {float(q[tuple(bad)])}: "
                                 "every coordinate must be a finite number")

    def check_limits(self, q: np.ndarray, *, name: str = "q") -> None:
        """ConfigurationError naming the first joint outside [lower, upper] (and its row in a batch)."""
        outside = (q < self.lower) | (q > self.upper)
        if outside.any():
            bad = np.argwhere(outside)[0]
            i = bad[-1]
            row = f"[{bad[0]}]" if q.ndim == 2 else ""
            why = (f" (narrowed so that mimic joint {', '.join(self._narrowed_by[i])})"
                   if i in self._narrowed_by else "")
            raise ConfigurationError(
                f"`{name}`{row} puts joint {self.names[i]!r} at {float(q[tuple(bad)])!r}, outside its limits "
                f"[{float(self.lower[i])!r}, {float(self.upper[i])!r}]{why}; clip q or pass check_limits=False")

    # -- construction -----------------------------------------------------------------------
    def from_mapping(self, values: Mapping[str, float], base: np.ndarray, *, strict: bool = True) -> np.ndarray:
        """q from joint name -> value (e.g. a ROS JointState); joints not named keep ``base``."""
        if not isinstance(values, Mapping):
            raise ConfigurationError(f"Expected a mapping of joint name to value, got {type(values).__name__}")
        q = base.copy()
        for joint, value in values.items():
            i = self._index.get(joint)
            if i is None:
                if not strict:
                    continue
                if joint in self._mimics:
                    raise ConfigurationError(
                        f"joint {joint!r} is a mimic joint that follows {self._mimics[joint]!r} and takes no "
                        "coordinate; set the leader instead (or pass strict=False to ignore it)")
                raise FrameNotFoundError(joint, self.names, kind="joint")
            try:
                v = float(value)
            except (TypeError, ValueError):
                raise ConfigurationError(f"joint {joint!r}: expected a number, got {value!r}") from None
            if not math.isfinite(v):
                raise ConfigurationError(f"joint {joint!r}: expected a finite number, got {v}")
            q[i] = v
        return q

    def sample(self, rng: np.random.Generator, size: int | None) -> np.ndarray:
        """Uniform samples within limits; unbounded (continuous) joints in [-π, π)."""
        if size is not None and (isinstance(size, bool) or not isinstance(size, (int, np.integer)) or size < 0):
            raise OptionError(f"`size` must be None or a number of configurations >= 0, got {size!r}")
        lo = np.where(np.isfinite(self.lower), self.lower, -np.pi)
        hi = np.where(np.isfinite(self.upper), self.upper, np.pi)
        shape = (self.dof,) if size is None else (size, self.dof)
        return rng.uniform(lo, hi, size=shape)
