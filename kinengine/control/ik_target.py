"""IK options and targets, checked once: :class:`Problem` (the validated options shared by every solver),
:class:`FrameGoal` (a frame's problem and target), the target pose p_d (3,) [m] / C_d (3, 3) in the root
frame I from a pose T_IF (4, 4), a batch (N, 4, 4) or parameters χ, and :class:`RandomSource` (``rng``)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from ..errors import OptionError, ParameterizationError
from ..kinematics.options import checked_seed, number_option
from ..parameterizations import get_position, get_rotation

if TYPE_CHECKING:  # named for the checker only
    from .robot_like import RobotLike

MAX_TARGET_DISTANCE = 1e9
"""[m] a target position farther than this from the root is refused (its squared error would overflow)."""
ROTATION_TOLERANCE = 1e-6
"""max |CᵀC − I| of a target's rotation block accepted (float32 poses, rounded print-outs)."""
ROTATION_EXACT = 1e-12
"""max |CᵀC − I| above which an accepted rotation block is replaced by its nearest rotation."""
ROW_NAMES = ("x", "y", "z", "rx", "ry", "rz")
_SIX_ROWS_POSITION = np.arange(6) < 3  # Problem.position_rows of a full target (shared, read-only)
_SIX_ROWS_POSITION.flags.writeable = False
_BOTTOM = [0.0, 0.0, 0.0, 1.0]


@dataclass(frozen=True)
class Problem:
    """Validated options shared by every solver (one per frame of a mapping target)."""

    fid: int
    frame: str
    rows: np.ndarray | None  # kept rows of e_D (None: all six rows of e in I, unweighted)
    sqrt_weights: np.ndarray | None
    position_rows: np.ndarray  # which kept rows are position rows
    tol_position: float
    tol_rotation: float
    max_iterations: int
    restarts: int
    damping_sq: float
    q_ns: np.ndarray | None
    q_ns_within: np.ndarray | None  # q_ns clipped into the joint limits (where a left-out coordinate sits)
    gain: float
    patient_first: bool  # the first attempt (from the caller's q0) never gives up early


@dataclass(frozen=True)
class Options:
    """inverse_kinematics' options as given, checked by :func:`checked_problem` (once per frame)."""

    tol_position: object
    tol_rotation: object
    max_iterations: object
    restarts: object
    nullspace_target: object
    nullspace_gain: object
    min_damping: object
    has_q0: bool


@dataclass(frozen=True)
class FrameGoal:
    """One frame's :class:`Problem` and target p_d (3,) [m], C_d (3, 3) in I (None: that part is free)."""

    problem: Problem
    p_d: np.ndarray | None
    C_d: np.ndarray | None

    @property
    def row_count(self) -> int:
        """Rows of the frame's error: the kept ``rows``, else 3 per fixed part (position, rotation)."""
        rows = self.problem.rows
        return len(rows) if rows is not None else 3 * ((self.p_d is not None) + (self.C_d is not None))


