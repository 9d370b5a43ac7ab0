"""The voxel grid of a reachability map: the reach bound of a frame and voxel lookup.

Reach bound: with q = 0 (Pinocchio's model: one joint per movable URDF joint), P_1 … P_n are the origins of
the joints that move ``frame`` and P_f the frame's origin, in the root link frame. The centre c is the
last of P_1, P_2, … that lies on the axis of every revolute joint before it (it never moves). The
radius r sums the lengths of the path from c to P_f, where a point P_k is skipped when P_{k+1} lies on
joint k's axis (P_{k+1} is then rigid to joint k's parent link, so |P_{k−1} P_{k+1}| never changes), and
a prismatic joint adds its largest travel. No configuration takes the frame's origin farther than r from
c; voxels whose centre is farther than r + (half a voxel diagonal) are left out of the map.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..errors import ConfigurationError, OptionError

MAX_CELLS = 200_000_000
"""Largest box of voxels (nx·ny·nz) a map may span: the lookup table holds 4 bytes a cell."""
ON_AXIS = 1e-9
"""Distance [m] below which a point counts as lying on a joint axis."""


@dataclass(frozen=True)
class ReachBall:
    """Centre c (3,) [m] in the root link frame and radius r [m]: the frame's origin never leaves the ball."""

    center: npt.NDArray[np.float64]
    radius: float


def reach_ball(
    model: pin.Model, frame_id: int, lower: npt.NDArray[np.float64], upper: npt.NDArray[np.float64]
) -> ReachBall:
    """The reach bound of the module doc, from Pinocchio's model at q = 0 (``lower``/``upper``: Pinocchio's
    joint limits (nq,), for prismatic travel)."""
    data = model.createData()
    q0 = pin.neutral(model)
    pin.forwardKinematics(model, data, q0)
    pin.updateFramePlacements(model, data)
    chain = []
    j = model.frames[frame_id].parentJoint
    while j > 0:
        chain.append(j)
        j = model.parents[j]
    chain.reverse()
    tip = data.oMf[frame_id].translation.copy()
    if not chain:
        return ReachBall(tip, 0.0)
    pin.computeJointJacobians(model, data, q0)
    points, axes, travel = [], [], []
    for j in chain:
        joint = model.joints[j]
        if joint.nv != 1:
            raise ConfigurationError(
                f"joint {model.names[j]!r} has {joint.nv} degrees of freedom; reachability maps take "
                "chains of revolute and prismatic joints"
            )
        S = pin.getJointJacobian(model, data, j, pin.LOCAL_WORLD_ALIGNED)[:, joint.idx_v]
        prismatic = np.linalg.norm(S[3:]) < 0.5
        points.append(data.oMi[j].translation.copy())
        axes.append(None if prismatic else S[3:] / np.linalg.norm(S[3:]))
        if prismatic:
            lo, hi = lower[joint.idx_q], upper[joint.idx_q]
            if not (np.isfinite(lo) and np.isfinite(hi)):
                raise ConfigurationError(
                    f"prismatic joint {model.names[j]!r} has no finite limits: give `bounds=` to the map"
                )
            travel.append(max(abs(lo), abs(hi)))
        else:
            travel.append(0.0)
    points.append(tip)
    axes.append(None)
    travel.append(0.0)

    def on_axis(p: np.ndarray, k: int) -> bool:
        a = axes[k]
        return a is not None and float(np.linalg.norm(np.cross(p - points[k], a))) <= ON_AXIS

    start = 0
    while start + 1 < len(points) and all(on_axis(points[start + 1], k) for k in range(start + 1)):
        start += 1
    path = [start]
    for k in range(start + 1, len(points)):
        # P_k is skipped when the next point lies on joint k's axis (rigid to joint k's parent link)
        if k + 1 < len(points) and on_axis(points[k + 1], k) and travel[k] == 0.0:
            continue
        path.append(k)
    radius = sum(float(np.linalg.norm(points[b] - points[a])) for a, b in itertools.pairwise(path))
    radius += sum(travel[start:])
    return ReachBall(points[start], radius)


