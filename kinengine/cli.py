"""The kinengine command line: list, info, pose, verify, bench and show.

Every sub-command handler takes the parsed arguments and returns an exit code;
kinengine errors are printed as one line and exit with status 2.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
import os
import re
import sys
import warnings

import numpy as np

from . import __version__, bench, show, verify
from .analytic import pose_map
from .arguments import parse_vector, summary
from .catalog import available_robots
from .errors import KinematicsError
from .loading import load


def _cmd_list(args: argparse.Namespace) -> int:
    for name in available_robots():
        print(name)
    return 0


def _cmd_info(args: argparse.Namespace) -> int:
    robot = load(args.robot)
    print(f"{robot.name}: {robot.dof} dof, source {robot.source}")
    print(f"end effector: {robot.end_effector}")
    print(f"root link (the frame poses are given in): {robot.description.root}")
    print(f"{'q':>3} {'joint':<28} {'type':<11} {'lower':>10} {'upper':>10}")
    kinds = {j.name: j.type for j in robot.description.joints}
    for i, (name, lo, hi) in enumerate(zip(robot.joint_names, robot.lower_limits, robot.upper_limits)):
        print(f"{i:>3} {name:<28} {kinds[name]:<11} {lo:>10.5g} {hi:>10.5g}")
    for joint in robot.description.joints:
        if joint.mimic is not None:
            m = joint.mimic
            print(f"  - {joint.name} (mimic, {joint.type}) = {m.multiplier:g}·{m.joint} + {m.offset:g}")
    print("frames: " + ", ".join(robot.frame_names))
    return 0


def _cmd_pose(args: argparse.Namespace) -> int:
    """Compute everything first, then print: an error leaves nothing half-printed."""
    robot = load(args.robot)
    q = robot.neutral() if args.q is None else robot.check_configuration(args.q, check_limits=False, batch=False)
    frame = args.frame or robot.end_effector
    T, J = robot.frame_pose(q, frame), robot.jacobian(q, frame, args.reference)
    analytic = args.rotation is not None or args.position != "cartesian"
    if analytic:
        labels = pose_map(args.position, args.rotation).labels
        chi = robot.pose_parameters(q, frame, args.position, args.rotation)
        JA = robot.analytic_jacobian(q, frame, args.position, args.rotation)
    np.set_printoptions(precision=5, suppress=True, linewidth=120)
    print(f"robot {robot.name} ({robot.dof} dof), frame {frame!r}")
    print("q [rad | m] = " + np.array2string(q))
    print(f"\nT (pose of {frame} in the root link frame {robot.description.root!r}):")
    print(T)
    print(f"\nJ ({args.reference}, rows [vx vy vz wx wy wz]):")
    print(J)
    if analytic:
        name = " + ".join(p for p in (args.position, args.rotation) if p)
        print(f"\nchi ({name}) = " + ", ".join(f"{label} {value:.5f}" for label, value in zip(labels, chi)))
        print(f"\nJ_A (rows {' '.join(labels)}):")
        print(JA)
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="kinengine", description=summary(__doc__))
    parser.add_argument("--version", action="version", version=f"kinengine {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("list", help="names that kinengine.load() accepts")
    p.set_defaults(handler=_cmd_list)

    p = sub.add_parser("info", help="joints, limits and frames of a robot")
    p.add_argument("robot", help="robot name or path to a .urdf file")
    p.set_defaults(handler=_cmd_info)

    p = sub.add_parser("pose", help="frame pose and geometric Jacobian at a configuration")
    p.add_argument("robot", help="robot name or path to a .urdf file")
    p.add_argument("--q", type=parse_vector, default=None,
                   help="comma-separated joint values [rad | m] (default: zero clipped into the limits)")
    p.add_argument("--frame", default=None, help="frame name (default: the end effector)")
    p.add_argument("--reference", default="local_world_aligned",
                   choices=["local_world_aligned", "world", "local"])
    p.add_argument("--position", default="cartesian", help="position parameterization for chi and J_A")
    p.add_argument("--rotation", default=None, help="rotation parameterization for chi and J_A, e.g. euler_zyz")
    p.set_defaults(handler=_cmd_pose)

    verify.add_parser(sub)
    bench.add_parser(sub)
    show.add_parser(sub)
    return parser


_VALUE_OPTIONS = ("--q", "--view")
_NEGATIVE_LIST = re.compile(r"-[0-9.]")


def join_negative_values(argv: Sequence[str]) -> list[str]:
    """['--q', '-0.5,0.2'] -> ['--q=-0.5,0.2']: argparse would read a leading minus as an option."""
    out: list[str] = []
    for arg in argv:
        if out and out[-1] in _VALUE_OPTIONS and _NEGATIVE_LIST.match(arg):
            out[-1] = f"{out[-1]}={arg}"
        else:
            out.append(arg)
    return out


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"kinengine: warning: {message}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(join_negative_values(sys.argv[1:] if argv is None else argv))
    with warnings.catch_warnings():
        warnings.showwarning = _one_line_warning
        try:
            return int(args.handler(args))
        except KinematicsError as exc:
            print(f"kinengine: error: {exc}", file=sys.stderr)
            return 2
        except BrokenPipeError:  # e.g. `kinengine pose ... | head`: the reader left, nothing to report
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return 141
