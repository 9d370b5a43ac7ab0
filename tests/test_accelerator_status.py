"""The one line ``kinengine --version`` and ``kinengine info`` print about the C accelerator: on, or off and
why (kinengine.model.accelerator.status), checked on real package folders: this process's, a copy of the
source tree without built extensions, and a subprocess with KINENGINE_PURE_PYTHON=1."""

from __future__ import annotations

import importlib.machinery
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import kinengine
from kinengine.cli.main import main
from kinengine.kinematics import compiler
from kinengine.model import accelerator

REPO = Path(__file__).resolve().parents[1]
SUFFIX = importlib.machinery.EXTENSION_SUFFIXES[0]


def _package(root: Path, *, checkout: bool, built: tuple[str, ...] = ()) -> Path:
    """A kinengine folder under root (beside a pyproject.toml when ``checkout``) with the named extension
    files present."""
    package = root / "kinengine"
    for name, folder in accelerator.EXTENSIONS.items():
        (root / folder).mkdir(parents=True, exist_ok=True)
        if name in built:
            (root / folder / f"{name}{SUFFIX}").write_bytes(b"")
    if checkout:
        (root / "pyproject.toml").write_text("[project]\nname = 'kinengine'\n")
    return package


def test_this_process_line_matches_accelerated() -> None:
    line = compiler.accelerator_status()
    assert line.startswith("accelerator: on" if kinengine.ACCELERATED else "accelerator: off"), line


def test_version_prints_version_then_accelerator_line(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["--version"])
    assert exit_info.value.code == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines == [f"kinengine {kinengine.__version__}", compiler.accelerator_status()]


def test_info_without_robot_reports_the_installation(capsys: pytest.CaptureFixture[str]) -> None:
    import numpy as np
    import pinocchio as pin

    assert main(["info"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith(f"kinengine {kinengine.__version__} (Python ")
    assert lines[1] == compiler.accelerator_status()
    assert f"numpy {np.__version__}" in lines
    assert f"pin {pin.__version__}" in lines


def test_source_tree_without_extensions(tmp_path: Path) -> None:
    package = _package(tmp_path, checkout=True)
    line = accelerator.status({"fastcall": "No module named x", "chainkernel": None}, package=package)
    assert line.startswith("accelerator: off (pure Python, chainkernel and fastcall missing): ")
    assert f"source tree {tmp_path}" in line and "`pip install -e .`" in line


def test_installed_without_extensions(tmp_path: Path) -> None:
    package = _package(tmp_path, checkout=False)
    line = accelerator.status({"fastcall": "No module named x"}, package=package)
    assert "not built when kinengine was installed (no working C compiler then)" in line, line


def test_built_but_not_loading_reports_the_error(tmp_path: Path) -> None:
    package = _package(tmp_path, checkout=True, built=("fastcall", "chainkernel"))
    line = accelerator.status({"fastcall": "undefined symbol: foo"}, package=package)
    assert line == "accelerator: off (pure Python, fastcall missing): the built extensions do not load " + (
        "(fastcall: undefined symbol: foo)"
    )


def test_switched_off_wins(tmp_path: Path) -> None:
    line = accelerator.status({}, switched_off=True, package=_package(tmp_path, checkout=False))
    assert "KINENGINE_PURE_PYTHON" in line and line.startswith("accelerator: off")


def _env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "KINENGINE_PURE_PYTHON")}
    return {**env, **extra}


def test_switched_off_in_a_subprocess() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "kinengine", "--version"],
        env=_env(KINENGINE_PURE_PYTHON="1"),
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    assert proc.stdout.splitlines()[1].startswith(
        "accelerator: off (pure Python): disabled by KINENGINE_PURE"
    )


def test_a_source_tree_copy_says_so(tmp_path: Path) -> None:
    """Python started inside a clone imports its kinengine/, where nothing is built: the line says so and
    names the fix (the copy has the Python files and pyproject.toml, no compiled extension)."""
    clone = tmp_path / "clone"
    shutil.copytree(
        REPO / "kinengine", clone / "kinengine", ignore=shutil.ignore_patterns("*.so", "*.pyd", "__pycache__")
    )
    shutil.copy2(REPO / "pyproject.toml", clone / "pyproject.toml")
    shutil.copytree(REPO / "robots", clone / "robots")
    code = "import kinengine, kinengine.kinematics.compiler as c; print(kinengine.__file__); print(c.accelerator_status())"
    proc = subprocess.run(
        [sys.executable, "-c", code],
        cwd=clone,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    imported, line = proc.stdout.splitlines()
    assert Path(imported).resolve().is_relative_to(clone.resolve())
    assert line.startswith("accelerator: off (pure Python, chainkernel and fastcall missing): kinengine is ")
    assert f"source tree {clone.resolve()}" in line and "`pip install -e .`" in line
