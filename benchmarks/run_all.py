"""Run the full benchmark and refresh benchmarks/results.json and results.png.

    python benchmarks/run_all.py                 # kinengine and raw Pinocchio
    python benchmarks/run_all.py --peers         # also roboticstoolbox, pytorch_kinematics, ikpy if installed

Extra arguments are passed on to ``kinengine bench``. Results depend on the machine: the JSON
records the CPU model, core count and library versions next to every figure.
"""

from __future__ import annotations

import sys
from pathlib import Path

from kinengine.cli import main

HERE = Path(__file__).resolve().parent
ROBOTS = ("abb_irb120", "ur5", "panda", "kinova")

if __name__ == "__main__":
    outputs = ["--json", str(HERE / "results.json"), "--plot", str(HERE / "results.png")]
    sys.exit(main(["bench", *ROBOTS, *outputs, *sys.argv[1:]]))
