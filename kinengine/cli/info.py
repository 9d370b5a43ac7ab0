"""``kinengine info [ROBOT]``: joints (coordinate index, type, position, velocity and effort limits), mimic
joints and frames; without a robot, the installation: version, whether the C accelerator is on (and why
not), dependency versions."""

from __future__ import annotations

import argparse
import platform
import sys
from importlib import metadata

from .. import __version__, accelerator_status
from ..loading import extra_coordinates
from .arguments import load_robot, printable, robot_command

DEPENDENCIES = (
    "pin",
    "numpy",
    "scipy",
    "example-robot-data",
    "yourdfpy",
    "lxml",
    "xacro",
    "qpsolvers",
    "daqp",
)
"""The distributions ``kinengine info`` reports the versions of (the core dependencies)."""


def installation() -> list[str]:
    """The lines ``kinengine info`` prints without a robot."""
    lines = [
        f"kinengine {__version__} (Python {platform.python_version()}, {sys.platform})",
        accelerator_status(),
    ]
    for name in DEPENDENCIES:
        try:
            version = metadata.version(name)
        except metadata.PackageNotFoundError:
            version = "not installed"
        lines.append(f"{name} {version}")
    return lines


def _run(args: argparse.Namespace) -> int:
    if args.robot is None:
        print("\n".join(installation()))
        return 0
    robot = load_robot(args)
    print(f"{printable(robot.name)}: {robot.dof} dof, source {printable(robot.source)}")
    print(f"end effector: {printable(robot.end_effector)}")
    print(f"root link (the frame poses are given in): {printable(robot.description.root)}")
    print(f"{'q':>3} {'joint':<28} {'type':<11} {'lower':>10} {'upper':>10} {'velocity':>10} {'effort':>10}")
    kinds = {j.name: j.type for j in robot.description.joints}
    rows = zip(
        robot.joint_names,
        robot.lower_limits,
        robot.upper_limits,
        robot.velocity_limits,
        robot.effort_limits,
        strict=True,
    )
    for i, (name, lo, hi, vel, eff) in enumerate(rows):
        print(
            f"{i:>3} {printable(name):<28} {kinds[name]:<11} {lo:>10.5g} {hi:>10.5g} "
            f"{vel:>10.5g} {eff:>10.5g}"
        )
    print("(limits in rad or m; velocity in rad/s or m/s; effort in N m or N; inf: none in the URDF)")
    for joint in robot.description.joints:
        if joint.mimic is not None:
            m = joint.mimic
            print(
                f"  - {printable(joint.name)} (mimic, {joint.type}) = "
                f"{m.multiplier:g}·{printable(m.joint)} + "
                f"{m.offset:g}"
            )
    print("frames: " + ", ".join(printable(f) for f in robot.frame_names))
    extra = [name for name in extra_coordinates(args.robot) if name in robot.joint_names]
    if extra:
        values = ", ".join(f"{name!r}: {robot.neutral()[robot.joint_names.index(name)]:g}" for name in extra)
        print(
            f"gripper coordinates: {', '.join(extra)}; an arm without them: robot.locked({{{values}}})"
            + (" or kinengine.load('panda_arm')" if args.robot == "panda" else "")
        )
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = robot_command(
        sub,
        "info",
        "joints, limits and frames of a robot; without one: versions and the C accelerator",
        nargs="?",
    )
    p.set_defaults(handler=_run)
