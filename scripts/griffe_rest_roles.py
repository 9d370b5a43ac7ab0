"""Griffe extension for the documentation site: reST roles in docstrings become Markdown code spans.

The docstrings cross-reference with Sphinx roles (``:class:`~kinengine.Robot```, ``:meth:`frame_pose```),
which Markdown would show as raw text. mkdocstrings (mkdocs.yml) loads this file; each role becomes a code
span naming the object (``~`` keeps only its last component, as in Sphinx). reST's double backticks are
already Markdown code spans.
"""

from __future__ import annotations

import re
from typing import Any

import griffe

_ROLE = re.compile(r":(?:py:)?(?:class|func|meth|mod|attr|data|exc|obj|const):`(~?)([^`]+)`")


def _code_span(match: re.Match[str]) -> str:
    tilde, target = match.groups()
    return f"`{target.rsplit('.', 1)[-1] if tilde else target}`"


class RestRoles(griffe.Extension):
    """Rewrite ``:role:`target``` into a code span in every docstring griffe loads."""

    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = _ROLE.sub(_code_span, obj.docstring.value)
