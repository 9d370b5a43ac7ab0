"""Run the full benchmark and refresh benchmarks/results.json and results.png: every figure of the
"Targets" section of docs/benchmarks.md comes from this one run.

    python benchmarks/run_all.py --peers         # the run of docs/benchmarks.md (~10 minutes quiet)
    python benchmarks/run_all.py                 # kinengine and raw Pinocchio only
    python benchmarks/run_all.py --peers --json /tmp/trial.json   # elsewhere (its PNG beside it)

then ``python benchmarks/render_targets.py --update docs/benchmarks.md`` rewrites the page's generated
sections from the JSON. Extra arguments are passed on to ``kinengine bench``. Results depend on the
machine: the JSON records the CPU model, core count and library versions next to every figure, and this
script adds the run's conditions (``"conditions"``): its wall time and the 1-minute load average at the
start, at the end and sampled every few seconds in between (the run itself keeps one core busy: about 1 on a
quiet machine). Run it on a quiet machine: the ratios are interleaved and hold up under load, the
absolute rates (M configurations/s, IK solves/s, µs per call) do not.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import threading
import time
from datetime import datetime, timezone
from pathlib import Path

from kinengine.cli import main
from kinengine.cli.bench.ik_cases import SOLUTIONS

HERE = Path(__file__).resolve().parent
ROBOTS = ("abb_irb120", "ur5", "panda", "kinova")
SAMPLE_S = 5.0
"""[s] between two readings of the load average during the run."""


class LoadSampler:
    """The 1-minute load average read every ``period`` seconds on a daemon thread until ``stop()``."""

    def __init__(self, period: float = SAMPLE_S) -> None:
        self.period, self.samples = period, [os.getloadavg()[0]]
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._done.wait(self.period):
            self.samples.append(os.getloadavg()[0])

    def stop(self) -> dict:
        self._done.set()
        self._thread.join()
        self.samples.append(os.getloadavg()[0])
        return {
            "start": self.samples[0],
            "end": self.samples[-1],
            "min": min(self.samples),
            "median": statistics.median(self.samples),
            "max": max(self.samples),
            "samples": len(self.samples),
        }


def run(arguments: list[str], json_path: Path) -> int:
    """``kinengine bench`` over ROBOTS into json_path (and results.png), then the conditions into the JSON."""
    outputs = ["--json", str(json_path), "--plot", str(json_path.with_suffix(".png"))]
    started, sampler, start = datetime.now(timezone.utc), LoadSampler(), time.perf_counter()
    code = main(["bench", *ROBOTS, *outputs, *arguments])
    seconds, load = time.perf_counter() - start, sampler.stop()
    if code == 0:
        report = json.loads(json_path.read_text())
        report["conditions"] = {
            "command": " ".join(["python benchmarks/run_all.py", *arguments]),  # without --json
            "started": started.isoformat(timespec="seconds"),
            "duration_s": round(seconds, 1),
            "load_average_1min": load,
        }
        json_path.write_text(json.dumps(report, indent=1, allow_nan=False) + "\n")
        print(
            f"run took {seconds / 60:.1f} min; 1-minute load average {load['start']:.2f} at the start, "
            f"{load['min']:.2f}–{load['max']:.2f} during the run (median {load['median']:.2f})"
        )
        if not any(row["case"] == SOLUTIONS for row in report["rows"]):
            print("no closed-form rows (issue 28's targets): pip install 'kinengine[ik]' and run again")
    return code


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0], add_help=False)
    parser.add_argument("--json", type=Path, default=HERE / "results.json")
    known, rest = parser.parse_known_args()
    sys.exit(run(rest, known.json))
