"""``kinengine show``: a PNG of the robot at q (skeleton, joint axes, frames, velocity ellipsoid).

    kinengine show ROBOT [--q v1,v2,...] [--frames tool0,...] [--ellipsoid tool0] [-o robot.png]
                   [--view ELEV,AZIM] [--dpi N]

Drawn by :func:`kinengine.presentation.plotting.plot_robot` in the root link frame [m], headless
(Agg backend).
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path
from typing import TYPE_CHECKING, cast

from ..errors import KinematicsError
from ..presentation.plotting import plot_robot
from .arguments import (
    add_frames_argument,
    add_q_argument,
    bounded_int,
    load_robot,
    name_argument,
    output_path,
    parse_vector,
    robot_command,
    summary,
)

if TYPE_CHECKING:  # matplotlib is imported only when a figure is drawn
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.axes3d import Axes3D

MAX_DPI = 600
"""The finest --dpi: the 6.4 x 4.8 inch figure is then 3840 x 2880 pixels (~44 MB in memory)."""


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``show`` on the kinengine command line."""
    p = robot_command(
        subparsers, "show", "draw the robot at q into a PNG", description=summary(__doc__), metavar="ROBOT"
    )
    add_q_argument(p)
    add_frames_argument(p)
    p.add_argument(
        "--ellipsoid",
        type=name_argument,
        default=None,
        metavar="FRAME",
        help="draw the velocity manipulability ellipsoid of FRAME",
    )
    p.add_argument(
        "-o",
        "--output",
        type=output_path,
        default=None,
        metavar="PATH",
        help="image to write, format from the extension (default: <robot>.png in the current directory)",
    )
    p.add_argument(
        "--view",
        type=parse_vector,
        default=None,
        metavar="ELEV,AZIM",
        help="camera elevation and azimuth [deg] (default: matplotlib's 30,-60)",
    )
    p.add_argument(
        "--dpi",
        type=bounded_int(1, MAX_DPI),
        default=100,
        help=f"resolution of the PNG, 1 to {MAX_DPI} (default 100)",
    )
    p.set_defaults(handler=handle)
    return p


def handle(args: argparse.Namespace) -> int:
    """Write the PNG and print its path."""
    from ..presentation.plotting import pyplot

    plt = pyplot(headless=True)
    if args.view is not None and len(args.view) != 2:
        raise KinematicsError(
            f"--view takes two angles ELEV,AZIM in degrees, e.g. --view 20,-75; got {args.view}"
        )
    if args.dpi <= 0:
        raise KinematicsError(
            f"--dpi must be a positive number of dots per inch, e.g. --dpi 100; got {args.dpi}"
        )
    robot = load_robot(args)
    frames = [robot.end_effector] if args.frames is None else args.frames
    output = args.output or Path(re.sub(r"[^\w.-]", "_", robot.name) + ".png")
    ax = plot_robot(robot, args.q, frames=frames, ellipsoid=args.ellipsoid)
    figure = cast("Figure", ax.figure)  # plot_robot draws on a figure of its own
    if args.view is not None:
        cast("Axes3D", ax).view_init(*args.view)  # a 3D axes
    try:
        figure.savefig(output, dpi=args.dpi)
    except (OSError, ValueError) as exc:
        raise KinematicsError(
            f"cannot write {str(output)!r}: {exc}; choose another -o PATH (e.g. robot.png)"
        ) from None
    finally:
        plt.close(figure)
    print(output)
    return 0


__all__ = ["add_parser", "handle"]
