"""Mimic joints in the model: each follower resolved to its root leader (θ = m·q_leader + o, chains
composed), and the leader's limits narrowed so that every follower stays within its own limits."""

from __future__ import annotations

import warnings

import numpy as np

from ..urdf import RobotDescription


def mimic_roots(description: RobotDescription) -> dict[str, tuple[str, float, float]]:
    """Mimic joint name -> (root leader, multiplier, offset), chains of mimics composed:
    θ_a = m₁θ_b + o₁ and θ_b = m₂θ_c + o₂ give θ_a = (m₁m₂)θ_c + (m₁o₂ + o₁)."""
    direct = {j.name: j.mimic for j in description.joints if j.movable and j.mimic is not None}
    roots: dict[str, tuple[str, float, float]] = {}
    for name in direct:
        multiplier, offset, leader, seen = 1.0, 0.0, name, {name}
        while leader in direct:  # the parser has refused cycles
            m = direct[leader]
            multiplier, offset = multiplier * m.multiplier, multiplier * m.offset + offset
            leader = m.joint
            if leader in seen:
                raise AssertionError(f"mimic cycle through {leader!r}")
            seen.add(leader)
        roots[name] = (leader, multiplier, offset)
    return roots


def narrow_by_mimics(
    description: RobotDescription,
    roots: dict[str, tuple[str, float, float]],
    index: dict[str, int],
    names: tuple[str, ...],
    lower: np.ndarray,
    upper: np.ndarray,
) -> dict[int, list[str]]:
    """A coordinate's limits also keep each mimic joint that follows it within that joint's own limits:
    lower ≤ m·q + o ≤ upper of the follower, i.e. q within [(lower − o)/m, (upper − o)/m]
    (swapped if m < 0).
    A follower whose limits would leave the leader an empty or zero-width range (sloppy gripper URDFs,
    e.g. a vendor's Robotiq 2F-85) is not enforced; one warning per leader names every such follower,
    and the leader keeps its own limits (narrowed by its other followers only)."""
    ignored: dict[int, list[tuple[str, str]]] = {}
    narrowed: dict[int, list[str]] = {}
    for joint in description.joints:
        if joint.name not in roots or joint.lower is None or joint.upper is None:
            continue
        root, m, o = roots[joint.name]
        if m == 0.0:
            continue
        i = index[root]
        a, b = (joint.lower - o) / m, (joint.upper - o) / m
        lo, hi = max(lower[i], min(a, b)), min(upper[i], max(a, b))
        follows = f"{joint.name!r} = {m:g}·q + {o:g} within [{joint.lower:g}, {joint.upper:g}]"
        if not lo < hi:
            ignored.setdefault(i, []).append(("no value" if lo > hi else "only one value", follows))
        elif lo > lower[i] or hi < upper[i]:
            lower[i], upper[i] = lo, hi
            narrowed.setdefault(i, []).append(follows)
    for i, ((what, follows), *more) in ignored.items():
        likewise = "".join(f"; likewise mimic joint {f} ({w})" for w, f in more)
        warnings.warn(
            f"{description.source}: {what} of joint {names[i]!r} keeps it within its limits and "
            f"mimic joint {follows}; the mimic joint's limits are not enforced{likewise}; "
            f"{names[i]!r} keeps [{lower[i]:g}, {upper[i]:g}]",
            UserWarning,
            stacklevel=4,
        )
    return narrowed
