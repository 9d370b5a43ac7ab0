"""MJCF (MuJoCo XML) models through MuJoCo's own compiler, as kinengine's own description.

:func:`read_mjcf_file` (:mod:`.reader`) compiles the file with ``mujoco.MjSpec`` (:mod:`.compiler`) after the
safety and size checks of :mod:`.compiler`, and converts the compiled model (:mod:`.convert`) into a
:class:`~kinengine.urdf.RobotDescription` and an equivalent kinematic URDF, which is what Pinocchio, the
independent reference of ``kinengine verify`` and the viewer read. :func:`.crosscheck.cross_check`
compares a loaded robot with MuJoCo's own kinematics. Needs ``pip install 'kinengine[mjcf]'``. Only
:func:`is_mjcf` is imported with the package; the rest (numpy, model editing) on first use.
"""

from __future__ import annotations

from importlib import import_module

from .compiler import is_mjcf

_LAZY = {"read_mjcf_file": "reader", "describe": "convert", "cross_check": "crosscheck"}


def __getattr__(name: str) -> object:
    """A lazily imported public name (see the module doc)."""
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(import_module(f".{_LAZY[name]}", __name__), name)


__all__ = ["cross_check", "describe", "is_mjcf", "read_mjcf_file"]