def _count(name: str, value: object, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 0 <= value <= high:
        raise OptionError(f"`{name}` must be a whole number from 0 to {high:,}, got {value!r}")
    return int(value)


def checked_problem(
    robot: RobotLike, frame: str | None, rows: object, weights: object, options: Options
) -> Problem:
    """The options of :func:`kinengine.control.ik.inverse_kinematics`, each checked (OptionError)."""
    frame = robot.end_effector if frame is None else frame
    fid, o = robot.frame_id(frame), options
    tol_p = number_option("`tol_position`", o.tol_position)
    tol_r = number_option("`tol_rotation`", o.tol_rotation)
    max_iterations = _count("max_iterations", o.max_iterations, 1_000_000)
    restarts = _count("restarts", o.restarts, 10_000)
    gain = number_option("`nullspace_gain`", o.nullspace_gain, 0.0, 1.0)
    damping = number_option("`min_damping`", o.min_damping, 0.0, 1e6)
    q_ns = checked_start(robot, o.nullspace_target, "nullspace_target", None)
    joints = robot.engine.coordinates
    q_ns_within = None if q_ns is None else np.clip(q_ns, joints.lower, joints.upper)
    kept, sqrt_w = None, None
    if rows is not None or weights is not None:
        kept = np.arange(6) if rows is None else _rows(rows)
        if weights is not None:
            w = np.asarray(weights, dtype=object)
            if w.shape != (len(kept),):
                raise OptionError(
                    f"`weights` must hold one number per kept row ({len(kept)}), got shape {w.shape}"
                )
            sqrt_w = np.sqrt([number_option("`weights[i]`", v, 0.0, 1e12) for v in w])
    position_rows = _SIX_ROWS_POSITION if kept is None else kept < 3
    limits = (tol_p, tol_r, max_iterations, restarts, damping**2)
    return Problem(fid, frame, kept, sqrt_w, position_rows, *limits, q_ns, q_ns_within, gain, o.has_q0)


def _rows(rows: object) -> np.ndarray:
    if isinstance(rows, (str, bytes)) or not hasattr(rows, "__iter__"):
        raise OptionError(f"`rows` must be a sequence of labels {ROW_NAMES} or indices 0-5, got {rows!r}")
    index = []
    for r in rows:
        if isinstance(r, str) and r in ROW_NAMES:
            index.append(ROW_NAMES.index(r))
        elif not isinstance(r, bool) and isinstance(r, (int, np.integer)) and 0 <= r < 6:
            index.append(int(r))
        else:
            raise OptionError(f"`rows` entries must be labels {ROW_NAMES} or indices 0-5, got {r!r}")
    if not index or len(set(index)) != len(index):
        raise OptionError(f"`rows` must name at least one row, each once, got {rows!r}")
    return np.array(sorted(index))


class RandomSource:
    """``rng`` checked now, made into a numpy Generator only when a random restart needs one (making one
    costs more than a converged solve)."""

    def __init__(self, rng: object) -> None:
        self.rng = checked_seed(rng)

    @cached_property
    def generator(self) -> np.random.Generator:
        return np.random.default_rng(self.rng)  # type: ignore[arg-type]  # checked in __init__

    def configurations(self, robot: RobotLike, size: int | None = None) -> np.ndarray:
        return robot.random_configuration(self.generator, size=size)


def checked_start(robot: RobotLike, q0: object, name: str, count: int | None) -> np.ndarray | None:
    """``q0`` None, (dof,) or, for ``count`` targets (None: one), one row per target (count, dof), checked
    (ConfigurationError, OptionError naming ``name``)."""
    if q0 is None:
        return None
    q = robot.engine.coordinates.check(q0, name=name, allow_batch=count is not None)
    if q.ndim == 2 and len(q) != count:
        raise OptionError(f"`{name}` must be (dof,) or one row per target ({count}), got {len(q)} rows")
    return q


def rotation_deviation(
    a: float, b: float, c: float, d: float, e: float, f: float, g: float, h: float, i: float
) -> float:
    """max |CᵀC − I| of C = [[a, b, c], [d, e, f], [g, h, i]] (row by row); inf when det C <= 0 or an entry
    is not finite, in plain floats (cheaper than numpy for one 3x3)."""
    if not a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g) > 0:
        return math.inf
    return max(
        abs(a * a + d * d + g * g - 1.0),
        abs(b * b + e * e + h * h - 1.0),
        abs(c * c + f * f + i * i - 1.0),
        abs(a * b + d * e + g * h),
        abs(a * c + d * f + g * i),
        abs(b * c + e * f + h * i),
    )


