"""Single-target IK throughput: ``robot.inverse_kinematics(T)`` one (4, 4) target per call, tolerance
1e-6 m / 1e-6 rad, on 1,000 random reachable targets (the frame poses of
``robot.random_configuration(rng, 1000)``), per robot: solves/s, success and mean iterations; and the
same for pink (pin-pink, a QP-based differential IK stepped to convergence) when it is importable.

    python benchmarks/ik_single.py [ROBOT ...]        # default: abb_irb120 ur5 panda_arm
    python benchmarks/ik_single.py --rounds 5 ur5     # best of 5 rounds (default 3)
    python benchmarks/ik_single.py --no-pink          # kinengine only

solves/s is the best of the rounds (a busy neighbour on the shared machine only slows a round, so the
fastest one is the least disturbed), by the wall clock and by this process's CPU time (which a neighbour
on another core does not inflate); every round solves the same targets with the same ``rng=i``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import kinengine

ROBOTS = ("abb_irb120", "ur5", "panda_arm")
TARGETS = 1000


def targets(robot: kinengine.Robot, n: int = TARGETS, seed: int = 2024) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return robot.frame_pose(robot.random_configuration(rng, size=n), robot.end_effector)


def kinengine_round(robot: kinengine.Robot, Ts: np.ndarray) -> tuple[float, float, int, float]:
    """(wall seconds, CPU seconds, successes, mean iterations) of one pass over Ts."""
    solve = robot.inverse_kinematics
    start, cpu = time.perf_counter(), time.process_time()
    results = [solve(T, rng=i, method="numeric") for i, T in enumerate(Ts)]
    elapsed, cpu = time.perf_counter() - start, time.process_time() - cpu
    return elapsed, cpu, sum(r.success for r in results), float(np.mean([r.iterations for r in results]))


def pink_round(robot: kinengine.Robot, Ts: np.ndarray, max_steps: int = 200) -> tuple[float, int, float]:
    """pink's differential IK (QP per step, ``solve_ik`` + integrate) from the middle of the ranges until
    the pose error is below 1e-6 m / 1e-6 rad or ``max_steps`` (one seed, no restarts)."""
    import pink
    import pinocchio as pin
    from pink.tasks import FrameTask

    model = robot.engine.model
    data = model.createData()
    frame = robot.end_effector
    lower, upper = model.lowerPositionLimit, model.upperPositionLimit
    middle = (lower + upper) / 2
    task = FrameTask(frame, position_cost=1.0, orientation_cost=1.0)
    dt = 1.0
    ok, iterations = 0, []
    start = time.perf_counter()
    for T in Ts:
        target = pin.SE3(T[:3, :3].copy(), T[:3, 3].copy())
        configuration = pink.Configuration(model, data, middle.copy())
        task.set_target(target)
        done, step = False, 0
        while step < max_steps:
            M = configuration.get_transform_frame_to_world(frame)
            ep = float(np.linalg.norm(T[:3, 3] - M.translation))
            er = float(np.linalg.norm(pin.log3(T[:3, :3] @ M.rotation.T)))
            if ep <= 1e-6 and er <= 1e-6:
                done = True
                break
            try:
                v = pink.solve_ik(configuration, [task], dt, solver="daqp", damping=1e-12)
            except pink.exceptions.PinkError:  # e.g. NoSolutionFound: this target fails
                break
            configuration.integrate_inplace(v, dt)
            step += 1
        ok += done
        iterations.append(step)
    elapsed = time.perf_counter() - start
    return elapsed, ok, float(np.mean(iterations))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("robots", nargs="*", default=list(ROBOTS))
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--no-pink", action="store_true")
    args = parser.parse_args()
    for name in args.robots:
        robot = kinengine.load(name)
        Ts = targets(robot)
        robot.inverse_kinematics(Ts[0], method="numeric")  # build the seed table outside the timing
        runs = [kinengine_round(robot, Ts) for _ in range(args.rounds)]
        elapsed, cpu = min(r[0] for r in runs), min(r[1] for r in runs)
        _, _, ok, iterations = runs[0]
        print(
            f"{name:12s} kinengine: {len(Ts) / elapsed:7.0f} solves/s ({len(Ts) / cpu:.0f}/s by CPU time)  "
            f"success {ok}/{len(Ts)}  mean iterations {iterations:.2f}"
        )
        if args.no_pink:
            continue
        try:
            import pink  # noqa: F401
        except ImportError:
            print(f"{name:12s} pink: not importable")
            continue
        sub = Ts[:100]
        try:
            elapsed, ok, iterations = pink_round(robot, sub)
        except Exception as error:  # pink's solver set-up varies by version: report, don't fail
            print(f"{name:12s} pink: failed ({type(error).__name__}: {error})")
            continue
        print(
            f"{name:12s} pink:      {len(sub) / elapsed:7.0f} solves/s  success {ok}/{len(sub)}  "
            f"mean iterations {iterations:.1f}  (first {len(sub)} targets, from the middle of the ranges)"
        )


if __name__ == "__main__":
    main()
