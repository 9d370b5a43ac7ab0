"""The controller loop of issue 30, timed against the inline code a user would write.

1. J̇ per call: ``robot.jacobian_time_variation(q, q̇, frame)`` against raw Pinocchio's
   ``computeJointJacobiansTimeVariation`` + ``getFrameJacobianTimeVariation`` (LOCAL_WORLD_ALIGNED) on the
   same q, q̇, interleaved in one process (best of --rounds rounds of --calls calls each).
2. The ABB IRB 120 circle (5 cm radius, 0.1 m/s, orientation held) at 1 kHz with gain 0.05 for --steps steps:
   kinengine's DifferentialIK with the target's twist as feed-forward, and the same loop (set target, solve,
   integrate) on pink and on mink (if installed; their frame tasks take no feed-forward, so they lag by
   |v| dt / k). All three: frame link_6, position and orientation cost 1 (weight 1), DAQP, damping 1e-12,
   no Levenberg-Marquardt term, joint position and URDF velocity limits. mink runs on the URDF loaded by
   MuJoCo (visual and collision elements removed). Steps per second count solve + integrate only; rounds
   interleave the three loops; the best round is reported. Tracking error: |p_d(t_k+1) − p(q_k+1)| after 1 s.
3. With ``--versus CHECKOUT [CHECKOUT ...]``: the cost of a plain single-level step (no twist, no
   acceleration limits, ``limits="clip"``) against other kinengine checkouts, as ratios to the first one
   (e.g. ``git worktree add --detach /tmp/old <commit>``, its C extensions copied in or built). Two packages
   of one name cannot share a process, so subprocesses alternate (this tree, then each CHECKOUT, --rounds
   times), each running on the ABB IRB 120 (tool0) and the Panda (panda_hand_tcp) a static PoseTarget plus
   a PostureTarget (weight 1e-3), DAQP, --steps steps from the same start, three times; each process reports
   its best µs/step (solve only). Printed: the medians, the spreads (min–max), the per-round ratios and the
   ratio of the minima, with the load average.

    python benchmarks/controller_loop.py --rounds 5
    python benchmarks/controller_loop.py --versus /tmp/old /tmp/older --rounds 9 --steps 2000
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import time

import numpy as np
import pinocchio as pin

import kinengine

DT, GAIN, FRAME = 1e-3, 0.05, "link_6"
Q0 = np.array([0.0, 0.2, 0.1, 0.0, 0.8, 0.0])


def circle(T0: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
    T = T0.copy()
    T[1, 3] += 0.05 * np.sin(2.0 * t)
    T[2, 3] += 0.05 * (np.cos(2.0 * t) - 1.0)
    twist = np.zeros(6)
    twist[1], twist[2] = 0.1 * np.cos(2.0 * t), -0.1 * np.sin(2.0 * t)
    return T, twist


def _jdot_pair(name: str, frame: str, calls: int) -> tuple:
    """(raw, ours): two functions making ``calls`` J̇ evaluations each on the same q, q̇."""
    robot = kinengine.load(name)
    rng = np.random.default_rng(0)
    q, v = robot.random_configuration(rng), rng.normal(size=robot.dof)
    model = robot.engine.model
    data = model.createData()
    fid = robot.frame_id(frame)
    jjtv, fjtv, lwa = (
        pin.computeJointJacobiansTimeVariation,
        pin.getFrameJacobianTimeVariation,
        pin.LOCAL_WORLD_ALIGNED,
    )

    def raw() -> None:
        for _ in range(calls):
            jjtv(model, data, q, v)
            fjtv(model, data, fid, lwa)

    def ours() -> None:
        for _ in range(calls):
            robot.jacobian_time_variation(q, v, frame)

    return raw, ours


def jdot_ratios(rounds: int, calls: int) -> None:
    for name, frame in (("abb_irb120", "tool0"), ("panda_arm", "panda_hand_tcp")):
        raw, ours = _jdot_pair(name, frame, calls)
        best = {raw: np.inf, ours: np.inf}
        for _ in range(rounds):
            for f in (raw, ours):
                t0 = time.perf_counter()
                f()
                best[f] = min(best[f], (time.perf_counter() - t0) / calls)
        print(
            f"J̇ {name}/{frame}: raw Pinocchio {best[raw] * 1e6:.2f} µs, kinengine {best[ours] * 1e6:.2f} µs, "
            f"ratio {best[ours] / best[raw]:.2f}"
        )


class Kinengine:
    name = "kinengine (feed-forward)"

    def __init__(self, robot: kinengine.Robot, T0: np.ndarray) -> None:
        self.target = kinengine.PoseTarget(FRAME, T0, gain=GAIN)
        self.ik = kinengine.DifferentialIK(robot, [self.target], lm_damping=0.0)

    def step(self, q: np.ndarray, T: np.ndarray, twist: np.ndarray) -> np.ndarray:
        self.target.T_target, self.target.twist = T, twist
        return q + self.ik.solve(q, DT) * DT


class Pink:
    name = "pink"

    def __init__(self, robot: kinengine.Robot, T0: np.ndarray) -> None:
        import pink
        from pink.tasks import FrameTask

        self.pink = pink
        self.model = robot.pinocchio_model()
        self.task = FrameTask(FRAME, position_cost=1.0, orientation_cost=1.0, gain=GAIN)
        self.configuration = pink.Configuration(self.model, self.model.createData(), Q0.copy())

    def step(self, q: np.ndarray, T: np.ndarray, twist: np.ndarray) -> np.ndarray:
        self.task.set_target(pin.SE3(T[:3, :3], T[:3, 3]))
        self.configuration.update(q)
        v = self.pink.solve_ik(self.configuration, [self.task], DT, solver="daqp")
        return q + v * DT


class Mink:
    name = "mink"

    def __init__(self, robot: kinengine.Robot, T0: np.ndarray) -> None:
        import mink
        import mujoco

        text = re.sub(r"<(visual|collision)>.*?</\1>", "", robot.urdf_text, flags=re.S)
        self.mink, self.mj = mink, mujoco.MjModel.from_xml_string(text)
        self.configuration = mink.Configuration(self.mj, Q0.copy())
        self.task = mink.FrameTask(FRAME, "body", position_cost=1.0, orientation_cost=1.0, gain=GAIN)
        velocities = dict(zip(robot.joint_names, robot.velocity_limits, strict=True))
        self.limits = [mink.ConfigurationLimit(self.mj), mink.VelocityLimit(self.mj, velocities)]

    def step(self, q: np.ndarray, T: np.ndarray, twist: np.ndarray) -> np.ndarray:
        self.task.set_target(
            self.mink.SE3.from_rotation_and_translation(self.mink.SO3.from_matrix(T[:3, :3]), T[:3, 3])
        )
        self.configuration.update(q)
        v = self.mink.solve_ik(self.configuration, [self.task], DT, solver="daqp", limits=self.limits)
        return q + v * DT


def loops(rounds: int, steps: int) -> None:
    robot = kinengine.load("abb_irb120")
    T0 = robot.frame_pose(Q0, FRAME)
    targets = [circle(T0, k * DT) for k in range(steps + 1)]
    runners = []
    for cls in (Kinengine, Pink, Mink):
        try:
            runners.append(cls(robot, T0))
        except ImportError as error:
            print(f"{cls.name}: not installed ({error})")
    best = {r.name: np.inf for r in runners}
    errors = {}
    for _ in range(rounds):
        for runner in runners:
            q, elapsed, err = Q0.copy(), 0.0, []
            for k in range(steps):
                T, twist = targets[k]
                t0 = time.perf_counter()
                q = runner.step(q, T, twist)
                elapsed += time.perf_counter() - t0
                err.append(np.linalg.norm(robot.frame_pose(q, FRAME)[:3, 3] - targets[k + 1][0][:3, 3]))
            best[runner.name] = min(best[runner.name], elapsed / steps)
            errors[runner.name] = max(err[round(1.0 / DT) :])
    for name in best:
        print(
            f"{name:26s} {1 / best[name]:8,.0f} steps/s  ({best[name] * 1e6:.1f} µs/step), "
            f"tracking error after 1 s: {errors[name]:.2e} m"
        )


VERSUS_CASES = (("abb_irb120", "tool0"), ("panda_arm", "panda_hand_tcp"))


def plain_steps(steps: int, repeats: int = 3) -> dict[str, float]:
    """{robot: best µs per solve}: a static PoseTarget plus a PostureTarget, one level, DAQP, clip."""
    out = {}
    for name, frame in VERSUS_CASES:
        robot = kinengine.load(name)
        q0 = np.clip(robot.neutral(), robot.lower_limits + 0.2, robot.upper_limits - 0.2)
        T_goal = robot.frame_pose(np.clip(q0 + 0.3, robot.lower_limits, robot.upper_limits), frame)
        best = np.inf
        for _ in range(repeats):
            ik = kinengine.DifferentialIK(
                robot, [kinengine.PoseTarget(frame, T_goal), kinengine.PostureTarget(q0.copy(), weight=1e-3)]
            )
            q, elapsed, solve = q0.copy(), 0.0, ik.solve
            for _ in range(steps):
                t0 = time.perf_counter()
                qdot = solve(q, DT)
                elapsed += time.perf_counter() - t0
                q = q + qdot * DT
            best = min(best, elapsed / steps)
        out[name] = best * 1e6
    return out


def versus(checkouts: list[str], rounds: int, steps: int) -> None:
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    trees = {"this tree": here} | {os.path.abspath(c): os.path.abspath(c) for c in checkouts}
    times: dict[str, dict[str, list[float]]] = {t: {n: [] for n, _ in VERSUS_CASES} for t in trees}
    print(f"load average before: {os.getloadavg()}")
    for _ in range(rounds):
        for tree, path in trees.items():
            env = dict(os.environ, PYTHONPATH=path)
            got = subprocess.run(
                [sys.executable, os.path.abspath(__file__), "--worker", "--steps", str(steps)],
                env=env,
                cwd="/",
                capture_output=True,
                text=True,
                check=True,
            )
            result = json.loads(got.stdout.strip().splitlines()[-1])
            if not result["file"].startswith(path):
                raise SystemExit(f"{tree}: imported kinengine from {result['file']}, not {path}")
            for name, _ in VERSUS_CASES:
                times[tree][name].append(result["us"][name])
    print(f"load average after: {os.getloadavg()}")
    base = os.path.abspath(checkouts[0])
    for name, _ in VERSUS_CASES:
        b = np.array(times[base][name])
        for tree in trees:
            a = np.array(times[tree][name])
            ratios = a / b
            print(
                f"{name} {tree}: median {np.median(a):.1f} µs/step (min {a.min():.1f}, max {a.max():.1f})"
                + (
                    ""
                    if tree == base
                    else f"; / {base}: median of the rounds' ratios {np.median(ratios):.3f}, ratio of "
                    f"the minima {a.min() / b.min():.3f} (rounds: {', '.join(f'{r:.2f}' for r in ratios)})"
                )
            )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--calls", type=int, default=20000)
    parser.add_argument("--steps", type=int, default=3000)
    parser.add_argument(
        "--versus", nargs="+", metavar="CHECKOUT", help="time a plain step against other checkouts"
    )
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        print(json.dumps({"file": kinengine.__file__, "us": plain_steps(args.steps)}))
        return 0
    if args.versus:
        versus(args.versus, args.rounds, args.steps)
        return 0
    jdot_ratios(args.rounds, args.calls)
    loops(args.rounds, args.steps)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
