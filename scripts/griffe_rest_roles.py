"""Griffe extension for the documentation site: kinengine's docstrings read as Markdown.

mkdocstrings (mkdocs.yml) loads this file. Two rewrites, outside code spans and code blocks:

* reST roles (``:class:`~kinengine.Robot```, ``:meth:`frame_pose```) become code spans naming the object
  (``~`` keeps only its last component, as in Sphinx); reST's double backticks already are code spans;
* square brackets are escaped. The docstrings use them for units and block matrices ("[m]",
  "rows [linear; angular]"), never for links, and Markdown would otherwise read "[v; ω] [m, rad]" as a
  reference link and the cross-reference plugin fail the strict build on it.
"""

from __future__ import annotations

import re
from typing import Any

import griffe

_ROLE = re.compile(r":(?:py:)?(?:class|func|meth|mod|attr|data|exc|obj|const):`(~?)([^`]+)`")
_CODE_SPAN = re.compile(r"(`+).+?\1")


def _code_span(match: re.Match[str]) -> str:
    tilde, target = match.groups()
    return f"`{target.rsplit('.', 1)[-1] if tilde else target}`"


def _escape_brackets(line: str) -> str:
    out, last = [], 0
    for span in _CODE_SPAN.finditer(line):
        out.append(line[last : span.start()].replace("[", r"\[").replace("]", r"\]"))
        out.append(span.group(0))
        last = span.end()
    out.append(line[last:].replace("[", r"\[").replace("]", r"\]"))
    return "".join(out)


def markdown_docstring(text: str) -> str:
    """The rewrites above; fenced blocks and doctest lines are left as they are."""
    lines, fenced = [], False
    for line in _ROLE.sub(_code_span, text).splitlines():
        stripped = line.lstrip()
        if stripped.startswith("```"):
            fenced = not fenced
        elif not fenced and not stripped.startswith((">>>", "...")):
            line = _escape_brackets(line)
        lines.append(line)
    return "\n".join(lines)


class MarkdownDocstrings(griffe.Extension):
    """Apply :func:`markdown_docstring` to every docstring griffe loads."""

    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = markdown_docstring(obj.docstring.value)
