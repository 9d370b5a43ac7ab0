"""The batched IK iteration's linear algebra and rotation log: what the solver uses against the alternative.

    python benchmarks/ik_batch_step.py [--columns 10000] [--rounds 30]

Per iteration of :mod:`kinengine.control.ik_batch` at r running attempts (6 rows, 6 joints, the ABB IRB
120's shape): (1) the damped step :func:`kinengine.control.ik_step.take_steps` (A's lower triangle and a
Cholesky factorization over all columns at once, one einsum per entry) against the same step by numpy
alone (matmul on (r, m, dof) stacks and numpy's stacked LU ``solve``); (2) log(C_d Cᵀ) of r rotation
pairs within 0.5 rad of each other (the IK regime) by the rotation-vector parameterization (what the
solver uses) against the closed form on columns the solver had before. The two variants of each run
interleaved in one process, min and median of ``--rounds`` calls; the project keeps its own version only
where it is at least 20 % faster (issue 27; tests/test_ik_batch.py covers its systems that are not
positive definite).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import pinocchio as pin
from scipy.spatial.transform import Rotation

from kinengine.control.ik_step import take_steps
from kinengine.parameterizations import ROTATION_PARAMETERIZATIONS


def numpy_step(q, J, err, w, diagonal):
    """The same step by numpy alone: (r, m, dof) stacks, matmul, numpy's stacked LU ``solve``."""
    m, r = len(J), J.shape[2]
    Jt = np.ascontiguousarray(J.transpose(2, 0, 1))
    JWt = Jt * w.T[:, None, :]
    A = np.matmul(JWt, Jt.transpose(0, 2, 1))
    A.reshape(r, m * m)[:, :: m + 1] += diagonal.T
    y = np.linalg.solve(A, err.T[..., None])
    return q + np.matmul(JWt.transpose(0, 2, 1), y)[..., 0].T


def column_log(Cd, C, out):
    """log(C_d Cᵀ) (3, r) in closed form on columns (Pinocchio's log3 within 0.15 rad of π)."""
    roll, back = [1, 2, 0], [2, 0, 1]
    w = np.einsum("ikn,ikn->in", Cd[back], C[roll]) - np.einsum("ikn,ikn->in", Cd[roll], C[back])
    norm = np.sqrt(np.einsum("in,in->n", w, w))
    cos = 0.5 * (np.einsum("ikn,ikn->n", Cd, C) - 1.0)
    theta = np.arctan2(0.5 * norm, cos)
    with np.errstate(divide="ignore", invalid="ignore"):
        np.multiply(w, np.where(norm > 1e-12, theta / norm, 0.5), out=out)
    for i in np.flatnonzero(cos < -0.988).tolist():
        out[:, i] = pin.log3(Cd[..., i] @ C[..., i].T)


def timed(fn, rounds):
    times = []
    for _ in range(rounds):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--columns", type=int, default=10_000)
    parser.add_argument("--rounds", type=int, default=30)
    args = parser.parse_args()
    r, m, dof, rng = args.columns, 6, 6, np.random.default_rng(0)
    J, err = rng.normal(size=(m, dof, r)), 1e-3 * rng.normal(size=(m, r))
    q, w = rng.normal(size=(dof, r)), rng.uniform(0.5, 1.0, size=(dof, r))
    diagonal = np.full((m, r), 1e-6)
    buffers = (np.empty((6, dof, r)), np.empty(36 * r))
    np.testing.assert_allclose(
        take_steps(q, J, err, w, diagonal, (None, 0.0, np.zeros(r)), buffers),
        numpy_step(q, J, err, w, diagonal),
        rtol=1e-6,
        atol=1e-9,
    )
    Cd = Rotation.random(r, random_state=1).as_matrix()
    # the IK regime: C near C_d (errors up to 0.5 rad, as seeds near their targets give)
    small = Rotation.from_rotvec(0.5 * Rotation.random(r, random_state=2).as_rotvec() / np.pi)
    C = (small * Rotation.from_matrix(Cd)).as_matrix()
    Cd_cols, C_cols = np.ascontiguousarray(Cd.transpose(1, 2, 0)), np.ascontiguousarray(C.transpose(1, 2, 0))
    log = ROTATION_PARAMETERIZATIONS["rotation_vector"].from_rotation
    out = np.empty((3, r))
    column_log(Cd_cols, C_cols, out)
    np.testing.assert_allclose(log(np.einsum("ikn,jkn->nij", Cd_cols, C_cols), warn=False).T, out, atol=1e-9)
    cases = {
        "step: column-wise Cholesky (take_steps)": lambda: take_steps(
            q, J, err, w, diagonal, (None, 0.0, np.zeros(r)), buffers
        ),
        "step: numpy matmul + stacked solve": lambda: numpy_step(q, J, err, w, diagonal),
        "log: rotation-vector parameterization": lambda: log(
            np.einsum("ikn,jkn->nij", Cd_cols, C_cols), warn=False
        ),
        "log: closed form on columns": lambda: column_log(Cd_cols, C_cols, out),
    }
    results: dict[str, list[float]] = {name: [] for name in cases}
    for _ in range(args.rounds):  # interleaved: a busy neighbour slows both variants alike
        for name, fn in cases.items():
            results[name] += timed(fn, 1)
    print(f"r = {r} columns, {args.rounds} rounds, numpy {np.__version__}")
    for name, times in results.items():
        print(f"{name:<42} min {min(times) * 1e3:7.3f} ms   median {np.median(times) * 1e3:7.3f} ms")


if __name__ == "__main__":
    main()