@dataclass(frozen=True)
class VoxelGrid:
    """Voxels of edge ``voxel`` [m] over the box ``lower`` + voxel·(i + ½) for i < ``shape`` (root link
    frame), keeping those inside the reach ball: ``cells`` (V,) flat indices into the box, ``centers``
    (V, 3) [m]."""

    voxel: float
    lower: npt.NDArray[np.float64]
    shape: tuple[int, int, int]
    cells: npt.NDArray[np.int64]
    centers: npt.NDArray[np.float64]

    @classmethod
    def build(cls, ball: ReachBall, voxel: float, bounds: npt.ArrayLike | None) -> VoxelGrid:
        if (
            isinstance(voxel, bool)
            or not isinstance(voxel, (int, float, np.floating, np.integer))
            or not (np.isfinite(voxel) and voxel > 0)
        ):
            raise OptionError(f"`voxel` must be a positive edge length in metres, got {voxel!r}")
        voxel = float(voxel)
        margin = ball.radius + voxel * np.sqrt(3.0) / 2.0
        if bounds is None:
            lo, hi = ball.center - margin, ball.center + margin
        else:
            b = np.asarray(bounds, dtype=np.float64) if _numeric(bounds) else None
            if b is None or b.shape != (2, 3) or not np.all(np.isfinite(b)) or np.any(b[1] <= b[0]):
                raise OptionError(
                    "`bounds` must be ((xmin, ymin, zmin), (xmax, ymax, zmax)) [m] in the root link frame "
                    f"with min < max, got {bounds!r}"
                )
            lo, hi = b[0], b[1]
        n = np.maximum(1, np.ceil((hi - lo) / voxel - 1e-9)).astype(np.int64)
        if float(np.prod(n.astype(np.float64))) > MAX_CELLS:
            raise OptionError(
                f"a voxel of {voxel} m over the box {lo.round(3).tolist()} .. {hi.round(3).tolist()} makes "
                f"{int(np.prod(n))} cells (more than {MAX_CELLS}): use a larger `voxel` or smaller `bounds`"
            )
        shape = (int(n[0]), int(n[1]), int(n[2]))
        axes = [lo[i] + voxel * (np.arange(shape[i]) + 0.5) for i in range(3)]
        keep = []
        centers = []
        for ix in range(shape[0]):  # one x layer at a time: bounded memory for large boxes
            X, Y, Z = np.meshgrid(axes[0][ix : ix + 1], axes[1], axes[2], indexing="ij")
            c = np.stack((X.ravel(), Y.ravel(), Z.ravel()), axis=1)
            inside = np.linalg.norm(c - ball.center, axis=1) <= margin
            keep.append(ix * shape[1] * shape[2] + np.flatnonzero(inside))
            centers.append(c[inside])
        return cls(voxel, lo.copy(), shape, np.concatenate(keep).astype(np.int64), np.concatenate(centers))

    def lookup(self, points: npt.NDArray[np.float64]) -> npt.NDArray[np.int64]:
        """Index into ``centers`` of the voxel holding each point (N, 3) [m]; -1 outside the map."""
        idx = np.floor((np.asarray(points, dtype=np.float64) - self.lower) / self.voxel)
        inside = np.all((idx >= 0) & (idx < np.array(self.shape)), axis=1)
        idx = np.where(inside[:, None], idx, 0).astype(np.int64)
        flat = (idx[:, 0] * self.shape[1] + idx[:, 1]) * self.shape[2] + idx[:, 2]
        pos = np.searchsorted(self.cells, flat)
        pos = np.minimum(pos, len(self.cells) - 1)
        found = inside & (self.cells[pos] == flat)
        return np.where(found, pos, -1)


def _numeric(value: object) -> bool:
    try:
        return np.asarray(value).dtype.kind in "iuf"
    except (ValueError, TypeError):
        return False
