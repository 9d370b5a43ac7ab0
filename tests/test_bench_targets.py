"""The one run behind docs/benchmarks.md's targets: the closed-form IK rows' achieved error (against the
pose a base-joint turn gives in closed form), rows kept from the peers, run_all.py's load record and
render_targets.py's table and verdicts (from reports whose figures the tests choose).

No timing is asserted: the figures here are made up or are errors, never speeds.
"""

from __future__ import annotations

import importlib
import math
import sys
from pathlib import Path

import numpy as np
import pytest

import kinengine
from kinengine.cli.bench import run as bench_run
from kinengine.cli.bench.ik_cases import SOLUTIONS
from kinengine.cli.bench.row import Case
from kinengine.errors import KinematicsError

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.fixture(scope="module")
def scripts():
    sys.path.insert(0, str(BENCHMARKS))
    try:
        yield importlib.import_module("render_targets"), importlib.import_module("run_all")
    finally:
        sys.path.remove(str(BENCHMARKS))


@pytest.fixture(scope="module")
def abb():
    robot = kinengine.load("abb_irb120")
    try:
        robot.ik_solutions(robot.frame_pose(robot.neutral()))
    except KinematicsError as exc:  # the ik extra is missing
        pytest.skip(str(exc))
    return robot


def _case(robot, targets):
    return Case("latency", SOLUTIONS, len(targets), None, None, targets=targets, robot=robot, frame="tool0")


def test_every_solution_is_checked_and_a_turned_base_gives_its_closed_form_error(abb):
    """A base turn δ about z (joint_1's axis through the origin) moves the tool by the chord 2 r sin(δ/2)
    (r its distance from the axis) and turns it by δ: the row's error is the larger, and the target is
    no longer reached; the other targets' solutions are exact."""
    rng = np.random.default_rng(5)
    T = abb.frame_pose(abb.random_configuration(rng, size=4))
    found = [abb.ik_solutions(t).q for t in T]
    exact = bench_run.ik_outcome(_case(abb, T), found)
    assert exact["success"] == 1.0 and exact["error_max"] <= 1e-9
    assert exact["solutions_per_target"] == pytest.approx(np.mean([len(q) for q in found]))
    delta = 1e-3
    turned = [q.copy() for q in found]
    turned[2][-1, 0] += delta
    outcome = bench_run.ik_outcome(_case(abb, T), turned)
    r = math.hypot(*T[2, :2, 3])
    assert outcome["success"] == 0.75
    assert outcome["error_max"] == pytest.approx(max(2 * r * math.sin(delta / 2), delta), rel=1e-6)


def test_a_batch_answer_padded_with_nan_counts_only_its_solutions(abb):
    T = abb.frame_pose(abb.random_configuration(np.random.default_rng(6), size=3))
    T[1, :3, 3] = [5.0, 0.0, 0.0]  # out of reach: no solution
    answer = abb.ik_solutions(T)
    outcome = bench_run.ik_outcome(_case(abb, T), answer.q)
    assert answer.count[1] == 0 and outcome["success"] == pytest.approx(2 / 3)
    assert outcome["solutions_per_target"] == pytest.approx(answer.count.mean())
    assert outcome["error_max"] <= 1e-9  # the reached targets' solutions: the unreachable has no error


def test_a_row_kept_from_the_peers_does_not_call_them():
    class Refusing:
        name = "refusing"

        def prepare(self, case):
            raise AssertionError("a peer was asked to time a row kept from the peers")

    one = np.eye(4)
    case = Case("latency", "kept", 1, lambda: one, None, "note", peers=False)
    row = bench_run.run_case(case, bench_run.Settings((1,), repeat=2, min_time=1e-4), [Refusing()])
    assert row["peers"] == {"refusing": {"status": "unsupported"}}


def test_the_load_sampler_keeps_the_start_the_end_and_the_range(scripts):
    _, run_all = scripts
    sampler = run_all.LoadSampler(period=0.01)
    load = sampler.stop()
    assert load["samples"] >= 2 and load["start"] == sampler.samples[0] and load["end"] == sampler.samples[-1]
    assert load["min"] <= load["median"] <= load["max"] and load["min"] == min(sampler.samples)


def _row(robot, case, ratio=None, group="latency", n=1, per_second=None, **extra):
    k = {"status": "ok", "min_us": 1.0 if per_second is None else n / per_second * 1e6}
    k["per_second"] = per_second or 1e6
    row = {
        "robot": robot,
        "case": case,
        "group": group,
        "n": n,
        "kinengine": k,
        "pinocchio": {"status": "none"},
    }
    row |= extra
    return row | ({"ratio": ratio} if ratio is not None else {})


