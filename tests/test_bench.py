"""``kinengine bench``: the quick run's JSON, table and PNG, the agreement checks, the timing helper.

No timing is asserted: only structure, units that must be consistent, and the values the benchmark
compares before it times (kinengine against its raw-Pinocchio floor, peers against kinengine).
"""

from __future__ import annotations

import importlib
import importlib.metadata
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import kinengine
from kinengine.cli.bench import command as bench
from kinengine.cli.bench import run as bench_run
from kinengine.cli.bench.cases import Case, throughput_cases
from kinengine.cli.bench.ik_cases import NEAREST, SOLUTIONS
from kinengine.parameterizations import ROTATION_PARAMETERIZATIONS

pytestmark = pytest.mark.slow  # runs the benchmark, with the peers where installed


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    json_path, png_path = out / "bench.json", out / "bench.png"
    code = bench.main(["abb_irb120", "--quick", "--peers", "--json", str(json_path), "--plot", str(png_path)])
    return code, json.loads(json_path.read_text()), png_path


def test_quick_run_writes_json_with_environment(quick_run):
    code, report, _ = quick_run
    assert code == 0
    assert report["schema"] == 1
    assert report["cores"] >= 1 and report["cpu"]
    assert report["versions"]["pin"] == importlib.metadata.version("pin")  # the installed Pinocchio
    assert report["versions"]["numpy"] == np.__version__
    assert report["timestamp"].endswith("+00:00")
    assert report["settings"]["sizes"] == list(bench_run.QUICK.sizes)
    assert report["robots"][0]["name"] == "abb_irb120" and report["robots"][0]["frame"] == "tool0"


def test_quick_run_has_every_row(quick_run):
    _, report, _ = quick_run
    cases = [(r["group"], r["case"], r["n"]) for r in report["rows"]]
    latency = {c for g, c, _ in cases if g == "latency"}
    assert {
        "frame_pose",
        "jacobian[local_world_aligned]",
        "jacobian[local]",
        "jacobian[world]",
        "task.update(q)",
        "task.update(q)[euler_zyz]",
        "task.update(q, qdot)",
        "kinematics",
        "frame().pose",
        "frame().jacobian",
        "frame().kinematics",
        "frame(), check_inputs=False.pose",
        "frame(), check_inputs=False.jacobian",
        "frame(), check_inputs=False.kinematics",
        "inverse_kinematics",
        "inverse_kinematics[random targets]",
    } <= latency
    assert ("throughput", "inverse_kinematics[random targets]", bench_run.QUICK.ik[1]) in cases
    assert {f"analytic_jacobian[{name}]" for name in ROTATION_PARAMETERIZATIONS} <= latency
    for n in bench_run.QUICK.sizes:
        for name in (
            "frame_pose",
            "jacobian[local_world_aligned]",
            "kinematics",
            "kinematics[out=]",
            "analytic_jacobian[euler_zyx]",
            "analytic_jacobian[quaternion]",
        ):
            assert ("throughput", name, n) in cases
    assert len(cases) == len(set(cases))


def test_timings_are_consistent(quick_run):
    _, report, _ = quick_run
    for row in report["rows"]:
        for side in [row["kinengine"], row["pinocchio"], *row["peers"].values()]:
            if side["status"] != "ok":
                assert "min_us" not in side
                continue
            assert 0 < side["min_us"] <= side["median_us"]
            assert side["per_second"] == pytest.approx(row["n"] / side["min_us"] * 1e6, rel=1e-12)
        if row["kinengine"]["status"] == "ok" and row["pinocchio"]["status"] != "none":
            expected = row["kinengine"]["min_us"] / row["pinocchio"]["min_us"]
            assert row["ratio"] == pytest.approx(expected, rel=1e-12)
            assert row["floor"]  # the floor's code is named
        else:
            assert "ratio" not in row and row["note"]


