"""Griffe extension for the documentation site: kinengine's docstrings read as Markdown.

mkdocstrings (mkdocs.yml) loads this file. Two rewrites, outside code spans and code blocks:

* reST roles (``:class:`~kinengine.Robot```, ``:meth:`frame_pose```) become code spans naming the object
  (``~`` keeps only its last component, as in Sphinx); reST's double backticks already are code spans;
* square brackets are escaped. The docstrings use them for units and block matrices ("[m]",
  "rows [linear; angular]"), never for links, and Markdown would otherwise read "[v; ω] [m, rad]" as a
  reference link and the cross-reference plugin fail the strict build on it.

And a class attribute written ``name = property(getter, doc="...")`` is documented as a property with that
text (griffe reads the source without running it, so it would otherwise see an undocumented attribute).
"""

from __future__ import annotations

import ast
import re
from typing import Any

import griffe

_ROLE = re.compile(r":(?:py:)?(?:class|func|meth|mod|attr|data|exc|obj|const):`(~?)([^`]+)`")
_CODE_SPAN = re.compile(r"(`+).+?\1")
_BRACKET = re.compile(r"(?<!\\)([\[\]])")  # not yet escaped: the rewrite may run twice on one docstring


def _code_span(match: re.Match[str]) -> str:
    tilde, target = match.groups()
    return f"`{target.rsplit('.', 1)[-1] if tilde else target}`"


def _escape_brackets(line: str) -> str:
    out, last = [], 0
    for span in _CODE_SPAN.finditer(line):
        out.append(_BRACKET.sub(r"\\\1", line[last : span.start()]))
        out.append(span.group(0))
        last = span.end()
    out.append(_BRACKET.sub(r"\\\1", line[last:]))
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

    def on_attribute_instance(self, *, node: Any, attr: griffe.Attribute, **kwargs: Any) -> None:
        value = getattr(node, "value", None)
        if not (
            isinstance(value, ast.Call) and isinstance(value.func, ast.Name) and value.func.id == "property"
        ):
            return
        for keyword in value.keywords:
            if (
                keyword.arg == "doc"
                and isinstance(keyword.value, ast.Constant)
                and isinstance(keyword.value.value, str)
            ):
                attr.docstring = griffe.Docstring(markdown_docstring(keyword.value.value), parent=attr)
                attr.labels.clear()  # a property, not a class or instance attribute with a value to show
                attr.labels.add("property")
                attr.value = None
