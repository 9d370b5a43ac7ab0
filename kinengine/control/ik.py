"""Differential inverse kinematics: damped least squares with Levenberg–Marquardt damping.

Error (decoupled): e = (p_d − p, log(C_d Cᵀ)) [m, rad] in the root frame I, p and C the frame's position
and orientation in I, so |e_p| is the position error [m] and |e_R| the rotation angle [rad] that the
tolerances are checked against; to first order its Jacobian is J = J_e0 ("local_world_aligned").
With ``rows=`` or ``weights=`` both halves are expressed in the target frame D (e_D = C_dᵀ e, J_D = C_dᵀ J
blockwise) and only the named rows count: rows=("x", "y", "z", "rx", "ry") is a 5-D target, position plus
tool axis (D's z axis): rotation about it is left free. ``weights`` (w ≥ 0, one per kept row) minimize
Σ w_i e_i² instead of |e|².
Step (λ² = ½|e|² + λ_min², Sugihara's Levenberg–Marquardt rule: strong damping far from the target or
near a singularity, Gauss–Newton speed close to it):
    Δq = Jᵀ (J Jᵀ + λ² I)⁻¹ e  +  (I − Jᵀ (J Jᵀ + λ² I)⁻¹ J)·z,   q ← clip(q + Δq, lower, upper),
with z = gain·min(1, score/NULLSPACE_FADE) · (q_ns − q) pulling towards ``nullspace_target`` in the (damped) nullspace of J.
Joint limits: every iterate is clipped into them, and Chan & Dubey's weights (:class:`LimitWeights`)
slow joints that approach a limit (Δq = W⁻¹Jᵀ (J W⁻¹Jᵀ + λ² I)⁻¹ e).
Seeds, in order, one attempt each of at most ``max_iterations`` iterations (an attempt whose error
is still above ``GIVE_UP`` after ``PROBE_ITERATIONS`` iterations makes way for the next seed):
``q0`` if given (its attempt never gives up early), else the middle of the joint ranges (or ``nullspace_target``) and the ``NEAREST_SEEDS``
configurations of a per-robot table (``SEED_TABLE_SIZE`` random in-limit configurations, fixed seed)
whose frame poses are nearest the target; then ``restarts`` uniformly random ones from ``rng``.
The same algorithm runs vectorized over a batch of targets (N, 4, 4): :mod:`kinengine.control.ik_batch`.
"""

from __future__ import annotations

import math
import threading
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import OptionError, ParameterizationError
from ..parameterizations import get_position, get_rotation

NEAREST_SEEDS = 10
PROBE_ITERATIONS = 10
GIVE_UP = 1e-2
"""[m] score |e_p| + 0.2 m/rad·|e_R| above which an attempt gives way after PROBE_ITERATIONS iterations."""
SEED_TABLE_SIZE = 4096
SEED_TABLE_BYTES = 1 << 21
"""At most 2 MiB per seed table (fewer than SEED_TABLE_SIZE rows for robots with many joints)."""
SEED_TABLES = 16
"""At most this many seed tables (frames × target kinds) are kept per robot, least recently used dropped."""
SEED_TABLE_RNG = 0x5EED_7AB1E
SEED_ROTATION_WEIGHT = 0.2
"""[m/rad]: pose distance |Δp| + 0.2·angle used to rank attempts and pick the stored seeds nearest a target."""
MAX_TARGET_DISTANCE = 1e9
"""[m] a target position farther than this from the root is refused (its squared error would overflow)."""
NULLSPACE_FADE = 5e-2
"""[m] the nullspace pull is gain · min(1, score / this): full strength far from the target, fading with
the error so that its second-order effect on the task (∝ |z|²) vanishes and the solve converges."""
ROW_NAMES = ("x", "y", "z", "rx", "ry", "rz")


@dataclass(frozen=True)
class IKResult:
    """Outcome of one IK solve: the best q found (dof,) [rad | m], within the limits."""

    q: np.ndarray
    success: bool
    iterations: int  # total over every attempt
    position_error: float  # |p_d − p| [m] over the kept position rows (0 if the position is free)
    rotation_error: float  # angle of C_d Cᵀ [rad] over the kept rotation rows (0 if the rotation is free)
    restarts: int  # attempts after the first one

    def __str__(self) -> str:
        state = "converged" if self.success else "did not converge"
        return (
            f"IK {state} after {self.iterations} iterations ({self.restarts} restarts): "
            f"position error {self.position_error:.3g} m, rotation error {self.rotation_error:.3g} rad"
        )