def test_kinengine_agrees_with_its_pinocchio_floor(quick_run):
    _, report, _ = quick_run
    compared = [r for r in report["rows"] if "difference" in r["pinocchio"]]
    # poses, Jacobians, the batches and the analytic Jacobians Pinocchio can convert (zyx, quaternion, log3)
    assert len(compared) >= 4 + 3 + 7 + 6 * len(bench_run.QUICK.sizes)
    for row in compared:
        assert row["pinocchio"]["status"] == "ok", row
        assert row["pinocchio"]["difference"] <= 1e-9


def test_missing_peers_are_reported_not_timed(quick_run):
    _, report, _ = quick_run
    for name, status in report["robots"][0]["peers"].items():
        if not status["loaded"]:
            assert status["note"]
            assert all(row["peers"][name]["status"] == "unsupported" for row in report["rows"])


def test_png_is_written(quick_run):
    _, _, png = quick_run
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_table_lists_every_row(quick_run):
    _, report, _ = quick_run
    table = bench.format_table(report)
    assert "pin min µs" in table and report["cpu"] in table
    main, _, peers = table.partition("\npeers:")
    assert len([line for line in main.splitlines() if line.startswith("abb_irb120 ")]) == len(report["rows"])
    peer_rows = [r for r in report["rows"] if any(v["status"] != "unsupported" for v in r["peers"].values())]
    assert len([line for line in peers.splitlines() if line.startswith("abb_irb120 ")]) == len(peer_rows)


def _peer_rows(report, name):
    status = report["robots"][0]["peers"][name]
    if not status["loaded"]:
        pytest.skip(f"{name} not installed here ({status['note']})")
    return {(r["case"], r["n"]): r["peers"][name] for r in report["rows"]}


def test_roboticstoolbox_agrees_before_it_is_timed(quick_run):
    _, report, _ = quick_run
    rows = _peer_rows(report, "roboticstoolbox")
    timed = [
        key for key, result in rows.items() if result["status"] == "ok" and not key[0].startswith("inverse")
    ]
    # poses and Jacobians (single and batched), and jacob0_analytical for its four representations
    assert {
        ("frame_pose", 1),
        ("jacobian[local_world_aligned]", 1),
        ("frame_pose", 1000),
        ("analytic_jacobian[euler_zyz]", 1),
        ("analytic_jacobian[euler_zyx]", 1),
        ("analytic_jacobian[euler_xyz]", 1),
        ("analytic_jacobian[rotation_vector]", 1),
    } <= set(timed)
    for key in timed:
        assert rows[key]["difference"] <= 1e-9 and rows[key]["min_us"] > 0, key
    assert rows[("analytic_jacobian[quaternion]", 1)]["status"] == "unsupported"
    assert report["versions"]["roboticstoolbox-python"]


def test_pytorch_kinematics_float32_origins_are_reported_not_timed(quick_run):
    """pytorch-kinematics parses <origin rpy> as float32: poses off by ~1e-8 m, over the 1e-9 tolerance."""
    _, report, _ = quick_run
    rows = _peer_rows(report, "pytorch_kinematics")
    checked = {key: result for key, result in rows.items() if result["status"] != "unsupported"}
    assert ("frame_pose", 1) in checked and ("jacobian[local_world_aligned]", 1000) in checked
    for key, result in checked.items():
        assert result["status"] == "disagrees" and "min_us" not in result, key
        assert 1e-9 < result["difference"] < 1e-6, key  # a rounding difference, not a convention mismatch
    assert report["versions"]["torch"].endswith("+cpu")  # the CPU build, never a CUDA download


@pytest.mark.parametrize("name", ["mujoco", "drake"])
def test_mujoco_and_drake_agree_before_they_are_timed(quick_run, name):
    _, report, _ = quick_run
    rows = _peer_rows(report, name)
    for key in (
        ("frame_pose", 1),
        ("jacobian[local_world_aligned]", 1),
        ("frame_pose", 100),
        ("jacobian[local_world_aligned]", 1000),
    ):
        assert rows[key]["status"] == "ok" and rows[key]["difference"] <= 1e-9 and rows[key]["min_us"] > 0, (
            key
        )
    assert report["versions"][name]


