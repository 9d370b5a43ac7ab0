"""The size limits every URDF must respect before kinengine does any real work.

They bound what a hostile or broken file can cost: the XML limits are checked
on the raw document, the model limits on the element counts, both before any
number is read or any tree is walked. Pass your own :class:`Limits` as ``limits=`` to
:func:`kinengine.load`, :func:`kinengine.load_urdf_string` or :func:`kinengine.urdf.parse_urdf`
to load a bigger model.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, fields

from ..errors import OptionError


@dataclass(frozen=True)
class Limits:
    """Parser and model-size limits (defaults in :data:`LIMITS`).

    - ``max_bytes``: size of the document [bytes] (a ``str`` counts in UTF-8).
    - ``max_tags``: number of ``<`` in the document, an upper bound of its elements.
    - ``max_depth``: element nesting depth, ``<robot>`` being depth 1.
    - ``max_attribute_length``: characters in any attribute value.
    - ``max_name_length``: characters in a robot, link, joint or mimic-target name.
    - ``max_links``, ``max_joints``: ``<link>`` and ``<joint>`` elements of ``<robot>``.
    - ``max_movable_joints``: joints whose type is not ``fixed`` (mimic joints included). Each
      Pinocchio ``Data`` (a Robot makes one per thread that uses it, a Task one more) grows like
      32·nv³ bytes and briefly needs twice that while it is made. Measured on pin 4.1 (resident memory
      added by ``createData()`` / its peak):
      nv = 64: 12 / 20 MiB, 128: 73 / 139 MiB, 192: 234 / 455 MiB, 256: 542 / 1062 MiB.
      128 keeps one Data under ~75 MiB and covers every example-robot-data model (at most 101).
    - ``max_tree_depth``: joints (fixed ones included) between the root and any link. Pinocchio's
      C++ URDF parser recurses once per level, ~2 KiB of stack each: measured on pin 4.1, a chain
      of ~3,800 levels overflows the 8 MiB main-thread stack, ~470 a 1 MiB thread stack, ~220 a
      512 KiB one. 128 levels need ~300 KiB, less than any platform's default thread stack. Pinocchio's
      build runs on a thread with a 16 MiB stack whatever thread loads the robot (see
      :mod:`kinengine.model.stack`; deeper trees get ~4 KiB per level), so the limit may be raised.
    - ``max_offset`` [m]: |x| of every joint and inertial origin coordinate and mimic offset, and
      ``max_multiplier``: |m| of every mimic multiplier (see :mod:`kinengine.urdf.magnitudes`): numbers
      finite one by one must not overflow a pose together.
    - ``max_macro_calls``: xacro macro calls one expansion may make (the most among the 133 vendor robot
      xacros that load is 117, franka's multi_arm; a macro that calls the next twice makes 2^depth).
    - ``max_xacro_seconds`` [s]: wall time of one xacro expansion (vendor robot xacros take well under
      a second each); both refused with :class:`~kinengine.errors.ResourceLimitError`.
    - ``max_xacro_memory`` [bytes]: address space of the child process that runs a trusted expansion
      (``trust_xacro=True``; the child starts at ~250 MB with Python, numpy and xacro); more is refused
      with ResourceLimitError. Enforced through ``RLIMIT_AS`` on Linux; macOS does not enforce it and
      Windows lacks it (there only the time bound holds).

    Each field is checked when a Limits is made (OptionError): a whole number (a finite real for
    ``max_offset``, ``max_multiplier`` and ``max_xacro_seconds``) within its bounds in :data:`BOUNDS`.
    """

    max_bytes: int = 32 * 1024 * 1024
    max_tags: int = 1_000_000
    max_depth: int = 64
    max_attribute_length: int = 4096
    max_name_length: int = 256
    max_links: int = 4096
    max_joints: int = 4096
    max_movable_joints: int = 128
    max_tree_depth: int = 128
    max_offset: float = 1e6
    max_multiplier: float = 1e6
    max_macro_calls: int = 5_000
    max_xacro_seconds: float = 60.0
    max_xacro_memory: int = 4 * 1024**3

    def __post_init__(self) -> None:
        for f in fields(self):
            value, (low, high) = getattr(self, f.name), BOUNDS[f.name]
            real = f.type in ("float", float)
            kinds = (numbers.Real,) if real else (numbers.Integral,)
            if (
                isinstance(value, bool)
                or not isinstance(value, kinds)
                or not ((not real or math.isfinite(value)) and not value < low and value <= high)
            ):
                kind = "a finite real number" if real else "a whole number"
                span = f"[{low:g}, {high:g}]" if real else f"[{low}, {high}]"
                raise OptionError(f"Limits.{f.name} must be {kind} in {span}, got {value!r}")


BOUNDS: dict[str, tuple[float, float]] = {
    "max_bytes": (1, 2**31),
    "max_tags": (1, 2**31),
    "max_depth": (1, 256),  # libxml2 itself refuses deeper nesting (lxml's huge_tree is off)
    "max_attribute_length": (1, 10**7),
    "max_name_length": (1, 10**6),
    "max_links": (1, 10**6),
    "max_joints": (1, 10**6),
    "max_movable_joints": (0, 10**6),  # Data beyond the memory left is refused when it is made
    "max_tree_depth": (1, 10**6),  # the build thread's stack grows with the depth
    "max_offset": (1e-9, 1e100),
    "max_multiplier": (1e-9, 1e100),
    "max_macro_calls": (1, 10**9),
    "max_xacro_seconds": (1e-3, 1e6),
    "max_xacro_memory": (2**28, 2**48),
}
"""(smallest, largest) value of each Limits field."""

LIMITS = Limits()
