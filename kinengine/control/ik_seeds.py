"""IK seeds: a per-robot, per-frame table of random configurations well inside the limits and a KD-tree
over their frame poses, so each target starts from the stored configurations whose poses are nearest it
(plus the middle of the joint ranges, or the nullspace target); one table serves the single and the batched
solver; tables are bounded in number and size (an LRU)."""

from __future__ import annotations

import math
import threading
from collections import OrderedDict
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from .ik_target import FrameGoal, Problem

if TYPE_CHECKING:  # named for the checker only
    from .robot_like import RobotLike

NEAREST_SEEDS = 10
SEED_TABLE_SIZE = 32768
SEED_TABLE_BYTES = 1 << 23
"""At most 8 MiB per seed table (fewer than SEED_TABLE_SIZE rows for robots with many joints)."""
SEED_TABLES = 8
"""At most this many seed tables (frames × target kinds, shared by the single and the batched solver) are
kept per robot, least recently used dropped: with their KD-trees ~130 MiB at most (kept per frame without
bound, 60 frames of a 30-dof chain held 550 MiB)."""
SEED_TABLE_RNG = 0x5EED_7AB1E
SEED_MARGIN = 0.05
"""Table configurations are drawn from the inner 1 − 2·this of each bounded joint's range: an attempt from a
seed on a limit often stalls against it."""
SEED_EPS = 2.0
"""Approximate nearest entries: within (1 + this) of the nearest distance (cKDTree's eps; exact ones cost
more search and reach no more targets)."""
FIRST_SEED_EPS = 3.0
"""... for every batch target's first entry at once; the further entries, wanted by the few targets whose
first attempt fails, with SEED_EPS."""
SEED_ROTATION_WEIGHT = 0.2
"""[m/rad]: pose distance |Δp| + 0.2·angle used to rank attempts and pick the stored seeds nearest a
target."""

SeedTable = tuple[np.ndarray, Any]
"""(configurations (K, dof), scipy cKDTree over their embedded frame poses)."""


class SeedTables:
    """A small LRU of seed tables (bounded: SEED_TABLES tables of at most SEED_TABLE_BYTES each)."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.tables: OrderedDict[tuple[str, bool, bool], SeedTable] = OrderedDict()

    def get(self, key: tuple[str, bool, bool], make: Callable[[], SeedTable]) -> SeedTable:
        with self.lock:  # made under the lock: another thread wanting a table waits for it
            if key not in self.tables:
                self.tables[key] = make()
                while len(self.tables) > SEED_TABLES:
                    self.tables.popitem(last=False)
            self.tables.move_to_end(key)
            return self.tables[key]


def seed_table(robot: RobotLike, frame: str, use_p: bool, use_R: bool) -> SeedTable:
    """The robot's seed table of ``frame`` for targets fixing the position / rotation (``use_p``, ``use_R``):
    (configurations (K, dof), a KD-tree over [p, w·vec(C)/√2] of ``frame`` at them), K <= SEED_TABLE_SIZE
    within SEED_TABLE_BYTES, made once (an LRU of SEED_TABLES per robot)."""

    def make() -> SeedTable:
        from scipy.spatial import cKDTree

        size = max(64, min(SEED_TABLE_SIZE, SEED_TABLE_BYTES // (8 * (robot.dof + 12))))
        configs = robot.random_configuration(np.random.default_rng(SEED_TABLE_RNG), size=size)
        coords, middle = robot.engine.coordinates, middle_of_ranges(robot)
        inner = np.isfinite(coords.lower) & np.isfinite(coords.upper)  # shrunk towards the middle
        configs[:, inner] = middle[inner] + (1 - 2 * SEED_MARGIN) * (configs[:, inner] - middle[inner])
        poses = robot.frame_pose(configs, frame)
        return configs, cKDTree(
            _embed(poses[:, :3, 3] if use_p else None, poses[:, :3, :3] if use_R else None, size)
        )

    tables = robot.engine.memoized("ik seed tables", SeedTables)
    return tables.get((frame, use_p, use_R), make)


def _embed(p: np.ndarray | None, C: np.ndarray | None, n: int) -> np.ndarray:
    """Points (n, ≤ 12) whose squared distance is |Δp|² + w²‖ΔC‖²/2 = |Δp|² + w²·2(1 − cos θ) ≈ |Δp|² + (wθ)²,
    for positions p (n, 3) and rotations C (n, 3, 3) (either None; n = 1: also p (3,), C (3, 3))."""
    parts = [p.reshape(n, 3)] if p is not None else []
    if C is not None:
        parts.append(C.reshape(n, 9) * (SEED_ROTATION_WEIGHT / math.sqrt(2.0)))
    return np.hstack(parts) if parts else np.zeros((n, 1))


def middle_of_ranges(robot: RobotLike) -> np.ndarray:
    """The middle of each joint's range; where a range is unbounded, 0 clipped into it (read-only, made
    once per robot)."""

    def make() -> np.ndarray:
        lower, upper = robot.engine.coordinates.lower, robot.engine.coordinates.upper
        bounded = np.isfinite(lower) & np.isfinite(upper)
        middle = np.clip(np.where(bounded, (np.where(bounded, lower, 0.0) + upper) / 2, 0.0), lower, upper)
        middle.flags.writeable = False
        return middle

    return robot.engine.memoized("ik middle of the ranges", make)


def _default_start(robot: RobotLike, problem: Problem) -> np.ndarray:
    """The seeded start that is not from a table: the middle of the joint ranges (0 for an unbounded joint),
    or the nullspace target clipped into the limits."""
    return middle_of_ranges(robot) if problem.q_ns_within is None else problem.q_ns_within


def _nearest(robot: RobotLike, goal: FrameGoal) -> np.ndarray:
    """The NEAREST_SEEDS configurations (k, dof) of the stored table of the goal's frame and target kind whose
    frame poses are nearest its target, nearest first."""
    configs, tree = seed_table(robot, goal.problem.frame, goal.p_d is not None, goal.C_d is not None)
    k = min(NEAREST_SEEDS, len(configs))
    return configs[np.reshape(tree.query(_embed(goal.p_d, goal.C_d, 1), k=k, eps=SEED_EPS)[1], k)]


def frame_seeds(robot: RobotLike, goals: list[FrameGoal], q0: np.ndarray | None) -> np.ndarray:
    """The seeded attempts' starts (S, dof): q0 clipped into the limits, else the stored seeds nearest the
    target, then the middle of the ranges (or the nullspace target: rarely the nearest). For several
    frames, the stored seeds nearest any frame's target, ranked by Σ_F (|Δp| + 0.2·‖ΔC‖_F/√2) over the
    frames' kept rows (‖ΔC‖_F/√2 = 2 sin(θ/2) ≈ θ, the metric of the tables)."""
    if q0 is not None:
        return np.clip(q0, robot.engine.coordinates.lower, robot.engine.coordinates.upper)[None]
    candidates = np.concatenate([_nearest(robot, g) for g in goals])
    if len(goals) > 1:
        score, n = np.zeros(len(candidates)), len(candidates)
        for g in goals:  # several frames: each a pose (4, 4)
            assert g.p_d is not None and g.C_d is not None
            T, rows = robot.frame_pose(candidates, g.problem.frame), g.problem.rows
            d = g.p_d - T[:, :3, 3]
            if rows is not None:
                d = (d @ g.C_d)[:, rows[rows < 3]]  # C_dᵀ Δp, kept rows
            score += np.sqrt(np.einsum("ij,ij->i", d, d))
            if rows is None or rows[-1] >= 3:  # rows are sorted: a rotation row is kept
                dC = (T[:, :3, :3] - g.C_d).reshape(n, 9)
                score += SEED_ROTATION_WEIGHT / math.sqrt(2.0) * np.sqrt(np.einsum("ij,ij->i", dC, dC))
        candidates = candidates[np.argsort(score, kind="stable")]
    return np.concatenate((candidates, _default_start(robot, goals[0].problem)[None]))


