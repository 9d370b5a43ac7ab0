"""Measuring the rows of ``kinengine bench`` (see :mod:`kinengine.bench` for the command).

Every row is timed timeit-style after a warm-up: ``repeat`` repeats of ``number`` calls each
(``number`` grows until a repeat lasts ``min_time``); min and median are per call [µs]; the rate is
n / min (configurations, or IK solves, per second); ratio = kinengine min / Pinocchio min (the floor,
see :mod:`kinengine.bench_cases`). Before timing, results that should agree are compared
(kinengine vs the floor to 1e-9 relative; each peer vs kinengine to ``--peer-atol``): a peer that
disagrees is reported and not timed. The JSON holds the rows with library versions, CPU model,
core count and a timestamp.
"""

from __future__ import annotations

import importlib.metadata
import math
import os
import platform
import statistics
import timeit
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import cast

import numpy as np
from tqdm import tqdm

from ...loading import load
from ...parameterizations import ROTATION_PARAMETERIZATIONS
from ...robot import Robot
from .cases import Case, latency_cases, throughput_cases
from .ik_cases import ik_cases
from .peers import RTB_IK_TOL, RUNTIMES, Peer, Skip, load_peers

DEFAULT_ROBOTS = ("abb_irb120",)


@dataclass(frozen=True)
class Settings:
    sizes: tuple[int, ...]
    repeat: int
    min_time: float  # [s] per repeat
    ik: tuple[int, int] = (200, 10_000)  # random IK targets: solved one by one, and as one batch


FULL = Settings((1, 100, 10_000, 100_000, 1_000_000), repeat=21, min_time=0.01)
QUICK = Settings((1, 100, 1_000), repeat=3, min_time=0.002, ik=(10, 100))
SLOW_CALL = 0.1
"""[s] a call slower than this is repeated only SLOW_REPEAT times."""
SLOW_REPEAT = 5
ROUNDING = 1e-9
"""[rad] slack on the 1e-6 rad of a reached IK target, for a solver measuring its angle another way."""


def measure(fn: Callable[[], object], settings: Settings) -> dict[str, float]:
    """min and median seconds per call of ``fn`` over ``settings.repeat`` repeats, after a warm-up."""
    return measure_interleaved([fn], settings)[0]


def measure_interleaved(fns: list[Callable[[], object]], settings: Settings) -> list[dict[str, float]]:
    """For each fn: min and median [µs] per call. Each fn's calls per repeat grow until a repeat lasts
    ``min_time``; then the repeats alternate between the fns (kinengine, its floor, kinengine, ...), so
    that a noisy neighbour on a shared machine slows both sides alike, and the min is taken. A fn whose
    call takes over SLOW_CALL is repeated only SLOW_REPEAT times, spread evenly among the others'."""
    timers, numbers, repeats = [timeit.Timer(fn) for fn in fns], [], []
    for timer in timers:
        number, elapsed = 1, timer.timeit(1)  # the warm-up call
        repeats.append(min(settings.repeat, SLOW_REPEAT) if elapsed > SLOW_CALL else settings.repeat)
        while elapsed < settings.min_time and number < 10**6:
            number *= 10 if elapsed < settings.min_time / 10 else 2
            elapsed = timer.timeit(number)
        numbers.append(number)
    times: list[list[float]] = [[] for _ in fns]
    rounds = max(repeats, default=0)
    for r in range(rounds):
        for k, timer in enumerate(timers):
            if (r + 1) * repeats[k] // rounds > r * repeats[k] // rounds:  # repeats[k] of the rounds, spread
                times[k].append(timer.timeit(numbers[k]) / numbers[k])
    return [
        {"min_us": min(t) * 1e6, "median_us": statistics.median(t) * 1e6, "calls": number}
        for t, number in zip(times, numbers, strict=True)
    ]


def max_relative_difference(a: object, b: object) -> float:
    """max |a − b| / max(1, max |b|) over the arrays of two results (tuples compared element-wise)."""
    if isinstance(a, tuple):
        if not isinstance(b, tuple) or len(b) != len(a):
            return float("inf")
        return max(max_relative_difference(x, y) for x, y in zip(a, b, strict=True))
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape:
        return float("inf")
    return float(np.max(np.abs(a - b), initial=0.0) / max(1.0, float(np.max(np.abs(b), initial=0.0))))


