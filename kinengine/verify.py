"""``kinengine verify``: cross-check a robot's answers against independent computations.

Compared, for every frame at q = 0, ``samples`` random configurations within the limits and
the corners of that box (all 2^dof if dof <= 8, else 64 drawn at random); a joint without a
usable range (continuous, or lower >= upper as in some exported files) spans [-π, π]:

* poses and Jacobians ("local_world_aligned", "local", "world") vs :mod:`kinengine.reference`
  (yourdfpy parsing, numpy kinematics): absolute 1e-10 [m, rad, m/rad];
* poses of every link vs yourdfpy's own forward kinematics (zero and random q): absolute 1e-9;
* Jacobians vs central finite differences of the engine's own poses (zero and random q):
  relative 1e-6, i.e. max |J − J_fd| / max(1, max |J_fd|);
* the end effector's analytic Jacobian of every parameterization vs finite differences of
  ``robot.pose_parameters`` (random q only, samples within 0.05 of a representation
  singularity skipped, and columns where χ(q) jumps or kinks at a branch cut): relative 1e-6.
"""

from __future__ import annotations

import itertools
import math
import sys
import warnings
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from .errors import OptionError
from .parameterizations.base import Parameterization
from .reference import REFERENCES, ReferenceKinematics, read_urdf

if TYPE_CHECKING:
    from .control.robot_like import RobotLike

REFERENCE_ATOL = 1e-10
YOURDFPY_ATOL = 1e-9
"""yourdfpy's scene-graph FK (trimesh) was measured 1.3e-10 off for a mimic joint turned by 1e-10 rad,
where the reference and Pinocchio agree to 1e-16: it is a second opinion, not the reference."""
FD_RTOL = 1e-6
FD_STEP = 1e-6
SINGULARITY_MARGIN = 0.05
MAX_CORNERS = 64
MAX_SAMPLES = 100_000
"""The most random configurations one verify run takes (each costs a finite-difference Jacobian per frame)."""
BOX = 100.0
"""[m or rad] joint limits beyond ±BOX are sampled within ±BOX (±1e308 would overflow the sampler)."""


@dataclass(frozen=True)
class CheckResult:
    """One row of the report: the worst error of one comparison over all frames and configurations."""

    check: str
    max_error: float
    tolerance: float
    compared: int  # number of (frame, configuration) pairs or samples compared
    note: str = ""

    @property
    def passed(self) -> bool:
        return bool(self.max_error <= self.tolerance)  # NaN fails


@dataclass(frozen=True)
class VerifyReport:
    """The outcome of :func:`verify`; ``passed`` is True when every check passed."""

    robot: str
    dof: int
    frames: int
    configurations: int
    checks: tuple[CheckResult, ...]

    @property
    def passed(self) -> bool:
        return all(c.passed for c in self.checks)

    def table(self) -> str:
        """The report as a fixed-width text table: check, max error, tolerance, pass."""
        width = max(len(c.check) for c in self.checks)
        lines = [
            f"{self.robot}: {self.dof} dof, {self.frames} frames, {self.configurations} configurations",
            f"{'check':<{width}}  {'max error':>10}  {'tolerance':>9}  pass",
        ]
        for c in self.checks:
            verdict = "NO  " if not c.passed else "skip" if c.compared == 0 else "yes "
            lines.append(
                f"{c.check:<{width}}  {c.max_error:>10.2e}  {c.tolerance:>9.0e}  {verdict}"
                + (f"  ({c.note})" if c.note else "")
            )
        lines.append("PASSED" if self.passed else "FAILED")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {
            **asdict(self),
            "passed": self.passed,
            "checks": [{**asdict(c), "passed": c.passed} for c in self.checks],
        }


