"""Batch throughput of ``robot.kinematics(Q, frame)`` (T (N, 4, 4) and J (N, 6, dof) in one call) against the
raw-Pinocchio loop a user would write, in one process.

    python benchmarks/batch_throughput.py [ROBOT ...]      # default: abb_irb120 ur5 panda kinova
    python benchmarks/batch_throughput.py --quick ur5      # fewer repeats

Per robot and N = 1k, 10k, 100k, 1M: configs/s (best of a few calls, the three kinds in turn; a busy
neighbour on the shared machine only slows a call, so the best one is the least disturbed) for
``robot.kinematics(Q, frame)`` (its outputs in the block of the dropped result of the call before,
kinengine/kinematics/outputs.py), the same call in new memory ("new": the kept blocks released before
each call, as a first call pays) and with ``out=(T, J)`` preallocated, the minor page faults of one call
(``ru_minflt`` delta) and its peak extra memory beyond the outputs (``tracemalloc``: numpy reports its
allocations to it), fresh and with ``out=``, after a first call; "scratch" is what the threads keep
between calls (workers x MiB each, allocated by the first call of that size and reused; none when the
C chain runs: it writes only the outputs). The floor is
the inline Pinocchio loop

    for i, q in enumerate(Q):
        pin.forwardKinematics(model, data, q)
        J[i] = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
        T[i] = pin.updateFramePlacement(model, data, fid).homogeneous

timed on 10k rows (its rate does not depend on N); "x floor" is configs/s over the floor's.
"""

from __future__ import annotations

import gc
import math
import resource
import sys
import time
import tracemalloc

import numpy as np
import pinocchio as pin

import kinengine
from kinengine.kinematics import batch

try:
    from kinengine.kinematics.outputs import release
except ImportError:  # an older kinengine: every output is new memory
    release = None  # type: ignore[assignment]

try:
    from kinengine.kinematics.chain import scratch_rows
except ImportError:  # an older kinengine: no scratch column
    scratch_rows = None  # type: ignore[assignment]

ROBOTS = ("abb_irb120", "ur5", "panda", "kinova")
SIZES = (1_000, 10_000, 100_000, 1_000_000)


def _best(fn, repeats: int, budget: float = 3.0) -> float:
    """The shortest of ``repeats`` timed calls (stops early after ``budget`` seconds)."""
    best, spent = float("inf"), 0.0
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        took = time.perf_counter() - start
        best, spent = min(best, took), spent + took
        if spent > budget:
            break
    return best


def _best_interleaved(fns: list, repeats: int, budget: float = 6.0) -> list[float]:
    """The shortest of ``repeats`` timed calls of each fn, the fns called in turn (a slow phase of the shared
    machine slows them alike; stops early after ``budget`` seconds)."""
    best, spent = [float("inf")] * len(fns), 0.0
    for _ in range(repeats):
        for k, fn in enumerate(fns):
            start = time.perf_counter()
            fn()
            took = time.perf_counter() - start
            best[k], spent = min(best[k], took), spent + took
        if spent > budget:
            break
    return best


def floor_rate(robot: kinengine.Robot, Q: np.ndarray) -> float:
    """configs/s of the inline Pinocchio loop over Q on ``robot.pinocchio_model()`` (one plain joint per
    movable URDF joint; Q mapped to its coordinates once, outside the timing: the identity without mimics)."""
    model = robot.pinocchio_model()
    data = model.createData()
    fid = robot.frame_id(robot.end_effector)
    Qp = np.array([robot.pinocchio_configuration(q) for q in Q])
    T = np.empty((len(Q), 4, 4))
    J = np.empty((len(Q), 6, model.nv))
    lwa = pin.LOCAL_WORLD_ALIGNED

    def loop() -> None:
        for i, q in enumerate(Qp):
            pin.forwardKinematics(model, data, q)
            J[i] = pin.computeFrameJacobian(model, data, q, fid, lwa)
            T[i] = pin.updateFramePlacement(model, data, fid).homogeneous

    return len(Q) / _best(loop, 3)


