"""kinengine.DifferentialIK against pink (pin-pink) on the same targets, start, stopping rule and tolerance.

For each robot: N random reachable targets T* = T_IF(q*) with q* uniform within the joint limits (seeded).
Both solvers start at the same q0 (robot.neutral()), iterate q <- q + q̇·dt with the same dt, gain 1,
the same Levenberg–Marquardt damping μ (error-scaled: μ‖e‖²) and the QP solver DAQP (through qpsolvers),
with joint position limits and the URDF's velocity limits. Success: ‖p* − p‖ < 1e-6 m and
‖log3(Cᵀ C*)‖ < 1e-6 rad at a q within the joint limits, checked with kinengine's forward kinematics for
both, within --iterations steps. With --restarts R, a run that has not converged after --iterations steps
starts again from a random configuration (the same seeded sequence for both solvers), up to R times.
Throughput: steps per second of the solver calls only (kinengine: ik.solve; pink: configuration.update +
solve_ik + integrate), measured over all steps.

The Panda's finger joint is locked (kinengine: velocity limit 0; pink: removed from a reduced model).

    /work/venv/bin/python benchmarks/compare_qp_ik.py --robots abb_irb120 ur5 panda --targets 1000
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import pinocchio as pin

import kinengine

FRAMES = {"abb_irb120": "tool0", "ur5": "tool0", "panda": "panda_hand_tcp"}
LOCKED = {"panda": ("panda_finger_joint1",)}


def converged(robot, frame, q, T_target, tol_p, tol_r) -> bool:
    T = robot.frame_pose(q, frame)
    if not (np.all(q >= robot.lower_limits - 1e-9) and np.all(q <= robot.upper_limits + 1e-9)):
        return False
    return (
        np.linalg.norm(T_target[:3, 3] - T[:3, 3]) < tol_p
        and np.linalg.norm(pin.log3(T[:3, :3].T @ T_target[:3, :3])) < tol_r
    )


class KinengineRunner:
    name = "kinengine"

    def __init__(self, robot, frame, lm_damping, solver):
        locked = dict.fromkeys(LOCKED.get(robot.name, ()), 0.0)
        self.target = kinengine.PoseTarget(frame, np.eye(4))
        self.ik = kinengine.DifferentialIK(
            robot, [self.target], lm_damping=lm_damping, velocity_limits=locked or None, solver=solver
        )

    def set_target(self, T):
        self.target.T_target = T

    def step(self, q, dt):
        return q + self.ik.solve(q, dt) * dt


class PinkRunner:
    name = "pink"

    def __init__(self, robot, frame, lm_damping, solver):
        import pink
        from pink.tasks import FrameTask

        self.pink, self.solver = pink, solver
        model = robot.pinocchio_model()
        locked = LOCKED.get(robot.name, ())
        self.keep = np.array([i for i, n in enumerate(robot.joint_names) if n not in locked])
        if locked:  # remove the fingers (and their mimic) from pink's model
            ids = [model.getJointId(n) for n in model.names[1:] if "finger" in n]
            model = pin.buildReducedModel(model, ids, robot.pinocchio_configuration(robot.neutral()))
        self.model, self.data = model, model.createData()
        self.task = FrameTask(frame, position_cost=1.0, orientation_cost=1.0, lm_damping=lm_damping, gain=1.0)
        self.full = None

    def set_target(self, T):
        self.task.set_target(pin.SE3(T[:3, :3], T[:3, 3]))

    def step(self, q, dt):
        conf = self.pink.Configuration(self.model, self.data, q[self.keep])
        v = self.pink.solve_ik(conf, [self.task], dt, solver=self.solver, damping=1e-12, safety_break=False)
        out = q.copy()
        out[self.keep] = conf.integrate(v, dt)
        return out


def run(robot, runners, targets, starts, dt, iterations, tol_p, tol_r):
    """Per target, each runner in turn (so load changes on a shared machine hit both alike).
    Returns per runner (successes, steps per second, median steps of the successful attempt)."""
    frame = FRAMES[robot.name]
    stats = {r.name: [0, 0, 0.0, []] for r in runners}  # successes, steps, seconds, steps used
    for T, restarts in zip(targets, starts, strict=False):
        for runner in runners:
            st = stats[runner.name]
            runner.set_target(T)
            done = False
            for q0 in [robot.neutral()] + list(restarts):
                q = q0.copy()
                for it in range(iterations):
                    if converged(robot, frame, q, T, tol_p, tol_r):
                        done = True
                        st[3].append(it)
                        break
                    t0 = time.perf_counter()
                    q = runner.step(q, dt)
                    st[2] += time.perf_counter() - t0
                    st[1] += 1
                if done:
                    break
            st[0] += done
    return {
        name: (ok, steps / seconds, float(np.median(used)) if used else float("nan"))
        for name, (ok, steps, seconds, used) in stats.items()
    }


def main(argv=None):
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--robots", nargs="+", default=["abb_irb120", "ur5", "panda"])
    parser.add_argument("--targets", type=int, default=1000)
    parser.add_argument("--iterations", type=int, default=100)
    parser.add_argument("--restarts", type=int, default=0)
    parser.add_argument("--dt", type=float, default=0.1)
    parser.add_argument("--lm-damping", type=float, default=1e-3)
    parser.add_argument("--solver", default="daqp")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--only", choices=["kinengine", "pink"], default=None)
    args = parser.parse_args(argv)
    print(
        f"targets {args.targets}, dt {args.dt} s, {args.iterations} steps per attempt, "
        f"restarts {args.restarts}, "
        f"lm_damping {args.lm_damping}, solver {args.solver}, tolerance 1e-6 m / 1e-6 rad"
    )
    for name in args.robots:
        robot = kinengine.load(name)
        rng = np.random.default_rng(args.seed)
        frame = FRAMES[name]
        Q = robot.random_configuration(rng, size=args.targets)
        for j in LOCKED.get(name, ()):
            Q[:, robot.joint_names.index(j)] = robot.neutral()[robot.joint_names.index(j)]
        targets = robot.frame_pose(Q, frame)
        starts = [robot.random_configuration(rng, size=args.restarts) if args.restarts else [] for _ in Q]
        for j in LOCKED.get(name, ()):
            for s in starts:
                if len(s):
                    s[:, robot.joint_names.index(j)] = robot.neutral()[robot.joint_names.index(j)]
        runners = [
            cls(robot, frame, args.lm_damping, args.solver)
            for cls in (KinengineRunner, PinkRunner)
            if not args.only or cls.name == args.only
        ]
        results = run(robot, runners, targets, starts, args.dt, args.iterations, 1e-6, 1e-6)
        for runner_name, (ok, rate, median) in results.items():
            print(
                f"{name:12s} {runner_name:10s} success {ok}/{args.targets} = "
                f"{100 * ok / args.targets:5.1f} %  "
                f"{rate:8.0f} steps/s  median steps to converge {median:g}",
                flush=True,
            )


if __name__ == "__main__":
    main()
