"""The pose error on SE(3): the twist that carries a frame's pose T onto a target pose T_target in unit time.

ξ = log6(T⁻¹ · T_target) (Pinocchio's ``pin.log6``), rows [v; ω], is the *body* twist: expressed in the
frame's own axes ("local"), constant over the unit time, and T · exp(ξ) = T_target exactly. The same
motion in other axes:

* "local": ξ itself (v and ω in the frame F's axes; v is the velocity of F's origin).
* "local_world_aligned" (default): (C_IF v, C_IF ω): the velocity of F's origin and the angular velocity,
  in the root frame I's axes, at the start of the motion (matches ``robot.jacobian(q)``'s rows).
* "world": Ad_T ξ, the spatial twist in I (linear part: velocity of the body point at I's origin).

Units: [m] for the linear rows and [rad] for the angular rows (a displacement: a twist times one unit of
time). ‖ω‖ is the rotation angle between C and C_target (in [0, π]).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..errors import OptionError

FRAMES = ("local", "local_world_aligned", "world")


def _as_pose(T: object, name: str) -> npt.NDArray[np.float64]:
    array = np.asarray(T, dtype=float)
    if array.shape[-2:] != (4, 4) or array.ndim not in (2, 3) or not np.isfinite(array).all():
        raise OptionError(
            f"`{name}` must be a finite homogeneous transform (4, 4) or a batch (N, 4, 4), "
            f"got shape {array.shape}"
        )
    return array


def pose_error(
    T: npt.ArrayLike, T_target: npt.ArrayLike, frame: str = "local_world_aligned"
) -> npt.NDArray[np.float64]:
    """ξ with T · exp(ξ_local) = T_target, (6,) rows [v; ω] [m, rad], in ``frame``'s axes (module doc).

    T, T_target: (4, 4) poses in a common frame (e.g. T_IF from ``robot.frame_pose``), or batches
    (N, 4, 4) (either may be a single pose) -> (N, 6).
    """
    if frame not in FRAMES:
        raise OptionError(f"frame must be one of {', '.join(FRAMES)}, got {frame!r}")
    A, B = _as_pose(T, "T"), _as_pose(T_target, "T_target")
    if A.ndim == 2 and B.ndim == 2:
        return _single(A, B, frame)
    A, B = np.broadcast_arrays(A.reshape(-1, 4, 4), B.reshape(-1, 4, 4))  # a single pose as a batch of one
    return np.array([_single(a, b, frame) for a, b in zip(A, B, strict=False)]).reshape(-1, 6)


def _single(T: np.ndarray, T_target: np.ndarray, frame: str) -> npt.NDArray[np.float64]:
    M = pin.SE3(T)
    xi = pin.log6(M.actInv(pin.SE3(T_target)))
    if frame == "world":
        xi = M.act(xi)
    elif frame == "local_world_aligned":  # the same twist in I's axes: rotated by C_IF only
        xi = pin.SE3(M.rotation, np.zeros(3)).act(xi)
    return np.array(xi.vector)


__all__ = ["FRAMES", "pose_error"]