def faults_and_memory(fn) -> tuple[int, float]:
    """(minor page faults of one call, peak memory [MiB] it allocates beyond what it returns)."""
    gc.collect()
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    result = fn()
    faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before
    del result
    gc.collect()
    tracemalloc.start()
    result = fn()
    kept, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    del result
    return faults, (peak - kept) / 2**20


def _c_chain() -> bool:
    """Whether batches run on the C chain (kinengine.kinematics.chainkernel)."""
    try:
        from kinengine.kinematics import compiler
    except ImportError:  # an older kinengine
        return False
    return compiler.KERNEL is not None


def _scratch(robot: kinengine.Robot, n: int) -> str:
    """The threads' reused scratch [MiB] for a batch of n (kept between calls; not in "extra")."""
    if _c_chain():
        return "none"
    if not hasattr(batch, "chunk_rows"):
        return "?"
    c = batch.compiled_chain(robot.engine, robot.frame_id(robot.end_effector))
    workers = max(1, min(batch.WORKERS, n // batch.MIN_PER_WORKER))
    rows = batch.chunk_rows(c, n, workers, True, True, None, pin.LOCAL_WORLD_ALIGNED)
    per = n / (workers * rows)  # as batch.run_chain splits
    pieces = workers * max(1, math.ceil(per) if batch.MIN_CHUNK < rows < batch.CHUNK else round(per))
    per_thread = -(-n // pieces) * 8 * scratch_rows(c, True, True)
    return f"{workers}x{per_thread / 2**20:.2f}"


def run(name: str, repeats: int) -> None:
    robot = kinengine.load(name)
    frame = robot.end_effector
    rng = np.random.default_rng(0)
    Q_all = robot.random_configuration(rng, size=max(SIZES))
    floor = floor_rate(robot, Q_all[:10_000])
    print(
        f"\n{name} ({robot.dof} dof, frame {frame!r}); workers {batch.WORKERS}; "
        f"chain {'C' if _c_chain() else 'numpy'}; "
        f"Pinocchio loop floor {floor / 1e6:.3f} M configs/s"
    )
    print(
        f"{'N':>9} {'M/s':>7} {'x floor':>7} {'M/s new':>8} {'M/s out=':>9} {'x floor':>7} "
        f"{'faults':>7} {'faults out=':>11} {'extra MiB':>9} {'(out=)':>9} {'out MiB':>8} {'scratch':>10}"
    )
    for n in SIZES:
        Q = np.ascontiguousarray(Q_all[:n])
        out = (np.empty((n, 4, 4)), np.empty((n, 6, robot.dof)))
        robot.kinematics(Q, frame, out=out)  # warm: pool threads, per-thread buffers, the compiled chain
        reps = repeats if n < 1_000_000 else max(2, repeats // 3)
        fresh, new, into = (
            n / t
            for t in _best_interleaved(
                [
                    lambda Q=Q: robot.kinematics(Q, frame),
                    lambda Q=Q: (release and release(), robot.kinematics(Q, frame)),
                    lambda Q=Q, out=out: robot.kinematics(Q, frame, out=out),
                ],
                reps,
            )
        )
        faults, extra = faults_and_memory(lambda Q=Q: robot.kinematics(Q, frame))
        faults_out, extra_out = faults_and_memory(lambda Q=Q, out=out: robot.kinematics(Q, frame, out=out))
        out_mib = (out[0].nbytes + out[1].nbytes) / 2**20
        print(
            f"{n:>9} {fresh / 1e6:7.3f} {fresh / floor:7.2f} {new / 1e6:8.3f} "
            f"{into / 1e6:9.3f} {into / floor:7.2f} "
            f"{faults:>7} {faults_out:>11} {extra:9.2f} {extra_out:9.2f} {out_mib:8.1f} "
            f"{_scratch(robot, n):>10}"
        )
        del out


def main(argv: list[str]) -> None:
    quick = "--quick" in argv
    names = [a for a in argv if not a.startswith("--")] or list(ROBOTS)
    print(f"python {sys.version.split()[0]}, numpy {np.__version__}, pinocchio {pin.__version__}")
    for name in names:
        run(name, 3 if quick else 7)


if __name__ == "__main__":
    main(sys.argv[1:])