def test_ik_rows_count_reached_targets_and_record_the_achieved_error(quick_run):
    """Rates are compared at equal accuracy: each IK row records, for kinengine and the peer, the share of
    targets within 1e-6 m / 1e-6 rad and the median and largest achieved error, consistent with it."""
    _, report, _ = quick_run
    ik_rows = [r for r in report["rows"] if r["case"] == "inverse_kinematics[random targets]"]
    assert len(ik_rows) == 2
    for row in ik_rows:
        assert 0.9 <= row["success"] <= 1.0 and row["pinocchio"]["status"] == "none"
        assert 0.0 <= row["error_median"] <= row["error_max"]
        assert row["error_median"] <= 1e-6 + 2e-8  # most targets reached: the median one too
        if row["success"] == 1.0:
            assert row["error_max"] <= 1e-6 + 2e-8
        rtb = row["peers"]["roboticstoolbox"]
        if report["robots"][0]["peers"]["roboticstoolbox"]["loaded"]:
            assert rtb["status"] == "ok" and 0.0 <= rtb["success"] <= 1.0
            assert 0.0 <= rtb["error_median"] <= rtb["error_max"]


def test_closed_form_rows_record_every_solution_and_its_error(quick_run):
    """The closed form on the numeric rows' targets: every solution (and the nearest one) exact, every
    target reached; the peers are not timed again on these targets."""
    _, report, _ = quick_run
    rows = {(r["group"], r["case"]): r for r in report["rows"]}
    if ("latency", SOLUTIONS) not in rows:
        pytest.skip("no closed form here (the ik extra is missing)")
    for group in ("latency", "throughput"):
        every, nearest = rows[(group, SOLUTIONS)], rows[(group, NEAREST)]
        assert every["n"] == nearest["n"] == rows[(group, "inverse_kinematics[random targets]")]["n"]
        assert every["success"] == nearest["success"] == 1.0
        assert every["error_max"] <= 1e-9 and nearest["error_max"] <= 1e-9
        assert 1.0 <= every["solutions_per_target"] <= 8.0  # a 6R arm has at most 8 within one turn
        for row in (every, nearest):
            assert all(peer == {"status": "unsupported"} for peer in row["peers"].values())


def test_render_targets_reads_the_figures_of_the_run(quick_run):
    """benchmarks/render_targets.py on the quick run's JSON: the frame_pose ratio and the single IK rate
    as the JSON has them."""
    _, report, _ = quick_run
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
    try:
        render = importlib.import_module("render_targets")
    finally:
        sys.path.pop(0)
    table = render.targets(report).splitlines()
    row = next(r for r in report["rows"] if (r["group"], r["case"]) == ("latency", "frame_pose"))
    assert next(line for line in table if line.startswith("| `frame_pose(q)`")).startswith(
        f"| `frame_pose(q)` ≤ 1.3× | {row['ratio']:.2f} | "
    )
    ik = next(r for r in report["rows"] if (r["group"], r["case"]) == ("latency", render.NUMERIC))
    assert f"| {ik['kinengine']['per_second']:,.0f}/s, {ik['success']:.1%}, error " in next(
        line for line in table if line.startswith("| single IK")
    )


def test_ikpy_poses_agree(quick_run):
    _, report, _ = quick_run
    rows = _peer_rows(report, "ikpy")
    assert rows[("frame_pose", 1)]["status"] == "ok" and rows[("frame_pose", 1)]["difference"] <= 1e-9
    assert rows[("jacobian[local_world_aligned]", 1)]["status"] == "unsupported"


class _Peer:
    """A stand-in peer whose answer is off by ``error``."""

    name = "fake"

    def __init__(self, error: float) -> None:
        self.error = error

    def prepare(self, case):
        return (lambda: case.kinengine()), (lambda out: np.asarray(out) + self.error)


