"""Kinematic singularity measures of the geometric Jacobian J_e0 (rows [linear; angular], in I).

A *kinematic* singularity is a property of the robot: J_e0(q) loses rank and some twist of the
frame cannot be produced by any q̇. It has nothing to do with the *representation* singularities
of a parameterization χ (E(χ) singular, :class:`~kinengine.RepresentationSingularityError`),
which another choice of χ removes; no choice of coordinates removes a kinematic one.

For J = J_e0[rows] (m, dof) with singular values σ_1 >= ... (SVD J = U Σ Vᵀ):
* Yoshikawa manipulability w = sqrt(det(J Jᵀ)) = Π σ_i (0 whenever m > dof);
* condition number κ = σ_max / σ_min (inf at a singularity);
* lost directions: an orthonormal basis of the twists J cannot produce (U's columns beyond the
  rank, rank = number of σ_i > ``tolerance``), rows of I (unit twists, [linear; angular] in I);
* velocity ellipsoid {J_v q̇ : |q̇| <= 1}: axes U_v, semi-axes σ_v [m/s per unit |q̇|].
Mixing linear [m/rad] and angular [1] rows makes κ and w depend on the unit of length.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from ..errors import ConfigurationError, KinematicSingularityError, ParameterizationError
from ..kinematics.options import checked_tolerance

if TYPE_CHECKING:  # named for the checker only
    from .robot_like import RobotLike

ROW_LABELS = ("vx", "vy", "vz", "wx", "wy", "wz")
ROW_SETS = {"all": (0, 1, 2, 3, 4, 5), "linear": (0, 1, 2), "angular": (3, 4, 5)}
DEFAULT_TOLERANCE = 1e-6
"""σ at or below which a direction counts as lost [m/rad for linear rows, 1 for angular rows]."""
Rows = str | Sequence[str | int]
"""'all', 'linear', 'angular', or row labels (vx vy vz wx wy wz) / indices 0-5."""


@dataclass(frozen=True)
class LostDirection:
    """A unit twist u (6,) in I that J cannot produce, with gain |Jᵀu| (0 at an exact singularity)."""

    twist: np.ndarray
    gain: float
    description: str


@dataclass(frozen=True)
class SingularityReport:
    """Singular values and measures of J_e0[rows] at one configuration (see the module doc)."""

    frame: str | None
    rows: tuple[str, ...]
    singular_values: np.ndarray
    manipulability: float
    condition_number: float
    rank: int
    tolerance: float
    lost_directions: tuple[LostDirection, ...]

    @property
    def is_singular(self) -> bool:
        """True if J[rows] has fewer than len(rows) singular values above ``tolerance``."""
        return self.rank < len(self.rows)

    def require_regular(self) -> SingularityReport:
        """This report if J[rows] has full row rank, else KinematicSingularityError (with ``.report``)."""
        if self.is_singular:
            error = KinematicSingularityError(
                f"{self}\nThe robot itself cannot move its frame along these directions at this q; "
                "no choice of pose parameterization changes that (unlike a representation singularity)."
            )
            error.report = self
            raise error
        return self

    def __str__(self) -> str:
        what = f"J_e0 rows {' '.join(self.rows)}" + (f" of frame {self.frame!r}" if self.frame else "")
        sv = ", ".join(f"{s:.4g}" for s in self.singular_values)
        head = (
            f"kinematic singularity: {what} has rank {self.rank} < {len(self.rows)}"
            if self.is_singular
            else f"regular: {what} has full rank {self.rank}"
        )
        lines = [
            head,
            f"  singular values: {sv}",
            f"  manipulability sqrt(det(J Jᵀ)) = {self.manipulability:.4g}, "
            f"condition number = {self.condition_number:.4g}",
        ]
        if self.lost_directions:
            lines.append(f"  lost twist directions in the root frame (σ <= {self.tolerance:.1e}):")
            lines += [f"    {d.description}  (gain {d.gain:.2e})" for d in self.lost_directions]
        return "\n".join(lines)


@dataclass(frozen=True)
class VelocityEllipsoid:
    """{J_v q̇ : |q̇| <= 1} of a frame origin: ``center`` [m] in I, ``axes`` (3, 3) unit columns in I,
    ``semi_axes`` (3,) [m/s per unit |q̇|], longest first (0 along a lost direction)."""

    center: np.ndarray
    axes: np.ndarray
    semi_axes: np.ndarray


def analyze_jacobian(
    J: npt.ArrayLike, rows: Rows = "all", *, tolerance: float = DEFAULT_TOLERANCE, frame: str | None = None
) -> SingularityReport:
    """The :class:`SingularityReport` of a geometric Jacobian J_e0 (6, dof) in "local_world_aligned"."""
    tolerance = checked_tolerance(tolerance)
    index = list(_rows(rows))
    J = np.asarray(J, dtype=float)
    if J.ndim != 2 or J.shape[0] != 6:
        raise ConfigurationError(f"Expected `J` to have shape (6, dof), got {J.shape}")
    Js, fits = J[index], len(index) <= J.shape[1]  # fits: m <= dof, else w = 0 and κ = inf
    U, s, _ = np.linalg.svd(Js, full_matrices=True)
    rank = int(np.count_nonzero(s > tolerance))
    w = float(np.prod(s)) if fits else 0.0
    kappa = float(s[0] / s[-1]) if fits and s.size and s[-1] > 0 else float("inf")
    twists = np.zeros((len(index) - rank, 6))  # the lost directions, rows [linear; angular] in I
    twists[:, index] = _readable_basis(U[:, rank:])
    lost = tuple(LostDirection(t, float(np.linalg.norm(Js.T @ t[index])), describe_twist(t)) for t in twists)
    labels = tuple(ROW_LABELS[i] for i in index)
    return SingularityReport(frame, labels, s, w, kappa, rank, tolerance, lost)


def singularity_report(
    robot: RobotLike,
    q: npt.ArrayLike,
    frame: str | None = None,
    rows: Rows = "all",
    *,
    tolerance: float = DEFAULT_TOLERANCE,
) -> SingularityReport:
    """The :class:`SingularityReport` of J_e0(q) of ``frame`` (default: end effector), q (dof,)."""
    frame = robot.end_effector if frame is None else frame
    q = robot.check_configuration(q, check_limits=False, batch=False)  # manipulability() takes batches
    return analyze_jacobian(robot.jacobian(q, frame), rows, tolerance=tolerance, frame=frame)


def manipulability(
    robot: RobotLike, q: npt.ArrayLike, frame: str | None = None, rows: Rows = "all"
) -> float | npt.NDArray[np.float64]:
    """Yoshikawa's w = sqrt(det(J Jᵀ)) of J_e0[rows]: float for q (dof,), (N,) for q (N, dof)."""
    index = list(_rows(rows))
    J = robot.jacobian(q, frame)[..., index, :]
    if len(index) > robot.dof:
        return 0.0 if J.ndim == 2 else np.zeros(len(J))
    if len(index) == robot.dof:  # square: Π σ_i = |det J| (an LU, several times cheaper than the SVD)
        w = np.abs(np.linalg.det(J))
    else:
        w = np.prod(np.linalg.svd(J, compute_uv=False), axis=-1)
    return float(w) if J.ndim == 2 else w


