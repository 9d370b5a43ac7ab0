"""examples/two_frame_tracking.py runs headless (matplotlib Agg), crosses a ZYX gimbal lock and the wrist
singularity of the ABB IRB 120 without an exception, writes its PNG and keeps the tracking errors bounded."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest
from example_modules import example_module

matplotlib.use("Agg")


@pytest.fixture(scope="module")
def example():
    yield from example_module("two_frame_tracking")


def test_tracks_through_both_singularities_and_writes_a_png(example, tmp_path, capsys):
    out = tmp_path / "tracking.png"
    run = example.main(["--duration", "1.0", "--output", str(out)])
    assert out.stat().st_size > 10_000 and out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "saved" in capsys.readouterr().out
    # the path really crosses both singular sets ...
    assert run.zyx_distance.min() < 1e-2 and run.sigma_min.min() < 1e-2
    # ... the controller switched away from ZYX before the gimbal lock ...
    assert len(run.switches) >= 1 and run.rotation[0] == "euler_zyx" and "euler_zyz" in run.rotation
    assert 0.0 < run.switches[0] < 0.5
    # ... and the errors stay bounded (faster motion than the 4 s default: larger but small errors)
    assert np.isfinite(run.position_error).all()
    assert (
        run.position_error.max() < 2e-3 and run.rotation_error.max() < 2e-3 and run.link4_error.max() < 2e-3
    )


def test_without_switching_the_nan_rows_keep_the_loop_alive(example):
    run = example.simulate(duration=1.0, switch_below=0.0)  # never switches: ZYX rows meet the gimbal lock
    assert run.switches == () and set(run.rotation) == {"euler_zyx"}
    assert np.isfinite(run.position_error).all() and run.position_error.max() < 1e-2
