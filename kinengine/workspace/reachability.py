"""Reachability maps (Zacharias et al.'s reachability index): a voxel grid over a frame's workspace, a set
of orientations, inverse kinematics for every (voxel, orientation) pose, the fraction reached per voxel.

Poses are T_IF of ``frame`` in the root link frame [m]: the voxel's centre with each rotation of
:mod:`~kinengine.workspace.orientations`. The map is computed in chunks of voxels, in this process (the
solvers' own threads) or as tasks of a Dask cluster (``client=``); with a Zarr ``store`` each chunk is
written as it finishes and a new run with the same arguments computes only the missing chunks. Every
chunk is solved the same way wherever it runs, so the map is the same bit for bit.
"""

from __future__ import annotations

import hashlib
import os
import sys
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from ..errors import OptionError
from ..robot import Robot
from .grid import VoxelGrid, reach_ball
from .orientations import nearest_orientation, orientation_set
from .solve import Chunk, closed_form_available, solve_chunk
from .store import FORMAT, MemoryStore, ZarrStore, write_chunk, zarr_module

if TYPE_CHECKING:
    from distributed import Client

POSES_PER_CHUNK = 20_000
"""A chunk holds about this many (voxel, orientation) poses: ~1 MB of targets, a few seconds of IK."""
METHODS = ("auto", "closed_form", "numeric")
Progress = bool | Callable[[int, int], None]