def manipulability_gradient(
    robot: RobotLike, q: npt.ArrayLike, frame: str | None = None, rows: Rows = "all"
) -> npt.NDArray[np.float64]:
    """∂w/∂q (dof,) of Yoshikawa's w = Π σ_i of J_e0[rows] at one q (dof,), from the kinematic Hessian
    H[:, j, k] = ∂J[:, j]/∂q_k: ∂σ_i/∂q_k = u_iᵀ (∂J/∂q_k) v_i (J = U Σ Vᵀ), so
    ∂w/∂q_k = Σ_i (Π_{j≠i} σ_j) u_iᵀ (∂J/∂q_k) v_i. Units of w per [rad | m]. Zero when len(rows) > dof
    (w ≡ 0). Exact where the σ_i are distinct; ascend it (q̇ = k·∂w/∂q, e.g. in a lower priority level)
    to steer away from singularities.
    """
    index = list(_rows(rows))
    J = robot.jacobian(q, frame)
    if J.ndim != 2:
        raise ParameterizationError("manipulability_gradient takes one configuration q (dof,), not a batch")
    if len(index) > robot.dof:
        return np.zeros(robot.dof)
    J = J[index]
    H = robot.kinematic_hessian(q, frame)[index]  # (m, dof, dof)
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    others = np.array([np.prod(np.delete(s, i)) for i in range(len(s))])
    dsigma = np.einsum("mi,mjk,ij->ik", U, H, Vt)  # [i, k] = u_iᵀ ∂J/∂q_k v_i
    return np.asarray(others @ dsigma, dtype=np.float64)


