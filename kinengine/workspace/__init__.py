"""Workspace analysis at scale: reachability maps and base placement.

:func:`reachability_map` solves inverse kinematics for every (voxel, orientation) pose of a frame's
workspace, in this process or on a Dask cluster, into memory or a resumable Zarr store;
:func:`base_placements` ranks base poses of the robot for a set of task poses with such a map.
"""

from .orientations import orientation_set
from .placement import BasePlacements, base_placements
from .reachability import ReachabilityMap, reachability_map

__all__ = ["BasePlacements", "ReachabilityMap", "base_placements", "orientation_set", "reachability_map"]
