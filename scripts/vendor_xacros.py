"""Load every robot xacro under a folder with kinengine's safe xacro evaluator and with trust_xacro=True.

Usage: python scripts/vendor_xacros.py FOLDER [--json OUT]
FOLDER holds checked-out vendor description repositories (e.g. ROS-Industrial abb, fanuc, ...);
ROS_PACKAGE_PATH is set to it so that packages of one repository find each other. A file counts as a
top-level robot xacro when the trusted expansion does not refuse it as a file that only defines macros.
Prints the counts that load in each mode and every file whose outcome differs (issue 25's acceptance).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings
from pathlib import Path

# values for arguments some vendor files leave without a default (tried when the first load misses them)
ARGUMENTS = {"name": "robot", "ur_type": "ur5e", "DEBUG": "false", "prefix": ""}


def outcome(path: Path, trust: bool) -> tuple[str, float]:
    import kinengine

    start = time.perf_counter()
    args: dict[str, str] = {}
    while True:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                kinengine.load(path, trust_xacro=trust, xacro_args=args or None)
            result = "ok"
        except Exception as exc:  # the point is to record every failure
            result = f"{type(exc).__name__}: {exc}"
            missing = next((n for n in ARGUMENTS if f"missing xacro argument '{n}'" in result), None)
            if missing is not None and missing not in args:
                args[missing] = ARGUMENTS[missing]
                continue
        return result, time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    os.environ["ROS_PACKAGE_PATH"] = str(args.folder.resolve())
    rows = []
    for path in sorted(args.folder.rglob("*.xacro")):
        trusted, t_trusted = outcome(path, True)
        if "only defines macros" in trusted:
            continue
        safe, t_safe = outcome(path, False)
        rows.append(
            {"file": str(path), "trusted": trusted, "safe": safe, "s_trusted": t_trusted, "s_safe": t_safe}
        )
    ok_trusted = sum(r["trusted"] == "ok" for r in rows)
    ok_safe = sum(r["safe"] == "ok" for r in rows)
    print(
        f"{len(rows)} top-level xacros: {ok_safe} load with the safe evaluator, "
        f"{ok_trusted} with trust_xacro=True"
    )
    for r in rows:
        if (r["trusted"] == "ok") != (r["safe"] == "ok"):
            print(f"DIFFERENT {r['file']}\n  trusted: {r['trusted'][:300]}\n  safe:    {r['safe'][:300]}")
    slowest = max(rows, key=lambda r: r["s_safe"], default=None)
    if slowest:
        print(f"slowest safe load: {slowest['s_safe']:.2f} s {slowest['file']}")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