def run_case(case: Case, settings: Settings, peers: list | None = None, peer_atol: float = 1e-9) -> dict:
    """Time one case (kinengine, its Pinocchio floor, then each peer) into one JSON row."""
    row: dict = {"group": case.group, "case": case.name, "n": case.n, "note": case.note, "floor": case.floor}
    result = None if case.kinengine is None else case.kinengine()
    floor: dict[str, object] = {"status": "ok" if case.pinocchio is not None else "none"}
    if case.compare and result is not None and case.pinocchio is not None:
        difference = max_relative_difference(result, case.pinocchio())
        floor["difference"] = difference if math.isfinite(difference) else None
        if not difference <= 1e-9:
            floor["status"] = "disagrees"
    timed = [fn for fn in (case.kinengine, case.pinocchio) if fn is not None]
    timings = iter(measure_interleaved(timed, settings))
    row["kinengine"] = (
        {"status": "skipped"} if case.kinengine is None else {"status": "ok", **_rate(next(timings), case.n)}
    )
    row["pinocchio"] = {**floor, **(_rate(next(timings), case.n) if case.pinocchio is not None else {})}
    if case.targets is not None and result is not None:
        row.update(ik_outcome(case, result))
    if case.kinengine is not None and case.pinocchio is not None:
        row["ratio"] = row["kinengine"]["min_us"] / row["pinocchio"]["min_us"]
    if peers:
        row["peers"] = {
            peer.name: _run_peer(peer, case, result, settings, peer_atol)
            if case.peers
            else {"status": "unsupported"}
            for peer in peers
        }
    return row


def ik_outcome(case: Case, Q: object, robot: Robot | None = None) -> dict[str, float]:
    """How well the solutions Q (n, dof) reach ``case.targets``: ``success`` the fraction within 1e-6 m and
    1e-6 rad (and the limits), and the achieved error max(|Δp| [m], angle [rad]) per target, its median
    ``error_median`` and maximum ``error_max``: rates are compared at the accuracy each library reaches."""
    if robot is None:
        robot = cast(Robot, case.robot)  # IK rows carry their robot
    T = case.targets
    assert T is not None  # IK rows carry their targets
    if (
        isinstance(Q, list) or np.ndim(cast(np.ndarray, Q)) == 3
    ):  # every solution of each target: (k, dof) each, or NaN-padded
        return _solutions_outcome(robot, case.frame, cast(Sequence[np.ndarray], Q), T)
    Q = np.asarray(Q, dtype=float)
    dp, angle, inside = _errors(robot, case.frame, Q, T)
    error = np.maximum(dp, angle)
    return {
        "success": float(np.mean((dp <= 1e-6) & (angle <= 1e-6 + ROUNDING) & inside)),
        "error_median": float(np.median(error)),
        "error_max": float(np.max(error)),
    }


def _errors(robot: Robot, frame: str, Q: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, ...]:
    """|Δp| [m], the rotation angle [rad] between the frame at each row of Q and T, and the limit check.
    The angle θ from |R − R_d|_F = 2√2 sin(θ/2), exact to rounding for small θ (arccos of the trace reads
    at least 2e-8 near the identity)."""
    F = robot.frame_pose(Q, frame)
    dp = np.linalg.norm(F[:, :3, 3] - T[:, :3, 3], axis=1)
    chord = np.linalg.norm(F[:, :3, :3] - T[:, :3, :3], axis=(1, 2)) / (2.0 * np.sqrt(2.0))
    angle = 2.0 * np.arcsin(np.clip(chord, 0.0, 1.0))
    inside = np.all((robot.lower_limits <= Q) & (robot.upper_limits >= Q), axis=1)
    return dp, angle, inside


def _solutions_outcome(
    robot: Robot, frame: str, Q: Sequence[np.ndarray] | np.ndarray, T: np.ndarray
) -> dict[str, float]:
    """:func:`ik_outcome` of every solution of each target: a target is reached when it has one and each
    is within 1e-6 m, 1e-6 rad and the limits; its error is its worst solution's (targets without one are
    not reached and have no error); ``solutions_per_target``: their mean count."""
    rows = [np.asarray(q, dtype=float).reshape(-1, robot.dof) for q in Q]
    rows = [q[~np.isnan(q).any(axis=1)] for q in rows]  # the padding of a batch's answer
    counts = np.array([len(q) for q in rows])
    out = {"success": 0.0, "solutions_per_target": float(counts.mean())}
    if not counts.any():
        return out
    owner = np.repeat(np.arange(len(rows)), counts)
    dp, angle, inside = _errors(robot, frame, np.concatenate(rows), T[owner])
    error, ok = np.maximum(dp, angle), (dp <= 1e-6) & (angle <= 1e-6 + ROUNDING) & inside
    worst = np.full(len(rows), np.nan)
    np.fmax.at(worst, owner, error)
    reached = counts > 0
    np.logical_and.at(reached, owner, ok)
    worst = worst[counts > 0]
    return out | {
        "success": float(reached.mean()),
        "error_median": float(np.median(worst)),
        "error_max": float(np.max(worst)),
    }


def _rate(timing: dict[str, float], n: int) -> dict[str, float]:
    return {**timing, "per_second": n / timing["min_us"] * 1e6}