@dataclass(frozen=True)
class Problem:
    """Validated options shared by the single and the batched solver."""

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
    gain: float
    patient_first: bool  # the first attempt (from the caller's q0) never gives up early


def inverse_kinematics(
    robot,
    target: object,
    frame: str | None = None,
    q0: object = None,
    *,
    position: str | None = None,
    rotation: str | None = None,
    rows: object = None,
    weights: object = None,
    tol_position: float = 1e-6,
    tol_rotation: float = 1e-6,
    max_iterations: int = 100,
    restarts: int = 3,
    rng: np.random.Generator | int | None = None,
    nullspace_target: object = None,
    nullspace_gain: float = 0.1,
    min_damping: float = 1e-6,
):
    """q (within the limits) that puts ``frame`` (default: end effector) at ``target`` in I.

    ``target``: T_IF (4, 4), a batch (N, 4, 4) (then an :class:`~kinengine.control.ik_batch.IKBatchResult`
    of N results, solved vectorized), or parameters χ = (χ_P, χ_R) of the parameterizations named by
    ``position``/``rotation`` (naming only one solves for that part alone). ``rows``: labels or indices
    of ("x", "y", "z", "rx", "ry", "rz") to keep, in the target's frame; ``weights``: one w ≥ 0 per kept
    row. Success: position error <= ``tol_position`` [m] and rotation error <= ``tol_rotation`` [rad].
    ``max_iterations``: per attempt; ``restarts``: random attempts after the seeded ones (``rng``).
    ``nullspace_target`` (dof,): preferred q, pursued with ``nullspace_gain`` [1/iteration] where the
    task leaves freedom. ``min_damping``: λ_min [1]. Every option is validated (OptionError).
    """
    batch = (
        position is None and rotation is None and np.ndim(target) == 3
        if not isinstance(target, str)
        else False
    )
    problem = _problem(
        robot,
        frame,
        rows,
        weights,
        tol_position,
        tol_rotation,
        max_iterations,
        restarts,
        nullspace_target,
        nullspace_gain,
        min_damping,
        q0 is not None,
    )
    if problem.rows is not None and (position is not None or rotation is not None):
        raise OptionError(
            "`rows=` and `weights=` apply to pose targets (4, 4) or (N, 4, 4); for parameters χ "
            "name only the parameterizations you need"
        )
    generator = _Generator(rng)
    joints = robot.engine.coordinates
    start = None if q0 is None else joints.check(q0, name="q0", allow_batch=batch)
    if batch:
        from .ik_batch import solve_batch

        p_d, C_d = _targets(target)
        if start is not None and start.ndim == 2 and len(start) != len(p_d):
            raise OptionError(
                f"`q0` must be (dof,) or one row per target ({len(p_d)}), got {len(start)} rows"
            )
        return solve_batch(robot, problem, p_d, C_d, start, generator)
    p_d, C_d = _target(target, position, rotation)
    seeds = first_seeds(
        robot, problem, p_d[None] if p_d is not None else None, C_d[None] if C_d is not None else None, start
    )[0]
    return solve_one(robot, problem, p_d, C_d, seeds, generator)


# -- options and targets ---------------------------------------------------------------------------
def _number(name: str, value: object, low: float, high: float = math.inf) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise OptionError(f"`{name}` must be a number, got {value!r}")
    value = float(value)
    if not (math.isfinite(value) and low <= value <= high):
        raise OptionError(f"`{name}` must be a finite number in [{low:g}, {high:g}], got {value!r}")
    return value