def exact_pose(T: np.ndarray, deviation: float | np.ndarray) -> np.ndarray:
    """Checked T (4, 4) or (N, 4, 4) and ``deviation`` (:func:`checked_pose`, :func:`checked_poses`) -> T
    C-contiguous, rotation blocks off by more than ``ROTATION_EXACT`` (a float32 or rounded target) replaced
    in a copy by their nearest rotations U·Vᵀ (C = U S Vᵀ), which answers then reproduce to 1e-9."""
    fix = deviation > ROTATION_EXACT
    if not (fix.any() if isinstance(fix, np.ndarray) else fix):
        return T if T.flags.c_contiguous else np.ascontiguousarray(T)
    out = np.array(T, dtype=np.float64)
    U, _, Vt = np.linalg.svd(out[..., :3, :3][fix])
    out[..., :3, :3][fix] = U @ Vt
    return out


def is_batch(target: object) -> bool:
    """Whether ``target`` is a batch (three-dimensional); False for a ragged nesting (refused later)."""
    try:
        return np.ndim(target) == 3  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return False


def _real(target: object, expected: str) -> np.ndarray:
    """``target`` as a float array; complex numbers are refused (a cast would drop their imaginary parts)."""
    try:
        raw = np.asarray(target)
        if not np.iscomplexobj(raw):
            return np.asarray(raw, dtype=float)
    except (TypeError, ValueError):
        raise ParameterizationError(f"Expected `target` to be {expected}, got {target!r:.80}") from None
    raise ParameterizationError(
        f"`target` holds complex numbers; expected {expected} of real numbers (the imaginary parts would be "
        "dropped)"
    )


def _within_reach(distance: float) -> None:
    """``distance``: the largest |coordinate| [m] of a target position in I."""
    if not distance <= MAX_TARGET_DISTANCE:
        raise ParameterizationError(
            f"`target`'s position is farther than {MAX_TARGET_DISTANCE:g} m from the root: no robot reaches "
            "it; give a target in metres within reach"
        )


def checked_pose(target: object, parameters: bool = True) -> tuple[np.ndarray, float]:
    """(T (4, 4) float64, max |CᵀC − I| of its rotation block): a pose target checked as :func:`checked_poses`
    checks each of a batch, accepted in plain floats (cheaper than numpy for one pose). ``parameters``: the
    caller also takes parameters χ (its errors then say how to give them)."""
    value = _real(target, "a (4, 4) pose or parameters χ" if parameters else "a (4, 4) pose")
    if value.shape != (4, 4):
        chi = "; for parameters χ name their position= and/or rotation= parameterization"
        raise ParameterizationError(
            f"Expected `target` to be a finite pose of shape (4, 4) or a batch (N, 4, 4), got "
            f"{value.shape}{chi if parameters else ''}"
        )
    flat = value.ravel().tolist()
    a, b, c, x, d, e, f, y, g, h, i, z = flat[:12]
    if (
        all(map(math.isfinite, flat))
        and (deviation := rotation_deviation(a, b, c, d, e, f, g, h, i)) <= ROTATION_TOLERANCE
        and all(abs(v - w) <= 1e-9 for v, w in zip(flat[12:], _BOTTOM, strict=True))
        and max(abs(x), abs(y), abs(z)) <= MAX_TARGET_DISTANCE
    ):
        return value, deviation
    return value, float(checked_poses(value[None], single=True)[1][0])  # raises, naming what is wrong