def verify(robot: RobotLike, samples: int = 20, seed: int = 0, progress: bool = False) -> VerifyReport:
    """Run every check on ``robot`` (a :class:`kinengine.Robot`) and return the report.

    ``samples``: random configurations, a whole number in [0, MAX_SAMPLES]; ``seed``: a whole number >= 0.
    Joint limits beyond ±BOX (m or rad) are sampled within ±BOX.
    """
    _check_count(samples, "samples", MAX_SAMPLES)
    _check_count(seed, "seed", 2**63 - 1)
    rng = np.random.default_rng(seed)
    ref = ReferenceKinematics.from_urdf_string(
        robot.urdf_text, joint_names=robot.joint_names, source=robot.source
    )
    lower, upper = _box(robot)
    q_smooth = np.vstack([np.zeros((1, robot.dof)), rng.uniform(lower, upper, size=(samples, robot.dof))])
    q_all = np.vstack([q_smooth, _corners(lower, upper, rng)])
    frames = [f for f in robot.frame_names if f in ref.frame_names]
    params = _parameterizations(robot) if robot.dof else []  # nothing to differentiate without joints
    bar = _progress_bar(progress, len(frames) + 1 + len(params or ()), robot.name)

    missing = sorted(set(robot.frame_names) ^ set(ref.frame_names))
    checks = [
        CheckResult(
            "frame names match the reference",
            float(len(missing)),
            0.0,
            len(set(robot.frame_names) | set(ref.frame_names)),
            f"only on one side: {', '.join(missing[:5])}" if missing else "",
        )
    ]
    pose_err, jac_err, fd_err = 0.0, dict.fromkeys(REFERENCES, 0.0), dict.fromkeys(REFERENCES, 0.0)
    for frame in frames:
        pose_err = max(pose_err, _max_abs(robot.frame_pose(q_all, frame) - ref.frame_pose(q_all, frame)))
        for r in REFERENCES:
            J = robot.jacobian(q_all, frame, r)
            jac_err[r] = max(jac_err[r], _max_abs(J - ref.jacobian(q_all, frame, r)))
            fd_err[r] = max(fd_err[r], _relative(J[: len(q_smooth)], _fd_jacobian(robot, q_smooth, frame, r)))
        bar.update()
    n = len(frames) * len(q_all)
    checks.append(CheckResult("pose vs reference", pose_err, REFERENCE_ATOL, n))
    checks += [CheckResult(f"jacobian {r} vs reference", jac_err[r], REFERENCE_ATOL, n) for r in REFERENCES]
    checks.append(_yourdfpy_check(robot, q_smooth))
    bar.update()
    checks += [
        CheckResult(f"jacobian {r} vs finite differences", fd_err[r], FD_RTOL, len(frames) * len(q_smooth))
        for r in REFERENCES
    ]
    if params is None:
        checks.append(
            CheckResult(
                "analytic jacobians vs finite differences",
                0.0,
                FD_RTOL,
                0,
                "skipped: robot has no analytic_jacobian",
            )
        )
    for kind, name, param in params or ():
        checks.append(_analytic_check(robot, q_smooth[1:], kind, name, param))
        bar.update()
    bar.close()
    return VerifyReport(robot.name, robot.dof, len(frames), len(q_all), tuple(checks))


def _box(robot: RobotLike) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """The sampled joint box: the limits, or [-π, π] where they are infinite or empty (lower >= upper)."""
    lower, upper = np.asarray(robot.lower_limits, float), np.asarray(robot.upper_limits, float)
    lower, upper = np.clip(lower, -BOX, BOX), np.clip(upper, -BOX, BOX)
    usable = lower < upper
    return np.where(usable, lower, -math.pi), np.where(usable, upper, math.pi)


def _check_count(value: object, name: str, most: int) -> None:
    whole = isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))
    if not (whole and isinstance(value, (int, np.integer)) and 0 <= value <= most):
        raise OptionError(f"{name} must be a whole number in [0, {most}], got {value!r:.40}")


def _corners(lower: np.ndarray, upper: np.ndarray, rng: np.random.Generator) -> npt.NDArray[np.float64]:
    """Corners of the joint box: all 2^dof if dof <= 8, else MAX_CORNERS drawn at random."""
    dof = len(lower)
    if dof <= 8:
        pick = np.array(list(itertools.product((0, 1), repeat=dof)), dtype=bool).reshape(2**dof, dof)
    else:
        pick = rng.integers(0, 2, size=(MAX_CORNERS, dof)).astype(bool)
    return np.where(pick, upper, lower)


