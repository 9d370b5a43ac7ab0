"""Two-frame tracking through a ZYX gimbal lock and a wrist singularity, without an exception.

The ABB IRB 120 follows a reference that passes through its home pose q = 0 halfway: there tool0's x axis
is vertical (ZYX Euler angles at gimbal lock, cos χ2 = 0) and q5 = 0 (the wrist is singular: J_e0 has
rank 5). The task stack has two frames:

* tool0: position (cartesian) and orientation (Euler angles; ZYX at the start), weight 1;
* link_4: position (cartesian), weight 0.3 (the forearm follows its own reference).

Each control step (500 Hz, explicit Euler):

1. ``task.update(q)`` fills χ, J_A = E(χ)·J_e0 for both frames (``on_singularity="nan"``: a singular
   parameterization would give NaN rows, never an exception);
2. if ``task.singularity_distances`` says the tool's Euler angles come closer than 0.3 to their singular
   set (|cos χ2| for ZYX, |sin χ2| for ZYZ), the task switches to the other sequence (ZYX ↔ ZYZ) before it
   gets there; rows that are NaN anyway (never here) are left out of the step;
3. commanded rates: χ̇_cmd = [ṗ_d + K e_p; E_R(χ)(ω_d + K e_R); ṗ4_d + K e_4] with e_R = log3(C_d C_ᵀ) (in I);
4. a QP step (DAQP through qpsolvers): min ‖J_A q̇ − χ̇_cmd‖²_W + λ‖q̇‖² subject to the URDF's joint velocity
   limits and the joint position limits over the step; the damping λ keeps q̇ bounded where J_A loses
   rank (the wrist singularity).

It saves a PNG of the tracking errors and of the two singularity measures over time.

    python examples/two_frame_tracking.py --output docs/images/two_frame_tracking.png
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
import qpsolvers

import kinengine
from kinengine import FrameTask
from kinengine.parameterizations import get_rotation

Q_A = np.array([-0.6, 0.35, -0.25, 0.5, -0.45, 0.3])  # [rad]; the reference runs from Q_A to −Q_A through 0
OTHER = {"euler_zyx": "euler_zyz", "euler_zyz": "euler_zyx"}


@dataclass(frozen=True)
class Run:
    """Times t (n,) [s]; errors (n,): tool0 position [m], tool0 rotation [rad], link_4 position [m];
    zyx_distance (n,) |cos χ2| of tool0's ZYX angles; sigma_min (n,) smallest singular value of tool0's
    J_e0; rotation (n,) the parameterization in use; switches: times of a switch [s]."""

    t: np.ndarray
    position_error: np.ndarray
    rotation_error: np.ndarray
    link4_error: np.ndarray
    zyx_distance: np.ndarray
    sigma_min: np.ndarray
    rotation: tuple[str, ...]
    switches: tuple[float, ...]


def reference(t: float, duration: float) -> tuple[np.ndarray, np.ndarray]:
    """q_d(t) [rad] and q̇_d(t) [rad/s]: Q_A → −Q_A with a cosine profile, through q = 0 at t = duration/2."""
    s = 0.5 - 0.5 * np.cos(np.pi * t / duration)  # 0 → 1
    ds = 0.5 * np.pi / duration * np.sin(np.pi * t / duration)
    return Q_A * (1 - 2 * s), -2 * Q_A * ds


def make_task(robot: kinengine.Robot, rotation: str) -> kinengine.Task:
    return robot.task(
        [FrameTask("tool0", rotation=rotation, weight=1.0), FrameTask("link_4", rotation=None, weight=0.3)],
        on_singularity="nan",
    )


def simulate(
    duration: float = 4.0,
    dt: float = 2e-3,
    gain: float = 20.0,
    damping: float = 1e-4,
    switch_below: float = 0.3,
) -> Run:
    robot = kinengine.load("abb_irb120")
    rotation = "euler_zyx"
    task = make_task(robot, rotation)
    vmax = np.array([j.velocity for j in robot.description.joints if j.name in robot.joint_names])
    lower, upper = robot.lower_limits, robot.upper_limits
    q = reference(0.0, duration)[0].copy()
    n = round(duration / dt) + 1
    out = {k: np.empty(n) for k in ("position", "rotation", "link4", "zyx", "sigma")}
    used, switches = [], []
    zyx = get_rotation("euler_zyx")
    for k in range(n):
        t = k * dt
        q_d, qdot_d = reference(t, duration)
        T_d, J_d = robot.kinematics(q_d, "tool0")
        T4_d, J4_d = robot.kinematics(q_d, "link_4")
        twist_d, v4_d = J_d @ qdot_d, (J4_d @ qdot_d)[:3]
        task.update(q)
        if task.singularity_distances[1] < switch_below:  # tool0's rotation: switch before the singular set
            rotation = OTHER[rotation]
            switches.append(t)
            task = make_task(robot, rotation)
            task.update(q)
        T, T4 = task.pose[0], task.pose[1]
        e_p = T_d[:3, 3] - T[:3, 3]
        e_R = pin.log3(T_d[:3, :3] @ T[:3, :3].T)  # rotation error in I [rad]
        e_4 = T4_d[:3, 3] - T4[:3, 3]
        E_R = get_rotation(rotation).E(task.chi[3:6])
        chi_dot = np.concatenate(
            [twist_d[:3] + gain * e_p, E_R @ (twist_d[3:] + gain * e_R), v4_d + gain * e_4]
        )
        JA = task.analytic_jacobian
        ok = np.isfinite(JA).all(axis=1)  # NaN rows (a singular parameterization): left out
        W = task.weights * ok
        A = np.where(ok[:, None], JA, 0.0)
        b = np.where(ok, chi_dot, 0.0)
        H = A.T @ (W[:, None] * A) + damping * np.eye(robot.dof)
        c = -A.T @ (W * b)
        lb = np.maximum(-vmax, (lower - q) / dt)
        ub = np.minimum(vmax, (upper - q) / dt)
        qdot = qpsolvers.solve_qp(H, c, lb=lb, ub=ub, solver="daqp")
        q = q + dt * qdot
        out["position"][k], out["rotation"][k], out["link4"][k] = (
            np.linalg.norm(e_p),
            np.linalg.norm(e_R),
            np.linalg.norm(e_4),
        )
        out["zyx"][k] = zyx.singularity_distance(zyx.from_rotation(T[:3, :3], warn=False))
        out["sigma"][k] = np.linalg.svd(task.jacobian[:6], compute_uv=False)[-1]
        used.append(rotation)
    return Run(
        np.arange(n) * dt,
        out["position"],
        out["rotation"],
        out["link4"],
        out["zyx"],
        out["sigma"],
        tuple(used),
        tuple(switches),
    )


def plot(run: Run, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    top.semilogy(run.t, np.maximum(run.position_error, 1e-12), label="tool0 position error [m]")
    top.semilogy(run.t, np.maximum(run.rotation_error, 1e-12), label="tool0 rotation error [rad]")
    top.semilogy(run.t, np.maximum(run.link4_error, 1e-12), label="link_4 position error [m]")
    top.set_ylabel("tracking error")
    top.legend(loc="upper right", fontsize=8)
    bottom.plot(run.t, run.zyx_distance, label="|cos χ2| of tool0's ZYX angles (0: gimbal lock)")
    bottom.plot(run.t, run.sigma_min, label="smallest singular value of J_e0 (0: wrist singular)")
    for i, s in enumerate(run.switches):
        for ax in (top, bottom):
            ax.axvline(
                s,
                color="gray",
                ls=":",
                lw=1,
                label="parameterization switch" if i == 0 and ax is bottom else None,
            )
    bottom.set_xlabel("t [s]")
    bottom.legend(loc="upper right", fontsize=8)
    top.set_title(
        "ABB IRB 120: two-frame task stack through q = 0 (ZYX gimbal lock and wrist singularity)", fontsize=9
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> Run:
    parser = argparse.ArgumentParser(
        description="Two-frame tracking through singularities (see the module doc)."
    )
    parser.add_argument("--duration", type=float, default=4.0, help="seconds (the singularity is at half)")
    parser.add_argument("--output", default="two_frame_tracking.png", help="PNG path")
    args = parser.parse_args(argv)
    run = simulate(args.duration)
    plot(run, args.output)
    print(
        f"max tool0 position error {run.position_error.max():.2e} m, rotation error "
        f"{run.rotation_error.max():.2e} rad, link_4 error {run.link4_error.max():.2e} m; "
        f"min |cos χ2| {run.zyx_distance.min():.1e}, min σ {run.sigma_min.min():.1e}; "
        f"switches at {', '.join(f'{s:.3f}' for s in run.switches)} s; saved {args.output}"
    )
    return run


if __name__ == "__main__":
    main()
