"""Import + load time of kinengine against the Pinocchio baseline, hyperfine-style: fresh interpreters,
alternating, min of many runs (a busy neighbour slows both alike).

    python benchmarks/import_time.py [RUNS] [--cached-bytecode]      # default 21 runs

kinengine:  import kinengine; kinengine.load("abb_irb120")
baseline:   import pinocchio; pinocchio.buildModelFromUrdf(<the same URDF file>)

The same difference is also measured inside each run of a third interpreter, which is less disturbed by
a busy machine (a window of ~30 ms instead of two of ~200 ms): there pinocchio is imported first, so the
clock sees only what kinengine adds: ``import kinengine; kinengine.load(...)`` minus
``pinocchio.buildModelFromUrdf(...)``.

Bytecode: with PYTHONDONTWRITEBYTECODE set and an editable install, kinengine's modules are compiled
from source in every run while numpy's and pinocchio's come from their installed .pyc files.
``--cached-bytecode`` compares like with like, as an installed wheel or a normal interpreter would
run: the children write and read bytecode under a private PYTHONPYCACHEPREFIX (the source tree is
left alone), after one untimed warm-up run of each command.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time

import kinengine

URDF = str(kinengine.load("abb_irb120").source)
COMMANDS = {
    "kinengine": "import kinengine; kinengine.load('abb_irb120')",
    "pinocchio": f"import pinocchio; pinocchio.buildModelFromUrdf({URDF!r})",
    "python": "pass",
}
IN_PROCESS = f"""
import time, pinocchio
start = time.perf_counter()
pinocchio.buildModelFromUrdf({URDF!r})
build = time.perf_counter() - start
start = time.perf_counter()
import kinengine
kinengine.load("abb_irb120")
print(time.perf_counter() - start - build)
"""


def main(runs: int = 21, cached_bytecode: bool = False) -> dict[str, float]:
    env = dict(os.environ)
    if cached_bytecode:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = os.path.join(tempfile.gettempdir(), "kinengine-import-time-pycache")
        for code in COMMANDS.values():  # warm-up: compiles and caches every module imported
            subprocess.run([sys.executable, "-c", code], check=True, env=env)
    best = {name: float("inf") for name in COMMANDS}
    added = float("inf")
    for _ in range(runs):
        for name, code in COMMANDS.items():
            start = time.perf_counter()
            subprocess.run([sys.executable, "-c", code], check=True, env=env)
            best[name] = min(best[name], time.perf_counter() - start)
        out = subprocess.run([sys.executable, "-c", IN_PROCESS], check=True, env=env, capture_output=True)
        added = min(added, float(out.stdout))
    mode = "cached bytecode" if cached_bytecode else "environment as is"
    if not cached_bytecode and env.get("PYTHONDONTWRITEBYTECODE"):
        mode += " (PYTHONDONTWRITEBYTECODE is set: modules without a .pyc are compiled in every run)"
    print(f"{runs} runs, {mode}")
    for name, seconds in best.items():
        print(f"{name:10s} {seconds * 1e3:7.1f} ms  ({COMMANDS[name]})")
    print(
        f"kinengine − pinocchio: {(best['kinengine'] - best['pinocchio']) * 1e3:.1f} ms "
        "(target: within 40 ms)"
    )
    print(f"in-process, after import pinocchio: kinengine adds {added * 1e3:.1f} ms")
    return best


if __name__ == "__main__":
    arguments = [a for a in sys.argv[1:] if a != "--cached-bytecode"]
    main(int(arguments[0]) if arguments else 21, cached_bytecode="--cached-bytecode" in sys.argv[1:])