def _count(name: str, value: object, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 0 <= value <= high:
        raise OptionError(f"`{name}` must be a whole number from 0 to {high:,}, got {value!r}")
    return int(value)


def _problem(
    robot,
    frame,
    rows,
    weights,
    tol_position,
    tol_rotation,
    max_iterations,
    restarts,
    nullspace_target,
    nullspace_gain,
    min_damping,
    has_q0: bool,
) -> Problem:
    frame = robot.end_effector if frame is None else frame
    fid = robot.frame_id(frame)
    tol_p, tol_r = _number("tol_position", tol_position, 0.0), _number("tol_rotation", tol_rotation, 0.0)
    max_iterations = _count("max_iterations", max_iterations, 1_000_000)
    restarts = _count("restarts", restarts, 10_000)
    gain = _number("nullspace_gain", nullspace_gain, 0.0, 1.0)
    damping = _number("min_damping", min_damping, 0.0, 1e6)
    q_ns = (
        None
        if nullspace_target is None
        else robot.engine.coordinates.check(nullspace_target, name="nullspace_target", allow_batch=False)
    )
    kept, sqrt_w = None, None
    if rows is not None or weights is not None:
        kept = np.arange(6) if rows is None else _rows(rows)
        if weights is not None:
            w = np.asarray(weights, dtype=object)
            if w.shape != (len(kept),):
                raise OptionError(
                    f"`weights` must hold one number per kept row ({len(kept)}), got shape {w.shape}"
                )
            sqrt_w = np.sqrt([_number("weights[i]", v, 0.0, 1e12) for v in w])
    position_rows = (kept if kept is not None else np.arange(6)) < 3
    return Problem(
        fid,
        frame,
        kept,
        sqrt_w,
        position_rows,
        tol_p,
        tol_r,
        max_iterations,
        restarts,
        damping**2,
        q_ns,
        gain,
        has_q0,
    )


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


class _Generator:
    """``rng`` checked now, made into a numpy Generator only when a random restart needs one (making one
    costs more than a converged solve)."""

    def __init__(self, rng: object) -> None:
        ok = (
            rng is None
            or isinstance(rng, (np.random.Generator, np.random.BitGenerator, np.random.SeedSequence))
            or (not isinstance(rng, bool) and isinstance(rng, (int, np.integer)) and rng >= 0)
        )
        if not ok:
            raise OptionError(f"`rng` must be None, a seed >= 0 or a numpy Generator, got {rng!r}")
        self.rng, self.generator = rng, None

    def configurations(self, robot, size: int | None = None) -> np.ndarray:
        if self.generator is None:
            self.generator = np.random.default_rng(self.rng)  # type: ignore[arg-type]
        return robot.random_configuration(self.generator, size=size)


def _rotation_ok(C: np.ndarray) -> bool:
    """CᵀC = I to 1e-6 and det C > 0 (in plain floats: cheaper than numpy for one 3x3)."""
    (a, b, c), (d, e, f), (g, h, i) = C.tolist()
    columns = ((a, d, g), (b, e, h), (c, f, i))
    for j in range(3):
        for k in range(j, 3):
            u, v = columns[j], columns[k]
            if not abs(u[0] * v[0] + u[1] * v[1] + u[2] * v[2] - (j == k)) <= 1e-6:
                return False
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g) > 0


def _position_ok(p: np.ndarray) -> None:
    if not float(np.max(np.abs(p), initial=0.0)) <= MAX_TARGET_DISTANCE:
        raise ParameterizationError(
            f"`target`'s position is farther than {MAX_TARGET_DISTANCE:g} m from the "
            "root: no robot reaches it; give a target in metres within reach"
        )