class BatchSeeds:
    """The seeded starts for a batch (N targets), as :func:`frame_seeds` orders them (the nearest table
    entries, then the middle of the ranges; or ``q0``), searched only when needed: every target's nearest
    entry at once, its further ones when the target first needs a second attempt. :meth:`starts` gives
    (m, dof) for (target, attempt) pairs, each attempt < ``count``."""

    def __init__(
        self, robot: RobotLike, problem: Problem, p_d: np.ndarray, C_d: np.ndarray, q0: np.ndarray | None
    ) -> None:
        joints, n = robot.engine.coordinates, len(p_d)
        self.given = (
            None if q0 is None else np.broadcast_to(np.clip(q0, joints.lower, joints.upper), (n, robot.dof))
        )
        self.count = 1
        if self.given is not None:
            return
        self.first = _default_start(robot, problem)
        self.configs, self.tree = seed_table(robot, problem.frame, True, True)
        self.k = min(NEAREST_SEEDS, len(self.configs))
        self.count = self.k + 1
        self.points = _embed(p_d, C_d, n)
        self.index = np.zeros((n, self.k), dtype=np.intp)
        self.depth = np.zeros(n, dtype=np.intp)  # table entries found so far, nearest first

    def _find(self, targets: np.ndarray, k: int) -> None:
        workers = -1 if len(targets) > 512 else 1  # scipy starts its threads per query: ~0.1 ms
        eps = FIRST_SEED_EPS if k == 1 else SEED_EPS
        _, index = self.tree.query(self.points[targets], k=k, eps=eps, workers=workers)
        self.index[targets, :k] = np.asarray(index).reshape(len(targets), k)
        self.depth[targets] = k

    def starts(self, targets: np.ndarray, attempts: np.ndarray) -> np.ndarray:
        """Starts (m, dof) of attempts ``attempts`` (m,) of targets ``targets`` (m,)."""
        if self.given is not None:
            return self.given[targets].copy()
        table = attempts < self.k
        need = table & (self.depth[targets] <= attempts)
        first = need & (attempts == 0)  # depth 0: every target's nearest entry, found once
        if first.any():
            self._find(targets[first], 1)
        if (need & ~first).any():
            self._find(np.unique(targets[need & ~first]), self.k)
        out = np.empty((len(targets), self.configs.shape[1]))
        out[table] = self.configs[self.index[targets[table], attempts[table]]]
        out[~table] = self.first
        return out


__all__ = [
    "FIRST_SEED_EPS",
    "NEAREST_SEEDS",
    "SEED_EPS",
    "SEED_MARGIN",
    "SEED_ROTATION_WEIGHT",
    "SEED_TABLES",
    "SEED_TABLE_BYTES",
    "SEED_TABLE_RNG",
    "SEED_TABLE_SIZE",
    "BatchSeeds",
    "SeedTables",
    "frame_seeds",
    "middle_of_ranges",
    "seed_table",
]
