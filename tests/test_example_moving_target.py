"""examples/moving_target_tracking.py runs headless, writes its plot, and its runs keep the bounds it states."""

from __future__ import annotations

import pytest
from example_modules import load_example


@pytest.fixture(scope="module")
def example():
    return load_example("moving_target_tracking")


def test_main_writes_a_png_and_states_the_errors(example, tmp_path, capsys):
    out = tmp_path / "tracking.png"
    assert example.main(["--output", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    lines = capsys.readouterr().out.splitlines()
    errors = {
        line.split(":")[0]: float(line.split("error ")[1].split(" m")[0])
        for line in lines
        if "max position" in line
    }
    assert errors["ABB with feed-forward"] <= 1e-5  # the docstring's ~2e-6 m
    assert errors["ABB feedback only"] == pytest.approx(2e-3, rel=0.05)  # |v| dt / k
    assert errors["Panda, posture on a lower level"] <= 5e-4 < errors["Panda, weighted posture"]
