"""Base placement with a reachability map (the inverse-map idea of Vahrenkamp et al.; ROS's reuleaux).

A candidate base pose B = Trans(x, y, z)·Rot_z(yaw) places the robot's root link frame in the world. A
task pose T_W (4, 4) in the world is T = B⁻¹ T_W in the root link frame; it scores when the map reached
its cell (voxel and nearest orientation). Every candidate of a planar grid × yaws is scored by the
number of task poses that score, ties broken by the sum of the reachability indices of their voxels (a
task pose in a voxel reached from most orientations is more likely reached at its own); the best ``top``
are re-checked by inverse kinematics on the real task poses (``verified``: how many are solved within the
joint limits) and ranked by that count first. A cell is coarser than a pose, so a score can promise more
than IK delivers: when no re-checked candidate is verified for any task pose, a warning says so.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from ..errors import OptionError
from ..robot import Robot
from .reachability import ReachabilityMap

DEFAULT_YAWS = 16
"""Yaws tried per position when none are given: every 22.5°."""
MAX_CANDIDATES = 5_000_000
"""Positions × yaws refused above this (each scores every task pose)."""


@dataclass(frozen=True)
class BasePlacements:
    """Candidate base poses and their scores.

    ``poses`` (C, 4, 4) base poses in the world [m]; ``xy`` (C, 2) [m], ``yaw`` (C,) [rad], ``z`` [m];
    ``scores`` (C,) task poses whose map cell is reached; ``depth`` (C,) the sum of their voxels'
    reachability indices; ``order`` (C,) candidates best first (verified count, then score, then depth);
    ``verified`` (C,) task poses solved by IK (−1 where not re-checked); ``best`` (4, 4) the first of
    ``order``; ``targets`` (N, 4, 4) the task poses in the world."""

    poses: npt.NDArray[np.float64]
    xy: npt.NDArray[np.float64]
    yaw: npt.NDArray[np.float64]
    z: float
    scores: npt.NDArray[np.int64]
    depth: npt.NDArray[np.float64]
    verified: npt.NDArray[np.int64]
    order: npt.NDArray[np.intp]
    targets: npt.NDArray[np.float64]

    @property
    def best(self) -> npt.NDArray[np.float64]:
        """(4, 4) the best base pose in the world."""
        return self.poses[self.order[0]].copy()

    def plot(self, path: str | os.PathLike[str] | None = None) -> Any:
        """Best score over the yaws at each candidate position (seen from above), the task positions and
        the best base pose; written to ``path`` (PNG) when given. Returns the figure."""
        from ..presentation.plotting import pyplot

        plt = pyplot(headless=path is not None)
        fig, ax = plt.subplots(figsize=(6, 5.2))
        keys, inverse = np.unique(self.xy.round(9), axis=0, return_inverse=True)
        best = np.zeros(len(keys))
        np.maximum.at(best, inverse.ravel(), self.scores)
        art = ax.scatter(keys[:, 0], keys[:, 1], c=best, cmap="viridis", marker="s", s=12, linewidths=0)
        fig.colorbar(art, ax=ax, label=f"task poses reached (of {len(self.targets)}), best yaw")
        ax.scatter(
            self.targets[:, 0, 3], self.targets[:, 1, 3], c="white", edgecolors="k", s=18, label="task poses"
        )
        b = self.best
        ax.quiver(b[0, 3], b[1, 3], b[0, 0], b[1, 0], color="red", scale=12, label="best base (x axis)")
        ax.set_aspect("equal")
        ax.set_xlabel("x [m] (world)")
        ax.set_ylabel("y [m]")
        ax.legend(loc="upper right", fontsize=7)
        if path is not None:
            fig.savefig(os.fspath(path), dpi=120, bbox_inches="tight")
        return fig


def base_placements(
    rmap: ReachabilityMap,
    targets: npt.ArrayLike,
    *,
    xy: float | npt.ArrayLike | None = None,
    yaws: int | npt.ArrayLike | None = None,
    z: float = 0.0,
    robot: Robot | None = None,
    top: int = 10,
) -> BasePlacements:
    """Score base poses for task poses ``targets`` (N, 4, 4) in the world with the map ``rmap``.

    ``xy``: candidate positions (M, 2) [m], or a grid step [m] (positions on its whole multiples) over
    the square around the targets that the map's reach can touch (default: the map's voxel); ``yaws``: a
    count of even steps over 2π (default 16) or angles [rad]; ``z``: the base height [m]; ``robot``: for
    the IK re-check of the ``top`` best (default: rebuilt from the map's URDF).
    """
    if not isinstance(rmap, ReachabilityMap):
        raise OptionError(
            f"`rmap` must be a ReachabilityMap (kinengine.reachability_map or ReachabilityMap.load), got "
            f"{type(rmap).__name__}"
        )
    T_w = _targets(targets)
    yaw_set = _yaws(yaws)
    positions = _positions(rmap, T_w, xy)
    if len(positions) * len(yaw_set) > MAX_CANDIDATES:
        raise OptionError(
            f"{len(positions)} positions × {len(yaw_set)} yaws is more than {MAX_CANDIDATES} candidates: "
            "use a coarser `xy` step or fewer `yaws`"
        )
    if isinstance(z, bool) or not isinstance(z, (int, float, np.floating, np.integer)) or not np.isfinite(z):
        raise OptionError(f"`z` must be a finite height in metres, got {z!r}")
    XY = np.repeat(positions, len(yaw_set), axis=0)
    YAW = np.tile(yaw_set, len(positions))
    poses = np.zeros((len(XY), 4, 4))
    c, s = np.cos(YAW), np.sin(YAW)
    poses[:, 0, 0], poses[:, 0, 1], poses[:, 1, 0], poses[:, 1, 1] = c, -s, s, c
    poses[:, 2, 2] = poses[:, 3, 3] = 1.0
    poses[:, 0, 3], poses[:, 1, 3], poses[:, 2, 3] = XY[:, 0], XY[:, 1], float(z)
    scores = np.zeros(len(poses), dtype=np.int64)
    depth = np.zeros(len(poses))
    inverse = np.linalg.inv(poses)
    index = np.append(rmap.index, 0.0)  # [-1]: outside the map
    step = max(1, 2_000_000 // len(T_w))  # candidates scored at once: bounded temporary memory
    for a in range(0, len(poses), step):
        local = np.einsum("cij,njk->cnik", inverse[a : a + step], T_w).reshape(-1, 4, 4)
        voxel, hit = rmap.lookup(local)
        hit = hit.reshape(-1, len(T_w))
        scores[a : a + step] = hit.sum(axis=1)
        depth[a : a + step] = np.where(hit, index[voxel].reshape(hit.shape), 0.0).sum(axis=1)
    if isinstance(top, bool) or not isinstance(top, (int, np.integer)) or top < 1:
        raise OptionError(f"`top` must be a positive count, got {top!r}")
    verified = np.full(len(poses), -1, dtype=np.int64)
    if robot is None:
        robot = rmap.robot()
    frame = rmap.metadata["frame"]
    for i in np.lexsort((-depth, -scores))[:top]:
        verified[i] = _solved(robot, frame, inverse[i] @ T_w, rmap.metadata["method"])
    order = np.lexsort((-depth, -scores, -verified))
    if verified.max() == 0:
        warnings.warn(
            f"none of the {min(top, len(poses))} best-scored base poses reaches a task pose by IK (the map's "
            "cells are coarser than the poses): raise `top`, or use a map with a finer voxel and more "
            "orientations",
            UserWarning,
            stacklevel=2,
        )
    return BasePlacements(poses, XY, YAW, float(z), scores, depth, verified, order, T_w)


def _solved(robot: Robot, frame: str, T: np.ndarray, method: str) -> int:
    """How many poses T (N, 4, 4) in the root link frame IK solves within the joint limits."""
    if method == "closed_form":
        return int(np.sum(np.asarray(robot.ik_solutions(T, frame).count) > 0))
    result = robot.inverse_kinematics(T, frame, method="numeric", restarts=10, rng=0)
    return int(np.sum(result.success))


def _targets(targets: npt.ArrayLike) -> np.ndarray:
    try:
        T = np.asarray(targets, dtype=np.float64)
    except (TypeError, ValueError):
        raise OptionError("`targets` must be task poses (N, 4, 4) [m]") from None
    if T.ndim == 2:
        T = T[None]
    if T.ndim != 3 or T.shape[1:] != (4, 4) or len(T) == 0 or not np.all(np.isfinite(T)):
        raise OptionError(f"`targets` must be finite task poses (N, 4, 4) [m], got shape {T.shape}")
    return T


def _yaws(yaws: int | npt.ArrayLike | None) -> np.ndarray:
    if yaws is None:
        yaws = DEFAULT_YAWS
    if isinstance(yaws, (int, np.integer)) and not isinstance(yaws, bool):
        if not 1 <= yaws <= 3600:
            raise OptionError(f"`yaws` as a count must be 1 to 3600, got {yaws}")
        return 2.0 * np.pi * np.arange(int(yaws)) / int(yaws)
    y = np.asarray(yaws, dtype=np.float64).ravel()
    if not len(y) or not np.all(np.isfinite(y)):
        raise OptionError("`yaws` must be a count or finite angles [rad]")
    return y


def _positions(rmap: ReachabilityMap, T_w: np.ndarray, xy: float | npt.ArrayLike | None) -> np.ndarray:
    if xy is not None and np.ndim(xy) == 2:
        P = np.asarray(xy, dtype=np.float64)
        if P.shape[1] != 2 or not np.all(np.isfinite(P)):
            raise OptionError("`xy` positions must be finite (M, 2) [m]")
        return P
    step = rmap.voxel if xy is None else xy
    if isinstance(step, bool) or not isinstance(step, (int, float, np.floating, np.integer)) or not step > 0:
        raise OptionError(f"`xy` must be positions (M, 2) or a grid step [m] > 0, got {xy!r}")
    reach = rmap.metadata["reach"]
    r = float(reach["radius"]) + float(np.hypot(*reach["center"][:2]))
    step = float(step)
    lo = np.floor((T_w[:, :2, 3].min(axis=0) - r) / step) * step  # a grid on whole multiples of the step
    hi = T_w[:, :2, 3].max(axis=0) + r
    n = np.floor((hi - lo) / step + 1e-9).astype(int) + 1
    if int(np.prod(n)) > MAX_CANDIDATES:
        raise OptionError(f"an `xy` step of {step} m makes {int(np.prod(n))} positions: use a coarser step")
    gx, gy = (lo[i] + step * np.arange(n[i]) for i in range(2))
    X, Y = np.meshgrid(gx, gy, indexing="ij")
    return np.stack((X.ravel(), Y.ravel()), axis=1)
