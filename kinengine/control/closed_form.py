"""Closed-form inverse kinematics of 6R chains by subproblem decomposition (EAIK).

Every joint solution of a pose T_IF (frame F in the root link frame I) of a chain of six revolute joints
that has a known decomposition into the canonical subproblems (a spherical wrist, three parallel or
intersecting axes, ...: Elias & Wen, IK-Geo, 2022; Ostermeier, Külz & Althoff, "Automatic Geometric
Decomposition for Analytical Inverse Kinematics", RA-L 2025).

Why EAIK (``eaik`` on PyPI, BSD-3-Clause, wheels) and not ``ik-geo``: EAIK finds the decomposition itself
from the axes and offsets (ik-geo makes the caller pick the kinematic family), solves a batch of poses in
C++ worker threads, and reports least-squares (non-exact) answers as such; ik-geo has neither a batch call
nor automatic family detection. The solver is never re-derived here: this module derives its inputs and
turns its raw answers into :class:`~kinengine.control.ik_solutions.IKSolutions`.

Inputs, from Pinocchio's model at q = 0 in I (product of exponentials, Robot Dynamics lecture notes, ETH
Zurich, §2.8): the revolute joints that move F in base-to-tip order (fixed and locked joints are part of
the geometry between them), each joint's unit axis h_i and a point a_i on it, P = (a_1, a_2 − a_1, ...,
p_F(0) − a_6) [m] and the frame's orientation C_IF(0): then C_IF(q) = Π_i exp(ĥ_i q_i) · C_IF(0). A tilted
base, a tool offset or a locked joint change only these numbers.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..errors import KinematicsError
from ..kinematics.compiler import compiled_chain
from .ik_candidates import candidates_to_solutions, shared_by_poses
from .ik_solutions import CONTINUOUS, MANY_TURNS, ONE_TURN, IKSolutions, joined
from .ik_target import checked_pose, checked_poses, checked_start, exact_pose, is_batch

if TYPE_CHECKING:  # the facade is a higher layer: named for the checker only
    from .robot_like import RobotLike

EXTRA_HINT = "closed-form IK needs the solver library EAIK: pip install 'kinengine[ik]'"
METHODS = ("auto", "closed_form", "numeric")
THREADS = max(1, min(4, os.cpu_count() or 1))
"""EAIK's worker threads for a batch (its C++ threads run without the GIL)."""
SNAP_AXIS = 1e-3
"""Axis entries below this (in I) count as zero when the exact chain has no decomposition (``snapped``)."""
SNAP_OFFSET = 1e-3
"""[m] offset entries below this count as zero alike; the ideal chain's answers are then polished on the
robot's own chain (:mod:`.ik_solutions`)."""
CHUNK_POSES = 16384
"""Larger batches are solved in chunks of this many poses (the candidates' arrays stay below ~100 MB)."""
SMALL_BATCH = 64
"""Batches up to this many poses are solved one call at a time (EAIK's thread start-up costs more)."""


def _eaik() -> object:
    """EAIK's compiled module (KinematicsError naming the extra when it is missing)."""
    try:
        import eaik.pybindings.EAIK as EAIK
    except ImportError:
        raise KinematicsError(EXTRA_HINT) from None
    return EAIK


def available() -> bool:
    """True if the solver library is installed."""
    try:
        _eaik()
    except KinematicsError:
        return False
    return True


@dataclass(frozen=True)
class Geometry:
    """The chain as EAIK takes it, all in the root link frame I at q = 0."""

    joints: tuple[str, ...]  # the revolute joints that move the frame, base to tip
    columns: np.ndarray  # their indices into q
    H: np.ndarray  # (n, 3) unit axes
    P: np.ndarray  # (n + 1, 3) offsets between points on consecutive axes [m]
    C_tool: np.ndarray  # (3, 3) C_IF(0)


def chain_geometry(robot: RobotLike, frame: str) -> Geometry:
    """Axes and offsets of the joints that move ``frame`` (KinematicsError for a prismatic or mimic joint)."""
    kin = robot.engine
    model, coords = kin.model, kin.coordinates
    fid = kin.frame_id(frame)
    supports = [k for k in model.supports[model.frames[fid].parentJoint] if k > 0]
    data = model.createData()
    q0 = np.zeros(model.nq)
    pin.forwardKinematics(model, data, q0)
    pin.computeJointJacobians(model, data, q0)
    pin.updateFramePlacements(model, data)
    joints, columns, axes, points = [], [], [], []
    mimics = {name for name in coords.pinocchio_names if name not in coords.names}
    for k in supports:
        name = model.names[k]
        joint = kin.description.joint(name)
        if joint.type == "prismatic":
            raise KinematicsError(
                f"frame {frame!r} is moved by the prismatic joint {name!r}: closed-form IK here solves "
                f"chains of revolute joints; lock it (robot.locked({{{name!r}: value}})) or use "
                "method='numeric'"
            )
        if name in mimics:
            raise KinematicsError(
                f"frame {frame!r} is moved by the mimic joint {name!r}: its angle is tied to another "
                "joint's, which no subproblem decomposition models; lock its leader or use method='numeric'"
            )
        J = np.reshape(pin.getJointJacobian(model, data, k, pin.LOCAL_WORLD_ALIGNED), (6, -1))  # nv = 1: (6,)
        joints.append(name)
        columns.append(coords.names.index(name))
        axes.append(J[3:, model.joints[k].idx_v])
        points.append(data.oMi[k].translation.copy())
    H = np.array(axes).reshape(-1, 3)
    A = np.array(points).reshape(-1, 3)
    tool = data.oMf[fid]
    P = np.diff(np.vstack((np.zeros(3), A, tool.translation)), axis=0)
    return Geometry(tuple(joints), np.array(columns, dtype=np.intp), H, P, tool.rotation.copy())


