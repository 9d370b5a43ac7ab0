"""Checks of the keyword options every public entry point shares: each bad value is one OptionError
(or ParameterizationError for parameterization names and rows) naming the option and what it takes.
The fast path of each is one ``type(...) is float`` test.
"""

from __future__ import annotations

import math
import numbers

import numpy as np

from ..errors import OptionError, ParameterizationError


def checked_nonnegative(value: object, name: str) -> float:
    """``value`` as a float if it is a finite real number >= 0; OptionError otherwise."""
    return number_option(name, value)


def number_option(
    what: str, value: object, low: float = 0.0, high: float = math.inf, open_low: bool = False
) -> float:
    """A finite real number in [low, high] ((low, high] with open_low), else OptionError naming ``what``."""
    if type(value) is float:  # the common case, checked cheaply
        x = value
        if (x > low if open_low else x >= low) and x <= high and x - x == 0.0:  # in range and finite
            return x
    if high == math.inf and not open_low:
        bound = f">= {low:g}"
    else:
        bound = f"in ({low:g}, {high:g}]" if open_low else f"in [{low:g}, {high:g}]"
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise OptionError(f"{what} must be a real number {bound}, got {type(value).__name__} {_short(value)}")
    try:
        x = float(value)
    except (OverflowError, TypeError, ValueError):  # e.g. an int beyond float range
        x = math.nan
    if not (math.isfinite(x) and (x > low if open_low else x >= low) and x <= high):
        raise OptionError(f"{what} must be a finite real number {bound}, got {_short(value)}")
    return x


def checked_threshold(value: object) -> float:
    """A valid ``singularity_threshold`` [distance to the parameterization's singular set]: NaN or a negative
    value would switch the singularity check off."""
    return checked_nonnegative(value, "singularity_threshold")


def checked_tolerance(value: object) -> float:
    """A valid ``tolerance`` [singular-value threshold]."""
    return checked_nonnegative(value, "tolerance")


def checked_flag(value: object, name: str) -> bool:
    """``value`` if it is a bool (or numpy bool); OptionError otherwise (an array's truth is ambiguous)."""
    if value is True or value is False:
        return value
    if isinstance(value, np.bool_):
        return bool(value)
    raise OptionError(f"{name} must be True or False, got {type(value).__name__} {_short(value)}")


def checked_frames(frames: object, kinds: tuple[type, ...]) -> None:
    """OptionError unless ``frames`` is None, one entry of ``kinds`` (a name, a FrameTask) or a list or tuple
    of them (an empty one is left to the task to refuse)."""
    if frames is None or isinstance(frames, kinds):
        return
    for bad in frames if isinstance(frames, (list, tuple)) else [frames]:
        if not isinstance(bad, kinds):
            raise OptionError(
                f"a task's frames are frame names or kinengine.FrameTask entries, got {_short(bad)}"
            )


def checked_seed(rng: object) -> object:
    """``rng`` as numpy's ``default_rng`` takes it: None (fresh entropy), a seed (a whole number >= 0), a
    Generator, BitGenerator or SeedSequence; OptionError otherwise."""
    if rng is None or isinstance(rng, (np.random.Generator, np.random.BitGenerator, np.random.SeedSequence)):
        return rng
    if isinstance(rng, (bool, np.bool_)) or not isinstance(rng, numbers.Integral) or rng < 0:
        raise OptionError(
            f"rng must be None, a seed (a whole number >= 0), a numpy.random.Generator, BitGenerator or "
            f"SeedSequence, got "
            f"{type(rng).__name__} {_short(rng)}"
        )
    return int(rng)


def checked_rng(rng: object) -> np.random.Generator:
    """A numpy Generator from ``rng`` (:func:`checked_seed`; a Generator: itself)."""
    return np.random.default_rng(checked_seed(rng))  # type: ignore[arg-type]


def checked_parameterization(position: object, rotation: object, rows: object) -> tuple:
    """(position, rotation, rows as a tuple or None), each of a valid type; ParameterizationError otherwise
    (the names and labels themselves are checked by the pose map)."""
    for option, value in (("position", position), ("rotation", rotation)):
        if value is not None and type(value) is not str:
            raise ParameterizationError(
                f"{option} must be a parameterization name (str) or None, got "
                f"{type(value).__name__} {_short(value)}"
            )
    if rows is None:
        return position, rotation, None
    if isinstance(rows, str):
        return position, rotation, (rows,)
    if isinstance(rows, (bytes, dict)) or not hasattr(rows, "__iter__"):
        raise ParameterizationError(
            "rows must be None, a row label or a sequence of labels (str) and "
            f"indices (int), got {type(rows).__name__} {_short(rows)}"
        )
    selected = tuple(rows)
    for row in selected:
        index = isinstance(row, (int, np.integer)) and not isinstance(row, (bool, np.bool_))
        if not (type(row) is str or index):
            raise ParameterizationError(
                f"rows must hold labels (str) and indices (int), got {type(row).__name__} {_short(row)}"
            )
    return position, rotation, selected


def _short(value: object) -> str:
    text = " ".join(repr(value).split())  # one line, e.g. for a numpy array
    return text if len(text) <= 40 else text[:37] + "..."


__all__ = [
    "checked_flag",
    "checked_frames",
    "checked_nonnegative",
    "checked_parameterization",
    "checked_rng",
    "checked_seed",
    "checked_threshold",
    "checked_tolerance",
    "number_option",
]
