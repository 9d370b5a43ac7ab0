"""MuJoCo's compiled model (``MjModel``) as kinengine's own :class:`~kinengine.urdf.RobotDescription`.

Only the compiled numbers are read (``body_pos``/``body_quat``, ``jnt_pos``/``jnt_axis``,
``site_pos``/``site_quat``, ``qpos0``, ``jnt_range``), so every ``<compiler>`` setting, default class,
orientation form and include is applied exactly as MuJoCo applies it. The root link is MuJoCo's world
body ``world``, so kinengine's poses are MuJoCo's ``xpos``/``xmat`` and ``site_xpos``/``site_xmat``.

MuJoCo moves body b by its joints in order (``mj_kinematics``): a hinge with anchor p (``jnt_pos``, in
the body frame) multiplies the body's pose by Trans(p)·Rot(a, q − q0)·Trans(−p), a slide by
Trans(a·(q − q0)). A URDF joint turns about its child link's origin, so each joint gets its own link:

- ``<body>`` with no joint: link ``body``, fixed joint ``body_fixed`` at (body_pos, body_quat);
- ``<body>`` with joints j1..jn: joint ``jk`` (hinge → revolute, or continuous when unlimited;
  slide → prismatic) at Trans(−p(k−1))·Trans(pk)·Rot(a, −q0) (the first one after body_pos/body_quat),
  between links ``body__jk``; the last joint's child is ``body`` itself, or, when its anchor is off
  the body origin, ``body__jn`` followed by the fixed joint ``body_fixed`` at Trans(−pn);
- ``<site>``: link ``site``, fixed joint ``site_fixed`` at (site_pos, site_quat).

The coordinate q of a joint is MuJoCo's ``qpos`` (the reference q0 = ``qpos0`` is folded into the
origin). A name taken twice gets a suffix ``_2``, ``_3``; unnamed bodies, joints and sites are
``body<i>``, ``joint<i>``, ``site<i>``. A linear ``<equality><joint polycoef="c0 c1 0 0 0">`` (MuJoCo:
q1 − q1₀ = c0 + c1·(q2 − q2₀)) becomes a mimic q1 = c1·q2 + (q1₀ + c0 − c1·q2₀).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import numpy.typing as npt

from ..errors import MJCFError
from ..model.editing import rpy_from_matrix
from ..urdf.description import Inertial, Joint, Link, Mimic, RobotDescription, Vector3
from ..urdf.limits import LIMITS, Limits
from ..urdf.magnitudes import check_magnitudes
from ..urdf.tree import assemble

FREE, BALL, SLIDE, HINGE = 0, 1, 2, 3  # mjtJoint
EQ_JOINT = 2  # mjtEq.mjEQ_JOINT
UNLIMITED_SLIDE = 1e16
"""[m] the limits written for a slide joint without a range (a URDF prismatic joint needs limits)."""


def describe(
    model: Any, source: str, *, root: str | None = None, limits: Limits = LIMITS
) -> RobotDescription:
    """The description of the tree of ``model`` whose top body is ``root`` (default: the child of the world
    body whose tree has the most joints, free joints not counted; the first of equals), rooted at link
    ``world``; MJCFError for what a fixed-base tree cannot hold."""
    names = MJCFNames(model, source, limits)
    top = _top_body(model, names, root, source)
    notes: list[str] = []
    links = [Link(name=names.body[0])]
    joints: list[Joint] = []
    in_tree = [False] * model.nbody
    in_tree[0] = True
    for b in range(1, model.nbody):
        parent = int(model.body_parentid[b])
        if (b != top and parent == 0) or not in_tree[parent]:
            continue
        in_tree[b] = True
        _add_body(model, b, names, links, joints, notes, source)
    for s in range(model.nsite):
        body = int(model.site_bodyid[s])
        if in_tree[body]:
            link = names.site[s]
            links.append(Link(name=link))
            joints.append(
                _fixed(names, link, names.body[body], pose_matrix(model.site_pos[s], model.site_quat[s]))
            )
    joints = _couple(model, names, joints, notes, source)
    others = [names.body[b] for b in range(1, model.nbody) if model.body_parentid[b] == 0 and b != top]
    if others and root is None:
        listed = ", ".join(repr(n) for n in others[:5]) + (", ..." if len(others) > 5 else "")
        notes.append(
            f"the world body holds {len(others) + 1} trees: loaded the one with the most joints, of body "
            f"{names.body[top]!r}, "
            f"not {listed}; pass root= to load another"
        )
    check_magnitudes(links, joints, source=source, limits=limits)
    description = assemble(names.model, links, joints, source=source, warnings=notes, limits=limits)
    return description


def _add_body(
    model: Any,
    b: int,
    names: MJCFNames,
    links: list[Link],
    joints: list[Joint],
    notes: list[str],
    source: str,
) -> None:
    """Link ``names.body[b]`` and the joints (and anchor links) that hang it from its parent body."""
    body = names.body[b]
    kinds = [int(model.jnt_type[j]) for j in _joints_of(model, b)]
    held = [j for j, k in zip(_joints_of(model, b), kinds, strict=True) if k in (FREE, BALL)]
    if held and model.body_parentid[b] == 0:
        what = ", ".join(
            f"{'free' if model.jnt_type[j] == FREE else 'ball'} joint {names.joint[j]!r}" for j in held
        )
        notes.append(
            f"body {body!r} hangs from the world by a {what}: kinengine models fixed-base robots, so "
            f"it is held at its pose in the file (qpos0) and the base's own motion is not a coordinate"
        )
    elif held:
        raise MJCFError(
            f"a {'free' if model.jnt_type[held[0]] == FREE else 'ball'} joint below the top body is not a "
            "kinematic joint kinengine models (hinge and slide are); replace it by hinges about three axes",
            source=source,
            element=f"joint {names.joint[held[0]]!r}",
        )
    moving = [j for j in _joints_of(model, b) if model.jnt_type[j] in (HINGE, SLIDE)]
    parent = names.body[int(model.body_parentid[b])]
    pending = pose_matrix(model.body_pos[b], model.body_quat[b])
    for k, j in enumerate(moving):
        axis = np.asarray(model.jnt_axis[j], dtype=float)
        q0 = float(model.qpos0[model.jnt_qposadr[j]])
        hinge = model.jnt_type[j] == HINGE
        anchor = np.asarray(model.jnt_pos[j], dtype=float) if hinge else np.zeros(3)
        at_origin = not anchor.any()
        child = body if k == len(moving) - 1 and at_origin else names.new_link(f"{body}__{names.joint[j]}")
        origin = pending @ translation(anchor) @ (_rotation(axis, -q0) if hinge else translation(-q0 * axis))
        lower = upper = None
        kind = "prismatic"
        if hinge:
            kind = "revolute" if model.jnt_limited[j] else "continuous"
        if model.jnt_limited[j]:
            lower, upper = (float(v) for v in model.jnt_range[j])
        elif not hinge:
            lower, upper = -UNLIMITED_SLIDE, UNLIMITED_SLIDE
        xyz, rpy = _xyz_rpy(origin)
        joints.append(
            Joint(
                name=names.joint[j],
                type=kind,
                parent=parent,
                child=child,
                xyz=xyz,
                rpy=rpy,
                axis=(float(axis[0]), float(axis[1]), float(axis[2])),
                lower=lower,
                upper=upper,
            )
        )
        if child != body:
            links.append(Link(name=child))
        parent, pending = child, translation(-anchor)
    links.append(Link(name=body, inertial=_inertial(model, b)))
    if parent != body:
        joints.append(_fixed(names, body, parent, pending))


def _couple(model: Any, names: MJCFNames, joints: list[Joint], notes: list[str], source: str) -> list[Joint]:
    """``joints`` with the linear joint equalities of ``model`` as mimics; other equalities noted."""
    by_name = {j.name: i for i, j in enumerate(joints)}
    ignored: list[str] = []
    for e in range(model.neq):
        label = f"equality {names.of(model, 'eq', e) or e}"
        if model.eq_type[e] != EQ_JOINT:
            ignored.append(label)
            continue
        j1, j2 = int(model.eq_obj1id[e]), int(model.eq_obj2id[e])
        c = [float(v) for v in model.eq_data[e, :5]]
        if j2 < 0:
            raise MJCFError(
                f"holds joint {names.joint[j1]!r} at a constant (no joint2): lock it instead, "
                f"robot.locked({{{names.joint[j1]!r}: value}})",
                source=source,
                element=label,
            )
        if any(c[2:]):
            raise MJCFError(
                f"polycoef {' '.join(f'{v:g}' for v in c)} couples joint {names.joint[j1]!r} to "
                f"{names.joint[j2]!r} by a nonlinear polynomial; kinengine couples joints linearly "
                "(a URDF mimic: polycoef c0 c1 0 0 0)",
                source=source,
                element=label,
            )
        follower, leader = names.joint[j1], names.joint[j2]
        if follower not in by_name or leader not in by_name:
            ignored.append(label + " (a joint outside the tree)")
            continue
        if not model.eq_active0[e]:
            ignored.append(label + " (inactive)")
            continue
        i = by_name[follower]
        first = joints[i].mimic
        if first is not None:
            raise MJCFError(
                f"joint {follower!r} is coupled twice (to {first.joint!r} and {leader!r})",
                source=source,
                element=label,
            )
        y0 = float(model.qpos0[model.jnt_qposadr[j1]])
        x0 = float(model.qpos0[model.jnt_qposadr[j2]])
        mimic = Mimic(joint=leader, multiplier=c[1], offset=y0 + c[0] - c[1] * x0)
        joints[i] = dataclasses.replace(joints[i], mimic=mimic)
    if ignored:
        notes.append(
            f"{len(ignored)} equality constraint(s) not modelled ({', '.join(ignored[:3])}"
            f"{', ...' if len(ignored) > 3 else ''}): kinengine keeps the kinematic tree and linear joint "
            "couplings, as MuJoCo's own mj_kinematics does"
        )
    return joints


def _top_body(model: Any, names: MJCFNames, root: str | None, source: str) -> int:
    tops = [b for b in range(1, model.nbody) if model.body_parentid[b] == 0]
    if not tops:
        raise MJCFError("the world body has no child body: there is no robot to load", source=source)
    if root is None:  # the tree with the most joints (a table or a floor beside the arm has none)
        joints = np.bincount(
            model.body_rootid[model.jnt_bodyid[model.jnt_type != FREE]], minlength=model.nbody
        )
        return max(tops, key=lambda b: (int(joints[b]), -b))
    for b in tops:
        if names.body[b] == root:
            return b
    known = ", ".join(repr(names.body[b]) for b in tops[:10])
    raise MJCFError(f"root={root!r} is not a child body of the world body; those are {known}", source=source)


def _joints_of(model: Any, b: int) -> range:
    start = int(model.body_jntadr[b])
    return range(start, start + int(model.body_jntnum[b])) if start >= 0 else range(0)


def _fixed(names: MJCFNames, child: str, parent: str, origin: npt.NDArray[np.float64]) -> Joint:
    xyz, rpy = _xyz_rpy(origin)
    return Joint(
        name=names.new_joint(f"{child}_fixed"), type="fixed", parent=parent, child=child, xyz=xyz, rpy=rpy
    )


def _inertial(model: Any, b: int) -> Inertial:
    xyz, rpy = _xyz_rpy(pose_matrix(model.body_ipos[b], model.body_iquat[b]))
    ixx, iyy, izz = (float(v) for v in model.body_inertia[b])
    return Inertial(mass=float(model.body_mass[b]), xyz=xyz, rpy=rpy, inertia=(ixx, 0.0, 0.0, iyy, 0.0, izz))


def pose_matrix(position: npt.ArrayLike, quaternion: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """(4, 4) transform of a position [m] and a unit quaternion (w, x, y, z), MuJoCo's order."""
    w, x, y, z = (float(v) for v in np.asarray(quaternion, dtype=float))
    T = np.eye(4)
    T[:3, :3] = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]
    T[:3, 3] = np.asarray(position, dtype=float)
    return T