def velocity_ellipsoid(robot: RobotLike, q: npt.ArrayLike, frame: str | None = None) -> VelocityEllipsoid:
    """The velocity manipulability ellipsoid of ``frame``'s origin (eigenvectors of J_v J_vᵀ), q (dof,)."""
    frame = robot.end_effector if frame is None else frame
    q = robot.check_configuration(q, check_limits=False, batch=False)
    T = robot.frame_pose(q, frame)
    U, s, _ = np.linalg.svd(robot.jacobian(q, frame)[:3], full_matrices=True)
    return VelocityEllipsoid(T[:3, 3].copy(), U, np.pad(s, (0, 3 - s.size)))


def require_regular(robot: RobotLike, q: npt.ArrayLike, *options: Any, **keywords: Any) -> SingularityReport:
    """:func:`singularity_report` (the same arguments: frame, rows, tolerance) if J_e0[rows] has full row
    rank, else KinematicSingularityError with ``.report`` (:meth:`SingularityReport.require_regular`)."""
    return singularity_report(robot, q, *options, **keywords).require_regular()


def describe_twist(twist: np.ndarray, digits: int = 2) -> str:
    """'linear along y', 'angular about (0.00, 0.71, 0.71)' or 'a·linear along … + b·angular about …'."""
    parts = []
    for kind, word, vec in (("linear", "along", twist[:3]), ("angular", "about", twist[3:])):
        norm = float(np.linalg.norm(vec))
        if norm < 10.0 ** -(digits + 1):
            continue
        unit = vec / norm
        axis = int(np.argmax(np.abs(unit)))
        if abs(unit[axis]) > 1.0 - 10.0 ** -(digits + 2):
            where = ("-" if unit[axis] < 0 else "") + "xyz"[axis]
        else:
            where = "(" + ", ".join(f"{c:.{digits}f}" for c in unit) + ")"
        parts.append((norm, f"{kind} {word} {where}"))
    if len(parts) <= 1:
        return parts[0][1] if parts else "zero twist"
    return " + ".join(f"{norm:.{digits}f}·{text}" for norm, text in parts)


def _rows(rows: Rows) -> tuple[int, ...]:
    """Row indices of J for "all", "linear", "angular" or a sequence of labels (vx … wz) / indices."""
    if isinstance(rows, str) and rows in ROW_SETS:
        return ROW_SETS[rows]
    items = (rows,) if isinstance(rows, str) else rows
    index: list[int] = []
    if not isinstance(items, (bytes, dict)) and hasattr(items, "__iter__"):
        for row in items:
            if isinstance(row, (int, np.integer)) and not isinstance(row, (bool, np.bool_)) and 0 <= row < 6:
                index.append(int(row))
            elif type(row) is str and row in ROW_LABELS:
                index.append(ROW_LABELS.index(row))
            else:
                index = []
                break
    if not index or len(set(index)) != len(index):
        raise ParameterizationError(
            f"Expected `rows` to be 'all', 'linear', 'angular' or distinct labels from {ROW_LABELS} "
            f"(or indices 0-5), at least one, got {' '.join(repr(rows).split())[:60]}"
        )
    return tuple(index)


def _readable_basis(N: np.ndarray) -> npt.NDArray[np.float64]:
    """The same subspace as N's orthonormal columns (m, r), rotated so that coordinate axes lying in it
    come out as basis vectors (pivoted QR of the projector picks the most axis-aligned first);
    each vector's largest entry is positive. Returns (r, m)."""
    P = N @ N.T  # its columns: the coordinate axes projected on the subspace
    basis = np.zeros((N.shape[1], N.shape[0]))
    for i in range(N.shape[1]):  # Gram–Schmidt on P's columns, longest remaining first
        column = P[:, np.argmax(np.linalg.norm(P, axis=0))]
        b = column / np.linalg.norm(column)
        basis[i] = b * np.sign(b[np.argmax(np.abs(b))])
        P = P - np.outer(b, b @ P)
    return basis
