"""``kinengine list``: the robot names that ``kinengine.load()`` accepts."""

from __future__ import annotations

import argparse

from .. import available_robots


def _run(args: argparse.Namespace) -> int:
    for name in available_robots():
        print(name)
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("list", help="names that kinengine.load() accepts")
    p.set_defaults(handler=_run)