def single_target(
    target: object, position: str | None, rotation: str | None
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(p_d (3,) or None, C_d (3, 3) or None) from a pose (4, 4) (made exact: :func:`exact_pose`) or
    parameters χ."""
    if position is None and rotation is None:
        T = exact_pose(*checked_pose(target))
        return T[:3, 3].copy(), T[:3, :3].copy()
    value = _real(target, "a (4, 4) pose or parameters χ")
    P = get_position(position) if position is not None else None
    R = get_rotation(rotation) if rotation is not None else None
    p_size = P.size if P else 0
    m = p_size + (R.size if R else 0)
    names = " + ".join(n for n in (position, rotation) if n)
    if value.shape != (m,) or not np.isfinite(value).all():
        raise ParameterizationError(
            f"Expected `target` to be finite parameters of shape ({m},) for {names}, got {value.shape}"
        )
    try:
        with np.errstate(all="ignore"):
            p_d = P.to_position(value[:p_size]) if P else None
            C_d = R.to_rotation(value[p_size:]) if R else None
    except (ArithmeticError, ValueError):  # e.g. a zero quaternion
        raise ParameterizationError(
            f"`target` {value.tolist()} describes no pose for {names}; give valid parameters"
        ) from None
    if p_d is not None:
        if not np.isfinite(p_d).all():
            raise ParameterizationError(f"`target` {value.tolist()} gives no finite position for {position}")
        _within_reach(float(np.abs(p_d).max()))
    if C_d is not None and not rotation_deviation(*C_d.ravel().tolist()) <= ROTATION_TOLERANCE:
        raise ParameterizationError(
            f"`target`'s {rotation} parameters {value[p_size:].tolist()} describe no "
            "rotation (e.g. a zero quaternion or matrix); give a valid one"
        )
    return p_d, C_d


def checked_poses(target: object, single: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(T (N, 4, 4) float64, deviation (N,) = max |CᵀC − I| per rotation block): a batch of pose targets
    checked (finite, rotation blocks rotations to ``ROTATION_TOLERANCE``, bottom rows (0, 0, 0, 1), positions
    within reach); ParameterizationError naming the first bad pose (``single``: the one pose, (1, 4, 4))."""
    value = _real(target, "a batch of poses (N, 4, 4)")
    if value.ndim != 3 or value.shape[1:] != (4, 4) or not len(value):
        raise ParameterizationError(
            f"Expected `target` to be a finite batch of poses (N >= 1, 4, 4), got {value.shape}"
        )
    name = "`target`" if single else "`target`[{}]"  # the first bad pose
    not_finite = np.flatnonzero(~np.isfinite(value).all(axis=(1, 2)))
    if len(not_finite):
        count = "" if single else f" ({len(not_finite)} of {len(value)} poses)"
        raise ParameterizationError(
            f"{name.format(not_finite[0])} holds NaN or inf{count}: a pose T_IF (4, 4) has finite entries"
        )
    C = value[:, :3, :3]
    deviation = np.abs(np.einsum("nki,nkj->nij", C, C) - np.eye(3)).max(axis=(1, 2))
    bad = np.flatnonzero((deviation > ROTATION_TOLERANCE) | (np.linalg.det(C) <= 0))
    if len(bad):
        raise ParameterizationError(
            f"{name.format(bad[0])}'s rotation block is not a rotation matrix (CᵀC ≠ I or det <= 0)"
        )
    bottom = np.flatnonzero(np.abs(value[:, 3, :] - _BOTTOM).max(axis=1) > 1e-9)
    if len(bottom):
        raise ParameterizationError(
            f"{name.format(bottom[0])}'s bottom row is {value[bottom[0], 3].tolist()}, expected "
            "[0, 0, 0, 1]: a pose T_IF (4, 4) is a homogeneous transform"
        )
    _within_reach(float(np.abs(value[:, :3, 3]).max()))
    return value, deviation


def batch_targets(target: object) -> tuple[np.ndarray, np.ndarray] | None:
    """(p_d (N, 3), C_d (N, 3, 3)) from a batch of poses (N, 4, 4), checked and made exact
    (:func:`exact_pose`); None for a target that is not three-dimensional."""
    if not is_batch(target):
        return None
    T = exact_pose(*checked_poses(target))
    return np.ascontiguousarray(T[:, :3, 3]), np.array(T[:, :3, :3])


__all__ = [
    "MAX_TARGET_DISTANCE",
    "ROTATION_EXACT",
    "ROTATION_TOLERANCE",
    "ROW_NAMES",
    "FrameGoal",
    "Options",
    "Problem",
    "RandomSource",
    "batch_targets",
    "checked_pose",
    "checked_poses",
    "checked_problem",
    "checked_start",
    "exact_pose",
    "is_batch",
    "rotation_deviation",
    "single_target",
]
