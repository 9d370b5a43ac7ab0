"""The chain from the root to a frame, compiled once per robot and frame from Pinocchio's model.

:func:`compiled_chain` gives a :class:`~kinengine.kinematics.chain.Chain` (the frames and constants
:mod:`kinengine.kinematics.chain` describes), evaluated by numpy or, when ``chainkernel.c`` was built and
``KINENGINE_PURE_PYTHON`` is not set, by its C twin (``Chain.kernel``, fed by :func:`program`).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable

import numpy as np
import pinocchio as pin

from ..model import accelerator
from .chain import Chain, Step, Terms, constant_terms
from .engine import Kinematics

ROUNDING = 1e-15
"""Compiled constants within this (relative) of 0 or ±1 are taken as exactly that (see _snap)."""
REFERENCE_CODES = {pin.LOCAL_WORLD_ALIGNED: 0, pin.WORLD: 1, pin.LOCAL: 2}
"""The C chain's number for each Jacobian reference."""
SIN_COS_TOLERANCE = 1e-15
"""Largest difference from the C library's sin and cos that the C chain's own sin_cos may show at import."""


def _kernel_type() -> tuple[type | None, str | None]:
    """The C chain (chainkernel.c), or None and why: not built (the ImportError), its sin and cos disagree
    with the C library's (one RuntimeWarning too), or KINENGINE_PURE_PYTHON (no reason)."""
    if accelerator.SWITCHED_OFF:
        return None, None
    try:
        from . import chainkernel
    except ImportError as exc:
        return None, str(exc)
    error = sin_cos_error(chainkernel.sin_check)
    if not error <= SIN_COS_TOLERANCE:
        warnings.warn(
            f"kinengine's C batch chain computes sin/cos up to {error:.3g} away from the C library's "
            "(was it built with -ffast-math?); batches run on the numpy chain instead. Reinstall kinengine "
            "without fast-math flags to use it.",
            RuntimeWarning,
            stacklevel=2,
        )
        return None, f"its sin/cos differ from the C library's by up to {error:.3g} (built with -ffast-math?)"
    return chainkernel.Kernel, None


def sin_cos_error(sin_check: Callable[[bytes], bytes]) -> float:
    """Largest |difference| between the kernel's sin_cos and math.sin/math.cos (the C library's) over angles
    that exercise every quadrant, the reduction near multiples of π/2 and large arguments [rad]."""
    angles = [k * 0.25 * math.pi + d for k in range(-64, 65) for d in (-1e-9, 0.0, 1e-9, 0.3)]
    angles += [math.ldexp(1.0, e) * sign for e in range(-30, 20) for sign in (1.0, -1.0)]
    angles += [1e5 + 0.37 * k for k in range(50)]
    values = np.frombuffer(sin_check(np.array(angles).tobytes()))
    expected = np.array([math.sin(a) for a in angles] + [math.cos(a) for a in angles])
    error = np.abs(values - expected).max()  # NaN if the kernel gave one
    return float(error) if error == error else math.inf


KERNEL, KERNEL_ERROR = _kernel_type()
"""The C chain's type, or None: every batch runs on numpy (tests set it to compare); and why it is None."""


def accelerator_status() -> str:
    """One line: whether kinengine's C accelerator runs in this process and, if not, why (what ``kinengine
    --version`` prints; the diagnosis is :func:`kinengine.model.accelerator.status`)."""
    missing: dict[str, str | None] = {}
    if not accelerator.AVAILABLE:
        missing["fastcall"] = accelerator.LOAD_ERROR
    if KERNEL is None:
        missing["chainkernel"] = KERNEL_ERROR
    return accelerator.status(missing)


def program(chain: Chain) -> bytes:
    """The chain for the C kernel: float64 [m, per step (prismatic, coordinate, scaling, offset,
    accumulate, K_i (3x3 row-major), t_i), C_IF's rotation after the last step (3x3 row-major), its
    translation]."""
    values: list[float] = [len(chain.steps)]
    for s in chain.steps:
        t, K = constant_terms(s.rotation, s.translation)
        values += [s.prismatic, s.coordinate, s.scaling, s.offset, s.accumulate, *K.ravel(), *t.ravel()]
    t, K = constant_terms(chain.rotation, chain.translation)
    return np.array([*values, *K.ravel(), *t.ravel()], dtype=np.float64).tobytes()


def _axis_basis(axis: np.ndarray) -> np.ndarray:
    """A rotation Q with Q e_z = axis (exact signed permutation when the axis is a coordinate axis)."""
    e = np.zeros(3)
    e[int(np.argmin(np.abs(axis)))] = 1.0
    x = e - (e @ axis) * axis
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(axis, x), axis])


def _snap(values: np.ndarray) -> np.ndarray:
    """Rounding residue (|v| <= ROUNDING of the largest entry, e.g. cos(π/2) = 6e-17 from an rpy of π/2)
    set to 0, and ±(1 − residue) to ±1: each costs a numpy pass per chunk for a change below 1e-15."""
    residue = ROUNDING * float(np.abs(values).max(initial=0.0))
    values = np.where(np.abs(values) <= residue, 0.0, values)
    return np.where(np.abs(np.abs(values) - 1.0) <= ROUNDING, np.sign(values), values)


def _nonzero(vector: np.ndarray) -> tuple[tuple[int, float], ...]:
    """The nonzero entries of a (snapped) 3-vector: ((row, value), ...)."""
    return tuple((m, float(value)) for m, value in enumerate(vector) if value != 0.0)


def _terms(matrix: np.ndarray) -> Terms:
    """Nonzero entries of a 3x3 rotation, column by column (snapped)."""
    return tuple(_nonzero(column) for column in _snap(matrix).T)


def _compile(kin: Kinematics, fid: int) -> Chain:
    """The chain of movable joints from the root to frame ``fid``, with its constants."""
    model, coords = kin.model, kin.coordinates
    joints = {j.name: j for j in kin.description.joints}
    frame = model.frames[fid]
    steps, seen = [], set()
    Q_parent = np.eye(3)
    for jid in list(model.supports[frame.parentJoint])[1:]:
        k = model.joints[jid].idx_v  # Pinocchio's coordinate: row k of the coordinate map
        joint = joints[model.names[jid]]
        coordinate = int(coords.leader[k])
        axis = np.asarray(joint.axis, dtype=float)
        Q = _axis_basis(axis / np.linalg.norm(axis))
        placement, scale = model.jointPlacements[jid], float(coords.multiplier[k])
        K, t = (
            _terms(Q_parent.T @ placement.rotation @ Q),
            _nonzero(_snap(Q_parent.T @ placement.translation)),
        )
        prismatic, offset = joint.type == "prismatic", float(coords.offset[k])
        steps.append(Step(prismatic, coordinate, scale, offset, K, t, coordinate in seen))
        seen.add(coordinate)
        Q_parent = Q
    rotation = _terms(Q_parent.T @ frame.placement.rotation)
    translation = _nonzero(_snap(Q_parent.T @ frame.placement.translation))
    chain = Chain(tuple(steps), rotation, translation, kin.dof)
    if KERNEL is not None:
        chain.kernel = KERNEL(kin.dof, program(chain))
    return chain


def compiled_chain(kin: Kinematics, fid: int) -> Chain:
    """The chain to frame ``fid``, compiled once per robot and frame."""
    return kin.memoized(("batch chain", fid), lambda: _compile(kin, fid))


__all__ = ["KERNEL", "REFERENCE_CODES", "ROUNDING", "compiled_chain", "program"]