def _run_peer(peer: Peer, case: Case, expected: object, settings: Settings, atol: float) -> dict:
    """Check the peer's answer against kinengine's, then time it (only if they agree to ``atol``)."""
    try:
        prepared = peer.prepare(case)
        if prepared is None:
            return {"status": "unsupported"}
        if expected is None:
            return {"status": "skipped", "note": "no kinengine result to check the answer against"}
        fn, to_numpy = prepared
        if case.targets is not None:  # IK: each library finds its own solutions; count the reached targets
            outcome = ik_outcome(case, to_numpy(fn()))
            return {"status": "ok", **outcome, **_rate(measure(fn, settings), case.n)}
        got, expected = np.asarray(to_numpy(fn()), dtype=float), np.asarray(expected, dtype=float)
    except Skip as skip:
        return {"status": "skipped", "note": str(skip)}
    except Exception as exc:  # a peer failing on some robot is a result, not a crash
        return {"status": "failed", "note": f"{type(exc).__name__}: {exc}"[:300]}
    if got.shape != expected.shape:
        return {
            "status": "disagrees",
            "difference": None,
            "note": f"shape {got.shape}, expected {expected.shape}",
        }
    difference = float(np.max(np.abs(got - expected)))
    if not difference <= atol:
        return {"status": "disagrees", "difference": difference if math.isfinite(difference) else None}
    return {"status": "ok", "difference": difference, **_rate(measure(fn, settings), case.n)}


def environment(peers: list | None = None) -> dict:
    """Library versions, CPU model, core count and a UTC timestamp."""
    versions: dict[str, str | None] = {}
    for dist in ("kinengine", "pin", "numpy", "scipy"):
        try:
            versions[dist] = importlib.metadata.version(dist)
        except importlib.metadata.PackageNotFoundError:
            versions[dist] = None
    from ... import ACCELERATED, __version__

    versions["kinengine"] = versions["kinengine"] or __version__
    for peer in peers or ():
        versions[peer.distribution] = peer.version
        for dist in RUNTIMES.get(peer.name, ()):
            versions[dist] = importlib.metadata.version(dist)
    return {
        "timestamp": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "cpu": cpu_model(),
        "cores": os.cpu_count(),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "versions": versions,
        "accelerator": ACCELERATED,
    }


def cpu_model() -> str:
    """/proc/cpuinfo's model name, with family, model and clock (a VM may give only "AMD EPYC")."""
    try:
        fields: dict[str, str] = {}
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            key, _, value = line.partition(":")
            fields.setdefault(key.strip(), value.strip())
    except OSError:
        fields = {}
    if "model name" not in fields:
        return platform.processor() or platform.machine()
    details = [f"{key} {fields[key]}" for key in ("cpu family", "model") if key in fields]
    if "cpu MHz" in fields:
        details.append(f"{float(fields['cpu MHz']):.0f} MHz")
    return fields["model name"] + (f" ({', '.join(details)})" if details else "")


def run(
    robots: list[str | Robot],
    settings: Settings,
    peers: bool = False,
    peer_atol: float = 1e-9,
    progress: bool | None = None,
) -> dict:
    """The whole benchmark as a JSON-ready dict: environment, settings and one row per case.

    ``progress``: a tqdm bar on stderr (None: only when stderr is a terminal).
    """
    rotations = list(ROTATION_PARAMETERIZATIONS)
    plans = []
    for name in robots:
        robot = load(name) if isinstance(name, str) else name  # a name, or a Robot loaded by the command
        frame = robot.end_effector
        cases = (
            latency_cases(robot, frame, rotations)
            + throughput_cases(robot, frame, list(settings.sizes))
            + ik_cases(robot, frame, *settings.ik)
        )
        plans.append((robot, frame, load_peers(robot, frame) if peers else None, cases))
    loaded = [peer for *_, robot_peers, _ in plans for peer in robot_peers or () if peer.loaded]
    report = {
        "schema": 1,
        **environment(loaded),
        "robots": [],
        "rows": [],
        "settings": {
            "sizes": list(settings.sizes),
            "repeat": settings.repeat,
            "min_time_s": settings.min_time,
            "peer_atol": peer_atol,
            "ik_peer_tol": RTB_IK_TOL,
        },
    }
    with tqdm(
        total=sum(len(c) for *_, c in plans),
        desc="kinengine bench",
        unit="row",
        leave=False,
        disable=None if progress is None else not progress,
    ) as bar:
        for robot, frame, robot_peers, cases in plans:
            report["robots"].append(
                {
                    "name": robot.name,
                    "dof": robot.dof,
                    "frame": frame,
                    "peers": {p.name: p.status() for p in robot_peers or ()},
                }
            )
            for case in cases:
                bar.set_postfix_str(f"{robot.name} {case.name} N={case.n}", refresh=False)
                row = run_case(case, settings, robot_peers, peer_atol)
                report["rows"].append({"robot": robot.name, **row})
                bar.update()
    return report
