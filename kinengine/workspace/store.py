"""Where a reachability map lives while it is computed: memory, or a Zarr store on disk or any fsspec
URL (chunked, compressed), written one chunk at a time so that a run can resume.

Layout of a store (a Zarr group): arrays ``reached`` (V, n_rot) bool in chunks of ``chunk_voxels`` rows,
``manipulability`` (V,), ``done`` (C,) bool (chunk c finished: set after its rows are written),
``centers`` (V, 3), ``cells`` (V,), ``orientations`` (O, 3, 3); attributes ``kinengine_map`` (the
metadata: robot, frame, URDF hash, voxel, grid, method, version).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from ..errors import OptionError

FORMAT = 1
"""Version of the store layout above."""


def zarr_module() -> Any:
    """The zarr package, or a one-line error naming the extra."""
    try:
        import zarr
    except ImportError:
        raise OptionError("reachability map stores need zarr: pip install 'kinengine[scale]'") from None
    return zarr


class MemoryStore:
    """The map's arrays in memory (no store given)."""

    def __init__(self, n_voxels: int, n_orientations: int, n_chunks: int) -> None:
        self.reached = np.zeros((n_voxels, n_orientations), dtype=bool)
        self.manipulability = np.zeros(n_voxels)
        self.done = np.zeros(n_chunks, dtype=bool)

    def write(
        self, chunk: int, start: int, reached: npt.NDArray[np.bool_], manip: npt.NDArray[np.float64]
    ) -> None:
        self.reached[start : start + len(reached)] = reached
        self.manipulability[start : start + len(manip)] = manip
        self.done[chunk] = True

    def missing(self) -> npt.NDArray[np.intp]:
        return np.flatnonzero(~self.done)

    def arrays(self) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.float64]]:
        return self.reached, self.manipulability


class ZarrStore:
    """The map's arrays in a Zarr group at ``location`` (a path or fsspec URL, or a zarr store)."""

    def __init__(self, location: object, group: Any) -> None:
        self.location = location
        self.group = group

    @classmethod
    def open(
        cls,
        location: object,
        metadata: dict[str, object],
        centers: npt.NDArray[np.float64],
        cells: npt.NDArray[np.int64],
        orientations: npt.NDArray[np.float64],
        chunk_voxels: int,
    ) -> ZarrStore:
        """Create the group, or reopen one made with the same metadata (a resumed run); a store of a
        different map is refused, naming the first difference."""
        zarr = zarr_module()
        try:
            group = zarr.open_group(location, mode="a")
        except Exception as exc:  # zarr/fsspec raise many kinds (bad URL, no permission, not a group)
            raise OptionError(f"cannot open the Zarr store {location!r}: {exc}") from None
        existing = group.attrs.get("kinengine_map")
        if existing is not None:
            for key, value in metadata.items():
                if existing.get(key) != value:
                    raise OptionError(
                        f"the store {location!r} holds another map ({key}: {existing.get(key)!r}, asked for "
                        f"{value!r}): give a new store, or the same arguments to resume it"
                    )
            return cls(location, group)
        if len(list(group.array_keys())):
            raise OptionError(f"the store {location!r} holds other data: give an empty or new store")
        V, n_rot = len(centers), len(orientations)
        n_chunks = -(-V // chunk_voxels) if V else 0
        for name, data in (("centers", centers), ("cells", cells), ("orientations", orientations)):
            group.create_array(name, data=np.ascontiguousarray(data))
        group.create_array(
            "reached", shape=(V, n_rot), chunks=(chunk_voxels, n_rot), dtype=bool, fill_value=False
        )
        group.create_array(
            "manipulability", shape=(V,), chunks=(chunk_voxels,), dtype="float64", fill_value=0.0
        )
        group.create_array("done", shape=(max(n_chunks, 1),), chunks=(1,), dtype=bool, fill_value=False)
        if n_chunks == 0:
            group["done"][:] = True
        group.attrs["kinengine_map"] = metadata  # last: a store without it is an unfinished creation
        return cls(location, group)

    def write(
        self, chunk: int, start: int, reached: npt.NDArray[np.bool_], manip: npt.NDArray[np.float64]
    ) -> None:
        """Rows first, then the chunk's done flag: a run stopped in between recomputes the chunk."""
        self.group["reached"][start : start + len(reached)] = reached
        self.group["manipulability"][start : start + len(manip)] = manip
        self.group["done"][chunk] = True

    def missing(self) -> npt.NDArray[np.intp]:
        return np.flatnonzero(~np.asarray(self.group["done"][:]))

    def arrays(self) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.float64]]:
        return np.asarray(self.group["reached"][:]), np.asarray(self.group["manipulability"][:])


def write_chunk(location: object, chunk: int, start: int, reached: np.ndarray, manip: np.ndarray) -> None:
    """Write one finished chunk into the store at ``location`` (what a cluster worker does)."""
    group = zarr_module().open_group(location, mode="r+")
    ZarrStore(location, group).write(chunk, start, reached, manip)
