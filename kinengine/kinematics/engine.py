"""The per-robot kinematics object: Pinocchio's model, each thread's Data, frame ids and a memo.

Frames and conventions
----------------------
* "world" in Pinocchio is the URDF's root link frame: the inertial frame I of the Robot Dynamics
  lecture notes, ETH Zurich, section 2.8.
* ``pose(q, fid)`` is T_IF, the pose of frame F in I, (4, 4), translation in [m].
* ``jacobian(q, fid, ref)``: rows [linear; angular], columns in the coordinate map's order.
  - LOCAL_WORLD_ALIGNED: I J_e0 of the lecture notes — velocity of F's origin and angular
    velocity, both in I.
  - LOCAL: the same twist expressed in F: blockdiag(C_IFᵀ, C_IFᵀ) · J_lwa.
  - WORLD: the spatial velocity in I: the linear rows are the velocity of the body point that
    currently coincides with I's origin, v_O = v_F − ω × p_F.

Every method here takes an already checked q (:meth:`CoordinateMap.check`). Pinocchio's Data is per
thread, so one object serves several threads at once.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import NamedTuple, TypeVar

import numpy as np
import pinocchio as pin

from ..errors import FrameNotFoundError, OptionError
from ..model import CoordinateMap, build_pinocchio_model
from ..urdf import RobotDescription
from .memory import create_data

T = TypeVar("T")

REFERENCES: dict[object, pin.ReferenceFrame] = {
    "world": pin.WORLD,
    "local": pin.LOCAL,
    "local_world_aligned": pin.LOCAL_WORLD_ALIGNED,
}
_ENUMS = (pin.WORLD, pin.LOCAL, pin.LOCAL_WORLD_ALIGNED)


def resolve_reference(reference: object) -> pin.ReferenceFrame:
    """Pinocchio's ReferenceFrame for "world", "local", "local_world_aligned" (or the enum itself).
    Anything else — including True, 1.0 and numpy integers — is an OptionError."""
    try:
        return REFERENCES[reference]
    except (KeyError, TypeError):  # TypeError: unhashable
        pass
    if type(reference) is pin.ReferenceFrame and reference in _ENUMS:
        return reference
    raise OptionError(
        f"unknown reference {reference!r}; use 'world', 'local' or "
        "'local_world_aligned' (or a pinocchio.ReferenceFrame)"
    )


class FramePath(NamedTuple):
    """How one frame's pose and Jacobian are computed at a checked q (see :meth:`Kinematics.frame_path`)."""

    model: pin.Model
    frame_id: int  # the frame's index in ``model``
    data: Callable[[], pin.Data]  # this thread's Data of ``model``
    mapped: bool  # True: q goes through q_pin = M q + b and J through J_pin · M; False: both as they are


Locked = tuple[pin.Model, Callable[[], pin.Data]] | None  # a reduced model and its per-thread Data


