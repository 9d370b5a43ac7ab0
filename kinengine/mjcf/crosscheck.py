"""Cross-checking an MJCF robot against MuJoCo's own kinematics of the same file.

For random in-range configurations q, MuJoCo's qpos is q on the robot's coordinates (their ``qpos0``
elsewhere, mimic followers at c1·q_leader + offset); every body's ``xpos``/``xmat`` and every site's
``site_xpos``/``site_xmat`` (``mj_kinematics``) is compared with ``robot.frame_pose(q, name)``, and
``mj_jacBody``/``mj_jacSite`` (after ``mj_comPos``; world axes at the frame's origin) with
``robot.jacobian(q, name, "local_world_aligned")``, MuJoCo's columns mapped onto q's by the chain rule
of the couplings. Used by the tests and ``scripts/check_mjcf.py``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from ..urdf.limits import LIMITS
from .compiler import compile_mjcf, mujoco_module
from .convert import FREE, MJCFNames

_BOX = 100.0  # [m or rad] limits beyond ±_BOX are sampled within ±_BOX


@dataclass(frozen=True)
class CrossCheck:
    """Worst absolute differences over all compared frames and configurations: positions [m],
    rotation-matrix entries, Jacobian entries [m/rad, 1]."""

    frames: int
    configurations: int
    position: float
    rotation: float
    jacobian: float

    @property
    def worst(self) -> float:
        return max(self.position, self.rotation, self.jacobian)


def cross_check(robot: Any, samples: int = 20, seed: int = 0) -> CrossCheck:
    """Compare ``robot`` (loaded from an MJCF file: ``robot.source``) with MuJoCo's kinematics of that file
    at ``samples`` random in-range configurations (seeded) and q = neutral."""
    mujoco = mujoco_module()
    source, model, _ = compile_mjcf(robot.source, limits=LIMITS)
    names = MJCFNames(model, source, LIMITS)
    data = mujoco.MjData(model)
    frames = set(robot.frame_names)
    bodies = [b for b in range(1, model.nbody) if names.body[b] in frames]
    sites = [s for s in range(model.nsite) if names.site[s] in frames]
    joint_of = {names.joint[j]: j for j in range(model.njnt)}
    S, qpos_of = _coupling(robot, model, joint_of)
    rng = np.random.default_rng(seed)
    lower = np.clip(robot.lower_limits, -_BOX, _BOX)
    upper = np.clip(robot.upper_limits, -_BOX, _BOX)
    lower = np.where(np.isinf(robot.lower_limits), -np.pi, lower)
    upper = np.where(np.isinf(robot.upper_limits), np.pi, upper)
    qs = [robot.neutral()] + [rng.uniform(lower, upper) for _ in range(samples)]
    jacp, jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))
    worst = np.zeros(3)
    for q in qs:
        data.qpos[:] = qpos_of(q)
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        for kind, index, name in [("body", b, names.body[b]) for b in bodies] + [
            ("site", s, names.site[s]) for s in sites
        ]:
            if kind == "body":
                p, R = data.xpos[index], data.xmat[index].reshape(3, 3)
                mujoco.mj_jacBody(model, data, jacp, jacr, index)
            else:
                p, R = data.site_xpos[index], data.site_xmat[index].reshape(3, 3)
                mujoco.mj_jacSite(model, data, jacp, jacr, index)
            T = robot.frame_pose(q, name)
            J = robot.jacobian(q, name, "local_world_aligned")
            expected = np.vstack([jacp, jacr]) @ S
            worst = np.maximum(
                worst, (np.abs(T[:3, 3] - p).max(), np.abs(T[:3, :3] - R).max(), np.abs(J - expected).max())
            )
    return CrossCheck(len(bodies) + len(sites), len(qs), float(worst[0]), float(worst[1]), float(worst[2]))


def _coupling(robot: Any, model: Any, joint_of: dict[str, int]) -> tuple[npt.NDArray[np.float64], Any]:
    """(S (nv, dof) with MuJoCo's qvel = S · q̇, the map q -> MuJoCo's qpos)."""
    column = {name: i for i, name in enumerate(robot.joint_names)}
    mimic = {j.name: j.mimic for j in robot.description.joints if j.mimic is not None}
    S = np.zeros((model.nv, robot.dof))

    def row(name: str) -> npt.NDArray[np.float64]:
        if name in column:
            out = np.zeros(robot.dof)
            out[column[name]] = 1.0
            return out
        m = mimic[name]
        return m.multiplier * row(m.joint)

    def value(name: str, q: npt.NDArray[np.float64]) -> float:
        if name in column:
            return float(q[column[name]])
        m = mimic[name]
        return m.multiplier * value(m.joint, q) + m.offset

    movable = [n for n in list(column) + list(mimic) if model.jnt_type[joint_of[n]] != FREE]
    for name in movable:
        S[model.jnt_dofadr[joint_of[name]]] = row(name)

    def qpos_of(q: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        qpos = model.qpos0.copy()
        for name in movable:
            qpos[model.jnt_qposadr[joint_of[name]]] = value(name, q)
        return qpos

    return S, qpos_of


__all__ = ["CrossCheck", "cross_check"]
