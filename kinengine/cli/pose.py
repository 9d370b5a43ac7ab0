"""``kinengine pose ROBOT``: frame pose, geometric Jacobian and (optionally) χ and J_A at a configuration."""

from __future__ import annotations

import argparse

import numpy as np

from ..parameterizations import parameter_labels
from .arguments import add_frame_argument, add_q_argument, load_robot, printable, robot_command


def _run(args: argparse.Namespace) -> int:
    """Compute everything first, then print: an error leaves nothing half-printed."""
    robot = load_robot(args)
    q = (
        robot.neutral()
        if args.q is None
        else robot.check_configuration(args.q, check_limits=False, batch=False)
    )
    frame = args.frame or robot.end_effector
    T, J = robot.frame_pose(q, frame), robot.jacobian(q, frame, args.reference)
    analytic = args.rotation is not None or args.position != "cartesian"
    if analytic:
        labels = parameter_labels(args.position, args.rotation)
        chi = robot.pose_parameters(q, frame, args.position, args.rotation, on_singularity=None)
        JA = robot.analytic_jacobian(q, frame, args.position, args.rotation)
    np.set_printoptions(precision=5, suppress=True, linewidth=120)
    print(f"robot {printable(robot.name)} ({robot.dof} dof), frame {printable(frame)!r}")
    print("q [rad | m] = " + np.array2string(q))
    print(f"\nT (pose of {printable(frame)} in the root link frame {printable(robot.description.root)!r}):")
    print(T)
    print(f"\nJ ({args.reference}, rows [vx vy vz wx wy wz]):")
    print(J)
    if analytic:
        name = " + ".join(p for p in (args.position, args.rotation) if p)
        print(
            f"\nchi ({name}) = "
            + ", ".join(f"{label} {value:.5f}" for label, value in zip(labels, chi, strict=True))
        )
        print(f"\nJ_A (rows {' '.join(labels)}):")
        print(JA)
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = robot_command(sub, "pose", "frame pose and geometric Jacobian at a configuration")
    add_q_argument(p)
    add_frame_argument(p)
    p.add_argument(
        "--reference", default="local_world_aligned", choices=["local_world_aligned", "world", "local"]
    )
    p.add_argument("--position", default="cartesian", help="position parameterization for chi and J_A")
    p.add_argument(
        "--rotation", default=None, help="rotation parameterization for chi and J_A, e.g. euler_zyz"
    )
    p.set_defaults(handler=_run)
