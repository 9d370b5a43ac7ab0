"""The generated sections of docs/benchmarks.md from one run's JSON (benchmarks/run_all.py).

    python benchmarks/render_targets.py [--json PATH]                 # print the Markdown
    python benchmarks/render_targets.py --update docs/benchmarks.md   # rewrite the page's generated blocks
    python benchmarks/render_targets.py --readme                      # the README's speed table (ABB)

Blocks (each between ``<!-- generated: NAME -->`` and ``<!-- end generated: NAME -->``; the text
outside them is the page's own):

* ``run``: the machine, the run's conditions and every row of every robot, then the floors
  (benchmarks/readme_table.py's tables);
* ``targets``: each speed target of issues 27 and 28 with its figure per robot and whether this run
  met it (by every robot it applies to), the achieved IK error next to every IK rate;
* ``ik``: the IK rows at equal accuracy: kinengine's numeric and closed-form solvers and Robotics
  Toolbox's ``ik_LM`` (tol 5e-13 on ½eᵀe, |e| ≤ 1e-6: as accurate as asked of kinengine) on the same
  targets, rate, share reached and achieved error side by side.

A figure a run did not measure (an older JSON, a robot without a closed form, peers not installed)
reads "–", and a target none of whose figures was measured "not measured".
"""

from __future__ import annotations

import argparse
import json
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from readme_table import floors, machine, markdown

from kinengine.cli.bench.ik_cases import NEAREST as CLOSED
from kinengine.cli.bench.ik_cases import SOLUTIONS

HERE = Path(__file__).resolve().parent
NAMES = {"abb_irb120": "ABB IRB 120", "ur5": "UR5", "panda": "Panda", "kinova": "Kinova"}
RATIO = 1.3
"""Issue 27: single calls at most this × their inline raw-Pinocchio floor."""
NUMERIC = "inverse_kinematics[random targets]"
RTB = "roboticstoolbox"

Figure = tuple[str, bool] | None
"""One robot's cell of a target: (text, met), or None where the run did not measure it."""


def find(report: dict, robot: str, case: str, group: str = "latency", n: int | None = None) -> dict | None:
    """The row of ``robot`` named ``case`` in ``group`` (with ``n`` rows per call, if given), or None."""
    for row in report["rows"]:
        same = (row["robot"], row["case"], row["group"]) == (robot, case, group) and n in (None, row["n"])
        if same and row["kinengine"]["status"] == "ok":
            return row
    return None


def exponent(value: float) -> str:
    """1.6e-4 style: one significant digit, no padded exponent."""
    return re.sub(r"e([+-])0*(\d)", r"e\1\2", f"{value:.0e}").replace("e+", "e")


def achieved(result: dict) -> str:
    """Share reached (1e-6 m and rad, within limits) and achieved error max(|Δp| [m], angle [rad]) per
    target: median / maximum."""
    if "error_median" not in result:
        return f"{result['success']:.1%} reached"
    return (
        f"{result['success']:.1%}, error {exponent(result['error_median'])} / {exponent(result['error_max'])}"
    )


def rate(per_second: float) -> str:
    return f"{per_second / 1e6:.2f} M" if per_second >= 1e6 else f"{per_second:,.0f}"


def ratios(cases: list[str], bound: float = RATIO) -> Callable[[dict, str], Figure]:
    """Single-call ratios to the floor, " / " between cases; met: each ≤ ``bound``."""

    def figure(report: dict, robot: str) -> Figure:
        rows = [find(report, robot, case) for case in cases]
        if any(row is None or "ratio" not in row for row in rows):
            return None
        values = [row["ratio"] for row in rows if row is not None]
        return " / ".join(f"{v:.2f}" for v in values), max(values) <= bound

    return figure


def analytic(report: dict, robot: str) -> Figure:
    """Every analytic_jacobian[...] single-call row: the range of ratios and the worst one's name."""
    rows = [r for r in report["rows"] if r["robot"] == robot and r["group"] == "latency" and "ratio" in r]
    rows = [r for r in rows if r["case"].startswith("analytic_jacobian[")]
    if not rows:
        return None
    worst = max(rows, key=lambda r: r["ratio"])
    low = min(r["ratio"] for r in rows)
    return f"{low:.2f}–{worst['ratio']:.2f} ({worst['case'][18:-1]})", worst["ratio"] <= RATIO


def batch_rate(case: str, n: int, at_least: float) -> Callable[[dict, str], Figure]:
    """Configurations (or poses) per second of a batch of ``n``; met: ≥ ``at_least``."""

    def figure(report: dict, robot: str) -> Figure:
        row = find(report, robot, case, "throughput", n)
        if row is None:
            return None
        return f"{rate(row['kinengine']['per_second'])}/s", row["kinengine"]["per_second"] >= at_least

    return figure


