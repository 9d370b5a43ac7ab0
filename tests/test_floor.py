"""The declared dependency ranges and the floor constraints CI installs (ci/floor.txt).

Every runtime dependency is a range ``>=floor,<next major``; ci/floor.txt pins each to its floor and must be
what scripts/floor_constraints.py writes from pyproject.toml; in the floor run of .ci/run
(KINENGINE_FLOOR_RUN=1) every dependency installed is exactly at its floor.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from importlib import metadata
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SCRIPT = REPO / "scripts" / "floor_constraints.py"

if sys.version_info < (3, 11):
    pytest.skip(
        "scripts/floor_constraints.py reads pyproject.toml with tomllib (Python 3.11+)",
        allow_module_level=True,
    )

_spec = importlib.util.spec_from_file_location("floor_constraints", SCRIPT)
assert _spec is not None and _spec.loader is not None
floor_constraints = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(floor_constraints)


def _ranges() -> list[tuple[str, str, str]]:
    import tomllib

    entries = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))["project"]["dependencies"]
    out = []
    for entry in entries:
        match = floor_constraints.RANGE.match(entry)
        assert match is not None, f"{entry!r} is not a range >=floor,<bound"
        name, floor = match.groups()
        out.append((name, floor, entry.rsplit("<", 1)[1].strip()))
    return out


def test_floor_file_is_in_sync_with_pyproject() -> None:
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--check"], capture_output=True, text=True, timeout=60, check=False
    )
    assert proc.returncode == 0, proc.stderr
    assert (REPO / "ci" / "floor.txt").read_text(encoding="utf-8") == floor_constraints.text()


def test_every_bound_is_a_major_release_line() -> None:
    """<N with N above the floor's major (pin: 3.x and 4.x, <5); for a 0.x floor, <0.N or <1."""
    for name, floor, bound in _ranges():
        major, minor = (int(part) for part in floor.split(".")[:2])
        if major >= 1:
            assert bound.isdigit() and int(bound) > major, f"{name}: <{bound} is not a major above {floor}"
        else:
            assert bound == "1" or (bound.startswith("0.") and int(bound[2:]) > minor), f"{name}: <{bound}"


def test_a_pin_is_refused(tmp_path: Path) -> None:
    pyproject = tmp_path / "pyproject.toml"
    pyproject.write_text('[project]\nname = "x"\ndependencies = ["pin==4.1.0"]\n', encoding="utf-8")
    with pytest.raises(ValueError, match=r"'pin==4.1.0' is not a range"):
        floor_constraints.floors(pyproject)


@pytest.mark.skipif(os.environ.get("KINENGINE_FLOOR_RUN") != "1", reason="only in the floor run of .ci/run")
def test_floor_run_installed_every_floor() -> None:
    def release(version: str) -> list[int]:  # "6.1" and "6.1.0" are the same release
        parts = [int(p) for p in version.split(".")]
        while parts and parts[-1] == 0:
            parts.pop()
        return parts

    for name, floor, _ in _ranges():
        installed = metadata.version(name)
        assert release(installed) == release(floor), f"{name} {installed} installed, the floor is {floor}"


@pytest.mark.parametrize(
    "failure, named",
    [
        ("liburdfdom_sensor.so.4.0: cannot open shared object file: No such file or directory", True),
        ("libtinyxml2.so.10: cannot open shared object file: No such file or directory", True),
        ("libboost_python311.so.1.90.0: cannot open shared object file", False),
    ],
)
def test_a_pin_3_wheel_beside_too_new_libraries_is_named(tmp_path: Path, failure: str, named: bool) -> None:
    """`import kinengine` where `import pinocchio` fails as a pin 3.x wheel does beside cmeel-urdfdom 6 or
    cmeel-tinyxml2 11 (a stand-in pinocchio package raising that ImportError): the error names the fix;
    any other failure is Pinocchio's own, unchanged."""
    fake = tmp_path / "pinocchio"
    fake.mkdir()
    (fake / "__init__.py").write_text(f"raise ImportError({failure!r})\n", encoding="utf-8")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    proc = subprocess.run(
        [sys.executable, "-c", "import kinengine"],
        env={**env, "PYTHONPATH": str(tmp_path)},
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    last = proc.stderr.strip().splitlines()[-1]
    assert proc.returncode == 1
    if named:
        assert last.startswith("ImportError: Pinocchio does not load (" + failure), last
        assert "pip install 'cmeel-urdfdom<5' 'cmeel-tinyxml2<11'" in last
    else:
        assert last == f"ImportError: {failure}", last