def _fd_jacobian(robot: RobotLike, q: np.ndarray, frame: str, reference: str) -> npt.NDArray[np.float64]:
    """(M, 6, dof) Jacobians by central differences of T_IF(q), each reference from its definition:
    local_world_aligned [ṗ; log(C+ C-^T)/2h], local T^-1·dT/dq, world dT/dq·T^-1 (twists [v; ω])."""
    M, dof = q.shape
    if dof == 0:
        return np.zeros((M, 6, 0))
    step = FD_STEP * np.eye(dof)
    T0 = robot.frame_pose(q, frame)
    Tp = robot.frame_pose((q[:, None] + step).reshape(M * dof, dof), frame).reshape(M, dof, 4, 4)
    Tm = robot.frame_pose((q[:, None] - step).reshape(M * dof, dof), frame).reshape(M, dof, 4, 4)
    if reference == "local_world_aligned":
        v = (Tp[..., :3, 3] - Tm[..., :3, 3]) / (2 * FD_STEP)
        C_rel = Tp[..., :3, :3] @ np.swapaxes(Tm[..., :3, :3], -1, -2)
        w = Rotation.from_matrix(C_rel.reshape(-1, 3, 3)).as_rotvec().reshape(M, dof, 3) / (2 * FD_STEP)
    else:
        dT = (Tp - Tm) / (2 * FD_STEP)
        T_inv = np.linalg.inv(T0)[:, None]
        twist = T_inv @ dT if reference == "local" else dT @ T_inv
        v = twist[..., :3, 3]
        w = np.stack([twist[..., 2, 1], twist[..., 0, 2], twist[..., 1, 0]], axis=-1)
    return np.swapaxes(np.concatenate([v, w], axis=-1), 1, 2)


def _yourdfpy_check(robot: RobotLike, q: np.ndarray) -> CheckResult:
    """Every link's pose vs yourdfpy's scene-graph forward kinematics (URDF.update_cfg)."""
    urdf = read_urdf(robot.urdf_text, source=robot.source, scene_graph=True)
    for joint in urdf.robot.joints:  # yourdfpy translates by q·axis without normalizing the axis
        if joint.type == "prismatic":
            joint.axis = joint.axis / np.linalg.norm(joint.axis)
    mimics = {j.name: j.mimic for j in urdf.robot.joints if j.mimic is not None}
    for (
        joint
    ) in urdf.robot.joints:  # yourdfpy follows one level of mimic: compose chains to their root leader
        m = joint.mimic
        while m is not None and m.joint in mimics:
            inner = mimics[m.joint]
            a, b = _or(m.multiplier, 1.0), _or(m.offset, 0.0)
            m = type(m)(inner.joint, a * _or(inner.multiplier, 1.0), a * _or(inner.offset, 0.0) + b)
        joint.mimic = m
    columns = [robot.joint_names.index(name) for name in urdf.actuated_joint_names]
    links = [name for name in urdf.link_map if name in robot.frame_names]
    poses = {link: robot.frame_pose(q, link) for link in links}
    err = 0.0
    for i, qi in enumerate(q):
        urdf.update_cfg(qi[columns])
        for link in links:
            err = max(err, _max_abs(poses[link][i] - urdf.get_transform(link, urdf.base_link)))
    return CheckResult("link poses vs yourdfpy", err, YOURDFPY_ATOL, len(links) * len(q))


def _or(value: float | None, default: float) -> float:
    return default if value is None else float(value)


