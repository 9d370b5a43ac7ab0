"""``kinengine view``: serve the robot in the browser (Viser) and run until Ctrl-C.

    kinengine view ROBOT [--q v1,v2,...] [--port N] [--host ADDR] [--frames tool0,...] [--ellipsoid FRAME]
                   [--parameterization euler_zyx] [--no-meshes] [--package NAME=PATH] [--xacro-arg NAME=VALUE]

Prints the page's URL (http://127.0.0.1:8080 unless that port is taken); the page shows the robot's
meshes or primitive visuals in the root link frame [m], a slider per coordinate, frame triads, the
velocity ellipsoid and the pose parameters. Needs the optional extra: ``pip install 'kinengine[view]'``.
"""

from __future__ import annotations

import argparse
import logging
import time

from ..presentation.viewer import view
from .arguments import (
    add_frames_argument,
    add_q_argument,
    flush_warnings,
    load_robot,
    robot_command,
    summary,
)


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``view`` on the kinengine command line."""
    p = robot_command(
        subparsers,
        "view",
        "show the robot in the browser (interactive 3D viewer)",
        description=summary(__doc__),
        metavar="ROBOT",
    )
    add_q_argument(p)
    p.add_argument(
        "--port",
        type=int,
        default=None,
        help="port to serve on (default 8080, or the next free one; 0: any free port)",
    )
    p.add_argument(
        "--host",
        default="127.0.0.1",
        help="address to listen on (default 127.0.0.1; 0.0.0.0 serves the whole network)",
    )
    add_frames_argument(p)
    p.add_argument(
        "--ellipsoid",
        default=None,
        metavar="FRAME",
        help="draw the velocity manipulability ellipsoid of FRAME (and read out its pose)",
    )
    p.add_argument(
        "--parameterization",
        default="euler_zyx",
        metavar="NAME",
        help="rotation parameterization of the pose readout (default euler_zyx)",
    )
    p.add_argument(
        "--no-meshes",
        dest="meshes",
        action="store_false",
        help="draw URDF primitives and the skeleton only, without reading mesh files",
    )
    p.set_defaults(handler=handle)
    return p


def handle(args: argparse.Namespace) -> int:
    """Serve the viewer, print its URL, and wait for Ctrl-C."""
    # a browser's speculative connections end without a request; websockets would log each as an error
    logging.getLogger("websockets.server").setLevel(logging.CRITICAL)
    robot = load_robot(args)
    frames = [robot.end_effector] if args.frames is None else args.frames
    viewer = view(
        robot,
        args.q,
        port=args.port,
        host=args.host,
        frames=frames,
        ellipsoid=args.ellipsoid,
        parameterization=args.parameterization,
        meshes=args.meshes,
    )
    try:
        print(
            f"kinengine: viewing {robot.name} at {viewer.url} (listening on {viewer.address} port "
            f"{viewer.port}; Ctrl-C to stop)",
            flush=True,
        )
        flush_warnings()  # e.g. that the page is served to the network: now, not after Ctrl-C
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        return 0
    finally:
        viewer.close()


__all__ = ["add_parser", "handle"]