def ik(case: str, group: str, at_least: float, success: float = 0.0) -> Callable[[dict, str], Figure]:
    """IK solves per second with the share reached and the achieved error; met: rate ≥ ``at_least`` and
    share reached ≥ ``success``."""

    def figure(report: dict, robot: str) -> Figure:
        row = find(report, robot, case, group)
        if row is None or "success" not in row:
            return None
        per_s = row["kinengine"]["per_second"]
        return f"{per_s:,.0f}/s, {achieved(row)}", per_s >= at_least and row["success"] >= success

    return figure


def one_pose(at_most_us: float) -> Callable[[dict, str], Figure]:
    """Every closed-form solution of one pose: µs per call, solutions per pose, achieved error."""

    def figure(report: dict, robot: str) -> Figure:
        row = find(report, robot, SOLUTIONS)
        if row is None:
            return None
        us = row["kinengine"]["min_us"] / row["n"]
        count = f", {row['solutions_per_target']:.1f} solutions" if "solutions_per_target" in row else ""
        error = f", error max {exponent(row['error_max'])}" if "error_max" in row else ""
        return f"{us:.1f} µs{count}{error}", us <= at_most_us

    return figure


@dataclass(frozen=True)
class Target:
    text: str  # Markdown
    figure: Callable[[dict, str], Figure]
    robots: tuple[str, ...] | None = None  # the robots the bound applies to (None: every robot)


def million(report: dict, robot: str) -> Figure:
    """N = 1,000,000 with ``out=`` against N = 100,000, per configuration; met: at most 10 % slower."""
    big = find(report, robot, "kinematics[out=]", "throughput", 1_000_000)
    small = find(report, robot, "kinematics[out=]", "throughput", 100_000)
    if big is None or small is None:
        return None
    b, s = big["kinengine"]["per_second"], small["kinengine"]["per_second"]
    return f"{b / 1e6:.2f} vs {s / 1e6:.2f} M/s", b >= 0.9 * s


TARGETS = (
    Target("`frame_pose(q)` ≤ 1.3×", ratios(["frame_pose"])),
    Target(
        "`jacobian(q)` ≤ 1.3× (local_world_aligned / local / world)",
        ratios([f"jacobian[{ref}]" for ref in ("local_world_aligned", "local", "world")]),
    ),
    Target(
        "checked `robot.frame(f)`: `.pose` / `.jacobian` / `.kinematics` ≤ 1.3×",
        ratios(["frame().pose", "frame().jacobian", "frame().kinematics"]),
    ),
    Target(
        "`robot.frame(f, check_inputs=False)` ≤ 1.1× (earlier target)",
        ratios([f"frame(), check_inputs=False.{w}" for w in ("pose", "jacobian", "kinematics")], 1.1),
    ),
    Target("`analytic_jacobian(q)` ≤ 1.3×, every parameterization (range, worst)", analytic),
    Target("`task.update(q)` ≤ 1.3× (ZYX / ZYZ)", ratios(["task.update(q)", "task.update(q)[euler_zyz]"])),
    Target("`kinematics(Q)`, N = 100,000, ≥ 12 M configurations/s", batch_rate("kinematics", 100_000, 12e6)),
    Target("`kinematics(Q, out=)`, N = 1,000,000 within 10 % of N = 100,000 (earlier target)", million),
    Target(
        "batched IK, N = 10,000 random targets, ≥ 80,000 solves/s at ≥ 99.5 % reached",
        ik(NUMERIC, "throughput", 80_000, 0.995),
    ),
    Target("single IK, random targets one by one, ≥ 4,000 solves/s", ik(NUMERIC, "latency", 4_000)),
    Target(
        "closed form, every solution of one pose (`ik_solutions(T)`), ≤ 20 µs per call (ABB)",
        one_pose(20.0),
        ("abb_irb120",),
    ),
    Target(
        "closed form, every solution of a batch of 10,000 poses, ≥ 150,000 poses/s (ABB)",
        batch_rate(SOLUTIONS, 10_000, 150_000),
        ("abb_irb120",),
    ),
)


def verdict(target: Target, figures: dict[str, Figure]) -> str:
    """met / **not met** (naming the robots that missed) over the robots the target applies to."""
    judged = {r: f for r, f in figures.items() if target.robots is None or r in target.robots}
    measured = {r: f for r, f in judged.items() if f is not None}
    if not measured:
        return "not measured"
    missed = [NAMES.get(r, r) for r, f in measured.items() if not f[1]]
    unmeasured = [NAMES.get(r, r) for r, f in judged.items() if f is None]
    text = f"**not met** ({', '.join(missed)})" if missed else "met"
    return text + (f"; not measured: {', '.join(unmeasured)}" if unmeasured else "")


