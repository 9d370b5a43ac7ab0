"""The control layer: the Task (a controller's one-call update), inverse kinematics, singularity
measures (manipulability, velocity ellipsoids) and the continuity rules of pose parameters.

Owns :class:`LazyModule`, which lets the Robot's method groups reach a control module (inverse
kinematics: seeds, targets, solver) that is imported on first use, not by ``import kinengine``.
"""

from __future__ import annotations

from importlib import import_module


class LazyModule:
    """Stands for the module ``name``: the first attribute read imports it (thread-safe, as every import);
    each read is then the module's attribute, as with a plain ``import`` (a replaced attribute is seen)."""

    __slots__ = ("name",)

    def __init__(self, name: str) -> None:
        self.name = name

    def __getattr__(self, attribute: str) -> object:
        return getattr(import_module(self.name), attribute)

    def __repr__(self) -> str:
        return f"<lazily imported module {self.name!r}>"
