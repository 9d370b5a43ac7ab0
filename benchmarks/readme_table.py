"""Print rows of benchmarks/results.json as the Markdown tables of docs/benchmarks.md (and the README).

    python benchmarks/readme_table.py [ROBOT ...] [--json PATH] [--floors] [--machine]

Default: every robot in the file. ``--floors`` adds the list of floor code (the inline raw-Pinocchio code
each ratio is taken against); ``--machine`` a line naming the CPU, cores, versions and date.
``python benchmarks/render_targets.py --update docs/benchmarks.md`` writes these tables into the page.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from kinengine.cli.bench.command import _achieved, _peer_cell, _us, case_label

HERE = Path(__file__).resolve().parent


def markdown(report: dict, robot: str) -> str:
    rows = [row for row in report["rows"] if row["robot"] == robot]
    peers = [
        name
        for name in (rows[0].get("peers", {}) if rows else {})
        if any(r["peers"][name]["status"] != "unsupported" for r in rows)
    ]
    head = ["case", "N", "kinengine min µs", "median µs", "per s", "floor min µs", "ratio", *peers]
    lines = ["| " + " | ".join(head) + " |", "|---|" + "--:|" * (len(head) - 1)]
    for row in rows:
        k, p = row["kinengine"], row["pinocchio"]
        ratio = f"{row['ratio']:.2f}" if "ratio" in row else ("–" if p["status"] == "none" else "")
        label = case_label(row) + (
            f" ({row['success']:.1%} reached, {_achieved(row)})" if "success" in row else ""
        )
        cells = [
            label,
            f"{row['n']:,}",
            _us(k["min_us"]),
            _us(k["median_us"]),
            f"{k['per_second']:,.0f}",
            _us(p["min_us"]) if "min_us" in p else "–",
            ratio,
        ]
        cells += [_peer_cell(row["peers"][name], k["min_us"]).replace("unsupported", "–") for name in peers]
        lines.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
    return "\n".join(lines)


def floors(report: dict) -> str:
    codes: dict[str, list[str]] = {}
    for row in report["rows"]:
        if row.get("floor") and row["pinocchio"]["status"] != "none":
            labels = codes.setdefault(row["floor"], [])
            if case_label(row) not in labels:
                labels.append(case_label(row))
    return "\n".join(f"- {', '.join(labels)}:\n  `{code}`" for code, labels in codes.items())


def machine(report: dict) -> str:
    v = report["versions"]
    peers = ", ".join(
        f"{name} {v[name]}"
        for name in ("roboticstoolbox-python", "pytorch-kinematics", "ikpy", "mujoco", "drake")
        if v.get(name)
    )
    return (
        f"{report['cpu']}, {report['cores']} cores, Python {report['python']}, kinengine {v['kinengine']}"
        + {True: " (C accelerator on)", False: " (pure Python)"}.get(report.get("accelerator"), "")
        + ", "
        + f"Pinocchio {v['pin']}, numpy {v['numpy']}"
        + (f"; peers: {peers}" if peers else "")
        + f"; run {report['timestamp']}"
    )


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("robots", nargs="*")
    parser.add_argument("--json", type=Path, default=HERE / "results.json")
    parser.add_argument("--floors", action="store_true")
    parser.add_argument("--machine", action="store_true")
    args = parser.parse_args()
    data = json.loads(args.json.read_text())
    if args.machine:
        print(machine(data) + "\n")
    for name in args.robots or [r["name"] for r in data["robots"]]:
        print(f"### {name}\n\n{markdown(data, name)}\n")
    if args.floors:
        print(floors(data))