def _target(target: object, position: str | None, rotation: str | None):
    """(p_d (3,) or None, C_d (3, 3) or None) from a pose (4, 4) or parameters χ."""
    try:
        value = np.asarray(target, dtype=float)
    except (TypeError, ValueError):
        raise ParameterizationError(
            f"Expected `target` to be a (4, 4) pose or parameters χ, got {target!r:.80}"
        ) from None
    if position is None and rotation is None:
        if value.shape != (4, 4) or not np.isfinite(value).all():
            raise ParameterizationError(
                f"Expected `target` to be a finite pose of shape (4, 4) or a batch (N, 4, 4), got {value.shape}; "
                "for parameters χ name their position= and/or rotation= parameterization"
            )
        C = value[:3, :3]
        if not _rotation_ok(C):
            raise ParameterizationError(
                "`target`'s rotation block is not a rotation matrix (CᵀC ≠ I or det <= 0)"
            )
        _position_ok(value[:3, 3])
        return value[:3, 3].copy(), C.copy()
    P = get_position(position) if position is not None else None
    R = get_rotation(rotation) if rotation is not None else None
    m = (P.size if P else 0) + (R.size if R else 0)
    if value.shape != (m,) or not np.isfinite(value).all():
        names = " + ".join(n for n in (position, rotation) if n)
        raise ParameterizationError(
            f"Expected `target` to be finite parameters of shape ({m},) for {names}, got {value.shape}"
        )
    try:
        with np.errstate(all="ignore"):
            p_d = P.to_position(value[: P.size]) if P else None
            C_d = R.to_rotation(value[m - R.size :]) if R else None
    except (ArithmeticError, ValueError):  # e.g. a zero quaternion
        raise ParameterizationError(
            f"`target` {value.tolist()} describes no pose for "
            f"{' + '.join(n for n in (position, rotation) if n)}; give valid parameters"
        ) from None
    if p_d is not None:
        if not np.isfinite(p_d).all():
            raise ParameterizationError(f"`target` {value.tolist()} gives no finite position for {position}")
        _position_ok(p_d)
    if C_d is not None and not (np.isfinite(C_d).all() and _rotation_ok(C_d)):
        raise ParameterizationError(
            f"`target`'s {rotation} parameters {value[m - R.size :].tolist()} describe no "
            "rotation (e.g. a zero quaternion or matrix); give a valid one"
        )
    return p_d, C_d


def _targets(target: object) -> tuple[np.ndarray, np.ndarray]:
    """(p_d (N, 3), C_d (N, 3, 3)) from a batch of poses (N, 4, 4), every one checked."""
    try:
        value = np.asarray(target, dtype=float)
    except (TypeError, ValueError):
        raise ParameterizationError("Expected `target` to be a batch of poses (N, 4, 4) of numbers") from None
    if value.ndim != 3 or value.shape[1:] != (4, 4) or not len(value) or not np.isfinite(value).all():
        raise ParameterizationError(
            f"Expected `target` to be a finite batch of poses (N >= 1, 4, 4), got {value.shape}"
        )
    C = value[:, :3, :3]
    bad = np.flatnonzero(
        (np.abs(np.einsum("nki,nkj->nij", C, C) - np.eye(3)).max(axis=(1, 2)) > 1e-6)
        | (np.linalg.det(C) <= 0)
    )
    if len(bad):
        raise ParameterizationError(
            f"`target`[{bad[0]}]'s rotation block is not a rotation matrix (CᵀC ≠ I or det <= 0)"
        )
    _position_ok(value[:, :3, 3])
    return np.ascontiguousarray(value[:, :3, 3]), np.ascontiguousarray(C)


# -- seeds -----------------------------------------------------------------------------------------
class _Tables:
    """A small LRU of seed tables (bounded: SEED_TABLES tables of at most SEED_TABLE_BYTES each)."""

    def __init__(self) -> None:
        self.lock, self.tables = threading.Lock(), OrderedDict()

    def get(self, key, make):
        with self.lock:
            if key in self.tables:
                self.tables.move_to_end(key)
                return self.tables[key]
        table = make()
        with self.lock:
            self.tables[key] = table
            while len(self.tables) > SEED_TABLES:
                self.tables.popitem(last=False)
        return table


