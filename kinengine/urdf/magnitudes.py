"""Bounds on a model's magnitudes: numbers finite one by one must not overflow together.

Two fixed joints at ``xyz="1e308 0 0"`` are each a finite number, yet their composition is inf and
every pose below them inf or NaN. So after the elements are read, every length the kinematics adds up
is bounded by :attr:`Limits.max_offset` [m] (joint and inertial origins, mimic offsets) and every
factor it multiplies by by :attr:`Limits.max_multiplier` (mimic multipliers). With at most
:attr:`Limits.max_tree_depth` joints between the root and a link and configurations bounded by
:data:`kinengine.model.coordinates.MAX_MAGNITUDE`, no pose or Jacobian can then overflow. Joint
limits are not bounded here (real files write ±1e16 for "no limit"); sampling clips them.
"""

from __future__ import annotations

from collections.abc import Sequence

from ..errors import URDFError
from .description import Joint, Link
from .limits import LIMITS, Limits


def check_magnitudes(
    links: Sequence[Link], joints: Sequence[Joint], *, source: str, limits: Limits = LIMITS
) -> None:
    """URDFError naming the element and the bound for the first number beyond the limits' magnitudes."""
    offset, factor = limits.max_offset, limits.max_multiplier
    for joint in joints:
        where = f"joint {joint.name!r}"
        _bounded(joint.xyz, offset, "origin xyz", "max_offset", "m", where, joint.line, source)
        if joint.mimic is not None:
            _bounded(
                (joint.mimic.offset,),
                offset,
                "mimic offset",
                "max_offset",
                "m or rad",
                where,
                joint.line,
                source,
            )
            _bounded(
                (joint.mimic.multiplier,),
                factor,
                "mimic multiplier",
                "max_multiplier",
                "",
                where,
                joint.line,
                source,
            )
    for link in links:
        if link.inertial is not None:
            _bounded(
                link.inertial.xyz,
                offset,
                "inertial origin xyz",
                "max_offset",
                "m",
                f"link {link.name!r}",
                link.line,
                source,
            )


def _bounded(
    values: Sequence[float],
    bound: float,
    what: str,
    field: str,
    unit: str,
    where: str,
    line: int | None,
    source: str,
) -> None:
    for value in values:
        if not abs(value) <= bound:
            raise URDFError(
                f"{what} {value!r} is beyond ±{bound:g}{' ' + unit if unit else ''} "
                f"(Limits.{field}), where poses could overflow; fix the number or pass "
                f"limits=Limits({field}=...)",
                source=source,
                element=where,
                line=line,
            )


__all__ = ["check_magnitudes"]
