"""One chunk of a reachability map: every (voxel, orientation) pose of a block of voxels, solved.

A pose counts as reached when the solver returns a configuration within the joint limits whose frame
pose equals the target: the closed-form solver's solutions are checked by forward kinematics to 1e-9
(:mod:`kinengine.control.ik_solutions`); the numeric solver's to its tolerances (1e-6 m, 1e-6 rad). The
numeric solver first tries each voxel's centre in position alone and solves the voxel's poses only
where that succeeds (a pose whose position is unreachable is unreachable).
The manipulability of a voxel is the largest Yoshikawa measure w = sqrt(det(J Jᵀ)) over every solution
of every reached pose in it (0 where none is reached).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ..errors import KinematicsError
from ..robot import Robot

NUMERIC_RESTARTS = 3
"""Random restarts of the numeric solver after its seeded attempt, per (voxel, orientation) pose."""
POSITION_RESTARTS = 10
"""Random restarts of the numeric solver for a voxel's centre alone (position rows): a voxel whose centre
it cannot reach in position is unreached in every orientation, and its poses are not solved."""


@dataclass(frozen=True)
class Chunk:
    """Rows ``start`` … ``stop`` − 1 of the map's voxels."""

    index: int
    start: int
    stop: int


def poses(centers: npt.NDArray[np.float64], rotations: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """(V·O, 4, 4) targets, voxel-major: every rotation (O, 3, 3) at every centre (V, 3) [m]."""
    V, n_rot = len(centers), len(rotations)
    T = np.zeros((V, n_rot, 4, 4))
    T[:, :, :3, :3] = rotations[None]
    T[:, :, :3, 3] = centers[:, None]
    T[:, :, 3, 3] = 1.0
    return T.reshape(V * n_rot, 4, 4)


def closed_form_available(robot: Robot, frame: str) -> str | None:
    """None when ``robot.ik_solutions`` solves ``frame`` in closed form, else the reason it does not."""
    T = np.eye(4)
    try:
        robot.ik_solutions(T, frame)
    except KinematicsError as exc:
        return str(exc)
    return None


def solve_chunk(
    robot: Robot,
    frame: str,
    centers: npt.NDArray[np.float64],
    rotations: npt.NDArray[np.float64],
    method: str,
    seed: np.random.SeedSequence,
) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.float64]]:
    """reached (V, O) and manipulability (V,) of the voxels ``centers`` (V, 3) for ``rotations``
    (O, 3, 3); ``method`` "closed_form" or "numeric" (``seed``: the numeric solver's random restarts)."""
    V, n_rot = len(centers), len(rotations)
    T = poses(centers, rotations)
    if method == "closed_form":
        sol = robot.ik_solutions(T, frame)
        q = sol.q
        valid = ~np.isnan(q[..., 0])
        reached = valid.any(axis=1)
        pose_of = np.nonzero(valid)[0]
        Q = q[valid]
    else:
        position_seed, pose_seed = seed.spawn(2)
        centre = robot.inverse_kinematics(
            poses(centers, np.eye(3)[None]),
            frame,
            rows=("x", "y", "z"),
            method="numeric",
            restarts=POSITION_RESTARTS,
            rng=np.random.default_rng(position_seed),
        )
        candidates = np.flatnonzero(np.repeat(np.asarray(centre.success, dtype=bool), n_rot))
        pose_of, Q = candidates[:0], np.zeros((0, robot.dof))
        if len(candidates):  # else no voxel of the chunk is reachable even in position
            result = robot.inverse_kinematics(
                T[candidates],
                frame,
                method="numeric",
                restarts=NUMERIC_RESTARTS,
                rng=np.random.default_rng(pose_seed),
            )
            success = np.asarray(result.success, dtype=bool)
            Q = np.asarray(result.q)[success]
            inside = np.all((robot.lower_limits <= Q) & (robot.upper_limits >= Q), axis=1)
            pose_of = candidates[success][inside]
            Q = Q[inside]
        reached = np.zeros(V * n_rot, dtype=bool)
        reached[pose_of] = True
    manip = np.zeros(V)
    if len(Q):
        w = np.atleast_1d(np.asarray(robot.manipulability(Q, frame), dtype=np.float64))
        np.maximum.at(manip, pose_of // n_rot, w)
    return reached.reshape(V, n_rot), manip
