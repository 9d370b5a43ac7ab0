"""A joint range's angles, numpy over many candidates (M, n) of a closed-form IK chain: wrapping into
(−π, π], the 2π shift into each joint's range nearest a reference, and every shift within the limits
(``all_turns``). kinengine/kinematics/chainkernel.c's ``place`` is the C twin of :func:`wrap_pi` and
:func:`shifted_into_ranges` (see :mod:`.ik_candidates`).
"""

from __future__ import annotations

import numpy as np

from .ik_solutions import TURN_TOL, TWO_PI, Chain


def wrap_pi(a: np.ndarray) -> np.ndarray:
    """Angles into (−π, π] (the solver's are in [−π, π] already: then only −π moves)."""
    if len(a) and np.abs(a).max() <= np.pi:
        return np.where(a == -np.pi, np.pi, a)
    return np.pi - np.mod(np.pi - a, TWO_PI)


def shifted_into_ranges(
    chain: Chain, wrapped: np.ndarray, ref: np.ndarray | None, shifts: bool
) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray] | None]:
    """Angles (M, n) in (−π, π] shifted by 2π·k into the joint ranges: k nearest (ref − angle)/2π (ref None:
    0) among k_min..k_max (the shifts inside [lower, upper], a limit met to TURN_TOL: on it); continuous
    joints unshifted; a joint no shift puts inside keeps the shift nearest ref. A range within (−π, π]
    (``chain.one_turn``) has only k = 0. Returns (angles, inside (M,), and with ``shifts`` (k_min, k_max,
    k_best) (M, n), 0 for continuous and one-turn joints)."""
    angles = wrapped.copy()
    inside = np.ones(len(wrapped), dtype=bool)
    one, many = chain.one_turn, chain.many_turns
    if len(one):
        w, lo, hi = wrapped[:, one], chain.lower[one], chain.upper[one]
        fits = (w >= lo - TURN_TOL) & (w <= hi + TURN_TOL)
        inside &= fits.all(axis=1)
        on = np.minimum(np.maximum(w, lo), hi)
        if ref is not None:  # no shift fits: the one nearest the reference
            w = w + TWO_PI * np.rint((ref[:, one] - w) / TWO_PI)
        angles[:, one] = np.where(fits, on, w)
    k = None
    if len(many):
        w, lo, hi = wrapped[:, many], chain.lower[many], chain.upper[many]
        k_min = np.ceil((lo - w) / TWO_PI - 1e-12)
        k_max = np.floor((hi - w) / TWO_PI + 1e-12)
        k_near = np.zeros_like(w) if ref is None else np.rint((ref[:, many] - w) / TWO_PI)
        fits = k_min <= k_max
        inside &= fits.all(axis=1)
        k_best = np.where(fits, np.minimum(np.maximum(k_near, k_min), k_max), k_near)
        a = w + TWO_PI * k_best
        angles[:, many] = np.where(fits, np.minimum(np.maximum(a, lo), hi), a)
        k = (k_min, k_max, k_best)
    if not shifts:
        return angles, inside, None
    full = tuple(np.zeros_like(wrapped) for _ in range(3))
    if k is not None:
        for f, part in zip(full, k, strict=True):
            f[:, many] = part
    return angles, inside, full  # type: ignore[return-value]


def all_turns_of(
    chain: Chain,
    row: np.ndarray,
    inside: np.ndarray,
    full: np.ndarray,
    k_min: np.ndarray,
    k_max: np.ndarray,
    k_best: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every 2π shift of each within-limits solution's joints whose range holds several (``many_turns``)
    that stays within the limits (the chosen one first), joint by joint: each solution repeated once per
    shift of that joint."""
    for j in chain.many_turns:
        shifts = np.where(inside, np.maximum(k_max[:, j] - k_min[:, j] + 1, 1), 1).astype(np.intp)
        source = np.repeat(np.arange(len(row)), shifts)
        step = np.arange(len(source)) - np.repeat(np.cumsum(shifts) - shifts, shifts)
        k = np.where(inside[source], k_min[source, j] + step, k_best[source, j])
        chosen = k == k_best[source, j]
        order = np.lexsort((~chosen, source))  # the chosen shift first within each solution
        source, k = source[order], k[order]
        row, inside, full = row[source], inside[source], full[source]
        k_min, k_max, k_best = k_min[source], k_max[source], k_best[source]
        full[:, chain.columns[j]] += TWO_PI * (k - k_best[:, j])
    return row, inside, full


__all__ = ["all_turns_of", "shifted_into_ranges", "wrap_pi"]