class Kinematics:
    """Pinocchio model + coordinate map of one robot; poses and Jacobians at checked configurations."""

    def __init__(self, description: RobotDescription) -> None:
        self.description = description
        self.model = model = build_pinocchio_model(description)
        self.coordinates = CoordinateMap(description)
        self.dof = self.coordinates.dof
        self.frame_ids = _frame_ids(self.model)
        self.frame_names: tuple[str, ...] = tuple(self.frame_ids)
        self._tls, self.data = thread_data(lambda: create_data(model, f"robot {description.name!r}"))
        """``data()``: this thread's Pinocchio Data (made on first use)."""
        self._memo: dict[object, object] = {}
        self._single: dict[int, Calls] = {}  # frame_calls, by frame index

    def frame_path(self, fid: int) -> FramePath:
        """The cheapest exact way to frame ``fid``: the model itself without mimic joints; for a frame that
        no mimic joint moves, the model with the mimic joints locked (its joints are q's coordinates, so q
        passes untouched); for one that a mimic joint moves, a model of its own joints alone when they are
        q's coordinates one for one (:meth:`_frame_joints_only`); the others take the map (``mapped``)."""
        if self.coordinates.identity:
            return FramePath(self.model, fid, self.data, False)
        model, independent = self.model, self.coordinates.names
        if any(model.names[k] not in independent for k in self.supports(fid)):
            locked = self.memoized(("frame's joints only", fid), lambda: self._frame_joints_only(fid))
        else:
            locked = self.memoized("mimic joints locked", self._locked_mimics)
        if locked is None:
            return FramePath(model, fid, self.data, True)
        reduced, reduced_data = locked
        frame = model.frames[fid]
        return FramePath(reduced, reduced.getFrameId(frame.name, frame.type), reduced_data, False)

    def supports(self, fid: int) -> list[int]:
        """Pinocchio joint indices (1-based) that move frame ``fid``."""
        return [k for k in self.model.supports[self.model.frames[fid].parentJoint] if k > 0]

    def _locked_mimics(self) -> Locked:
        """Pinocchio's model with every mimic joint locked at 0 and its per-thread Data (None if its joints
        were not q's coordinates in q's order)."""
        model, names = self.model, set(self.coordinates.names)
        mimic_joints = [k for k in range(1, model.njoints) if model.names[k] not in names]
        return self._locked(mimic_joints, in_order=True)

    def _frame_joints_only(self, fid: int) -> Locked:
        """Pinocchio's model with every joint that does not move frame ``fid`` locked, when its joints are q's
        coordinates one for one: the k-th is coordinate k or a mimic of it with multiplier 1 and offset 0
        (the Panda's right finger). Then q_pin = q and J_pin = J; None when the frame needs the map."""
        model, coords = self.model, self.coordinates
        supports = self.supports(fid)
        if len(supports) != self.dof:
            return None
        position = {name: k for k, name in enumerate(coords.pinocchio_names)}
        for k, joint in enumerate(supports):
            i = position[model.names[joint]]
            if coords.leader[i] != k or coords.multiplier[i] != 1.0 or coords.offset[i] != 0.0:
                return None
        return self._locked([k for k in range(1, model.njoints) if k not in supports])  # moving no support

    def _locked(self, joints: list[int], in_order: bool = False) -> Locked:
        """Pinocchio's model with ``joints`` held at 0 and its per-thread Data; None where Pinocchio cannot
        build it (a locked joint's frame would take an existing frame's name: the callers then map q) or
        its joints are not dof coordinates (``in_order``: q's own, in q's order)."""
        try:
            reduced = pin.buildReducedModel(self.model, joints, np.zeros(self.model.nq))
        except (ValueError, RuntimeError):
            return None
        if reduced.nq != self.dof or (in_order and tuple(reduced.names)[1:] != self.coordinates.names):
            return None
        what = f"robot {self.description.name!r}"
        return reduced, thread_data(lambda: create_data(reduced, what))[1]

    def pinocchio_q(self, q: np.ndarray) -> np.ndarray:
        """Pinocchio's configuration (nq,) for a checked q (dof,): M q + b (CoordinateMap.to_pinocchio)."""
        return self.coordinates.to_pinocchio(q)

    def memoized(self, key: object, make: Callable[[], T]) -> T:
        """A constant derived from the model (a compiled chain, an IK seed table), made once per key.
        Two threads may both make it the first time; their results are equal and one is kept."""
        try:
            return self._memo[key]  # type: ignore[return-value]
        except KeyError:
            return self._memo.setdefault(key, make())  # type: ignore[return-value]

    def per_thread(self, key: object, make: Callable[[], T]) -> T:
        """A value made once per thread and key (e.g. views into this thread's Data)."""
        try:
            return self._tls.values[key]
        except AttributeError:
            self._tls.values = {}
        except KeyError:
            pass
        value = self._tls.values[key] = make()
        return value

    def frame_id(self, frame: object) -> int:
        """Pinocchio's frame index of a frame name (FrameNotFoundError with suggestions otherwise)."""
        try:
            return self.frame_ids[frame]  # type: ignore[index]
        except (KeyError, TypeError):
            raise FrameNotFoundError(frame, self.frame_names) from None

    # -- single configurations (q checked by the caller) ----------------------------------------
    def frame_calls(self, fid: int) -> Calls:
        """pose(q), jacobian(q, ref), kinematics(q, ref) of frame ``fid``: :func:`single_calls`, made once."""
        try:
            return self._single[fid]
        except KeyError:
            return self._single.setdefault(fid, single_calls(self.coordinates, *self.frame_path(fid)))

    def pose(self, q: np.ndarray, fid: int) -> np.ndarray:
        """T_IF (4, 4) at a checked q (dof,)."""
        return (self._single.get(fid) or self.frame_calls(fid))[0](q)

    def jacobian(self, q: np.ndarray, fid: int, ref: pin.ReferenceFrame) -> np.ndarray:
        """J (6, dof) in ``ref`` at a checked q (dof,)."""
        return (self._single.get(fid) or self.frame_calls(fid))[1](q, ref)