def translation(p: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    T = np.eye(4)
    T[:3, 3] = p
    return T


def _rotation(axis: npt.NDArray[np.float64], angle: float) -> npt.NDArray[np.float64]:
    """(4, 4) rotation by ``angle`` [rad] about the unit ``axis`` (Rodrigues)."""
    x, y, z = axis
    K = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    T = np.eye(4)
    T[:3, :3] += math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)
    return T


def _xyz_rpy(T: npt.NDArray[np.float64]) -> tuple[Vector3, Vector3]:
    return (float(T[0, 3]), float(T[1, 3]), float(T[2, 3])), rpy_from_matrix(T[:3, :3])


class MJCFNames:
    """The URDF names of the model's bodies (``body[i]``), joints (``joint[i]``) and sites (``site[i]``):
    unique, bounded, never 'universe'; and fresh names for the links and joints kinengine adds."""

    def __init__(self, model: Any, source: str, limits: Limits) -> None:
        self.source, self.limits = source, limits
        self.model = self.of(model, "model", 0) or "mjcf"
        self.links: set[str] = set()
        self.joints: set[str] = set()
        self.body = [self.new_link(self.of(model, "body", b) or f"body{b}") for b in range(model.nbody)]
        self.joint = [self.new_joint(self.of(model, "jnt", j) or f"joint{j}") for j in range(model.njnt)]
        self.site = [self.new_link(self.of(model, "site", s) or f"site{s}") for s in range(model.nsite)]

    def of(self, model: Any, kind: str, i: int) -> str:
        """The name MuJoCo gives object ``i`` of ``kind`` ('body', 'jnt', 'site', 'eq', 'model'), or ''."""
        start = 0 if kind == "model" else int(getattr(model, f"name_{kind}adr")[i])
        raw = bytes(model.names[start : model.names.index(b"\0", start)])
        name = raw.decode("utf-8", errors="replace")
        if len(name) > self.limits.max_name_length:
            raise MJCFError(
                f"the {kind} name {name[:40]!r}... has {len(name)} characters, more than "
                f"Limits.max_name_length = {self.limits.max_name_length}",
                source=self.source,
            )
        return name

    def new_link(self, base: str) -> str:
        return self._fresh(base, self.links)

    def new_joint(self, base: str) -> str:
        return self._fresh(base, self.joints)

    @staticmethod
    def _fresh(base: str, used: set[str]) -> str:
        name, n = base, 1
        while name in used or name == "universe":
            n += 1
            name = f"{base}_{n}"
        used.add(name)
        return name


__all__ = ["UNLIMITED_SLIDE", "MJCFNames", "describe", "pose_matrix", "translation"]
