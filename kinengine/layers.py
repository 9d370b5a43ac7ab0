"""The architecture, written once: kinengine's layers from the bottom up.

A module may import modules of its own layer or of lower layers, never of a higher one; the
command line imports only the public API. Layers above the kinematics take a Robot object as an
argument and use its public methods, typed against a Protocol of their own layer or a lower one
(``kinengine.control.robot_like.RobotLike``), never against the facade's class; only the facade
(``kinengine.robot``) constructs one.
``tests/test_architecture.py`` reads every module's imports from the source (ast) and enforces these
rules, no import cycles, and no import of another module's private (underscore) names.
"""

from __future__ import annotations

LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("errors and array types", ("kinengine.errors", "kinengine.arrays")),
    ("description and math", ("kinengine.urdf", "kinengine.parameterizations", "kinengine.reference")),
    ("model", ("kinengine.model", "kinengine.mjcf")),
    ("kinematics", ("kinengine.kinematics",)),
    ("analytic", ("kinengine.analytic",)),
    ("collision", ("kinengine.collision",)),
    ("control", ("kinengine.control",)),
    ("tools and presentation", ("kinengine.verify", "kinengine.presentation")),
    ("facade", ("kinengine.robot", "kinengine.loading")),
    ("workspace", ("kinengine.workspace",)),
    ("public API", ("kinengine", "kinengine.layers")),
    ("command line", ("kinengine.cli", "kinengine.__main__")),
)
"""(layer name, module prefixes) from the bottom up; a module belongs to the longest prefix it matches."""

PUBLIC_API: tuple[str, ...] = (
    "kinengine",
    "kinengine.errors",
    "kinengine.parameterizations",
    "kinengine.urdf",
    "kinengine.collision",
    "kinengine.verify",
    "kinengine.reference",
    "kinengine.presentation",
    "kinengine.loading",
    "kinengine.robot",
    "kinengine.workspace",
)
"""What the command line may import (besides its own modules)."""

INDEPENDENT: tuple[str, ...] = ("kinengine.reference",)
"""Packages that must import nothing of kinengine but its errors (the independent reference)."""


def layer_of(module: str) -> int:
    """Index into LAYERS of a dotted module name (ValueError if it belongs to none)."""
    best, index = -1, -1
    for i, (_, prefixes) in enumerate(LAYERS):
        for prefix in prefixes:
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > best:
                best, index = len(prefix), i
    if index < 0:
        raise ValueError(f"module {module!r} belongs to no layer of kinengine.layers.LAYERS")
    return index


__all__ = ["INDEPENDENT", "LAYERS", "PUBLIC_API", "layer_of"]