def _parameterizations(robot: RobotLike) -> list[tuple[str, str, Parameterization]] | None:
    """(kind, name, parameterization) for every position and rotation parameterization, or None
    when this robot has no analytic Jacobians yet."""
    if not (hasattr(robot, "analytic_jacobian") and hasattr(robot, "pose_parameters")):
        return None
    from .parameterizations import POSITION_PARAMETERIZATIONS, ROTATION_PARAMETERIZATIONS

    return [("position", n, p) for n, p in POSITION_PARAMETERIZATIONS.items()] + [
        ("rotation", n, p) for n, p in ROTATION_PARAMETERIZATIONS.items()
    ]


def _analytic_check(
    robot: RobotLike, q: np.ndarray, kind: str, name: str, param: Parameterization
) -> CheckResult:
    """J_A of the end effector vs central differences of χ(q), away from singularities and branch cuts."""
    row = f"analytic {name} vs finite differences"
    frame, dof = robot.end_effector, robot.dof
    position = name if kind == "position" else None  # kind is "position" or "rotation"
    rotation = name if kind == "rotation" else None

    def chi(qs: np.ndarray) -> npt.NDArray[np.float64]:
        with warnings.catch_warnings():  # χ at a singular pose warns; such samples are skipped
            warnings.simplefilter("ignore")
            return robot.pose_parameters(qs, frame, position=position, rotation=rotation, on_singularity=None)

    chi0 = chi(q)
    regular = np.atleast_1d(param.singularity_distance(chi0)) >= SINGULARITY_MARGIN
    q, chi0 = q[regular], chi0[regular]
    if len(q) == 0:
        return CheckResult(row, 0.0, FD_RTOL, 0, "skipped: every sample near a singularity")
    M, m = chi0.shape
    step = FD_STEP * np.eye(dof)
    chi_p = chi((q[:, None] + step).reshape(M * dof, dof)).reshape(M, dof, m)
    chi_m = chi((q[:, None] - step).reshape(M * dof, dof)).reshape(M, dof, m)
    forward, backward = (chi_p - chi0[:, None]) / FD_STEP, (chi0[:, None] - chi_m) / FD_STEP
    # A jump (angle wrap, quaternion sign) or kink (θ = π) makes the one-sided differences disagree.
    smooth = np.abs(forward - backward) <= 1e-2 * np.maximum(1.0, np.abs(forward) + np.abs(backward))
    smooth = smooth.all(axis=2)[:, None, :]  # per (sample, column)
    J_fd = np.swapaxes((chi_p - chi_m) / (2 * FD_STEP), 1, 2)
    scale = np.maximum(1.0, np.max(np.abs(J_fd), axis=(1, 2), keepdims=True))
    err = np.where(
        smooth,
        np.abs(robot.analytic_jacobian(q, frame, position=position, rotation=rotation) - J_fd) / scale,
        0.0,
    )
    skipped = [f"{int(np.sum(~regular))} samples near a singularity"] if not regular.all() else []
    skipped += [f"{int(np.sum(~smooth))} columns at a branch cut"] if not smooth.all() else []
    return CheckResult(
        row, float(np.max(err, initial=0.0)), FD_RTOL, M, "skipped " + ", ".join(skipped) if skipped else ""
    )


def _max_abs(a: np.ndarray) -> float:
    return float(np.max(np.abs(a), initial=0.0))


def _relative(J: np.ndarray, J_fd: np.ndarray) -> float:
    """max over samples of max |J − J_fd| / max(1, max |J_fd|)."""
    if J.size == 0:
        return 0.0
    scale = np.maximum(1.0, np.max(np.abs(J_fd), axis=(1, 2)))
    return float(np.max(np.max(np.abs(J - J_fd), axis=(1, 2)) / scale))


class _Bar(Protocol):
    """The part of a tqdm progress bar verify uses."""

    def update(self) -> object: ...
    def close(self) -> object: ...


class _NoBar:
    def update(self) -> None: ...
    def close(self) -> None: ...


def _progress_bar(enabled: bool, total: int, name: str) -> _Bar:
    if not enabled:
        return _NoBar()
    from tqdm import tqdm

    return tqdm(total=total, desc=f"verify {name}", unit="step", file=sys.stderr, leave=False)


__all__ = ["CheckResult", "VerifyReport", "verify"]
