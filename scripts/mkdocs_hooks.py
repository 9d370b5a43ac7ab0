"""MkDocs hook (mkdocs.yml `hooks:`): pages generated from the code at build time, so they cannot drift.

* ``<!-- cli-reference -->`` (docs/cli.md) becomes the ``--help`` text of ``kinengine`` and of every
  sub-command, from ``kinengine.cli.main.build_parser()``;
* ``<!-- robot-catalog -->`` (docs/robots.md) becomes a table of every name ``kinengine.load()`` accepts,
  each robot loaded to read its dof, default end effector and frames.
"""

from __future__ import annotations

import argparse
import os
from typing import Any

CLI_MARKER = "<!-- cli-reference -->"
CATALOG_MARKER = "<!-- robot-catalog -->"


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


def robot_catalog() -> str:
    """Markdown table: name, dof, default end effector, frames, gripper coordinates, where it comes from."""
    import warnings

    import kinengine
    from kinengine.model.catalog import catalog_entry

    rows = [
        "| name | dof | end effector | frames | gripper coordinates | from |",
        "|---|--:|---|--:|---|---|",
    ]
    for name in kinengine.available_robots():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # vendor files' own quirks are reported by `kinengine info`
            robot = kinengine.load(name)
        entry = catalog_entry(name)
        extra = ", ".join(f"`{c}`" for c in entry.extra_coordinates) or "–"
        origin = "shipped (`robots/`)" if entry.origin == "kinengine" else entry.origin
        if entry.locked:
            origin += " (" + ", ".join(f"`{j}` locked at {v:g}" for j, v in entry.locked) + ")"
        rows.append(
            f"| `{name}` | {robot.dof} | `{robot.end_effector}` | {len(robot.frame_names)} | "
            f"{extra} | {origin} |"
        )
    return "\n".join(rows) + "\n"


def on_page_markdown(markdown: str, **kwargs: Any) -> str:
    if CLI_MARKER in markdown:
        markdown = markdown.replace(CLI_MARKER, cli_reference())
    if CATALOG_MARKER in markdown:
        markdown = markdown.replace(CATALOG_MARKER, robot_catalog())
    return markdown
