"""One row of ``kinengine bench`` (:class:`Case`): a kinengine call, its raw-Pinocchio floor, and what
the runner and the peers need to time and check them."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Case:
    """One benchmark row; each call does ``n`` configurations (or IK solves)."""

    group: str  # "latency" or "throughput"
    name: str  # e.g. "jacobian[local]"
    n: int
    kinengine: Callable[[], object] | None  # None: the API does not exist (see note)
    pinocchio: Callable[[], object] | None  # None: no floor timed (see note)
    note: str = ""
    compare: bool = False  # both return the same array: check before timing
    q: np.ndarray | None = None  # the input: q (dof,) or Q (n, dof), for the peers
    floor: str = ""  # the floor's code, as a user would write it
    targets: np.ndarray | None = None  # IK rows: the target poses (n, 4, 4), for the peers
    robot: object = None  # IK rows: the robot and frame the targets are for
    frame: str = ""
    peers: bool = True  # False: no peer is timed on this row (it repeats another row's targets)


__all__ = ["Case"]