def test_a_peer_that_disagrees_is_reported_and_not_timed():
    robot = kinengine.load("abb_irb120")
    case = next(c for c in throughput_cases(robot, "tool0", [3]) if c.name == "frame_pose")
    settings = bench_run.Settings((3,), repeat=2, min_time=1e-4)
    row = bench_run.run_case(case, settings, [_Peer(1e-6)], peer_atol=1e-9)
    assert row["peers"]["fake"] == {"status": "disagrees", "difference": pytest.approx(1e-6, rel=1e-6)}
    row = bench_run.run_case(case, settings, [_Peer(1e-12)], peer_atol=1e-9)
    assert row["peers"]["fake"]["status"] == "ok" and row["peers"]["fake"]["min_us"] > 0


def test_a_floor_that_disagrees_is_flagged():
    one = np.eye(4)
    case = Case("latency", "wrong", 1, lambda: one, lambda: one * 2.0, compare=True)
    row = bench_run.run_case(case, bench_run.Settings((1,), repeat=2, min_time=1e-4))
    assert row["pinocchio"]["status"] == "disagrees" and row["pinocchio"]["difference"] == pytest.approx(0.5)


def test_max_relative_difference():
    a = np.array([[1.0, 2.0], [3.0, 400.0]])
    assert bench_run.max_relative_difference(a, a) == 0.0
    assert bench_run.max_relative_difference(a + 4.0, a) == pytest.approx(4.0 / 400.0)
    assert bench_run.max_relative_difference(np.full(2, 0.25), np.zeros(2)) == 0.25  # absolute below 1
    assert bench_run.max_relative_difference((a, a), (a, a + 1.0)) == pytest.approx(1.0 / 401.0)
    assert math.isinf(bench_run.max_relative_difference(a, a[0]))


def test_measure_counts_calls_until_min_time():
    calls = []
    timing = bench_run.measure(lambda: calls.append(1), bench_run.Settings((1,), repeat=3, min_time=1e-3))
    assert timing["calls"] >= 1 and timing["min_us"] <= timing["median_us"]
    assert len(calls) >= 1 + 3 * timing["calls"]


def test_a_slow_side_is_repeated_less_and_spread_among_the_fast_sides_repeats(monkeypatch):
    """A side slower than SLOW_CALL per call takes SLOW_REPEAT repeats; the other keeps every repeat, and the
    slow side's repeats are spread over the run: with 21 rounds and 5 slow repeats, in rounds 4, 8, 12, 16
    and 20 (0-based), i.e. after 5, 9, 13, 17 and 21 of the fast side's repeats."""
    monkeypatch.setattr(bench_run, "SLOW_CALL", 0.02)
    order: list[str] = []

    def slow() -> None:
        order.append("slow")
        time.sleep(0.03)

    timings = bench_run.measure_interleaved(
        [lambda: order.append("fast"), slow], bench_run.Settings((1,), repeat=21, min_time=1e-4)
    )
    assert timings[1]["calls"] == 1
    timed = order[order.index("slow") + 1 :]  # after the slow side's warm-up
    fast_calls = timings[0]["calls"]
    assert timed.count("slow") == bench_run.SLOW_REPEAT
    assert timed.count("fast") == 21 * fast_calls
    fast_before = [timed[:k].count("fast") // fast_calls for k, call in enumerate(timed) if call == "slow"]
    assert fast_before == [5, 9, 13, 17, 21]


def test_a_planar_arm_is_benched_without_the_parameterizations_singular_everywhere(tmp_path, capsys):
    """planar_3dof turns about z only: euler_yxy and euler_yzy are within 0.1 of their singular sets at
    every configuration (χ2 stays at 0 or π); their rows are left out with a warning, the rest is timed."""
    from kinengine.cli import main

    path = tmp_path / "planar.json"
    assert main(["bench", "planar_3dof", "--quick", "--json", str(path)]) == 0
    err = capsys.readouterr().err
    assert "the analytic rows of euler_yxy, euler_yzy are not timed" in err
    names = {row["case"] for row in json.loads(path.read_text())["rows"]}
    assert "analytic_jacobian[euler_zyx]" in names and "analytic_jacobian[euler_yxy]" not in names
