"""Reachability maps: time, poses/s, and the figures of the workspace page (docs/workspace.md).

    python benchmarks/reachability.py local abb_irb120 --voxel 0.02 --orientations 100 [--store DIR]
    python benchmarks/reachability.py local panda_arm --voxel 0.05 --orientations 50
    python benchmarks/reachability.py cluster abb_irb120 --voxel 0.03 --orientations 100 --workers 2
    python benchmarks/reachability.py unreached abb_irb120 --voxel 0.05 --orientations 50 --sample 2000

``local``: one in-process run (the solvers' threads; into a fresh Zarr store with ``--store``): seconds,
voxels, poses, poses/s, mean index. ``cluster``: the same map on a ``distributed.LocalCluster`` of
``--workers`` processes with one thread each, then in this process, interleaved (cluster, local, cluster,
local); poses/s per core of each and their ratio (local uses every core this process may use), and
whether the two maps are equal bit for bit. ``unreached``: a random sample of unreached (voxel,
orientation) cells re-solved by the numeric solver with 20 restarts: the fraction that stays unreached.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

import numpy as np

import kinengine
from kinengine.workspace.solve import poses


def local(robot, args) -> kinengine.ReachabilityMap:
    store = None
    if args.store:
        store = os.path.join(tempfile.mkdtemp(dir=args.store), "map.zarr")
    t = time.perf_counter()
    rmap = kinengine.reachability_map(
        robot, voxel=args.voxel, orientations=args.orientations, store=store, progress=False
    )
    dt = time.perf_counter() - t
    n = len(rmap.centers) * len(rmap.orientations)
    print(
        f"{robot.name} local ({rmap.metadata['method']}{', zarr store' if store else ''}): {dt:.1f} s, "
        f"{len(rmap.centers)} voxels x {len(rmap.orientations)} = {n} poses, {n / dt:,.0f} poses/s, "
        f"mean index {rmap.index.mean():.4f}"
    )
    return rmap


def cluster(robot, args) -> None:
    from distributed import Client, LocalCluster

    cores = len(os.sched_getaffinity(0))
    rates: dict[str, list[float]] = {"cluster": [], "local": []}
    maps = {}
    with (
        LocalCluster(
            n_workers=args.workers, threads_per_worker=1, dashboard_address=None, silence_logs=40
        ) as lc,
        Client(lc) as client,
    ):
        for _ in range(args.rounds):
            for kind in ("cluster", "local"):
                folder = tempfile.mkdtemp()
                t = time.perf_counter()
                rmap = kinengine.reachability_map(
                    robot,
                    voxel=args.voxel,
                    orientations=args.orientations,
                    store=os.path.join(folder, "m.zarr"),
                    client=client if kind == "cluster" else None,
                    progress=False,
                )
                dt = time.perf_counter() - t
                n = len(rmap.centers) * len(rmap.orientations)
                per_core = n / dt / (args.workers if kind == "cluster" else cores)
                rates[kind].append(per_core)
                maps[kind] = rmap
                print(f"  {kind}: {dt:.1f} s, {n / dt:,.0f} poses/s, {per_core:,.0f} per core")
    equal = np.array_equal(maps["cluster"].reached, maps["local"].reached) and np.array_equal(
        maps["cluster"].manipulability, maps["local"].manipulability
    )
    c, loc = max(rates["cluster"]), max(rates["local"])
    print(
        f"{robot.name}: per core, cluster {c:,.0f} poses/s, local {loc:,.0f} ({cores} cores): "
        f"ratio {c / loc:.2f}; maps equal bit for bit: {equal}"
    )


def unreached(robot, args) -> None:
    rmap = local(robot, args)
    T = poses(rmap.centers, rmap.orientations)[~rmap.reached.ravel()]
    rng = np.random.default_rng(0)
    sample = T[rng.choice(len(T), min(args.sample, len(T)), replace=False)]
    res = robot.inverse_kinematics(sample, method="numeric", restarts=20, rng=1)
    stay = 1.0 - float(np.mean(res.success))
    print(
        f"{robot.name}: {len(sample)} unreached cells re-solved with 20 restarts: {stay:.2%} stay unreached"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("local", "cluster", "unreached"))
    parser.add_argument("robot")
    parser.add_argument("--voxel", type=float, default=0.05)
    parser.add_argument("--orientations", type=int, default=50)
    parser.add_argument("--store", default=None, help="folder for a fresh Zarr store (local)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--rounds", type=int, default=1)
    parser.add_argument("--sample", type=int, default=2000)
    args = parser.parse_args()
    robot = kinengine.load(args.robot)
    {"local": local, "cluster": cluster, "unreached": unreached}[args.what](robot, args)


if __name__ == "__main__":
    main()
