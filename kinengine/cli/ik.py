"""``kinengine ik ROBOT --xyz X,Y,Z --rpy R,P,Y``: every closed-form IK solution of a pose (table or JSON)."""

from __future__ import annotations

import argparse
import json

import numpy as np

from ..errors import ConfigurationError, KinematicsError
from ..parameterizations import get_rotation
from .arguments import add_frame_argument, load_robot, parse_vector, printable, robot_command


def _triple(text: str) -> list[float]:
    values = parse_vector(text)
    if len(values) != 3 or not np.isfinite(values).all():
        raise argparse.ArgumentTypeError(f"expected three finite comma-separated numbers, got {text!r:.60}")
    return values


def _lock(text: str) -> tuple[str, float]:
    name, equals, value = text.partition("=")
    values = parse_vector(value) if equals and name.strip() else []
    if len(values) != 1 or not np.isfinite(values[0]):
        raise argparse.ArgumentTypeError(
            f"expected JOINT=VALUE [rad or m], e.g. panda_joint7=0, got {text!r:.60}"
        )
    return name.strip(), values[0]


def _run(args: argparse.Namespace) -> int:
    """Solve first, then print: an error leaves nothing half-printed."""
    robot = load_robot(args)
    if args.lock:
        robot = robot.locked(dict(args.lock))
    frame = args.frame or robot.end_effector
    roll, pitch, yaw = args.rpy
    T = np.eye(4)
    T[:3, :3] = get_rotation("euler_zyx").to_rotation(np.array([yaw, pitch, roll]))  # URDF rpy
    T[:3, 3] = args.xyz
    try:
        near = (
            None
            if args.near is None
            else robot.check_configuration(args.near, check_limits=False, batch=False)
        )
    except ConfigurationError as exc:
        raise ConfigurationError(f"--near: {exc}") from None
    try:
        found = robot.ik_solutions(T, frame, q_near=near, within_limits=not args.all, all_turns=args.all)
    except KinematicsError as exc:
        if "locking" not in str(exc):
            raise
        raise KinematicsError(f"{exc} (on the command line: --lock JOINT=VALUE)") from None
    if args.json:
        report = {
            "robot": robot.name,
            "frame": frame,
            "pose": T.tolist(),
            "joint_names": list(robot.joint_names),
            "count": int(found.count),
            "reachable": bool(found.reachable),
            "singular": bool(found.singular),
            "solutions": found.q.tolist(),
            "within_limits": found.within_limits.tolist(),
        }
        print(json.dumps(report, indent=2))
        return 0
    name, where = printable(robot.name), printable(frame)
    print(f"robot {name} ({robot.dof} dof), frame {where!r}: {found.count} solution(s)", end="")
    print(", singular pose (a representative set of a continuum)" if found.singular else "")
    if not found.count:
        outside = 0 if args.all else robot.ik_solutions(T, frame, within_limits=False).count
        print(
            f"{outside} solution(s) outside the joint limits (--all lists them)"
            if outside
            else "the pose is out of reach"
        )
        return 0
    names = [printable(n) for n in robot.joint_names]
    width = max(9, *(len(n) for n in names))
    header = ["#".rjust(3)] + [n.rjust(width) for n in names] + (["  limits"] if args.all else [])
    print(" ".join(header) + ("   |q - near|" if near is not None else ""))
    for i, q in enumerate(found.q):
        cells = [str(i + 1).rjust(3)] + [f"{v:{width}.5f}" for v in q]
        if args.all:
            cells.append("  inside" if found.within_limits[i] else "  OUTSIDE")
        if near is not None:
            cells.append(f"{np.linalg.norm(q - near):13.5f}")
        print(" ".join(cells))
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = robot_command(sub, "ik", "every closed-form inverse-kinematics solution of a pose (the ik extra)")
    p.add_argument("--xyz", type=_triple, required=True, help="position X,Y,Z [m] in the root link frame")
    p.add_argument(
        "--rpy", type=_triple, default=[0.0, 0.0, 0.0], help="orientation roll,pitch,yaw [rad] as in URDF"
    )
    add_frame_argument(p)
    p.add_argument(
        "--all",
        action="store_true",
        help="also solutions outside the joint limits (flagged) and every 2π turn within them",
    )
    p.add_argument(
        "--near",
        type=parse_vector,
        default=None,
        metavar="Q",
        help="comma-separated joint values [rad]: sort the solutions by distance to them",
    )
    p.add_argument(
        "--lock",
        type=_lock,
        action="append",
        metavar="JOINT=VALUE",
        help="hold a joint at a value [rad or m] (repeatable): lock one joint of a 7-joint arm",
    )
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.set_defaults(handler=_run)