def _seed_table(robot, frame: str, use_p: bool, use_R: bool):
    """(configurations (K, dof), a KD-tree over [p, w·vec(C)/√2] of ``frame`` at them)."""
    from scipy.spatial import cKDTree

    size = max(64, min(SEED_TABLE_SIZE, SEED_TABLE_BYTES // (8 * (robot.dof + 12))))
    configs = robot.random_configuration(np.random.default_rng(SEED_TABLE_RNG), size=size)
    poses = robot.frame_pose(configs, frame)
    return configs, cKDTree(
        _embed(poses[:, :3, 3] if use_p else None, poses[:, :3, :3] if use_R else None, len(configs))
    )


def _embed(p, C, n: int) -> np.ndarray:
    """Points whose squared distance is |Δp|² + w²‖ΔC‖²/2 = |Δp|² + w²·2(1 − cos θ) ≈ |Δp|² + (wθ)²."""
    parts = [p] if p is not None else []
    if C is not None:
        parts.append(C.reshape(n, 9) * (SEED_ROTATION_WEIGHT / math.sqrt(2.0)))
    return np.hstack(parts) if parts else np.zeros((n, 1))


def first_seeds(robot, problem: Problem, p_d, C_d, q0) -> np.ndarray:
    """The seeded attempts' starts (N, S, dof) for targets p_d (N, 3) | None, C_d (N, 3, 3) | None."""
    joints = robot.engine.coordinates
    n = len(p_d) if p_d is not None else len(C_d)
    if q0 is not None:
        return np.broadcast_to(np.clip(q0, joints.lower, joints.upper), (n, robot.dof))[:, None, :].copy()
    bounded = np.isfinite(joints.lower) & np.isfinite(joints.upper)
    middle = (np.where(bounded, joints.lower, 0.0) + np.where(bounded, joints.upper, 0.0)) / 2
    first = middle if problem.q_ns is None else np.clip(problem.q_ns, joints.lower, joints.upper)
    tables = robot.engine.memoized("ik seed tables", _Tables)
    key = (problem.frame, p_d is not None, C_d is not None)
    configs, tree = tables.get(
        key, lambda: _seed_table(robot, problem.frame, p_d is not None, C_d is not None)
    )
    k = min(NEAREST_SEEDS, len(configs))
    _, index = tree.query(_embed(p_d, C_d, n), k=k, workers=-1 if n > 256 else 1)
    seeds = np.empty((n, k + 1, robot.dof))
    seeds[:, :k] = configs[np.asarray(index).reshape(n, k)]
    seeds[:, k] = first  # the middle of the ranges (or the nullspace target): rarely the nearest
    return seeds


# -- joint-limit weights ---------------------------------------------------------------------------
class LimitWeights:
    """Chan & Dubey's weighted least norm: w_i = 1 + |∂φ/∂q_i| while joint i approaches a limit (|∂φ/∂q_i|
    grew since the last iteration), else 1, with φ = Σ (u−l)² / (4 (u−q)(q−l)), so
    ∂φ/∂q = (u−l)² (2q − u − l) / (4 (u−q)² (q−l)²); unbounded joints: 1. Works on q (dof,) or (n, dof)."""

    def __init__(self, lower: np.ndarray, upper: np.ndarray) -> None:
        self.bounded = np.isfinite(lower) & np.isfinite(upper)
        self.any = bool(self.bounded.any())
        self.lower, self.upper = np.where(self.bounded, lower, -1.0), np.where(self.bounded, upper, 1.0)
        self.middle_twice = self.lower + self.upper
        self.quarter_span_sq = np.where(self.bounded, self.upper - self.lower, 0.0) ** 2 / 4  # 0: unbounded
        self._lower, self._upper = self.lower.tolist(), self.upper.tolist()
        self._mid2, self._quarter = self.middle_twice.tolist(), self.quarter_span_sq.tolist()

    def inverse_weights(self, q: np.ndarray, previous: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        """(1 / w, |∂φ/∂q|) at q, given |∂φ/∂q| of the last iteration (None: the first). Distances to the
        limits are floored at 1e-12 (a joint on its limit gets a huge finite gradient, weight ~0)."""
        distances = np.maximum(self.upper - q, 1e-12) * np.maximum(q - self.lower, 1e-12)
        grad = self.quarter_span_sq * np.abs(2 * q - self.middle_twice) / (distances * distances)
        inverse = 1.0 / (1.0 + grad)
        if previous is None:
            return inverse, grad
        return np.where(grad > previous, inverse, 1.0), grad

    def inverse_weights_one(self, q: np.ndarray, previous: list | None) -> tuple[np.ndarray, list]:
        """:meth:`inverse_weights` for one q (dof,) in plain floats (a dozen numpy calls on a 6-vector cost
        more than the arithmetic); ``previous`` and the returned gradient are lists."""
        grad, inverse = [], []
        for i, (qi, lo, hi, mid2, quarter) in enumerate(
            zip(q.tolist(), self._lower, self._upper, self._mid2, self._quarter)
        ):
            du, dl = hi - qi, qi - lo
            d = (du if du > 1e-12 else 1e-12) * (dl if dl > 1e-12 else 1e-12)
            g = quarter * abs(2.0 * qi - mid2) / (d * d)
            grad.append(g)
            inverse.append(1.0 / (1.0 + g) if previous is None or g > previous[i] else 1.0)
        return np.array(inverse), grad


# -- the single-target solver ----------------------------------------------------------------------
def solve_one(robot, problem: Problem, p_d, C_d, seeds: np.ndarray, generator, wrap: bool = True) -> IKResult:
    """Attempts from each seed, then ``restarts`` random ones; the first converged (or the best) wins."""
    kin = robot.engine
    joints = kin.coordinates
    model, data = kin.model, kin.data()
    lower, upper, fid = joints.lower, joints.upper, problem.fid
    tol_p, tol_r, max_iterations = problem.tol_position, problem.tol_rotation, problem.max_iterations
    rows, sqrt_w, position_rows = problem.rows, problem.sqrt_weights, problem.position_rows
    damping_sq, q_ns, gain = problem.damping_sq, problem.q_ns, problem.gain
    attempts = len(seeds) + problem.restarts
    e = np.zeros(6)
    full = rows is None and p_d is not None and C_d is not None
    part = slice(0 if p_d is not None else 3, 6 if C_d is not None else 3)
    pinocchio_q, fold, identity = kin.pinocchio_q, joints.fold, joints.identity
    frame_jacobian, place, log3, LWA = (
        pin.computeFrameJacobian,
        pin.updateFramePlacement,
        pin.log3,
        pin.LOCAL_WORLD_ALIGNED,
    )
    solve, maximum, minimum, hypot = np.linalg.solve, np.maximum, np.minimum, math.hypot
    m = len(rows) if rows is not None else part.stop - part.start
    eye = np.eye(m)
    limits = LimitWeights(lower, upper)
    best, total = None, 0
    for attempt in range(attempts):
        q = (seeds[attempt] if attempt < len(seeds) else generator.configurations(robot)).copy()
        last = attempt == attempts - 1 or (attempt == 0 and problem.patient_first)
        iteration, previous = 0, None
        while True:
            J = frame_jacobian(model, data, q if identity else pinocchio_q(q), fid, LWA)
            M = place(model, data, fid)
            if p_d is not None:
                e[:3] = p_d - M.translation
            if C_d is not None:
                e[3:] = log3(C_d @ M.rotation.T)
            if rows is None:
                e0, e1, e2, e3, e4, e5 = e.tolist()
                ep, er = hypot(e0, e1, e2), hypot(e3, e4, e5)
                err = e if full else e[part]
            else:
                e_d = np.concatenate((C_d.T @ e[:3], C_d.T @ e[3:]))[rows]
                ep = math.sqrt(float(e_d[position_rows] @ e_d[position_rows]))
                er = math.sqrt(float(e_d[~position_rows] @ e_d[~position_rows]))
                err = e_d if sqrt_w is None else e_d * sqrt_w
            score = ep + SEED_ROTATION_WEIGHT * er
            done = ep <= tol_p and er <= tol_r
            if (
                done
                or iteration == max_iterations
                or (iteration == PROBE_ITERATIONS and score > GIVE_UP and not last)
            ):
                break
            iteration += 1
            if not identity or J.ndim == 1:
                J = fold(J.reshape(6, -1))
            if rows is not None:
                J = np.vstack((C_d.T @ J[:3], C_d.T @ J[3:]))[rows]
                if sqrt_w is not None:
                    J = J * sqrt_w[:, None]
            elif not full:
                J = J[part]
            if limits.any:
                w, previous = limits.inverse_weights_one(q, previous)
                JW = J * w
            else:
                JW = J
            A = JW @ J.T
            A += (0.5 * float(err @ err) + damping_sq) * eye
            if q_ns is None:
                q += JW.T @ solve(A, err)
            else:
                z = (gain * min(1.0, score / NULLSPACE_FADE)) * (q_ns - q)
                y = solve(A, np.column_stack((err, J @ z)))
                q += JW.T @ (y[:, 0] - y[:, 1]) + z
            minimum(maximum(q, lower, out=q), upper, out=q)
        total += iteration
        if best is None or score < best[3]:
            best = (q, ep, er, score, attempt)
        if done:
            break
    q, ep, er, _, attempt = best
    if wrap:
        q[joints.continuous] = np.remainder(q[joints.continuous] + np.pi, 2 * np.pi) - np.pi  # into [-π, π)
    return IKResult(q, bool(ep <= tol_p and er <= tol_r), total, ep, er, attempt)


__all__ = ["IKResult", "inverse_kinematics"]
