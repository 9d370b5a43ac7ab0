"""Distances and collisions of one robot's shape pairs at a configuration, on Pinocchio + coal.

``distances(q)``: per checked shape pair the signed distance d [m] (negative: penetration depth) and the
witness points p1, p2 on the two shapes, in the root link frame I, with p2 − p1 = d·n (n the unit normal from
shape 1 to shape 2). ``gradients(q, rows)``: ∂d/∂q (rows, dof) from the witness points:
∂d/∂q = nᵀ (J_p2 − J_p1), where J_p is the Jacobian of the body point at p (the velocity of the point of
the shape's body that is at p; zero for obstacles), folded onto kinengine's q (J = J_pin · M). This is the
distance's exact derivative wherever the closest points are unique (the shapes are convex; see
:mod:`kinengine.collision.geometry`). Each thread gets its own Pinocchio Data and GeometryData. Distance
queries do not start GJK from the previous call's answer (Pinocchio's default does): a distance depends on
q alone; warm-started it would vary with the call history by up to coal's GJK tolerance (1e-6 m). The
yes/no collision test keeps Pinocchio's warm start (1.5-1.8× faster): its answer can depend on the call
history only for shapes within that tolerance of touching.
"""

from __future__ import annotations

import threading
import warnings
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..kinematics.engine import Kinematics
from ..kinematics.memory import create_data
from .pairs import LinkPair, link_of

FloatArray = npt.NDArray[np.float64]
_distances, _collisions, _place = pin.computeDistances, pin.computeCollisions, pin.updateGeometryPlacements
_LWA = pin.LOCAL_WORLD_ALIGNED


class Distances(NamedTuple):
    """One configuration's shape-pair distances: ``pairs`` (P,) shape-name pairs, ``links`` (P,) their link
    names (an obstacle: its name), ``distance`` (P,) [m] (signed), ``p1``, ``p2`` (P, 3) witness points in
    the root link frame [m]."""

    pairs: tuple[tuple[str, str], ...]
    links: tuple[LinkPair, ...]
    distance: FloatArray
    p1: FloatArray
    p2: FloatArray


