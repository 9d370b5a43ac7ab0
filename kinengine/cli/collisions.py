"""``kinengine collision-pairs ROBOT``: the self-collision link pairs a robot needs checked, found by sampling
(as MoveIt's setup assistant does): adjacent links are left out, and so are pairs that collide in no sampled
configuration (never) or in every one (always, e.g. overlapping shapes at a joint); ``--write`` saves those
as an SRDF's ``<disable_collisions>`` for ``robot.with_srdf(...)``."""

from __future__ import annotations

import argparse
import itertools

from ..collision import sample_pairs, write_srdf
from .arguments import (
    ROBOT_HELP,
    add_robot_arguments,
    load_robot,
    output_path,
    positive_int,
    printable,
    whole_number,
)


def _run(args: argparse.Namespace) -> int:
    robot = load_robot(args)
    checker = robot.collision_checker()  # a robot without collision shapes: its URDFError, before sampling
    links = list(dict.fromkeys(checker.links))
    shaped = list(dict.fromkeys(name for pair in checker.links for name in pair))
    for obj in checker.geometry.geometryObjects:  # links with shapes that take part in no pair
        name = checker.model.frames[obj.parentFrame].name
        if name not in shaped:
            shaped.append(name)
    excluded = [p for p in itertools.combinations(shaped, 2) if p not in links and p[::-1] not in links]
    Q = robot.random_configuration(rng=args.seed, size=args.samples)
    never, always = sample_pairs(checker.colliding_pairs, Q, checker.links)
    print(
        f"{printable(robot.name)}: {len(shaped)} links with collision shapes, "
        f"{len(excluded)} pairs adjacent or rigidly joined"
    )
    print(f"{len(links)} pairs sampled in {args.samples} random configurations (seed {args.seed}):")
    checked = len(links) - len(never) - len(always)
    print(f"  never colliding: {len(never)}; always colliding: {len(always)}; to check: {checked}")
    for a, b in always:
        print(f"  always: {printable(a)} - {printable(b)}")
    if args.write:
        reasons = [(p, "Adjacent") for p in excluded] + [(p, "Never") for p in never]
        reasons += [(p, "Always") for p in always]
        with open(args.write, "w", encoding="utf-8") as f:
            f.write(write_srdf(robot.name, reasons))
        print(f"wrote {len(reasons)} <disable_collisions> to {printable(str(args.write))}")
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("collision-pairs", help="self-collision pairs by sampling; write an SRDF")
    p.add_argument("robot", help=ROBOT_HELP)
    p.add_argument(
        "--samples", type=positive_int, default=10000, help="random configurations (default 10000)"
    )
    p.add_argument("--seed", type=lambda s: whole_number(s, 0, 2**63 - 1), default=0, help="random seed")
    p.add_argument(
        "--write", type=output_path, metavar="SRDF", help="write the disabled pairs to this SRDF file"
    )
    add_robot_arguments(p)
    p.set_defaults(handler=_run)