@dataclass(frozen=True, eq=False)
class ReachabilityMap:
    """A computed reachability map.

    ``centers`` (V, 3) [m] voxel centres in the root link frame; ``reached`` (V, n_rot) bool; ``index`` (V,)
    fraction of the O orientations reached; ``manipulability`` (V,) the best Yoshikawa measure among the
    voxel's reached poses (0 where none); ``orientations`` (O, 3, 3) rotations C_IF; ``metadata`` (robot,
    frame, urdf_sha256, voxel, grid, method, kinengine version); ``stats`` of the run that produced it
    (chunks computed and resumed, seconds). Two maps are equal (``==``) when their arrays and metadata are;
    ``stats`` do not count."""

    centers: npt.NDArray[np.float64]
    reached: npt.NDArray[np.bool_]
    manipulability: npt.NDArray[np.float64]
    orientations: npt.NDArray[np.float64]
    cells: npt.NDArray[np.int64]
    metadata: dict[str, Any]
    stats: dict[str, float] = field(default_factory=dict, compare=False)

    @property
    def index(self) -> npt.NDArray[np.float64]:
        """(V,) reachability index: the fraction of orientations reached in each voxel."""
        return self.reached.mean(axis=1) if self.reached.size else np.zeros(len(self.centers))

    @property
    def voxel(self) -> float:
        return float(self.metadata["voxel"])

    @property
    def grid(self) -> VoxelGrid:
        g = self.metadata["grid"]
        return VoxelGrid(self.voxel, np.array(g["lower"]), tuple(g["shape"]), self.cells, self.centers)

    def reachable(self, T: npt.ArrayLike) -> bool | npt.NDArray[np.bool_]:
        """Whether the map reached the cell of pose T (4, 4) (or of each of (N, 4, 4)): the voxel holding its
        position and the map's orientation nearest its rotation. False outside the map."""
        single = np.ndim(T) == 2
        out = self.lookup(T)[1]
        return bool(out[0]) if single else out

    def lookup(self, T: npt.ArrayLike) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.bool_]]:
        """(voxel index (N,), −1 outside the map; reached (N,)) of the cells of poses T (N, 4, 4) or (4, 4),
        as :meth:`reachable` judges them."""
        T = np.asarray(T, dtype=np.float64)
        T = T.reshape(-1, 4, 4) if T.shape[-2:] == (4, 4) else None  # type: ignore[assignment]
        if T is None:
            raise OptionError("`T` must be a pose (4, 4) or poses (N, 4, 4)")
        if not np.all(np.isfinite(T)):
            raise OptionError("`T` holds NaN or inf: a pose T_IF (4, 4) has finite entries")
        C = T[:, :3, :3]
        if np.any(np.abs(np.einsum("nki,nkj->nij", C, C) - np.eye(3)) > 1e-6) or np.any(
            np.linalg.det(C) <= 0
        ):
            raise OptionError("`T`'s rotation block is not a rotation matrix (CᵀC ≠ I or det <= 0)")
        v = self.grid.lookup(T[:, :3, 3])
        k = nearest_orientation(self.orientations, T[:, :3, :3])
        return v, (v >= 0) & self.reached[np.maximum(v, 0), k]

    def slice(self, z: float) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """The voxel layer holding height z [m]: its centres (n, 3) and reachability indices (n,)."""
        g = self.metadata["grid"]
        layer = int(np.floor((z - g["lower"][2]) / self.voxel))
        at = (self.cells % g["shape"][2]) == layer
        return self.centers[at], self.index[at]

    def plot(self, z: float | None = None, path: str | os.PathLike[str] | None = None) -> object:
        """A picture of the layer at height z [m] (default: the layer with the most reached voxels),
        voxels coloured by reachability index; written to ``path`` (PNG) when given. Returns the figure."""
        from .pictures import reachability_slice  # matplotlib only when asked for

        if z is None:
            g = self.metadata["grid"]
            layers = self.cells % g["shape"][2]
            counts = np.bincount(layers, weights=self.index, minlength=g["shape"][2])
            z = g["lower"][2] + self.voxel * (int(np.argmax(counts)) + 0.5)
        centers, index = self.slice(z)
        return reachability_slice(
            centers, index, self.voxel, z, f"{self.metadata['robot']} · {self.metadata['frame']}", path
        )

    def view(self, robot: Robot | None = None, *, min_index: float = 0.0, port: int | None = None) -> object:
        """The map in the browser viewer: the robot (``robot``, else rebuilt from the stored URDF) and a
        point per voxel with index > ``min_index``, coloured by index (red 0 → green 1); the view extra."""
        viewer = (self.robot() if robot is None else robot).view(port=port)
        keep = self.index > min_index
        viewer.add_points(
            "/reachability", self.centers[keep], index_colors(self.index[keep]), self.voxel * 0.6
        )
        return viewer

    def robot(self) -> Robot:
        """The robot the map was made for, rebuilt from the URDF text it keeps (its joints checked)."""
        from ..loading import load_urdf_string

        robot = load_urdf_string(self.metadata["urdf"], source=f"<map of {self.metadata['robot']}>")
        if list(robot.joint_names) != list(self.metadata["joints"]):
            raise OptionError(
                f"the map's URDF gives joints {list(robot.joint_names)}, the map was made with "
                f"{self.metadata['joints']}: pass the robot (robot=...)"
            )
        return robot

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the map: ``*.npz`` (numpy, no extra needed) or a Zarr store (any other path or URL);
        OptionError naming the path when it cannot be written."""
        path = os.fspath(path)
        try:
            self._save(path)
        except OSError as exc:
            raise OptionError(
                f"cannot write the reachability map to {path!r}: {exc.strerror or exc}"
            ) from None

    def _save(self, path: str) -> None:
        if path.endswith(".npz"):
            np.savez_compressed(
                path,
                centers=self.centers,
                reached=self.reached,
                manipulability=self.manipulability,
                orientations=self.orientations,
                cells=self.cells,
                metadata=np.array(_json(self.metadata)),
            )
            return
        zarr = zarr_module()
        group = zarr.open_group(path, mode="w")
        for name in ("centers", "cells", "orientations", "reached", "manipulability"):
            group.create_array(name, data=np.ascontiguousarray(getattr(self, name)))
        group.create_array("done", data=np.ones(max(1, int(self.metadata["chunks"])), dtype=bool))
        group.attrs["kinengine_map"] = self.metadata

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> ReachabilityMap:
        """A map written by :meth:`save` or by :func:`reachability_map` into a store (complete runs only)."""
        path = os.fspath(path)
        if "://" not in path and not os.path.exists(path):
            raise OptionError(f"no reachability map at {path!r} (a .npz file or a Zarr store)")
        if path.endswith(".npz"):
            import json

            try:
                with np.load(path, allow_pickle=False) as f:
                    return cls(
                        f["centers"],
                        f["reached"],
                        f["manipulability"],
                        f["orientations"],
                        f["cells"],
                        json.loads(str(f["metadata"])),
                    )
            except (OSError, ValueError, KeyError) as exc:
                raise OptionError(f"{path!r} is no reachability map written by kinengine: {exc}") from None
        try:
            group = zarr_module().open_group(path, mode="r")
            metadata = group.attrs.get("kinengine_map")
        except OptionError:
            raise
        except Exception as exc:  # zarr/fsspec raise many kinds (not a group, bad URL, no permission)
            raise OptionError(f"cannot read a reachability map from {path!r}: {exc}") from None
        if metadata is None:
            raise OptionError(f"{path!r} holds no kinengine reachability map")
        if not np.all(group["done"][:]):
            raise OptionError(
                f"the map in {path!r} is unfinished ({int(np.sum(~group['done'][:]))} chunks missing): run "
                "reachability_map again with the same arguments and store to complete it"
            )
        return cls(
            np.asarray(group["centers"][:]),
            np.asarray(group["reached"][:]),
            np.asarray(group["manipulability"][:]),
            np.asarray(group["orientations"][:]),
            np.asarray(group["cells"][:]),
            dict(metadata),
        )

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ReachabilityMap):
            return NotImplemented
        arrays = ("centers", "reached", "manipulability", "orientations", "cells")
        return self.metadata == other.metadata and all(
            np.array_equal(getattr(self, name), getattr(other, name)) for name in arrays
        )

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        reached = float(self.index.mean()) if len(self.centers) else 0.0
        return (
            f"<ReachabilityMap {self.metadata['robot']!r} {self.metadata['frame']!r}: "
            f"{len(self.centers)} voxels of {self.voxel} m × {len(self.orientations)} orientations, "
            f"mean index {reached:.3f}>"
        )


def index_colors(index: npt.NDArray[np.float64]) -> npt.NDArray[np.uint8]:
    """(n, 3) RGB for reachability indices in [0, 1]: red (0) through yellow to green (1)."""
    i = np.clip(index, 0.0, 1.0)[:, None]
    red, green = np.minimum(1.0, 2.0 * (1.0 - i)), np.minimum(1.0, 2.0 * i)
    return (255 * np.concatenate((red, green, 0.1 * np.ones_like(i)), axis=1)).astype(np.uint8)


def reachability_map(
    robot: Robot,
    frame: str | None = None,
    *,
    voxel: float = 0.05,
    orientations: int | tuple[int, int] | npt.ArrayLike = 50,
    bounds: npt.ArrayLike | None = None,
    method: str = "auto",
    store: str | os.PathLike[str] | None = None,
    client: Client | None = None,
    progress: Progress = True,
) -> ReachabilityMap:
    """The reachability map of ``frame`` (default: the end effector).

    ``voxel`` edge [m]; ``orientations`` a count, (directions, rolls) or (O, 3, 3) rotations
    (:func:`~kinengine.workspace.orientations.orientation_set`); ``bounds`` ((xmin, ymin, zmin), (xmax, ymax,
    zmax)) [m] in the root link frame (default: the box around the frame's reach ball); ``method`` "auto"
    (closed form when the chain has one, else numeric), "closed_form" or "numeric"; ``store`` a Zarr store
    (path or URL) written chunk by chunk, resumed when it already holds part of the same map; ``client`` a
    ``dask.distributed.Client``: each chunk a task on its cluster (workers write into ``store``);
    ``progress`` a bar on stderr (True), none (False), or a callable(chunks_done, chunks_total).
    """
    if not isinstance(robot, Robot):
        raise OptionError(f"`robot` must be a kinengine Robot, got {type(robot).__name__}")
    frame = robot.end_effector if frame is None else frame
    frame_id = robot.frame_id(frame)  # FrameNotFoundError with suggestions
    if method not in METHODS:
        raise OptionError(f"`method` must be one of {', '.join(map(repr, METHODS))}, got {method!r}")
    model = robot.pinocchio_model()
    ball = reach_ball(model, frame_id, model.lowerPositionLimit, model.upperPositionLimit)
    grid = VoxelGrid.build(ball, voxel, bounds)
    rotations = orientation_set(orientations)
    method = _resolve_method(robot, frame, method)
    V, n_rot = len(grid.centers), len(rotations)
    chunk_voxels = max(1, POSES_PER_CHUNK // n_rot)
    n_chunks = -(-V // chunk_voxels)
    metadata: dict[str, Any] = {
        "format": FORMAT,
        "robot": robot.name,
        "frame": frame,
        "joints": list(robot.joint_names),
        "urdf_sha256": hashlib.sha256(robot.urdf_text.encode()).hexdigest(),
        "voxel": float(grid.voxel),
        "grid": {"lower": grid.lower.tolist(), "shape": list(grid.shape)},
        "reach": {"center": ball.center.tolist(), "radius": ball.radius},
        "orientations": n_rot,
        "orientations_sha256": hashlib.sha256(rotations.tobytes()).hexdigest(),
        "method": method,
        "chunks": n_chunks,
        "chunk_voxels": chunk_voxels,
        "kinengine": _version(),
        "urdf": robot.urdf_text,
    }
    if client is not None and store is None:
        raise OptionError(
            "a cluster run (`client=`) writes into a `store`: give a Zarr path or URL the workers reach"
        )
    target: MemoryStore | ZarrStore
    if store is None:
        target = MemoryStore(V, n_rot, n_chunks)
    else:
        target = ZarrStore.open(store, metadata, grid.centers, grid.cells, rotations, chunk_voxels)
    chunks = [
        Chunk(int(c), int(c) * chunk_voxels, min(V, (int(c) + 1) * chunk_voxels)) for c in target.missing()
    ]
    chunks = [c for c in chunks if c.start < V]
    started = time.perf_counter()
    bar = _progress(progress, n_chunks, n_chunks - len(chunks), f"reach {robot.name}")
    try:
        job = MapJob(robot, frame, grid.centers, rotations, method)
        if client is None:
            _run_local(job, chunks, target, bar)
        else:
            _run_cluster(client, job, chunks, store, bar)
    finally:
        bar.close()
    reached, manip = target.arrays()
    stats = {
        "chunks": float(n_chunks),
        "computed": float(len(chunks)),
        "resumed": float(n_chunks - len(chunks)),
        "seconds": time.perf_counter() - started,
        "poses": float(sum(c.stop - c.start for c in chunks) * n_rot),
    }
    return ReachabilityMap(grid.centers, reached, manip, rotations, grid.cells, metadata, stats)


def chunk_seed(chunk: int) -> np.random.SeedSequence:
    """The numeric solver's random source for a chunk: fixed by its index, wherever it runs."""
    return np.random.SeedSequence([0x6B696E, chunk])


def _resolve_method(robot: Robot, frame: str, method: str) -> str:
    if method == "numeric":
        return method
    reason = closed_form_available(robot, frame)
    if reason is None:
        return "closed_form"
    if method == "closed_form":
        raise OptionError(f"method='closed_form': {reason}")
    return "numeric"


@dataclass(frozen=True)
class MapJob:
    """What every chunk of one map is solved with (a cluster task receives it by pickle)."""

    robot: Robot
    frame: str
    centers: npt.NDArray[np.float64]
    rotations: npt.NDArray[np.float64]
    method: str

    def solve(self, chunk: Chunk) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.float64]]:
        """reached (rows, O) and manipulability (rows,) of the chunk's voxels."""
        centers = self.centers[chunk.start : chunk.stop]
        return solve_chunk(
            self.robot, self.frame, centers, self.rotations, self.method, chunk_seed(chunk.index)
        )


