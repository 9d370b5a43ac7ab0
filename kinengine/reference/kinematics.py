"""Forward kinematics and geometric Jacobians in plain numpy: the lecture notes' formulas made executable.

An independent reference for the Pinocchio-based engine: it shares nothing with
it but the URDF text. Frames: I is the root link frame (T_I0 = identity, the
robot is fixed-base). Every function is vectorized over a batch of N
configurations. Equation numbers refer to the Robot Dynamics lecture notes, ETH
Zurich, section 2.8 (Kinematics of Systems of Bodies).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..errors import ConfigurationError, FrameNotFoundError, KinematicsError
from .tree import KinematicTree, TreeJoint, read_urdf, resolve_mimic

REFERENCES = ("local_world_aligned", "local", "world")


class ReferenceKinematics:
    """Frame poses T_IF(q) and geometric Jacobians of a fixed-base URDF tree.

    q holds one coordinate per independent movable joint ([rad] for revolute and
    continuous, [m] for prismatic) in ``joint_names`` order: depth-first from the
    root with children in file order, unless ``joint_names`` (any permutation of
    those joints) is given to match another library's order.
    """

    def __init__(self, tree: KinematicTree, joint_names: Sequence[str] | None = None) -> None:
        own = tree.independent_joints
        names = own if joint_names is None else tuple(joint_names)
        for name in names:
            if name not in own:
                raise FrameNotFoundError(name, own, kind="joint")
        if sorted(names) != sorted(own):
            raise ConfigurationError(
                f"joint_names must name each of the {len(own)} independent movable "
                f"joints exactly once: {', '.join(own)}"
            )
        self._tree = tree
        self._joint_names = names
        self._frames = tree.frames
        column = {name: k for k, name in enumerate(names)}
        # q_j = a · q[column] + b for every movable joint j: (1, 0) and its own column for an independent
        # joint, a mimic joint's chain of leaders composed down to the independent joint that drives it.
        by_name = {j.name: j for j in tree.joints}
        self._coordinate = {}
        for j in tree.joints:
            if j.movable:
                root, a, b = resolve_mimic(by_name, j.name)
                self._coordinate[j.name] = (column[root], a, b)

    @classmethod
    def from_urdf_string(
        cls, text: str | bytes, *, joint_names: Sequence[str] | None = None, source: str = "<string>"
    ) -> ReferenceKinematics:
        """Reference kinematics of URDF text, parsed strictly by yourdfpy."""
        return cls(KinematicTree.from_urdf(read_urdf(text, source=source), source=source), joint_names)

    @classmethod
    def from_file(
        cls, path: str | os.PathLike[str], *, joint_names: Sequence[str] | None = None
    ) -> ReferenceKinematics:
        """Reference kinematics of a .urdf file."""
        return cls.from_urdf_string(Path(path).read_bytes(), joint_names=joint_names, source=str(path))

    name = property(lambda self: self._tree.name, doc="The URDF's robot name.")
    root = property(lambda self: self._tree.root, doc="The root link: the inertial frame I.")
    joint_names = property(lambda self: self._joint_names, doc="Names of q's coordinates, in order.")
    dof = property(lambda self: len(self._joint_names), doc="Number of coordinates in q.")
    frame_names = property(lambda self: tuple(self._frames), doc="Every link and joint frame name.")

    def frame_pose(self, q: object, frame: str) -> np.ndarray:
        """T_IF(q) by the chain product of eq. 2.127; q (dof,) -> (4, 4), (N, dof) -> (N, 4, 4). [m]"""
        qb, batched = self._check(q)
        T_I_F = self._chain_poses(qb, frame)[1]
        return T_I_F if batched else T_I_F[0]

    def jacobian(self, q: object, frame: str, reference: str = "local_world_aligned") -> np.ndarray:
        """Geometric Jacobian of ``frame``, rows [linear; angular]; (6, dof) or (N, 6, dof).

        * "local_world_aligned": I J_e0 of eqs. 2.154/2.155, column k = [n_k × r_kE; n_k]
          (revolute, continuous) or [n_k; 0] (prismatic), all in I. A mimic joint adds
          a × its own column to the column of the independent joint that drives it (chain rule;
          a = the product of the multipliers along a chain of mimic joints).
        * "local": the same twist in F: [C_IF^T v; C_IF^T ω].
        * "world": the spatial velocity in I; the linear part is the velocity of the body
          point at I's origin, v_O = v_F + ω × (0 − r_IF) (rigid-body velocity field).
        """
        if reference not in REFERENCES:
            raise KinematicsError(f"unknown reference {reference!r}; use one of {', '.join(REFERENCES)}")
        qb, batched = self._check(q)
        joints, T_I_F = self._chain_poses(qb, frame)
        r_IF = T_I_F[:, :3, 3]
        J = np.zeros((len(qb), 6, self.dof))
        for joint, T_I_J in joints:
            column, multiplier, _ = self._coordinate[joint.name]
            # eq. 2.156: I n_k = C_I,joint · axis; the joint's own motion leaves its axis fixed.
            n_k = T_I_J[:, :3, :3] @ joint.axis
            if joint.kind == "prismatic":
                J[:, :3, column] += multiplier * n_k
            else:
                r_kF = r_IF - T_I_J[:, :3, 3]  # from the joint (on its axis) to F's origin
                J[:, :3, column] += multiplier * np.cross(n_k, r_kF)
                J[:, 3:, column] += multiplier * n_k
        if reference == "local":
            C_FI = np.swapaxes(T_I_F[:, :3, :3], 1, 2)
            J = np.concatenate([C_FI @ J[:, :3], C_FI @ J[:, 3:]], axis=1)
        elif reference == "world":
            J[:, :3] -= np.cross(J[:, 3:], r_IF[:, :, None], axis=1)
        return J if batched else J[0]

    def _chain_poses(
        self, q: np.ndarray, frame: str
    ) -> tuple[list[tuple[TreeJoint, np.ndarray]], np.ndarray]:
        """Eq. 2.127 along the root -> frame chain: per movable joint its pose T_I,joint (N, 4, 4)
        taken before its own motion, and T_IF (N, 4, 4)."""
        try:
            link = self._frames[frame]
        except (KeyError, TypeError):
            raise FrameNotFoundError(frame, self._frames) from None
        T = np.broadcast_to(np.eye(4), (len(q), 4, 4))  # T_I0 = identity
        movable = []
        for joint in self._tree.chain(link):
            T = T @ joint.origin  # T_{k-1,k}(q_k) = origin · motion(q_k)
            if joint.movable:
                movable.append((joint, T))
                column, multiplier, offset = self._coordinate[joint.name]
                T = T @ _motion(joint, multiplier * q[:, column] + offset)
        return movable, np.array(T)

    def _check(self, q: object) -> tuple[np.ndarray, bool]:
        """q as a float (N, dof) batch, and whether the caller passed a batch."""
        try:
            arr = np.asarray(q, dtype=float)
        except (TypeError, ValueError):
            raise ConfigurationError(f"Expected `q` to be numeric, got {type(q).__name__}") from None
        if arr.ndim not in (1, 2) or arr.shape[-1] != self.dof:
            raise ConfigurationError(
                f"Expected `q` to have shape ({self.dof},) or (N, {self.dof}), got {arr.shape}"
            )
        if not np.all(np.isfinite(arr)):
            raise ConfigurationError("`q` has non-finite values")
        return (arr if arr.ndim == 2 else arr[None]), arr.ndim == 2


def _motion(joint: TreeJoint, value: np.ndarray) -> np.ndarray:
    """The joint's own motion (N, 4, 4): rotation by ``value`` [rad] about the unit axis
    (Rodrigues: C = I + sin θ [n]× + (1 − cos θ) [n]×²) or translation by ``value`` [m] along it."""
    M = np.tile(np.eye(4), (len(value), 1, 1))
    if joint.kind == "prismatic":
        M[:, :3, 3] = value[:, None] * joint.axis
        return M
    nx, ny, nz = joint.axis
    K = np.array([[0.0, -nz, ny], [nz, 0.0, -nx], [-ny, nx, 0.0]])
    M[:, :3, :3] += np.sin(value)[:, None, None] * K + (1.0 - np.cos(value))[:, None, None] * (K @ K)
    return M