def _report(ratio_ur5=1.2, kinematics_rate=13e6):
    rows = []
    for robot in ("abb_irb120", "ur5"):
        rows += [
            _row(robot, "frame_pose", 1.1),
            _row(robot, "analytic_jacobian[euler_zyx]", 1.12),
            _row(robot, "analytic_jacobian[rotation_vector]", ratio_ur5 if robot == "ur5" else 1.25),
            _row(robot, "kinematics", group="throughput", n=100_000, per_second=kinematics_rate),
            _row(
                robot,
                "inverse_kinematics[random targets]",
                group="throughput",
                n=10_000,
                per_second=90_000,
                success=0.999,
                error_median=2e-8,
                error_max=0.1,
                peers={
                    "roboticstoolbox": {
                        "status": "ok",
                        "per_second": 9_000,
                        "min_us": 1e10 / 9_000,
                        "success": 1.0,
                    }
                },
            ),
        ]
    rows.append(
        _row("abb_irb120", SOLUTIONS, per_second=40_000, n=200, success=1.0, solutions_per_target=3.9)
    )
    return {
        "robots": [{"name": "abb_irb120", "frame": "tool0"}, {"name": "ur5", "frame": "tool0"}],
        "rows": rows,
        "timestamp": "2026-11-27T03:45",
        "settings": {"ik_peer_tol": 5e-13},
    }


def _line(table, start):
    return next(line for line in table.splitlines() if line.startswith("| " + start))


def test_targets_are_met_only_when_every_robot_meets_them(scripts):
    render, _ = scripts
    table = render.targets(_report())
    assert _line(table, "`frame_pose(q)`") == "| `frame_pose(q)` ≤ 1.3× | 1.10 | 1.10 | met |"
    assert "1.12–1.25 (rotation_vector) | 1.12–1.20 (rotation_vector) | met |" in table
    assert _line(table, "`kinematics(Q)`").endswith("| 13.00 M/s | 13.00 M/s | met |")
    assert _line(table, "batched IK").endswith(
        "| 90,000/s, 99.9%, error 2e-8 / 1e-1 | 90,000/s, 99.9%, error 2e-8 / 1e-1 | met |"
    )
    missed = render.targets(_report(ratio_ur5=1.31, kinematics_rate=11.9e6))
    assert _line(missed, "`analytic_jacobian").endswith("| **not met** (UR5) |")
    assert _line(missed, "`kinematics(Q)`").endswith("| **not met** (ABB IRB 120, UR5) |")
    assert _line(missed, "single IK").endswith("| – | – | not measured |")  # no one-by-one row here


def test_the_closed_form_bound_applies_to_the_abb_alone(scripts):
    render, _ = scripts
    line = _line(render.targets(_report()), "closed form, every solution of one pose")
    # 200 poses per call at 40,000 poses/s: 25 µs per pose, over the 20 µs bound; the UR5 has no row
    assert line.endswith("| 25.0 µs, 3.9 solutions | – | **not met** (ABB IRB 120) |")


def test_the_ik_table_puts_each_rate_beside_its_error(scripts):
    render, _ = scripts
    table = render.ik_rows(_report())
    assert (
        "| ABB IRB 120 | 10,000, one batch | kinengine, numeric | 90,000 | 99.9%, error 2e-8 / 1e-1 |"
        in table
    )
    assert (
        "| UR5 | 10,000, one batch | Robotics Toolbox `ik_LM`, tol 5e-13, one by one | 9,000 | 100.0% reached |"
        in table
    )


def test_update_rewrites_only_the_generated_blocks(scripts):
    render, _ = scripts
    page = "intro\n<!-- generated: ik -->\nold\n<!-- end generated: ik -->\noutro\n"
    assert render.update(page, {"ik": "new\nrows"}) == (
        "intro\n<!-- generated: ik -->\nnew\nrows\n<!-- end generated: ik -->\noutro\n"
    )
    with pytest.raises(SystemExit, match="generated: run"):
        render.update(page, {"run": "x"})


def test_the_readme_row_of_batched_ik_gives_each_rate_its_accuracy_and_the_time_ratio(scripts):
    render, _ = scripts
    line = _line(render.readme(_report()), "`inverse_kinematics`, batch")
    assert line == (
        "| `inverse_kinematics`, batch of 10,000 random targets | 90,000/s (99.9%, median error 2e-8) | – | – "
        "| 9,000/s (100.0%) (10.0×) | – | – |"
    )