def _run_local(job: MapJob, chunks: Sequence[Chunk], target: MemoryStore | ZarrStore, bar: _Bar) -> None:
    """Chunks in this process: two at a time (the solvers release the GIL in their numpy and C parts)."""
    workers = max(1, min(2, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1))
    with ThreadPoolExecutor(workers) as pool:
        for c, (reached, manip) in zip(chunks, pool.map(job.solve, chunks), strict=True):
            target.write(c.index, c.start, reached, manip)
            bar.update(1)


def _cluster_chunk(job: MapJob, chunk: Chunk, store: str) -> int:
    """A cluster task: solve one chunk and write it into the store."""
    reached, manip = job.solve(chunk)
    write_chunk(store, chunk.index, chunk.start, reached, manip)
    return chunk.index


def _run_cluster(client: Client, job: MapJob, chunks: Sequence[Chunk], store: object, bar: _Bar) -> None:
    """Each chunk a task of the Dask cluster behind ``client``; a lost worker's tasks run again elsewhere."""
    try:
        from distributed import as_completed
    except ImportError:
        raise OptionError("cluster runs need Dask: pip install 'kinengine[scale]'") from None
    if not isinstance(store, (str, os.PathLike)):
        raise OptionError("a cluster run needs `store` as a path or URL that every worker reaches")
    location = os.fspath(store)
    [job_f] = client.scatter([job], broadcast=True)
    tag = hashlib.sha1(location.encode()).hexdigest()[:8]
    futures = [
        client.submit(_cluster_chunk, job_f, c, location, key=f"kinengine-reach-{c.index}-{tag}", pure=False)
        for c in chunks
    ]
    for future in as_completed(futures):
        future.result()  # a task that failed on every retry raises here
        bar.update(1)


