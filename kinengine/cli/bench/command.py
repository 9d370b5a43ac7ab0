"""``kinengine bench``: single-call latency and batched throughput, next to raw Pinocchio (and peers).

    kinengine bench [ROBOT ...] [--quick] [--peers] [--json PATH] [--plot PATH]

Rows and floors: :mod:`.cases`; interleaved timing and checks: :mod:`.run`; peers: :mod:`.peers`.
Times are per call [µs], min and median over repeats (kinengine and its floor alternate); "per s"
is configurations (or IK solves) per second at the min; ratio = kinengine / floor (min). Every
floor is the inline raw-Pinocchio code a user would write for the same output; the table names it.
The speed targets the project tracks (measured, never asserted) and their figures: the "Targets" section
of docs/benchmarks.md, rendered from this command's JSON by benchmarks/render_targets.py.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from ..arguments import add_robot_arguments, load_robot, output_path, summary
from .run import DEFAULT_ROBOTS, FULL, QUICK, run

PEER_WIDTH = 20


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``bench`` on the kinengine command line."""
    p = subparsers.add_parser(
        "bench",
        help="time kinengine against raw Pinocchio (and other libraries)",
        description=summary(__doc__),
    )
    p.add_argument(
        "robots",
        nargs="*",
        metavar="ROBOT",
        help=f"robot names or .urdf / .xacro paths (default: {' '.join(DEFAULT_ROBOTS)})",
    )
    p.add_argument("--quick", action="store_true", help="few repeats and small batches (tests, CI)")
    p.add_argument(
        "--peers",
        action="store_true",
        help="also time roboticstoolbox-python, pytorch-kinematics, ikpy, MuJoCo and Drake where installed",
    )
    p.add_argument(
        "--peer-atol",
        type=float,
        default=1e-9,
        help="a peer whose answer differs from kinengine's by more is reported, not timed",
    )
    p.add_argument("--json", type=output_path, default=None, metavar="PATH", help="write the results as JSON")
    p.add_argument(
        "--plot", type=output_path, default=None, metavar="PATH", help="write a PNG bar chart (log scale)"
    )
    add_robot_arguments(p)
    p.set_defaults(handler=handle)


def handle(args: argparse.Namespace) -> int:
    if args.plot is not None:  # say that matplotlib is missing before the run, not after it
        from ...presentation.plotting import pyplot

        pyplot(headless=True)
    report = run(
        [load_robot(args, name) for name in args.robots or DEFAULT_ROBOTS],
        QUICK if args.quick else FULL,
        args.peers,
        args.peer_atol,
    )
    print(format_table(report))
    if args.json is not None:
        args.json.write_text(json.dumps(report, indent=1, allow_nan=False) + "\n")
        print(f"\nwrote {args.json}")
    if args.plot is not None:
        plot(report, args.plot)
        print(f"wrote {args.plot}")
    return 0


def case_label(row: dict) -> str:
    """The row's case, marked "(batch)" for the throughput rows (q of shape (N, dof))."""
    return row["case"] + (" (batch)" if row["group"] == "throughput" else "")


def _us(value: float) -> str:
    return f"{value:,.2f}" if value < 100 else f"{value:,.0f}"


def _accelerator(report: dict) -> str:
    """Whether the run had the C accelerator of the hot path (kinengine.ACCELERATED)."""
    on = report.get("accelerator")
    return "C accelerator on" if on else "pure Python" if on is False else "accelerator not recorded"


def format_table(report: dict) -> str:
    """The rows as a text table, then the peers' table and any disagreement."""
    versions = report["versions"]
    lines = [
        f"kinengine {versions['kinengine']} ({_accelerator(report)}) · Pinocchio {versions['pin']} · "
        + f"numpy {versions['numpy']} · {report['cpu']} ({report['cores']} cores) · {report['timestamp']}",
        "",
    ]
    header = (
        f"{'robot':<12} {'case':<42} {'N':>7} {'min µs':>10} {'median µs':>10} {'per s':>12} "
        f"{'pin min µs':>10} {'ratio':>6}  note"
    )
    lines += [header, "-" * len(header)]
    for row in report["rows"]:
        k, p = row["kinengine"], row["pinocchio"]
        ours = (
            f"{_us(k['min_us']):>10} {_us(k['median_us']):>10} {k['per_second']:>12,.0f}"
            if k["status"] == "ok"
            else f"{'skipped':>10} {'':>10} {'':>12}"
        )
        ratio = f"{row['ratio']:>6.2f}" if "ratio" in row else f"{'':>6}"
        note = row["note"] + (
            f" [floor disagrees: {p.get('difference')}]" if p["status"] == "disagrees" else ""
        )
        if "success" in row:
            note = f"{row['success']:.1%} reached, {_achieved(row)}; " + note
        floor_us = _us(p["min_us"]) if "min_us" in p else "-"
        lines.append(
            f"{row['robot']:<12} {case_label(row):<42} {row['n']:>7} {ours} {floor_us:>10} "
            f"{ratio}  {note}".rstrip()
        )
    codes: dict[str, list[str]] = {}
    for row in report["rows"]:
        if row.get("floor") and row["pinocchio"]["status"] != "none":
            codes.setdefault(row["floor"], []).append(case_label(row))
    if codes:
        lines += [
            "",
            "floors (inline raw Pinocchio on robot.pinocchio_model(), "
            "q_pin = robot.pinocchio_configuration(q)):",
        ]
        for code, labels in codes.items():
            names = sorted(set(labels), key=labels.index)
            lines.append(f"  {', '.join(names)}:\n      {code}")
    peer_rows = [
        row
        for row in report["rows"]
        if any(v["status"] != "unsupported" for v in row.get("peers", {}).values())
    ]
    if peer_rows:
        names = list(peer_rows[0]["peers"])
        lines += ["", "peers: min µs per call (× kinengine's min); 'disagrees' rows were not timed", ""]
        head = f"{'robot':<12} {'case':<42} {'N':>7} {'kinengine':>10} " + " ".join(
            f"{n[:PEER_WIDTH]:>{PEER_WIDTH}}" for n in names
        )
        lines += [head, "-" * len(head)]
        for row in peer_rows:
            ours = row["kinengine"].get("min_us")
            cells = [_peer_cell(row["peers"][n], ours) for n in names]
            lines.append(
                f"{row['robot']:<12} {case_label(row):<42} {row['n']:>7} "
                f"{_us(ours) if ours else '-':>10} " + " ".join(f"{c:>{PEER_WIDTH}}" for c in cells)
            )
    notes = [
        f"  {robot['name']} / {name}: {status['note']}"
        for robot in report["robots"]
        for name, status in robot["peers"].items()
        if status["note"]
    ]
    return "\n".join(lines + (["", "peer notes:"] + notes if notes else []))