Calls = tuple[Callable[..., np.ndarray], Callable[..., np.ndarray], Callable[..., tuple]]


def single_calls(
    coords: CoordinateMap, model: pin.Model, pfid: int, data: Callable[[], pin.Data], mapped: bool
) -> Calls:
    """The single-configuration calls on a frame's model (see :class:`FramePath`), for a q (dof,) already
    checked: ``pose(q)``, ``jacobian(q, ref)``, ``kinematics(q, ref)`` with ``ref`` a pin.ReferenceFrame. A
    ``mapped`` frame takes q_pin = M q + b and J_pin · M; a 1-dof Jacobian comes back from eigenpy as (6,)
    and is reshaped; Pinocchio 4.1 crashes on a frame Jacobian with nv = 0: a 0-dof one is zeros (6, 0)."""
    forward, place, frame_jacobian = pin.forwardKinematics, pin.updateFramePlacement, pin.computeFrameJacobian
    local_frame, dof = pin.LOCAL, coords.dof
    fold: Callable[[np.ndarray], np.ndarray] = _same if dof > 1 else (lambda J: J.reshape(6, dof))
    if mapped:
        fold = lambda J: coords.fold(J.reshape(6, -1))  # noqa: E731
    if dof == 0:  # Pinocchio 4.1 crashes computing a frame Jacobian with nv = 0
        frame_jacobian = lambda *_: np.zeros((6, 0))  # noqa: E731

    def pose(q: np.ndarray) -> np.ndarray:
        state = data()
        forward(model, state, coords.to_pinocchio(q) if mapped else q)
        return place(model, state, pfid).homogeneous

    def jacobian(q: np.ndarray, ref: pin.ReferenceFrame) -> np.ndarray:
        return fold(frame_jacobian(model, data(), coords.to_pinocchio(q) if mapped else q, pfid, ref))

    def kinematics(q: np.ndarray, ref: pin.ReferenceFrame) -> tuple[np.ndarray, np.ndarray]:
        state, qp = data(), coords.to_pinocchio(q) if mapped else q
        if ref == local_frame or dof == 0:  # the LOCAL frame Jacobian does not place the joints
            forward(model, state, qp)
        J = fold(frame_jacobian(model, state, qp, pfid, ref))  # otherwise it places them
        return place(model, state, pfid).homogeneous, J

    return pose, jacobian, kinematics


def _same(x: np.ndarray) -> np.ndarray:
    return x


def thread_data(make: Callable[[], pin.Data]) -> tuple[threading.local, Callable[[], pin.Data]]:
    """(local, data): ``data()`` is this thread's ``local.data``, made by ``make()`` on first use."""
    local = threading.local()

    def data() -> pin.Data:
        try:
            return local.data
        except AttributeError:
            local.data = make()
            return local.data

    return local, data


def _frame_ids(model: pin.Model) -> dict[str, int]:
    """Frame name -> index for every frame but 'universe'; a link wins over a joint of the same name."""
    ids: dict[str, int] = {}
    for fid in sorted(range(model.nframes), key=lambda k: model.frames[k].type != pin.FrameType.BODY):
        ids.setdefault(model.frames[fid].name, fid)  # links first, each kind in index order
    ids.pop("universe", None)
    return dict(sorted(ids.items(), key=lambda kv: kv[1]))


__all__ = ["REFERENCES", "FramePath", "Kinematics", "resolve_reference", "single_calls", "thread_data"]
