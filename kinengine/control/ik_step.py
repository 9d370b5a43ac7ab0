"""One IK step, written once for every solver (single target, several frames, batches): the damping rule,
the joint-limit weights, the nullspace pull, the give-way rule and the damped least-squares step itself.

Step (Robot Dynamics lecture notes, ETH Zurich, §2.8; Sugihara's Levenberg–Marquardt damping): with the
error e [m, rad] and its Jacobian J (m, dof),
    Δq = W⁻¹Jᵀ (J W⁻¹Jᵀ + λ² S⁻²)⁻¹ (e − J z) + z,    q ← clip(q + Δq, lower, upper),
λ² = DAMPING_SCALE·|S e|² + λ_min², S = diag(1, 1, 1, ρ, ρ, ρ) on a full pose's rows (ρ =
ROTATION_ROW_WEIGHT [m/rad]; S = I for rows=/weights= targets), W Chan & Dubey's limit weights
(:class:`LimitWeights`), z = gain·min(1, score / NULLSPACE_FADE)·(q_ns − q) the pull towards the nullspace
target: :func:`take_step` for one configuration, :func:`take_steps` for columns of them. Coordinates that
move no target frame are left out (:func:`moving`). :func:`gives_way`: when an attempt makes way for the
next seed (still far, stalled, crawling) or ends (stuck).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .ik_seeds import SEED_ROTATION_WEIGHT

if TYPE_CHECKING:  # named for the checker only
    from ..kinematics.engine import Kinematics

PROBE_ITERATIONS = 10
GIVE_UP = 1e-2
"""[m] score |e_p| + 0.2 m/rad·|e_R| above which an attempt gives way after PROBE_ITERATIONS iterations."""
STALL_FROM, STALL_SPAN, STALL_RATIO = 4, 3, 0.8
"""From iteration STALL_FROM on, an attempt whose score is above STALL_RATIO × its score STALL_SPAN iterations
earlier gives way (stuck on a joint limit or in a local minimum)."""
CRAWL = 30
"""An attempt that is not the last gives way after this many iterations unconverged: it crawls (a joint on a
limit, whose clipped step leaves the others' short, shrinks the error only linearly) where the next seed
converges in a few (crawling attempts held a batch of Panda targets for max_iterations)."""
STUCK_SPAN, STUCK_RATIO = 10, 0.9
"""An attempt, the last one too (but not one from the caller's q0), ends after STUCK_SPAN iterations without a
score below STUCK_RATIO × its best (in a local minimum or against a limit: it would crawl to max_iterations
unchanged)."""
DAMPING_SCALE = 0.1
"""λ² = DAMPING_SCALE·|e|² + λ_min² (Sugihara's rule λ² = ½ eᵀW_E e + λ_min² with W_E = 0.2·I, e weighted as
below): weaker than ½|e|², so the first steps from a stored seed go further."""
ROTATION_ROW_WEIGHT = SEED_ROTATION_WEIGHT
"""[m/rad] a full pose's rotation rows (error and Jacobian) are weighted by this in the least squares, which
then minimizes |e_p|² + (0.2 m/rad·|e_R|)², the squared pose distance that ranks attempts and seeds."""
POSE_ROW_DAMPING = np.array([1.0, 1.0, 1.0] + [1.0 / ROTATION_ROW_WEIGHT**2] * 3)
"""S⁻² of a full pose's six rows: λ² S⁻² is the damping on the diagonal of J W⁻¹Jᵀ."""
NULLSPACE_FADE = 5e-2
"""[m] the nullspace pull is gain · min(1, score / this): full strength far from the target, fading with
the error so that its second-order effect on the task (∝ |z|²) vanishes and the solve converges."""


class LimitWeights:
    """Chan & Dubey's weighted least norm: w_i = 1 + |∂φ/∂q_i| while joint i approaches a limit (|∂φ/∂q_i|
    grew since the last iteration), else 1, with φ = Σ (u−l)² / (4 (u−q)(q−l)), so
    ∂φ/∂q = (u−l)² (2q − u − l) / (4 (u−q)² (q−l)²); unbounded joints: 1.
    ``continuous`` (dof,) bool, optional: kept as the indices of the joints a solution wraps into [-π, π)
    (None if there are none)."""

    def __init__(self, lower: np.ndarray, upper: np.ndarray, continuous: np.ndarray | None = None) -> None:
        self.bounds, self.bounded = (lower, upper), np.isfinite(lower) & np.isfinite(upper)
        self.any = bool(self.bounded.any())
        self.lower, self.upper = np.where(self.bounded, lower, -1.0), np.where(self.bounded, upper, 1.0)
        self.middle_twice = self.lower + self.upper
        self.quarter_span_sq = np.where(self.bounded, self.upper - self.lower, 0.0) ** 2 / 4  # 0: unbounded
        columns = (self.lower, self.upper, self.middle_twice, self.quarter_span_sq)
        self._rows = np.column_stack(columns).tolist()  # per joint (l, u, l + u, (u − l)²/4)
        self.continuous = np.flatnonzero(continuous) if continuous is not None and continuous.any() else None

    def wrap(self, q: np.ndarray) -> None:
        """The continuous joints' angles of q (dof,) or (n, dof) into [-π, π), in place."""
        turns = self.continuous
        if turns is not None:
            q[..., turns] = np.remainder(q[..., turns] + np.pi, 2 * np.pi) - np.pi

    def inverse_weights(self, q: np.ndarray, previous: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(1 / w, |∂φ/∂q|) for columns q (dof, r) (one configuration a column, the batched solver's layout),
        given |∂φ/∂q| of the last iteration (dof, r) (−1 where there is none: every joint weighted).
        Distances to the limits are floored at 1e-12 (a joint on its limit gets a huge finite gradient,
        weight ~0)."""
        lower, upper = self.lower[:, None], self.upper[:, None]
        distances = np.maximum(upper - q, 1e-12) * np.maximum(q - lower, 1e-12)
        spread = np.abs(2 * q - self.middle_twice[:, None])
        grad = self.quarter_span_sq[:, None] * spread / (distances * distances)
        return np.where(grad > previous, 1.0 / (1.0 + grad), 1.0), grad

    def inverse_weights_one(self, q: np.ndarray, previous: list | None) -> tuple[np.ndarray, list]:
        """:meth:`inverse_weights` for one q (dof,) in plain floats (a dozen numpy calls on a 6-vector cost
        more than the arithmetic); ``previous`` and the returned gradient are lists."""
        grad: list[float] = []
        append = grad.append
        for qi, (lo, hi, mid2, quarter) in zip(q.tolist(), self._rows, strict=True):
            du, dl = hi - qi, qi - lo
            d = (du if du > 1e-12 else 1e-12) * (dl if dl > 1e-12 else 1e-12)
            append(quarter * abs(2.0 * qi - mid2) / (d * d))
        if previous is None:
            return np.array([1.0 / (1.0 + g) for g in grad]), grad
        inverse = [1.0 / (1.0 + g) if g > p else 1.0 for g, p in zip(grad, previous, strict=True)]
        return np.array(inverse), grad


@dataclass(frozen=True)
class Moving:
    """The coordinates ``coords`` = [c0, c1) spanning every one that moves a set of frames (the ``free``
    others' Jacobian columns are zero: left out of the step, at the nullspace target if there is one), the
    run ``pin`` of Pinocchio's q and v they are one for one with (None: mapped), and their ``limits``."""

    coords: slice
    pin: slice | None
    limits: LimitWeights
    free: np.ndarray


def moving(kin: Kinematics, fids: tuple[int, ...]) -> Moving:
    """The :class:`Moving` coordinates of frames ``fids`` (Pinocchio frame ids), made once per set."""

    def make() -> Moving:
        model, c = kin.model, kin.coordinates
        joints = {j for fid in fids for j in model.supports[model.frames[fid].parentJoint] if j}
        rows = [model.joints[j].idx_v + k for j in joints for k in range(model.joints[j].nv)]
        used = np.flatnonzero(c.matrix[rows].any(axis=0))
        c0, c1 = (int(used[0]), int(used[-1]) + 1) if len(used) else (0, c.dof)
        entries = np.flatnonzero((c.leader >= c0) & (c.leader < c1))  # Pinocchio's q from [c0, c1)
        pin = slice(int(entries[0]), int(entries[0]) + c1 - c0) if len(entries) == c1 - c0 > 0 else None
        one = (
            pin is not None and (c.leader[pin] == np.arange(c0, c1)).all() and (c.multiplier[pin] == 1).all()
        )
        limits = LimitWeights(c.lower[c0:c1], c.upper[c0:c1], c.continuous[c0:c1])
        free = np.r_[0:c0, c1 : c.dof].astype(np.intp)
        return Moving(slice(c0, c1), pin if one and not c.offset[pin].any() else None, limits, free)

    return kin.memoized(("ik moving", fids), make)


def gives_way(
    iteration: int | np.ndarray,
    score: float | np.ndarray,
    history: Sequence[float] | np.ndarray,
    patient: bool | np.ndarray,
    since: int | np.ndarray,
    from_q0: bool | np.ndarray,
) -> bool | np.ndarray:
    """Whether an attempt ends without converging at this iteration: one that is not ``patient`` (not the
    last, nor from the caller's q0) when its score is still above GIVE_UP after PROBE_ITERATIONS, stalled
    (from STALL_FROM on, above STALL_RATIO × its score STALL_SPAN iterations earlier) or crawling (CRAWL
    iterations); any but one ``from_q0`` when stuck (``since`` >= STUCK_SPAN iterations without a score
    below STUCK_RATIO × its best): the caller's start may crawl to max_iterations, as near a joint limit.
    ``history``: the earlier scores, oldest first (a list for one attempt; rows (≥ STALL_SPAN, r) for
    columns of attempts, with the other arguments (r,): an array out)."""
    if isinstance(iteration, int):  # one attempt, in plain floats
        probed = (iteration == PROBE_ITERATIONS and score > GIVE_UP) or iteration >= CRAWL
        stalled = iteration >= STALL_FROM and score > STALL_RATIO * history[-STALL_SPAN]
        return (since >= STUCK_SPAN and not from_q0) or (not patient and (probed or stalled))
    probed = ((iteration == PROBE_ITERATIONS) & (score > GIVE_UP)) | (iteration >= CRAWL)
    stalled = (iteration >= STALL_FROM) & (score > STALL_RATIO * history[-STALL_SPAN])
    return ((probed | stalled) & ~patient) | ((since >= STUCK_SPAN) & ~from_q0)


def damping(squared: float | np.ndarray, damping_sq: float) -> float | np.ndarray:
    """λ² = DAMPING_SCALE·|S e|² + λ_min² for the weighted squared error |S e|² (a float or (r,))."""
    return DAMPING_SCALE * squared + damping_sq


def nullspace_pull(gain: float, score: float | np.ndarray, q_ns: np.ndarray, q: np.ndarray) -> np.ndarray:
    """z = gain·min(1, score / NULLSPACE_FADE)·(q_ns − q), for q (dof,) or columns q (dof, r), q_ns (dof,)."""
    if q.ndim == 2:
        return (gain * np.minimum(1.0, score / NULLSPACE_FADE)) * (q_ns[:, None] - q)
    return (gain * min(1.0, float(score) / NULLSPACE_FADE)) * (q_ns - q)


def take_step(
    q: np.ndarray,
    J: np.ndarray,
    err: np.ndarray,
    normal: tuple[np.ndarray, np.ndarray],
    diagonal: np.ndarray | float,
    weigh: Callable[[np.ndarray, list | None], tuple[np.ndarray, list]] | None,
    previous: list | None,
    bounds: tuple[np.ndarray, np.ndarray],
    nullspace: tuple[np.ndarray | None, float, float],
    dposv: Callable[..., tuple],
) -> list | None:
    """One step for one configuration, in place: q ← clip(q + W⁻¹Jᵀ A⁻¹ (e − J z) + z, lower, upper) with
    A = J W⁻¹Jᵀ + diag(``diagonal``) (λ² S⁻²) written into ``normal`` = (A (m, m), a view of its diagonal)
    and solved by Cholesky (``dposv``; least squares where it is not positive definite). ``weigh``:
    LimitWeights.inverse_weights_one (None: W = I), ``previous`` its last gradient, which is returned for the
    next step. ``nullspace`` (q_ns, gain, score): the pull z towards q_ns (None: none)."""
    JW = J
    if weigh is not None:
        w, previous = weigh(q, previous)
        JW = J * w
    A, A_diagonal = normal
    np.dot(JW, J.T, out=A)
    A_diagonal += diagonal
    q_ns, gain, score = nullspace
    z = None if q_ns is None else nullspace_pull(gain, score, q_ns, q)
    b = err if z is None else err - J @ z
    _, x, info = dposv(A, b)
    q += np.dot(JW.T, x if info == 0 else np.linalg.lstsq(A, b, rcond=None)[0])
    if z is not None:
        q += z
    np.minimum(np.maximum(q, bounds[0], out=q), bounds[1], out=q)
    return previous


CHOLESKY_FROM = 256
"""From this many columns on, :func:`take_steps` factorizes A column-wise (one numpy pass per entry over all
columns, ``benchmarks/ik_batch_step.py``); below it numpy's stacked solve (fewer calls)."""


def take_steps(
    q: np.ndarray,
    J: np.ndarray,
    err: np.ndarray,
    w: np.ndarray | None,
    diagonal: np.ndarray,
    nullspace: tuple[np.ndarray | None, float, np.ndarray],
    buffers: tuple[np.ndarray, np.ndarray],
) -> np.ndarray:
    """q + Δq for every column (q (dof, r), J (m, dof, r), err (m, r), 1/w (dof, r) or None, ``diagonal``
    λ² S⁻² (m, r)): the step of :func:`take_step` for each column, not clipped. From CHOLESKY_FROM columns
    on, A = J W⁻¹Jᵀ + diag(λ² S⁻²) is factorized A = L Lᵀ column-wise (:func:`_cholesky_solve`) and a
    column whose A is not positive definite (a pivot <= 0) is solved again by numpy; below it, numpy solves
    them all (:func:`_solve_stacked`: LU, least squares where A is singular). ``buffers``: (J W⁻¹
    (≥m, dof, ≥r), A (≥ m·m·r, flat)), reused between iterations."""
    m, r = len(J), J.shape[2]
    JW = J if w is None else np.multiply(J, w, out=buffers[0][:m, : J.shape[1], :r])
    q_ns, gain, score = nullspace
    z = None if q_ns is None else nullspace_pull(gain, score, q_ns, q)
    if z is not None:
        err = err - np.einsum("ijn,jn->in", J, z)
    if r < CHOLESKY_FROM:
        y = _solve_stacked(_normal_stack(JW, J, diagonal, buffers[1]), err)
    else:
        A = buffers[1][: m * m * r].reshape(m, m, r)
        for i in range(m):  # the lower triangle: the factorization reads no more
            np.einsum("kn,jkn->jn", JW[i], J[: i + 1], out=A[i, : i + 1])
            A[i, i] += diagonal[i]
        y, refused = _cholesky_solve(A, err)
        if refused.any():  # A was overwritten by L: rebuilt for those columns
            A_k = _normal_stack(JW[..., refused], J[..., refused], diagonal[:, refused], None)
            y[:, refused] = _solve_stacked(A_k, err[:, refused])
    return q + np.einsum("ijn,in->jn", JW, y) + (0.0 if z is None else z)


def _normal_stack(
    JW: np.ndarray, J: np.ndarray, diagonal: np.ndarray, buffer: np.ndarray | None
) -> np.ndarray:
    """A = J W⁻¹Jᵀ + diag(``diagonal``) as a stack (r, m, m), in ``buffer`` (flat) if given."""
    m, r = len(J), J.shape[2]
    A = np.empty((r, m, m)) if buffer is None else buffer[: r * m * m].reshape(r, m, m)
    np.einsum("ikn,jkn->nij", JW, J, out=A)
    A.reshape(r, m * m)[:, :: m + 1] += diagonal.T
    return A


def _solve_stacked(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """x (m, r) with A x = b for a stack A (r, m, m), by numpy's stacked LU solve; the least-squares
    solution (pseudo-inverse) where one of them is singular."""
    try:
        return np.linalg.solve(A, b.T[..., None])[..., 0].T
    except np.linalg.LinAlgError:  # exactly singular (λ_min = 0 where no joint moves the frame)
        return (np.linalg.pinv(A) @ b.T[..., None])[..., 0].T


def _cholesky_solve(A: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(x, refused): x with A x = b for the columns of symmetric A (m, m, r) (lower triangle read and
    overwritten by L, A = L Lᵀ), b (m, r), each step over every column at once; ``refused`` (r,) bool marks
    the columns where a pivot was not positive (A not positive definite: their x is not valid)."""
    m, L = len(A), A
    inverse, refused = np.empty_like(b), np.zeros(b.shape[1], dtype=bool)  # 1 / L_jj
    for j in range(m):
        pivot = A[j, j] - np.einsum("kn,kn->n", L[j, :j], L[j, :j]) if j else A[j, j]
        bad = ~(pivot > 0.0)  # NaN too
        if bad.any():
            refused |= bad
            pivot = np.where(bad, 1.0, pivot)
        inverse[j] = 1.0 / np.sqrt(pivot)
        if j + 1 < m:
            column = A[j + 1 :, j] - np.einsum("ikn,kn->in", L[j + 1 :, :j], L[j, :j]) if j else A[1:, 0]
            L[j + 1 :, j] = column * inverse[j]
    x = np.empty_like(b)  # y of L y = b, then overwritten from the bottom up by x of Lᵀ x = y
    for i in range(m):
        x[i] = (b[i] - np.einsum("kn,kn->n", L[i, :i], x[:i]) if i else b[i]) * inverse[i]
    for i in range(m - 1, -1, -1):
        if i + 1 < m:
            x[i] = (x[i] - np.einsum("kn,kn->n", L[i + 1 :, i], x[i + 1 :])) * inverse[i]
        else:
            x[i] *= inverse[i]
    return x, refused


__all__ = ["LimitWeights", "Moving", "damping", "gives_way", "moving", "take_step", "take_steps"]