class CollisionChecker:
    """A robot's collision model: Pinocchio's GeometryModel with its checked pairs (see the module doc)."""

    def __init__(
        self, kin: Kinematics, geometry: pin.GeometryModel, pairs: Sequence[tuple[int, int]]
    ) -> None:
        self.kin, self.model, self.geometry = kin, kin.model, geometry
        geometry.removeAllCollisionPairs()
        for i, j in pairs:
            geometry.addCollisionPair(pin.CollisionPair(i, j))
        self.index_pairs = tuple((int(i), int(j)) for i, j in pairs)
        names = [str(obj.name) for obj in geometry.geometryObjects]
        self.pairs = tuple((names[i], names[j]) for i, j in self.index_pairs)
        self.links = tuple(
            (link_of(self.model, geometry, i), link_of(self.model, geometry, j)) for i, j in self.index_pairs
        )
        self._joints = np.array(
            [
                [geometry.geometryObjects[i].parentJoint, geometry.geometryObjects[j].parentJoint]
                for i, j in pairs
            ],
            dtype=np.intp,
        ).reshape(-1, 2)
        self._tls = threading.local()

    def data(self) -> tuple[pin.Data, pin.GeometryData]:
        """This thread's (Data, GeometryData)."""
        try:
            return self._tls.both
        except AttributeError:
            gdata = pin.GeometryData(self.geometry)
            with warnings.catch_warnings():  # deprecated in coal 3, yet the one switch that does this
                warnings.simplefilter("ignore", DeprecationWarning)
                for requests in (gdata.distanceRequests,):
                    for request in requests:
                        request.enable_cached_gjk_guess = False  # the same q gives the same answer
            both = self._tls.both = (create_data(self.model, "collision checks"), gdata)
            self._tls.results = list(gdata.distanceResults)  # live proxies, read without re-wrapping
            return both

    # -- queries at a checked q (dof,) -----------------------------------------------------------
    def min_distance(self, q: np.ndarray) -> float:
        """The smallest signed distance over the pairs [m] (+inf without pairs)."""
        if not self.index_pairs:
            return float("inf")
        data, gdata = self.data()
        k = _distances(self.model, data, self.geometry, gdata, self.kin.pinocchio_q(q))
        return float(gdata.distanceResults[k].min_distance)

    def distances(self, q: np.ndarray) -> Distances:
        """Every pair's signed distance and witness points (module doc)."""
        data, gdata = self.data()
        n = len(self.index_pairs)
        d, p1, p2 = np.empty(n), np.empty((n, 3)), np.empty((n, 3))
        if n:
            _distances(self.model, data, self.geometry, gdata, self.kin.pinocchio_q(q))
            for k, result in enumerate(self._tls.results):
                d[k] = result.min_distance
                p1[k] = result.getNearestPoint1()
                p2[k] = result.getNearestPoint2()
        return Distances(self.pairs, self.links, d, p1, p2)

    def in_collision(self, q: np.ndarray) -> bool:
        """True if a pair touches or overlaps at q (coal's collision test, stopping at the first)."""
        if not self.index_pairs:
            return False
        data, gdata = self.data()
        return bool(_collisions(self.model, data, self.geometry, gdata, self.kin.pinocchio_q(q), True))

    def in_collision_batch(self, Q: np.ndarray) -> npt.NDArray[np.bool_]:
        """(N,) bool for Q (N, dof)."""
        out = np.zeros(len(Q), dtype=bool)
        if not self.index_pairs:
            return out
        data, gdata = self.data()
        model, geometry, to_pin = self.model, self.geometry, self.kin.coordinates.to_pinocchio
        for k, q_pin in enumerate(to_pin(Q)):
            out[k] = _collisions(model, data, geometry, gdata, q_pin, True)
        return out

    def colliding_pairs(self, q: np.ndarray) -> npt.NDArray[np.bool_]:
        """(P,) bool: which pairs collide at q (every pair tested)."""
        out = np.zeros(len(self.index_pairs), dtype=bool)
        if not self.index_pairs:
            return out
        data, gdata = self.data()
        _collisions(self.model, data, self.geometry, gdata, self.kin.pinocchio_q(q), False)
        for k, result in enumerate(gdata.collisionResults):
            out[k] = result.isCollision()
        return out

    def gradients(
        self, q: np.ndarray, below: float = np.inf
    ) -> tuple[npt.NDArray[np.intp], FloatArray, FloatArray]:
        """(rows (R,), d (R,), ∂d/∂q (R, dof)) of the pairs whose distance is below ``below`` [m] at q, from
        one distance pass (module doc); rows index :attr:`pairs`."""
        data, gdata = self.data()
        q_pin = self.kin.pinocchio_q(q)
        if not self.index_pairs:
            return np.zeros(0, dtype=np.intp), np.zeros(0), np.zeros((0, self.kin.dof))
        _distances(self.model, data, self.geometry, gdata, q_pin)
        results = self._tls.results
        rows = np.flatnonzero(np.fromiter((r.min_distance < below for r in results), bool, len(results)))
        d, G = np.empty(len(rows)), np.zeros((len(rows), self.model.nv))
        if len(rows):
            pin.computeJointJacobians(self.model, data, q_pin)
        for r, k in enumerate(rows):
            result = results[int(k)]
            d[r] = result.min_distance
            n = np.asarray(result.normal)
            for side, joint, point in (
                (-1.0, self._joints[k, 0], result.getNearestPoint1()),
                (1.0, self._joints[k, 1], result.getNearestPoint2()),
            ):
                if joint == 0:
                    continue
                J = pin.getJointJacobian(self.model, data, int(joint), _LWA).reshape(6, -1)  # (6,) if nv = 1
                r_op = point - data.oMi[int(joint)].translation  # joint origin -> point, in I
                Jv = J[:3] - np.cross(r_op[:, None], J[3:], axis=0)  # v_p = v_o + ω × r = v_o − r × ω
                G[r] += side * (n @ Jv)
        return rows, d, self.kin.coordinates.fold(G)


__all__ = ["CollisionChecker", "Distances"]
