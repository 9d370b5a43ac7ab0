"""Print one robot's rows of benchmarks/results.json as the Markdown table the README shows.

    python benchmarks/readme_table.py [ROBOT] [--json PATH]      # default: abb_irb120, results.json
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from kinengine.cli.bench.command import _peer_cell, _us, case_label

HERE = Path(__file__).resolve().parent


def markdown(report: dict, robot: str) -> str:
    rows = [row for row in report["rows"] if row["robot"] == robot]
    peers = list(rows[0].get("peers", {})) if rows else []
    head = ["case", "N", "kinengine min µs", "median µs", "configs/s", "Pinocchio min µs", "ratio", *peers]
    lines = ["| " + " | ".join(head) + " |", "|---|" + "--:|" * (len(head) - 1)]
    for row in rows:
        k, p = row["kinengine"], row["pinocchio"]
        cells = [case_label(row), f"{row['n']:,}", _us(k["min_us"]), _us(k["median_us"]), f"{k['per_second']:,.0f}",
                 _us(p["min_us"]), f"{row['ratio']:.2f}" if "ratio" in row else ""]
        cells += [_peer_cell(row["peers"][name], k["min_us"]).replace("unsupported", "–") for name in peers]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("robot", nargs="?", default="abb_irb120")
    parser.add_argument("--json", type=Path, default=HERE / "results.json")
    args = parser.parse_args()
    print(markdown(json.loads(args.json.read_text()), args.robot))
