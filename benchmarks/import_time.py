"""Import + load time of kinengine against the Pinocchio baseline, hyperfine-style: fresh interpreters,
alternating, min of many runs (a busy neighbour slows both alike).

    python benchmarks/import_time.py [RUNS]          # default 21

kinengine:  import kinengine; kinengine.load("abb_irb120")
baseline:   import pinocchio; pinocchio.buildModelFromUrdf(<the same URDF file>)
"""

from __future__ import annotations

import subprocess
import sys
import time

import kinengine

URDF = str(kinengine.load("abb_irb120").source)
COMMANDS = {
    "kinengine": "import kinengine; kinengine.load('abb_irb120')",
    "pinocchio": f"import pinocchio; pinocchio.buildModelFromUrdf({URDF!r})",
    "python": "pass",
}


def main(runs: int = 21) -> dict[str, float]:
    best = {name: float("inf") for name in COMMANDS}
    for _ in range(runs):
        for name, code in COMMANDS.items():
            start = time.perf_counter()
            subprocess.run([sys.executable, "-c", code], check=True)
            best[name] = min(best[name], time.perf_counter() - start)
    for name, seconds in best.items():
        print(f"{name:10s} {seconds * 1e3:7.1f} ms  ({COMMANDS[name]})")
    print(
        f"kinengine − pinocchio: {(best['kinengine'] - best['pinocchio']) * 1e3:.1f} ms "
        "(target: within 40 ms)"
    )
    return best


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 21)
