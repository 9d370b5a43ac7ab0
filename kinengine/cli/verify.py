"""``kinengine verify TARGET``: cross-check a robot against the independent reference (table, JSON)."""

from __future__ import annotations

import argparse
import json

from ..verify import MAX_SAMPLES, verify
from .arguments import ROBOT_HELP, add_robot_arguments, bounded_int, load_robot, output_path


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``verify TARGET [--samples N] [--seed S] [--json PATH]`` on the kinengine CLI."""
    p = subparsers.add_parser("verify", help="cross-check poses and Jacobians against independent references")
    p.add_argument("target", metavar="TARGET", help=ROBOT_HELP)
    add_robot_arguments(p)
    p.add_argument(
        "--samples",
        type=bounded_int(1, MAX_SAMPLES),
        default=20,
        help=f"random configurations, 1 to {MAX_SAMPLES} (default 20)",
    )
    p.add_argument(
        "--seed",
        type=bounded_int(0, 2**63 - 1),
        default=0,
        help="seed of the random configurations (default 0)",
    )
    p.add_argument(
        "--json", type=output_path, metavar="PATH", default=None, help="also write the report as JSON to PATH"
    )
    p.set_defaults(handler=_cmd_verify)
    return p


def _cmd_verify(args: argparse.Namespace) -> int:
    """Print the table; exit code 0 when every check passed, 1 otherwise."""
    report = verify(load_robot(args, args.target), samples=args.samples, seed=args.seed, progress=True)
    print(report.table())
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(report.to_dict(), fh, indent=2)
    return 0 if report.passed else 1


__all__ = ["add_parser"]
