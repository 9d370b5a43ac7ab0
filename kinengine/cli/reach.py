"""``kinengine reach ROBOT -o map.zarr`` and ``kinengine place MAP --targets poses.npy``: reachability maps
and base placement (:mod:`kinengine.workspace`)."""

from __future__ import annotations

import argparse

import numpy as np

from ..errors import OptionError
from ..workspace import ReachabilityMap, base_placements, reachability_map
from .arguments import add_frame_argument, bounded_int, load_robot, output_path, robot_command, strict_float


def _run_reach(args: argparse.Namespace) -> int:
    robot = load_robot(args)
    client = None
    if args.scheduler:
        try:
            from distributed import Client
        except ImportError:
            raise OptionError("--scheduler needs Dask: pip install 'kinengine[scale]'") from None
        try:
            client = Client(args.scheduler, timeout="10s")
        except (OSError, ValueError, TypeError) as exc:  # unreachable, or no address (missing port, scheme)
            raise OptionError(f"cannot reach the Dask scheduler {args.scheduler!r}: {exc}") from None
    try:
        rmap = reachability_map(
            robot,
            args.frame,
            voxel=args.voxel,
            orientations=args.orientations,
            method=args.method,
            store=args.output,
            client=client,
            progress=True,
        )
    finally:
        if client is not None:
            client.close()
    s = rmap.stats
    print(
        f"{rmap!r}\nmethod {rmap.metadata['method']}; {int(s['computed'])} of {int(s['chunks'])} chunks "
        "computed "
        f"({int(s['resumed'])} already in the store), {s['poses']:.0f} poses in {s['seconds']:.1f} s; "
        f"written to {args.output}"
    )
    if args.png:
        rmap.plot(path=args.png)
        print(f"slice picture: {args.png}")
    return 0


def _run_place(args: argparse.Namespace) -> int:
    rmap = ReachabilityMap.load(args.map)
    try:
        targets = np.load(args.targets, allow_pickle=False)
    except OSError as exc:
        raise OptionError(f"cannot read task poses from {args.targets!r}: {exc.strerror or exc}") from None
    except ValueError:  # numpy's text advises unpickling, which kinengine never does with a user's file
        raise OptionError(
            f"{args.targets!r} is not a .npy array of numbers: task poses are a .npy of shape (N, 4, 4) [m] "
            "(np.save('poses.npy', T))"
        ) from None
    result = base_placements(rmap, targets, xy=args.step, yaws=args.yaws, z=args.z, top=args.top)
    print(f"{'rank':>4} {'x [m]':>8} {'y [m]':>8} {'yaw [deg]':>9} {'score':>6} {'IK-verified':>11}")
    for rank, i in enumerate(result.order[: args.top], start=1):
        print(
            f"{rank:>4} {result.xy[i, 0]:>8.3f} {result.xy[i, 1]:>8.3f} {np.degrees(result.yaw[i]):>9.1f} "
            f"{result.scores[i]:>6} {result.verified[i]:>11}"
        )
    print(f"of {len(result.targets)} task poses; base height z = {result.z} m")
    if args.png:
        result.plot(args.png)
        print(f"picture: {args.png}")
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = robot_command(sub, "reach", "reachability map of a frame (voxels × orientations, IK for each)")
    add_frame_argument(p, "frame to map (default: end effector)")
    p.add_argument("--voxel", type=strict_float, default=0.05, help="voxel edge [m] (default 0.05)")
    p.add_argument(
        "--orientations", type=bounded_int(1, 100_000), default=50, help="orientations per voxel (default 50)"
    )
    p.add_argument(
        "--method",
        choices=("auto", "closed_form", "numeric"),
        default="auto",
        help="IK solver: closed form when the chain has one (auto), or numeric",
    )
    p.add_argument(
        "-o", "--output", required=True, help="Zarr store (folder or URL); an unfinished one is resumed"
    )
    p.add_argument(
        "--scheduler", default=None, metavar="ADDRESS", help="Dask scheduler, e.g. tcp://host:8786"
    )
    p.add_argument("--png", type=output_path, default=None, help="also draw the fullest z layer to this PNG")
    p.set_defaults(handler=_run_reach)

    q = sub.add_parser("place", help="rank base poses for task poses with a reachability map")
    q.add_argument(
        "map", help="a map written by `kinengine reach` (Zarr store) or ReachabilityMap.save (.npz)"
    )
    q.add_argument("--targets", required=True, help="task poses in the world, a .npy of shape (N, 4, 4) [m]")
    q.add_argument(
        "--step",
        type=strict_float,
        default=None,
        help="grid step of candidate positions [m] (default: the voxel)",
    )
    q.add_argument("--yaws", type=bounded_int(1, 3600), default=16, help="yaws per position (default 16)")
    q.add_argument("--z", type=strict_float, default=0.0, help="base height [m] (default 0)")
    q.add_argument(
        "--top",
        type=bounded_int(1, 1000),
        default=10,
        help="candidates re-checked by IK and shown (default 10)",
    )
    q.add_argument("--png", type=output_path, default=None, help="also draw the scores to this PNG")
    q.set_defaults(handler=_run_place)
