"""SO(3) building blocks shared by the rotation parameterizations, written over ``xp`` (math or numpy).

Quaternions here are Hamilton, scalar first: q = (w, x, y, z), C = C_IE = I + 2w[v]x + 2[v]x².
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from .base import SMALL_ANGLE_SQ, Component, Entries, Namespace, where


def quaternion_from_matrix(xp: Namespace, *C: Component) -> tuple[Component, Component, Component, Component]:
    """Unit quaternion (w, x, y, z) of C_IE (9 entries, row-major), like scipy's ``as_quat(canonical=True)``.

    Canonical: w > 0, or w = 0 and the first nonzero of (x, y, z) > 0. The case split on the largest
    of (C00, C11, C22, trace) is scipy's (Shepperd's method), so results match scipy to rounding.
    """
    c00, c01, c02, c10, c11, c12, c20, c21, c22 = C
    trace = c00 + c11 + c22
    cases = (  # 4x·(x, y, z, w), 4y·(...), 4z·(...), 4w·(...): Shepperd's case for C00, C11, C22, trace
        (1.0 - trace + 2.0 * c00, c10 + c01, c20 + c02, c21 - c12),
        (c10 + c01, 1.0 - trace + 2.0 * c11, c21 + c12, c02 - c20),
        (c20 + c02, c21 + c12, 1.0 - trace + 2.0 * c22, c10 - c01),
        (c21 - c12, c02 - c20, c10 - c01, 1.0 + trace),
    )
    if xp is math:
        diagonal = (c00, c11, c22, trace)
        x, y, z, w = cases[diagonal.index(max(diagonal))]  # the first maximum, like numpy's argmax
        negative = w < 0.0 or (w == 0.0 and (x < 0.0 or (x == 0.0 and (y < 0.0 or (y == 0.0 and z < 0.0)))))
    else:
        choice = np.argmax(np.stack([c00, c11, c22, trace], axis=-1), axis=-1)
        x, y, z, w = (np.choose(choice, [case[k] for case in cases]) for k in range(4))
        negative = (w < 0) | ((w == 0) & ((x < 0) | ((x == 0) & ((y < 0) | ((y == 0) & (z < 0))))))
    norm = xp.sqrt(x * x + y * y + z * z + w * w)
    norm = where(xp, negative, -norm, norm)
    return w / norm, x / norm, y / norm, z / norm


def rotation_entries(alpha: Component, beta: Component, x: Component, y: Component, z: Component) -> Entries:
    """Row-major entries of I + α[u]x + β[u]x² for u = (x, y, z) ([u]x² = u u^T − |u|² I)."""
    bx, by, bz = beta * x, beta * y, beta * z
    bxx, byy, bzz, bxy, bxz, byz = bx * x, by * y, bz * z, bx * y, bx * z, by * z
    ax, ay, az = alpha * x, alpha * y, alpha * z
    return (
        1.0 - byy - bzz, bxy - az, bxz + ay,
        bxy + az, 1.0 - bxx - bzz, byz - ax,
        bxz - ay, byz + ax, 1.0 - bxx - byy,
    )  # fmt: skip


def series_or_closed(
    xp: Namespace,
    t: Component,
    series: Callable[[Component], Component],
    closed: Callable[[Namespace, Component], Component],
) -> Component:
    """series(t) where t < SMALL_ANGLE_SQ, else closed(xp, t) (jaxlie's small-angle branch, on t = θ²)."""
    if xp is math:
        return series(t) if t < SMALL_ANGLE_SQ else closed(math, t)
    small = t < SMALL_ANGLE_SQ
    return np.where(small, series(t), closed(np, np.where(small, 1.0, t)))


def cross_matrix(x: Component, y: Component, z: Component) -> Entries:
    """Row-major entries of [u]x for u = (x, y, z), the matrix with [u]x w = u × w."""
    return (0.0, -z, y, z, 0.0, -x, -y, x, 0.0)
