"""Running commands for the tests that build or install kinengine into a fresh virtual environment
(test_packaging, test_binary_wheel, test_coexistence): an environment that points nowhere else, and a
run that fails the test with the command's output."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

DROPPED = (
    "PYTHONPATH",
    "PYTHONHOME",
    "PYTHONSTARTUP",
    "PYTHONSAFEPATH",
    "VIRTUAL_ENV",
    "__PYVENV_LAUNCHER__",
    "PYTHONUSERBASE",
    "KINENGINE_PURE_PYTHON",
    "PIP_CONSTRAINT",
)


def clean_env(**extra: str) -> dict[str, str]:
    """The environment without anything that would point Python at the checkout or another venv."""
    env = {k: v for k, v in os.environ.items() if k not in DROPPED}
    return {
        **env,
        "PYTHONNOUSERSITE": "1",
        "PIP_DISABLE_PIP_VERSION_CHECK": "1",
        "MPLBACKEND": "Agg",
        **extra,
    }


def run(
    cmd: list[object], *, cwd: Path, timeout: float, env: dict[str, str]
) -> subprocess.CompletedProcess[str]:
    """Run ``cmd``; the test fails with its exit status and output unless it exits 0."""
    proc = subprocess.run(
        [str(c) for c in cmd],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
        stdin=subprocess.DEVNULL,
        check=False,
    )
    assert proc.returncode == 0, (
        f"{' '.join(map(str, cmd))} exited {proc.returncode}\n"
        f"--- stdout ---\n{proc.stdout[-4000:]}\n--- stderr ---\n{proc.stderr[-4000:]}"
    )
    return proc