def conditions(report: dict) -> str:
    """When, how long and under what load the run ran (run_all.py's ``conditions``), if recorded."""
    c = report.get("conditions")
    if c is None:
        return f"Run {report['timestamp']} (its JSON predates the record of the run's duration and load)."
    load = c["load_average_1min"]
    return (
        f"`{c['command']}`, started {c['started']}, {c['duration_s'] / 60:.1f} min; 1-minute load average "
        f"{load['start']:.2f} at the start, {load['min']:.2f}–{load['max']:.2f} during the run "
        f"(median {load['median']:.2f}, {load['samples']} readings; the run itself accounts for about 1)."
    )


def targets(report: dict) -> str:
    robots = [r["name"] for r in report["robots"]]
    head = ["target", *(NAMES.get(r, r) for r in robots), "this run"]
    lines = [
        "| " + " | ".join(head) + " |",
        "|---|" + "--:|" * len(robots) + "---|",
    ]
    for target in TARGETS:
        figures = {robot: target.figure(report, robot) for robot in robots}
        cells = [
            "–"
            if f is None
            else f[0] + ("" if target.robots is None or r in target.robots else " (no bound)")
            for r, f in figures.items()
        ]
        lines.append("| " + " | ".join([target.text, *cells, verdict(target, figures)]) + " |")
    return "\n".join(lines)


def ik_rows(report: dict) -> str:
    """Every IK solver on the same random targets, per robot: rate, share reached, achieved error."""
    lines = [
        "The same random reachable targets (poses of random in-limit configurations, rng 2024) for every "
        "solver of the run; reached: within 1e-6 m and 1e-6 rad with the joints within their limits; error: "
        "max(|Δp| [m], angle [rad]) per target, median / maximum over the targets (for `ik_solutions`, each "
        "target's worst solution). Robotics Toolbox's C++ `ik_LM` is asked for the accuracy kinengine is "
        "asked for (tol on ½eᵀe; 5e-13 is |e| ≤ 1e-6, its default leaves a median error of 1.6e-4 m).",
        "",
        "| robot | targets | solver | per s | reached, error median / max |",
        "|---|---|---|--:|---|",
    ]
    tol = report.get("settings", {}).get("ik_peer_tol")
    tol = "tol not recorded" if tol is None else f"tol {exponent(tol)}"
    for robot in [r["name"] for r in report["robots"]]:
        for group in ("latency", "throughput"):
            numeric = find(report, robot, NUMERIC, group)
            if numeric is None:
                continue
            how = f"{numeric['n']:,}, " + ("one by one" if group == "latency" else "one batch")
            solvers = [("kinengine, numeric", numeric)]
            for label, case in (
                ("kinengine, closed form (nearest)", CLOSED),
                ("`ik_solutions(T)`, every one", SOLUTIONS),
            ):
                row = find(report, robot, case, group)
                if row is not None:
                    solvers.append((label, row))
            for label, row in solvers:
                per_s = rate(row["kinengine"]["per_second"]) + (" poses" if row["case"] == SOLUTIONS else "")
                lines.append(f"| {NAMES.get(robot, robot)} | {how} | {label} | {per_s} | {achieved(row)} |")
            peer = numeric.get("peers", {}).get(RTB, {"status": "unsupported"})
            if peer["status"] == "ok":
                lines.append(
                    f"| {NAMES.get(robot, robot)} | {how} | Robotics Toolbox `ik_LM`, {tol}, one by one "
                    f"| {rate(peer['per_second'])} | {achieved(peer)} |"
                )
    return "\n".join(lines)


README_PEERS = {"roboticstoolbox": "Robotics Toolbox", "mujoco": "MuJoCo", "drake": "Drake"}
README_ROWS = (  # (label, case, group, n)
    ("`frame_pose(q)`", "frame_pose", "latency", 1),
    ("`jacobian(q)`", "jacobian[local_world_aligned]", "latency", 1),
    ("`robot.frame(FRAME).jacobian(q)` (checked)", "frame().jacobian", "latency", 1),
    ("`analytic_jacobian(q)`, ZYZ angles", "analytic_jacobian[euler_zyz]", "latency", 1),
    ("`task.update(q)`, ZYX angles", "task.update(q)", "latency", 1),
    ("`frame_pose(Q)`, batch of 10,000", "frame_pose", "throughput", 10_000),
    ("`kinematics(Q)` (poses + Jacobians), batch of 100,000", "kinematics", "throughput", 100_000),
    ("`inverse_kinematics`, one target (random targets)", NUMERIC, "latency", None),
    ("`inverse_kinematics`, batch of 10,000 random targets", NUMERIC, "throughput", 10_000),
    ("[`ik_solutions(T)`](docs/ik.md), every solution of one pose", SOLUTIONS, "latency", None),
    ("`ik_solutions(T)`, batch of 10,000 poses", SOLUTIONS, "throughput", 10_000),
)