class ClosedFormChain:
    """One robot's frame: its geometry, EAIK's solver for it, and the joint data the answers need."""

    def __init__(self, robot: RobotLike, frame: str) -> None:
        EAIK = _eaik()
        self.frame = frame
        self.geometry = g = chain_geometry(robot, frame)
        n = len(g.joints)
        if n != 6:
            raise KinematicsError(_not_six_message(robot, frame, g, EAIK))
        self.solver, self.approximate = _decomposed(EAIK, g, []), False
        if self.solver is None:  # a description written with rounded angles (1.5708): solve the ideal chain
            self.solver, self.approximate = _decomposed(EAIK, snapped(g), []), True
        if self.solver is None:
            raise KinematicsError(
                f"the 6 joints that move frame {frame!r} ({', '.join(g.joints)}) have no known "
                "subproblem decomposition (no spherical wrist, no three parallel or intersecting axes): "
                "use method='numeric'"
            )
        coords = robot.engine.coordinates
        self.joints, self.columns = g.joints, g.columns
        self.lower = coords.lower[g.columns]
        self.upper = coords.upper[g.columns]
        self.continuous = coords.continuous[g.columns] | ~np.isfinite(self.upper - self.lower)
        within = (self.lower > -np.pi + 1e-9) & (self.upper < np.pi - 1e-9)  # angle in (−π, π]: no shift
        self.one_turn = np.flatnonzero(~self.continuous & within)
        self.many_turns = np.flatnonzero(~self.continuous & ~within)
        kinds = np.full(n, MANY_TURNS)
        kinds[self.one_turn], kinds[self.continuous] = ONE_TURN, CONTINUOUS
        self.table = np.column_stack((g.columns, kinds, self.lower, self.upper)).astype(np.float64)
        """(n, 4) per joint: its column in q, kind of range, lower, upper [rad] (the C kernel's table)."""
        self.robot, self.dof = robot, robot.dof
        self.neutral = robot.neutral()
        self.neutral.flags.writeable = False
        self.kernel = compiled_chain(robot.engine, robot.engine.frame_id(frame)).kernel
        """The C chain of the frame (``Kernel.candidates`` checks the answers), None without the extension."""

    def solve_one(self, T: np.ndarray) -> Any:
        """EAIK's answer object for one pose T (4, 4): ``.Q`` (k, 6) [rad], ``.is_LS`` (k,)."""
        try:
            return self.solver.calculate_IK(T)
        except RuntimeError as exc:  # not seen in the tests; EAIK's own message, as a kinengine error
            raise KinematicsError(f"the closed-form solver failed on frame {self.frame!r}: {exc}") from None

    def raw(self, T: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """EAIK's answers for poses T (N, 4, 4), flat: pose index (M,), angles (M, 6) [rad], least-squares
        flags (M,)."""
        n = len(T)
        try:
            if n <= SMALL_BATCH:
                answers = [self.solver.calculate_IK(T[i]) for i in range(n)]
            else:
                answers = self.solver.calculate_IK_batched(list(T), THREADS)
        except RuntimeError as exc:  # not seen in the tests; EAIK's own message, as a kinengine error
            raise KinematicsError(f"the closed-form solver failed on frame {self.frame!r}: {exc}") from None
        Qs = [a.Q for a in answers]
        counts = np.fromiter(map(len, Qs), dtype=np.intp, count=n)
        total = int(counts.sum())
        if not total:
            return np.zeros(0, dtype=np.intp), np.zeros((0, 6)), np.zeros(0, dtype=bool)
        Q = np.concatenate([Q for Q in Qs if len(Q)])
        LS = np.concatenate([a.is_LS for a in answers]).astype(bool, copy=False)
        return np.repeat(np.arange(n), counts), Q, LS


def chain_of(robot: RobotLike, frame: str | None) -> ClosedFormChain | KinematicsError:
    """The robot's closed-form solver of ``frame`` (default: end effector), built once and kept; the error
    that says why there is none, kept likewise."""
    name = robot.end_effector if frame is None else frame
    if not isinstance(name, str):
        robot.engine.frame_id(name)  # FrameNotFoundError (not a key to keep)
    return robot.engine.memoized(("closed-form IK", name), lambda: _built(robot, name))


def _built(robot: RobotLike, frame: str) -> ClosedFormChain | KinematicsError:
    robot.engine.frame_id(frame)  # FrameNotFoundError with suggestions first, not kept
    _eaik()  # likewise the missing extra
    try:
        return ClosedFormChain(robot, frame)
    except KinematicsError as exc:  # kept too: the answer "no closed form" is as costly to find
        return exc


def solver_of(robot: RobotLike, frame: str | None) -> ClosedFormChain:
    chain = chain_of(robot, frame)
    if isinstance(chain, KinematicsError):
        raise type(chain)(*chain.args)
    return chain


def ik_solutions(
    robot: RobotLike,
    T: npt.ArrayLike,
    frame: str | None = None,
    *,
    q_near: object = None,
    within_limits: bool = True,
    all_turns: bool = False,
) -> IKSolutions:
    """Every solution of T_IF (4, 4) or of each pose of (N, 4, 4); see :class:`IKSolutions`."""
    chain = solver_of(robot, frame)
    poses = exact_pose(*(checked_poses(T) if is_batch(T) else checked_pose(T, parameters=False)))
    single = poses.ndim == 2
    poses = poses[None] if single else poses
    near = checked_start(robot, q_near, "q_near", None if single else len(poses))
    reference = chain.neutral if near is None else near
    if single:  # the solver's answer object as it comes: no batch gathering
        answer = chain.solve_one(poses[0])
        Q, ls = answer.Q, answer.is_LS
        return candidates_to_solutions(
            chain,
            poses,
            np.zeros(len(ls), dtype=np.intp),
            Q if len(Q) else np.zeros((0, len(chain.joints))),
            np.array(ls, dtype=bool) if np.count_nonzero(ls) else None,
            reference,
            near is not None,
            within_limits=bool(within_limits),
            all_turns=bool(all_turns),
            single=True,
        )

    def solve(a: int, b: int) -> IKSolutions:
        """Poses a..b: the solver's answers (its threads), then their post-processing."""
        row, Q, LS = chain.raw(poses[a:b])
        has_ls = bool(LS.any())

        def post(c0: int, c1: int, i0: int, i1: int, workers: int | None) -> IKSolutions:
            return candidates_to_solutions(
                chain,
                poses[a + c0 : a + c1],
                row[i0:i1] - c0,
                Q[i0:i1],
                LS[i0:i1] if has_ls else None,
                reference[a + c0 : a + c1] if reference.ndim == 2 else reference,
                near is not None,
                within_limits=bool(within_limits),
                all_turns=bool(all_turns),
                single=single,
                workers=workers,
            )

        return shared_by_poses(b - a, row, post)

    # bounded memory: the candidates' arrays of one chunk at a time
    done = [solve(a, min(a + CHUNK_POSES, len(poses))) for a in range(0, len(poses), CHUNK_POSES)]
    return done[0] if len(done) == 1 else joined(done)


def snapped(g: Geometry) -> Geometry:
    """The geometry with axis entries below ``SNAP_AXIS`` and offset entries below ``SNAP_OFFSET`` [m] in I
    set to zero (axes renormalized): the ideal chain of a description written with rounded numbers."""
    H = np.where(np.abs(g.H) < SNAP_AXIS, 0.0, g.H)
    H /= np.linalg.norm(H, axis=1)[:, None]
    P = np.where(np.abs(g.P) < SNAP_OFFSET, 0.0, g.P)
    return Geometry(g.joints, g.columns, H, P, g.C_tool)


def _decomposed(EAIK: object, g: Geometry, locked: list[tuple[int, float]]) -> Any:
    """EAIK's solver of the chain (joints ``locked`` at (index, angle)), None if it finds no decomposition
    (it raises RuntimeError for some geometries, e.g. a lock that leaves two parallel axes it would
    intersect)."""
    try:
        solver = EAIK.Robot(g.H.T, g.P.T, g.C_tool, locked, True)  # type: ignore[attr-defined]
        return solver if solver.has_known_decomposition() else None
    except RuntimeError:
        return None


def _not_six_message(robot: RobotLike, frame: str, g: Geometry, EAIK: object) -> str:
    n = len(g.joints)
    joints = f"{n} revolute joint{'' if n == 1 else 's'}" + (f" ({', '.join(g.joints)})" if n else "")
    head = f"frame {frame!r} is moved by {joints}; closed-form IK needs 6"
    if n != 7:
        return head + ": use method='numeric'"
    lockable = []
    for i, name in enumerate(g.joints):
        if any(_decomposed(EAIK, chain, [(i, 0.0)]) is not None for chain in (g, snapped(g))):
            lockable.append(name)
    if not lockable:
        return head + ": locking no single one of them leaves a known decomposition; use method='numeric'"
    example = lockable[-1]
    return (
        head + f": locking one of {', '.join(lockable)} leaves a chain with a known decomposition, e.g. "
        f"robot.locked({{{example!r}: 0.0}}).ik_solutions(T); or use method='numeric'"
    )


__all__ = [
    "EXTRA_HINT",
    "METHODS",
    "ClosedFormChain",
    "Geometry",
    "IKSolutions",
    "available",
    "chain_geometry",
    "ik_solutions",
]
