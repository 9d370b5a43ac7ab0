"""What one xacro expansion may spend, and the files it reads.

Owns :class:`Budget` (macro calls, expanded bytes, bytes read and wall time of one expansion, from its
:class:`~kinengine.urdf.Limits`), :class:`MacroStack` (xacro's stack of macros being expanded, which
charges each call to the budget) and :func:`read_file` (every file xacro reads, opened by
:func:`.source.read_bytes_once`: without blocking, regular files only). Used by :mod:`.xacro`.
"""

from __future__ import annotations

import errno
import os
import re
import time
from types import ModuleType
from typing import Any
from xml.sax.saxutils import quoteattr

from ..errors import ResourceLimitError, URDFError
from .limits import Limits
from .source import read_bytes_once


class Budget:
    """What one expansion may still spend: bytes read, macro calls, expanded bytes, wall time."""

    def __init__(self, limits: Limits) -> None:
        self.limits = limits
        self.read = limits.max_bytes
        self.calls = limits.max_macro_calls
        self.written = limits.max_bytes
        self.deadline = time.monotonic() + limits.max_xacro_seconds
        self.texts: dict[str, str] = {}  # file -> its text, to find the line of a refused expression
        self.body_sizes: dict[int, tuple[object, int]] = {}

    def tick(self) -> None:
        if time.monotonic() > self.deadline:
            raise ResourceLimitError(
                f"{failing_file('?')}: the xacro expansion takes more than Limits.max_xacro_seconds = "
                f"{self.limits.max_xacro_seconds:g} s; pass kinengine.load(..., limits=Limits("
                "max_xacro_seconds=...)) if the file is meant to be that large"
            )

    def macro_call(self, body: object) -> None:
        self.tick()
        self.calls -= 1
        if self.calls < 0:
            raise ResourceLimitError(
                f"{failing_file('?')}: the xacro expansion makes more than Limits.max_macro_calls = "
                f"{self.limits.max_macro_calls} macro calls (a macro that expands exponentially?); "
                "pass kinengine.load(..., limits=Limits(max_macro_calls=...)) if the file is meant to make "
                "that many"
            )
        if body is None:
            return
        known = self.body_sizes.get(id(body))
        if known is None or known[0] is not body:
            known = (body, len(body.toxml()))  # type: ignore[attr-defined]
            self.body_sizes[id(body)] = known
        self.written -= known[1]
        if self.written < 0:
            raise ResourceLimitError(
                f"{failing_file('?')}: the xacro expansion writes more than Limits.max_bytes = "
                f"{self.limits.max_bytes} bytes (a macro that expands exponentially?)"
            )

    def locate(self, expression: str) -> tuple[str, int | None]:
        file = failing_file("?")
        text = self.texts.get(file, "")
        escaped = quoteattr(expression)[1:-1]
        for written in (expression, escaped, escaped.replace("&quot;", '"')):  # as written in the XML
            spaced = r"\s*".join(map(re.escape, "".join(written.split())))  # spaces as the file has them
            found = re.search(spaced, text)
            if found:
                return file, text.count("\n", 0, found.start()) + 1
        return file, None


class MacroStack(list):
    """xacro's stack of the macros being expanded; each push is one macro call, charged to the budget."""

    def __init__(self, budget: Budget) -> None:
        super().__init__()
        self.budget = budget

    def append(self, macro: Any) -> None:
        self.budget.macro_call(getattr(macro, "body", None))
        super().append(macro)


def read_file(filename: str, budget: Budget, limits: Limits, xacro: ModuleType, pop: bool = True) -> bytes:
    """The bytes of one file xacro reads, opened without blocking (a FIFO or device is refused),
    within the per-file and total byte budget."""
    budget.tick()
    try:
        _, data = read_bytes_once(filename, limits)
    except URDFError:
        if os.path.lexists(filename):
            raise
        if pop:
            xacro.filestack.pop()  # as xacro.parse does: the error is not "in" the missing file
        missing = FileNotFoundError(errno.ENOENT, os.strerror(errno.ENOENT), filename)
        raise xacro.XacroException(f"cannot read {filename!r}: {missing.strerror}", exc=missing) from None
    budget.read -= len(data)
    if budget.read < 0:
        raise URDFError(
            f"all files read are more than Limits.max_bytes = {limits.max_bytes} bytes",
            source=filename,
        )
    return data


def failing_file(source: str) -> str:
    """The file xacro was in when it failed (innermost include), else ``source``."""
    import xacro

    stack = [f for f in (getattr(xacro, "filestack", None) or []) if f]
    return stack[-1] if stack else source
