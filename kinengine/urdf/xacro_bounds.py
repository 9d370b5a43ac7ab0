"""The bounds kinengine's safe xacro evaluator (:mod:`.xacro_eval`) adds to ``simpleeval``'s.

simpleeval bounds powers, shifts and the length of strings and lists each operation makes; an
expression can still build a huge integer by repeated multiplication, a huge text with ``%`` or
``str()`` of a list that repeats one long string, or a long loop with ``range``. Owns those bounds:
the operators and functions the evaluator uses in place of the plain ones, and :func:`text_size`.
"""

from __future__ import annotations

import ast
import math
import operator
from collections.abc import Callable, Mapping
from typing import Any

import simpleeval

SIMPLEEVAL_REQUIREMENT = "simpleeval>=1.0.3,<2"
MAX_INT_BITS = 4096
"""Largest integer an expression may make [bits] (a double's range needs 1,024)."""
MAX_ITEMS = simpleeval.MAX_COMPREHENSION_LENGTH
"""Longest ``range`` and comprehension."""
MAX_TEXT = 1_000_000
"""Longest text of one expression's result [characters] (xacro writes every result with ``str``)."""
STRING_METHODS = frozenset(
    {"split", "rsplit", "strip", "lstrip", "rstrip", "startswith", "endswith", "lower", "upper"}
)
"""Methods a string may call (each one's result is no longer than the string)."""
SLOW_MATH = frozenset({"factorial", "comb", "perm", "prod", "lcm"})
MATH = {k: v for k, v in vars(math).items() if not k.startswith("_") and k not in SLOW_MATH}
"""xacro's math names (its ``math.*`` and bare names), less those whose cost grows with the argument."""
XACRO_NAMES = (
    "load_yaml",
    "arg",
    "tokenize",
    "dotify",
    "abs_filename",
    "message",
    "warning",
    "error",
    "fatal",
)


class Refused(simpleeval.InvalidExpression):
    """An expression uses something outside the allow-list or past a bound."""


def check_int(value: object) -> object:
    if type(value) is int and value.bit_length() > MAX_INT_BITS:
        raise Refused(f"an integer of more than {MAX_INT_BITS} bits")
    return value


def _power(a: Any, b: Any) -> Any:
    if isinstance(a, int) and isinstance(b, int) and b > 0 and (abs(a).bit_length() - 1) * b > MAX_INT_BITS:
        raise Refused(f"{a} ** {b} has more than {MAX_INT_BITS} bits")
    return check_int(a**b)


def _multiply(a: Any, b: Any) -> Any:
    return check_int(simpleeval.safe_mult(a, b))


def _modulo(a: Any, b: Any) -> Any:
    if isinstance(a, (str, bytes)):
        raise Refused("'%' formatting of strings")
    return a % b


def _range(*args: int) -> range:
    result = range(*args)
    if len(result) > MAX_ITEMS:
        raise Refused(f"range of {len(result)} elements (at most {MAX_ITEMS})")
    return result


def _round(number: Any, ndigits: int | None = None) -> Any:
    if ndigits is not None and abs(operator.index(ndigits)) > 400:
        raise Refused(f"round(..., {ndigits}): at most 400 digits")
    return number if ndigits is None and isinstance(number, int) else round(number, ndigits)


def text_size(value: object, limit: int = MAX_TEXT) -> int:
    """An upper estimate of ``len(str(value))``, stopping once it passes ``limit``."""
    if isinstance(value, (str, bytes)):
        return len(value) + 2
    if isinstance(value, Mapping):
        items: list[object] = [*value.keys(), *value.values()]
    elif isinstance(value, (list, tuple, set, frozenset, range)):
        items = list(value) if not isinstance(value, range) else []
    else:
        return 32 if not isinstance(value, int) else value.bit_length() // 3 + 2
    total = 2
    for item in items:
        total += text_size(item, limit - total) + 2
        if total > limit:
            break
    return total


def _str(*args: Any) -> str:
    if args and text_size(args[0]) > MAX_TEXT:
        raise Refused(f"str() of a value of more than {MAX_TEXT} characters")
    return str(*args)


FUNCTIONS: dict[str, Callable[..., Any]] = {
    "len": len,
    "min": min,
    "max": max,
    "abs": abs,
    "round": _round,
    "int": int,
    "float": float,
    "str": _str,
    "bool": bool,
    "list": list,
    "tuple": tuple,
    "dict": dict,
    "set": set,
    "range": _range,
}
OPERATORS = {
    **simpleeval.DEFAULT_OPERATORS,
    ast.Pow: _power,
    ast.Mult: _multiply,
    ast.Mod: _modulo,
    ast.LShift: lambda a, b: check_int(simpleeval.safe_lshift(a, b)),
}
