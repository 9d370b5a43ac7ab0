"""The optional C accelerator of the hot path, and the switch between it and pure Python.

``kinengine/model/fastcall.c`` is built by ``pip install`` when a C compiler is present (an optional
extension: without one the install goes on). It does three things the interpreter makes slow:

* the input check of a single q, :attr:`CoordinateMap.ready` (a float64 C-contiguous (dof,) array with
  every |q_i| <= MAX_MAGNITUDE): about 0.02 µs in C against 0.3 µs in Python;
* the batch chain of :mod:`kinengine.kinematics.chain` (``kinengine/kinematics/chainkernel.c``, loaded
  there): poses and Jacobians of N configurations, 64 side by side, without the GIL and with tens of kB
  of scratch per call, where numpy needs ~80 passes over chunks of configurations and 84 float64 rows
  of scratch each;
* a frame handle's plain calls ``pose(q)``, ``jacobian(q, reference)``, ``kinematics(q, reference)``:
  the same Pinocchio calls in the same order, on the same per-thread Data, without a Python frame.
  Anything else (a q that needs converting or refusing, a batch, another argument) goes to the
  pure-Python closures of :mod:`kinengine.kinematics.handle`, so results are equal bit for bit and
  every message is written once.

``AVAILABLE`` says whether the accelerator runs. It is off when the extension was not built or does not
import (numpy's C API is checked by its import), or when the environment variable
``KINENGINE_PURE_PYTHON`` is set to anything but "" or "0" (for comparisons). :func:`status` says
which, in the one line ``kinengine --version`` and ``kinengine info`` print.
"""

from __future__ import annotations

import importlib.machinery
import os
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

SWITCHED_OFF = os.environ.get("KINENGINE_PURE_PYTHON", "") not in ("", "0")
"""KINENGINE_PURE_PYTHON is set: no C module is used."""


LOAD_ERROR: str | None = None
"""Why the C module did not load (an ImportError's or the layout check's text), None when it did or when
KINENGINE_PURE_PYTHON is set."""


def _load() -> ModuleType | None:
    global LOAD_ERROR
    if SWITCHED_OFF:
        return None
    try:
        from . import fastcall
    except (
        ImportError
    ) as exc:  # not built (no C compiler at install time), or built against another numpy ABI
        LOAD_ERROR = str(exc)
        return None
    return fastcall


native: ModuleType | None = _load()
"""The C module, or None when kinengine runs in pure Python (tests set it to None to compare)."""

AVAILABLE = native is not None

PACKAGE = Path(__file__).resolve().parents[1]
"""The folder of the kinengine package this process imported."""

EXTENSIONS = {"fastcall": "kinengine/model", "chainkernel": "kinengine/kinematics"}
"""The C extensions (module name: folder relative to the package's parent), all optional."""


def _built(name: str, package: Path) -> bool:
    """Whether the extension file for this Python (e.g. fastcall.cpython-311-x86_64-linux-gnu.so) exists."""
    folder = package.parent / EXTENSIONS[name]
    return any((folder / f"{name}{suffix}").is_file() for suffix in importlib.machinery.EXTENSION_SUFFIXES)


def status(
    missing: dict[str, str | None],
    *,
    switched_off: bool = SWITCHED_OFF,
    package: Path = PACKAGE,
) -> str:
    """One line: whether the C accelerator is on and, if not, why. ``missing`` maps each C extension
    that did not load (``fastcall``, ``chainkernel``) to its load error (None: not known); empty when
    both loaded. ``package`` is the kinengine folder imported (a checkout when it sits beside a
    pyproject.toml)."""
    if switched_off:
        return "accelerator: off (pure Python): disabled by KINENGINE_PURE_PYTHON (unset it, or set it to 0)"
    if not missing:
        return "accelerator: on (C extensions fastcall and chainkernel loaded)"
    names = " and ".join(sorted(missing))
    unbuilt = [name for name in missing if not _built(name, package)]
    if unbuilt and (package.parent / "pyproject.toml").is_file():
        why = (
            f"kinengine is imported from the source tree {package.parent}, where the C extensions are not "
            "built; `pip install -e .` there builds them in place (a C compiler is needed), or run from "
            "another folder to import the installed kinengine"
        )
    elif unbuilt:
        why = (
            "the C extensions were not built when kinengine was installed (no working C compiler then); "
            "install a binary wheel, or a compiler and reinstall kinengine"
        )
    else:
        errors = "; ".join(f"{name}: {error}" for name, error in sorted(missing.items()) if error)
        why = f"the built extensions do not load ({errors or 'unknown error'})"
    return f"accelerator: off (pure Python, {names} missing): {why}"


def ready_check(dof: int, limit: float) -> Callable[[object], bool] | None:
    """The C predicate for :attr:`CoordinateMap.ready`, or None (then the caller builds the Python one)."""
    return None if native is None else native.Ready(dof, limit).check


def frame_calls(**bound: Any) -> tuple[Callable[..., Any], Callable[..., Any], Callable[..., Any]] | None:
    """(pose, jacobian, kinematics) in C for one frame, or None. ``bound`` names what
    :mod:`kinengine.kinematics.handle` binds: dof, limit, checking, model, frame_id, local, state, forward,
    place, frame_jacobian, references, default_reference, local_reference, and the pure-Python
    slow_pose, slow_jacobian, slow_kinematics that take every call the C side does not."""
    if native is None:
        return None
    calls = native.FrameCalls(**bound)
    return calls.pose, calls.jacobian, calls.kinematics


__all__ = ["AVAILABLE", "LOAD_ERROR", "SWITCHED_OFF", "frame_calls", "native", "ready_check", "status"]