def readme(report: dict, robot: str = "abb_irb120") -> str:
    """The README's speed table for one robot: time (µs) or rate per row, its floor, the ratio, and the
    peers' (× kinengine's time); IK rows give the share reached and the median achieved error."""
    frame = next(r["frame"] for r in report["robots"] if r["name"] == robot)
    head = [f"call ({NAMES.get(robot, robot)}, `{frame}`)", "kinengine", "raw Pinocchio", "ratio"]
    head += README_PEERS.values()
    lines = ["| " + " | ".join(head) + " |", "|---|" + "--:|" * (len(head) - 1)]
    for label, case, group, n in README_ROWS:
        row = find(report, robot, case, group, n)
        if row is None:
            continue
        k, p = row["kinengine"], row["pinocchio"]
        single = group == "latency" and row["n"] == 1

        def cell(side: dict, k: dict = k, single: bool = single, row: dict = row) -> str:
            if "success" in row:  # IK: rate, share reached, median error
                median = f", median error {exponent(side['error_median'])}" if "error_median" in side else ""
                return f"{side['per_second']:,.0f}/s ({side['success']:.1%}{median})"
            if single:
                return f"{side['min_us']:.2f} µs"
            return f"{side['per_second'] / 1e6:.2f} M/s"

        if row["case"] == SOLUTIONS:  # every solution: per pose, and the worst solution's error
            ours = (
                f"{k['min_us'] / row['n']:.1f} µs"
                if group == "latency"
                else f"{k['per_second']:,.0f} poses/s"
            )
            ours += f" (max error {exponent(row['error_max'])})" if "error_max" in row else ""
        else:  # an IK row's outcome is the row's, a peer's its own
            ours = cell({**k, **{key: row[key] for key in ("success", "error_median") if key in row}})
        cells = [
            label.replace("FRAME", f'"{frame}"'),
            ours,
            cell(p) if "min_us" in p else "–",
            f"{row['ratio']:.2f}" if "ratio" in row else "–",
        ]
        for name in README_PEERS:
            peer = row.get("peers", {}).get(name, {"status": "unsupported"})
            if peer["status"] != "ok":
                cells.append("–")
                continue
            times = peer["min_us"] / k["min_us"]
            cells.append(f"{cell(peer)} ({times:.1f}×)")  # × kinengine's time, as the README says
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def run_block(report: dict) -> str:
    tables = "\n\n".join(f"### {r['name']}\n\n{markdown(report, r['name'])}" for r in report["robots"])
    return f"Machine: {machine(report)}\n\n{conditions(report)}\n\n{tables}\n\n### Floors\n\n{floors(report)}"


def blocks(report: dict) -> dict[str, str]:
    return {
        "run": run_block(report),
        "targets": f"{conditions(report)}\n\n{targets(report)}",
        "ik": ik_rows(report),
    }


def update(text: str, generated: dict[str, str]) -> str:
    """text with each ``<!-- generated: NAME -->`` ... ``<!-- end generated: NAME -->`` block refilled."""
    for name, body in generated.items():
        pattern = re.compile(
            rf"(<!-- generated: {name} -->\n)(?:.*?\n)?(<!-- end generated: {name} -->)", re.S
        )
        if not pattern.search(text):
            raise SystemExit(f"no '<!-- generated: {name} -->' ... '<!-- end generated: {name} -->' block")
        text = pattern.sub(lambda m, body=body: m.group(1) + body + "\n" + m.group(2), text)
    return text


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, default=HERE / "results.json")
    parser.add_argument("--update", type=Path, default=None, metavar="PAGE", help="rewrite PAGE's blocks")
    parser.add_argument("--readme", action="store_true", help="print the README's speed table (ABB) only")
    args = parser.parse_args()
    report = json.loads(args.json.read_text())
    if args.readme:
        print(readme(report))
        return
    generated = blocks(report)
    if args.update is None:
        print("\n\n".join(f"<!-- {name} -->\n{body}" for name, body in generated.items()))
        return
    args.update.write_text(update(args.update.read_text(), generated))
    print(f"rewrote {', '.join(generated)} in {args.update}")


if __name__ == "__main__":
    main()
