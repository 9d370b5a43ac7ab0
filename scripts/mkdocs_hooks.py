"""MkDocs hook (mkdocs.yml `hooks:`): the CLI reference page is generated from the real parser.

In docs/cli.md the line ``<!-- cli-reference -->`` is replaced by the ``--help`` text of ``kinengine`` and of
every sub-command, taken from ``kinengine.cli.main.build_parser()`` at build time, so the page cannot drift
from the command line.
"""

from __future__ import annotations

import argparse
import os
from typing import Any

MARKER = "<!-- cli-reference -->"


def cli_reference() -> str:
    """Markdown: one section per command with its full ``--help`` output."""
    os.environ["COLUMNS"] = "100"  # argparse wraps help at the terminal width; fix it for the page
    from kinengine.cli.main import build_parser

    parser = build_parser()
    parts = ["## kinengine\n", "```text\n" + parser.format_help().rstrip() + "\n```\n"]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                parts.append(f"## kinengine {name}\n")
                parts.append("```text\n" + sub.format_help().rstrip() + "\n```\n")
    return "\n".join(parts)


def on_page_markdown(markdown: str, **kwargs: Any) -> str:
    return markdown.replace(MARKER, cli_reference()) if MARKER in markdown else markdown