class _Bar:
    """Progress: a tqdm bar, nothing, or the caller's callable(done, total)."""

    def __init__(
        self, total: int, done: int, callback: Callable[[int, int], None] | None, tqdm_bar: Any
    ) -> None:
        self.total, self.done, self.callback, self.tqdm = total, done, callback, tqdm_bar

    def update(self, n: int) -> None:
        self.done += n
        if self.tqdm is not None:
            self.tqdm.update(n)
        if self.callback is not None:
            self.callback(self.done, self.total)

    def close(self) -> None:
        if self.tqdm is not None:
            self.tqdm.close()


def _progress(progress: Progress, total: int, done: int, desc: str) -> _Bar:
    if callable(progress) and not isinstance(progress, bool):
        return _Bar(total, done, progress, None)
    if not isinstance(progress, bool):
        raise OptionError(f"`progress` must be True, False or a callable(done, total), got {progress!r}")
    if not progress:
        return _Bar(total, done, None, None)
    from tqdm import tqdm

    return _Bar(
        total,
        done,
        None,
        tqdm(total=total, initial=done, desc=desc, unit="chunk", file=sys.stderr, leave=False),
    )


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("kinengine")
    except PackageNotFoundError:  # a source tree on sys.path, not installed
        return "unknown"


def _json(metadata: dict[str, Any]) -> str:
    import json

    return json.dumps(metadata)
