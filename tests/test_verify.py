"""``kinengine verify``: passes on every available robot and on random URDFs, fails on broken engines."""

from __future__ import annotations

import argparse
import json
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from urdf_strategies import random_urdfs

import kinengine
from kinengine.cli.verify import add_parser
from kinengine.verify import VerifyReport, verify

REFERENCE_ROWS = (
    "pose vs reference",
    "jacobian local_world_aligned vs reference",
    "jacobian local vs reference",
    "jacobian world vs reference",
    "link poses vs yourdfpy",
)


def _load(name: str) -> kinengine.Robot:
    with warnings.catch_warnings():  # some example-robot-data files trigger parser warnings
        warnings.simplefilter("ignore")
        return kinengine.load(name)


def _run_cli(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="kinengine")
    add_parser(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    return args.handler(args)


def _failed(report: VerifyReport) -> set[str]:
    return {c.check for c in report.checks if not c.passed}


@pytest.mark.parametrize("name", kinengine.available_robots())
def test_verify_passes_on_every_available_robot(name):
    robot = _load(name)
    report = verify(robot, samples=4, seed=1)
    assert report.passed, report.table()
    rows = {c.check: c for c in report.checks}
    for row in REFERENCE_ROWS:
        assert rows[row].compared > 0, row
    corners = 2**robot.dof if robot.dof <= 8 else 64
    assert report.configurations == 1 + 4 + corners


@settings(max_examples=20, deadline=None)
@given(random_urdfs(max_links=6))
def test_verify_passes_on_random_urdfs(text):
    report = verify(kinengine.load_urdf_string(text), samples=3)
    assert report.passed, report.table()


def test_cli_prints_the_table_writes_json_and_exits_zero(tmp_path, capsys):
    path = tmp_path / "report.json"
    assert _run_cli(["verify", "ur5", "--samples", "3", "--seed", "2", "--json", str(path)]) == 0
    out = capsys.readouterr().out
    assert "pose vs reference" in out and "analytic quaternion vs finite differences" in out
    assert out.rstrip().endswith("PASSED")
    data = json.loads(path.read_text())
    assert data["passed"] is True and data["robot"] == "ur5" and data["dof"] == 6
    assert all(row["passed"] for row in data["checks"])


def _world_linear_rows_wrong(original):
    def jacobian(self, q, frame=None, reference="local_world_aligned", **kw):
        J = original(self, q, frame, reference, **kw)
        if reference != "world":
            return J
        return np.concatenate(
            [original(self, q, frame, "local_world_aligned", **kw)[..., :3, :], J[..., 3:, :]], axis=-2
        )  # forgot v_O = v − ω × p

    return jacobian


def _pose_off_by_10_nm(original):
    def frame_pose(self, q, frame=None, **kw):
        T = np.array(original(self, q, frame, **kw))
        T[..., 0, 3] += 1e-8
        return T

    return frame_pose


def _mimic_column_dropped(original):
    def jacobian(self, q, frame=None, reference="local_world_aligned", **kw):
        J = np.array(original(self, q, frame, reference, **kw))
        J[..., self.joint_names.index("panda_finger_joint1")] *= 0.5  # only the leader's own motion
        return J

    return jacobian


def _analytic_scaled(original):
    def analytic_jacobian(self, q, frame=None, position="cartesian", rotation="euler_zyx", **kw):
        J = original(self, q, frame, position, rotation, **kw)
        return J * (1 + 1e-4) if rotation == "euler_zyx" else J

    return analytic_jacobian


@pytest.mark.parametrize(
    "robot_name, method, breakage, expected",
    [
        (
            "ur5",
            "jacobian",
            _world_linear_rows_wrong,
            {"jacobian world vs reference", "jacobian world vs finite differences"},
        ),
        ("ur5", "frame_pose", _pose_off_by_10_nm, {"pose vs reference", "link poses vs yourdfpy"}),
        (
            "panda",
            "jacobian",
            _mimic_column_dropped,
            {f"jacobian {r} vs reference" for r in ("local_world_aligned", "local", "world")}
            | {f"jacobian {r} vs finite differences" for r in ("local_world_aligned", "local", "world")},
        ),
        ("ur5", "analytic_jacobian", _analytic_scaled, {"analytic euler_zyx vs finite differences"}),
    ],
)
def test_verify_fails_on_a_broken_engine(monkeypatch, capsys, robot_name, method, breakage, expected):
    monkeypatch.setattr(kinengine.Robot, method, breakage(getattr(kinengine.Robot, method)))
    report = verify(_load(robot_name), samples=3)
    assert expected <= _failed(report), report.table()
    assert _run_cli(["verify", robot_name, "--samples", "3"]) == 1
    assert capsys.readouterr().out.rstrip().endswith("FAILED")


def test_analytic_rows_are_skipped_when_the_robot_has_none():
    class WithoutAnalytic:
        def __init__(self, robot):
            self._robot = robot

        def __getattr__(self, name):
            if name in ("analytic_jacobian", "pose_parameters"):
                raise AttributeError(name)
            return getattr(self._robot, name)

    report = verify(WithoutAnalytic(_load("ur5")), samples=2)
    assert report.passed
    assert [c.note for c in report.checks if c.check.startswith("analytic")] == [
        "skipped: robot has no analytic_jacobian"
    ]
