"""The orientation set of a reachability map: approach directions on a sphere × rolls about them.

Construction (deterministic, the same arguments give the same rotations bit for bit):

* approach directions: the spherical Fibonacci lattice of n points, d_k = (√(1−z²) cos φ_k,
  √(1−z²) sin φ_k, z) with z_k = 1 − (2k + 1)/n and φ_k = k·π(3 − √5) (the golden angle);
* the frame's z axis points along d_k (a tool's approach axis, as ROS-Industrial's ``tool0``);
  its x axis is e₁ rotated by the roll ψ about d_k, with e₁ the unit vector along d_k × a
  (a = root x axis, or y when d_k is within 0.1 rad of x) and y = z × x;
* rolls: ``orientations=n`` gives one roll per direction, ψ_k = 2π·frac(k/φ) (golden ratio φ), a
  near-uniform set of n rotations of SO(3); ``orientations=(n, m)`` gives every direction with each of
  m rolls ψ_j = 2πj/m (n·m rotations, direction-major).

Rotations are C_IE (3, 3): the columns are the frame's axes in the root link frame.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from ..errors import OptionError

MAX_ORIENTATIONS = 100_000
"""More rotations than this per voxel is refused (the map's memory is voxels × orientations)."""

GOLDEN = (1.0 + 5.0**0.5) / 2.0


def fibonacci_directions(n: int) -> npt.NDArray[np.float64]:
    """(n, 3) unit vectors of the spherical Fibonacci lattice (module doc)."""
    k = np.arange(n, dtype=np.float64)
    z = 1.0 - (2.0 * k + 1.0) / n
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    phi = k * np.pi * (3.0 - 5.0**0.5)
    return np.stack((r * np.cos(phi), r * np.sin(phi), z), axis=1)


def approach_rotations(
    directions: npt.NDArray[np.float64], rolls: npt.NDArray[np.float64]
) -> npt.NDArray[np.float64]:
    """(n, 3, 3) rotations whose z axis is ``directions[k]`` and x axis is rolled by ``rolls[k]`` [rad]."""
    d = directions / np.linalg.norm(directions, axis=1, keepdims=True)
    a = np.tile(np.array([1.0, 0.0, 0.0]), (len(d), 1))
    near_x = np.abs(d[:, 0]) > np.cos(0.1)
    a[near_x] = (0.0, 1.0, 0.0)
    e1 = np.cross(d, a)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(d, e1)
    c, s = np.cos(rolls)[:, None], np.sin(rolls)[:, None]
    x = c * e1 + s * e2
    y = np.cross(d, x)
    return np.stack((x, y, d), axis=2)


def orientation_set(orientations: int | tuple[int, int] | npt.ArrayLike) -> npt.NDArray[np.float64]:
    """(O, 3, 3) rotations: ``n`` (n directions, golden rolls), ``(n, m)`` (n directions × m rolls) or
    an explicit (O, 3, 3) array of rotation matrices (checked: orthonormal, det +1, to 1e-9)."""
    if isinstance(orientations, (bool, np.bool_)):
        raise OptionError(
            "`orientations` must be a count, (directions, rolls) or (O, 3, 3) rotations, "
            f"got {orientations!r}"
        )
    if isinstance(orientations, (int, np.integer)):
        n = _count(int(orientations), "orientations")
        k = np.arange(n, dtype=np.float64)
        return approach_rotations(fibonacci_directions(n), 2.0 * np.pi * np.mod(k / GOLDEN, 1.0))
    if (
        isinstance(orientations, tuple)
        and len(orientations) == 2
        and all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in orientations)
    ):
        n, m = _count(int(orientations[0]), "directions"), _count(int(orientations[1]), "rolls")
        _count(n * m, "orientations")
        d = np.repeat(fibonacci_directions(n), m, axis=0)
        rolls = np.tile(2.0 * np.pi * np.arange(m) / m, n)
        return approach_rotations(d, rolls)
    R = np.asarray(orientations)
    if (
        R.dtype.kind not in "iuf"
        or R.ndim != 3
        or R.shape[1:] != (3, 3)
        or not 0 < len(R) <= MAX_ORIENTATIONS
    ):
        raise OptionError(
            f"`orientations` must be a count, (directions, rolls) or an (O, 3, 3) array of rotations with "
            f"1 <= O <= {MAX_ORIENTATIONS}, got an array of shape {R.shape} ({R.dtype})"
        )
    R = R.astype(np.float64)
    if not np.all(np.isfinite(R)):
        raise OptionError("`orientations` holds NaN or inf")
    err = np.abs(np.einsum("kji,kjl->kil", R, R) - np.eye(3)).max(axis=(1, 2))
    bad = np.flatnonzero((err > 1e-9) | (np.linalg.det(R) < 0))
    if bad.size:
        raise OptionError(f"`orientations[{bad[0]}]` is not a rotation matrix (orthonormal, det +1, to 1e-9)")
    return np.ascontiguousarray(R)


def _count(n: int, what: str) -> int:
    if not 1 <= n <= MAX_ORIENTATIONS:
        raise OptionError(f"`{what}` must be between 1 and {MAX_ORIENTATIONS}, got {n}")
    return n


def nearest_orientation(R_set: npt.NDArray[np.float64], C: npt.NDArray[np.float64]) -> npt.NDArray[np.intp]:
    """Index into ``R_set`` (O, 3, 3) of the rotation nearest each of C (N, 3, 3) by geodesic angle
    (largest trace of R_kᵀ C)."""
    traces = np.einsum("kij,nij->nk", R_set, C)
    return np.argmax(traces, axis=1)
