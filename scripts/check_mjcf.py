"""Cross-check every MJCF model of a folder against MuJoCo's own kinematics, as a Markdown table.

    python scripts/check_mjcf.py FOLDER [--samples 20] [--tolerance 1e-12] [--verify]

Each ``*.xml`` file with a ``<mujoco>`` root that no other file of the folder includes is loaded
with ``kinengine.load`` and compared by :func:`kinengine.mjcf.crosscheck.cross_check`: every body
and site pose (``xpos``/``xmat``, ``site_xpos``/``site_xmat``) and Jacobian (``mj_jacBody`` /
``mj_jacSite`` after ``mj_comPos``, vs kinengine's "local_world_aligned") at q = neutral and
``--samples`` random in-range configurations. ``--verify`` also runs ``kinengine verify`` (the
independent URDF reference) on the URDF kinengine wrote. Files MuJoCo cannot compile here (e.g.
missing mesh files: strip the mesh geoms first) are listed with the error. Exit status 1 if any
model is off by more than the tolerance or fails to load.
"""

from __future__ import annotations

import argparse
import re
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path

import kinengine
from kinengine.mjcf import is_mjcf
from kinengine.mjcf.crosscheck import cross_check

_INCLUDE = re.compile(r"<include\s+file\s*=\s*[\"']([^\"']+)[\"']")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--samples", type=int, default=20)
    parser.add_argument("--tolerance", type=float, default=1e-12)
    parser.add_argument("--verify", action="store_true", help="also run kinengine verify on each robot")
    args = parser.parse_args(argv)
    candidates = sorted(p for p in args.folder.glob("*.xml") if is_mjcf(p))
    included = {
        m for p in candidates for m in _INCLUDE.findall(p.read_text(encoding="utf-8", errors="replace"))
    }
    files = [p for p in candidates if p.name not in included]  # an included file is part of a model
    print(
        "| model | dof | frames compared | worst pose difference | worst Jacobian difference |"
        + (" verify |" if args.verify else "")
    )
    print("|---|---|---|---|---|" + ("---|" if args.verify else ""))
    failed = False
    for path in files:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                robot = kinengine.load(path)
        except kinengine.KinematicsError as exc:
            print(f"| {path.name} | — | — | not loaded: {exc} | |")
            failed = True
            continue
        check = cross_check(robot, samples=args.samples)
        pose = max(check.position, check.rotation)
        row = f"| {path.name} | {robot.dof} | {check.frames} | {pose:.1e} | {check.jacobian:.1e} |"
        if args.verify:
            from kinengine.verify import verify

            report = verify(robot, samples=args.samples)
            row += f" {'passed' if report.passed else 'FAILED'} |"
            failed |= not report.passed
        print(row)
        failed |= not check.worst <= args.tolerance
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