def _achieved(result: dict) -> str:
    """The achieved IK error max(|Δp| [m], angle [rad]) per target: median and maximum."""
    if "error_median" not in result:  # a report written before the errors were recorded
        return "error not recorded"
    return f"error median {result['error_median']:.0e}, max {result['error_max']:.0e}"


def _peer_cell(result: dict, ours: float | None) -> str:
    if result["status"] == "ok":
        reached = f" [{result['success']:.0%}, {_achieved(result)}]" if "success" in result else ""
        return _us(result["min_us"]) + (f" ({result['min_us'] / ours:.1f}×)" if ours else "") + reached
    if result["status"] == "disagrees":
        return "disagrees" + (f" {result['difference']:.0e}" if result["difference"] is not None else "")
    return result["status"]


def plot(report: dict, path: Path) -> None:
    """Horizontal bars on log axes: per-call latency [µs] and batch throughput [configurations/s]."""
    from ...presentation.plotting import pyplot

    plt = pyplot(headless=True)
    from matplotlib.patches import Patch

    robots = [r["name"] for r in report["robots"]]
    rows = report["rows"]
    height = max(
        len([r for r in rows if r["robot"] == name and r["group"] == g])
        for name in robots
        for g in ("latency", "throughput")
    )
    fig, axes = plt.subplots(len(robots), 2, figsize=(14, 0.32 * height * len(robots) + 1.5), squeeze=False)
    for axes_row, name in zip(axes, robots, strict=True):
        panels = (
            (axes_row[0], "latency", "min_us", "µs per configuration or IK solve (min)"),
            (axes_row[1], "throughput", "per_second", "configurations / s"),
        )
        for ax, group, key, xlabel in panels:
            selected = [r for r in rows if r["robot"] == name and r["group"] == group]
            labels = [r["case"] + (f"  N={r['n']:,}" if group == "throughput" else "") for r in selected]
            per = [r["n"] if group == "latency" else 1 for r in selected]  # latency: per configuration/solve
            sides = {
                "kinengine": [r["kinengine"] for r in selected],
                "Pinocchio (floor)": [r["pinocchio"] for r in selected],
            }
            for peer in selected[0].get("peers", {}) if selected else {}:
                sides[peer] = [r["peers"][peer] for r in selected]
            series = [
                (
                    label,
                    [None if v.get(key) is None else v[key] / n for v, n in zip(results, per, strict=True)],
                )
                for label, results in sides.items()
            ]
            width, handles = 0.8 / len(series), []
            for s, (label, values) in enumerate(series):
                ys = [i + s * width for i, v in enumerate(values) if v]
                ax.barh(ys, [v for v in values if v], height=width, color=f"C{s}")
                handles.append(Patch(color=f"C{s}", label=label if ys else f"{label} (not timed here)"))
            ax.set_yticks([i + 0.4 - width / 2 for i in range(len(labels))], labels, fontsize=7)
            ax.invert_yaxis()
            ax.set_xscale("log")
            ax.set_xlabel(xlabel)
            ax.set_title(f"{name}: {group}")
            ax.grid(axis="x", which="both", alpha=0.3)
            ax.legend(handles=handles, fontsize=7)
    fig.suptitle(
        f"kinengine bench · {report['cpu']} ({report['cores']} cores) · {report['timestamp']}", fontsize=9
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m kinengine.bench ...`` without the main CLI."""
    parser = argparse.ArgumentParser(prog="kinengine")
    add_parser(parser.add_subparsers(dest="command", required=True))
    return handle(parser.parse_args(["bench", *(sys.argv[1:] if argv is None else argv)]))


if __name__ == "__main__":
    raise SystemExit(main())
