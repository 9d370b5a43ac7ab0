"""The distributions a user installs: sdist and wheel built, checked, installed and run.

The build starts from a copy of the files git tracks (``git ls-files``, with their working-tree
contents), so untracked junk never enters and a module that was never ``git add``-ed fails here
as it would in a clean clone. ``python -m build`` builds the sdist and then the wheel *from the
sdist*, so an sdist missing a file cannot pass. The wheel is installed with its dependencies into
a fresh virtual environment (no ``--system-site-packages``: the editable kinengine of the test
environment must not leak in), and the ``kinengine`` command is run from a folder outside the
checkout. Everything is built and installed once per module (about a minute, most of it pip).
"""

from __future__ import annotations

import ast
import importlib.util
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import tarfile
import zipfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from fresh_venv import clean_env, run

import kinengine

pytestmark = pytest.mark.slow  # builds the sdist and wheel and installs them into a fresh venv

REPO = Path(__file__).resolve().parents[1]
SHIPPED_ROBOTS = sorted(p.parent.name for p in (REPO / "robots").glob("*/*.urdf") if p.stem == p.parent.name)

if importlib.util.find_spec("build") is None or importlib.util.find_spec("twine") is None:
    pytest.skip("needs the packaging tools build and twine (test extra)", allow_module_level=True)


def _run(cmd: list, *, cwd: Path, timeout: float) -> subprocess.CompletedProcess[str]:
    return run(cmd, cwd=cwd, timeout=timeout, env=clean_env())


def _tracked_files() -> list[str]:
    """Paths git tracks (index), relative to the repository, that exist in the working tree."""
    if shutil.which("git") is None:
        pytest.skip("git is not installed")
    proc = subprocess.run(
        ["git", "ls-files", "-z", "--cached"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=60,
        stdin=subprocess.DEVNULL,
    )
    if proc.returncode != 0:
        pytest.skip(f"not a git checkout ({proc.stderr.strip()})")
    return sorted(p for p in proc.stdout.split("\0") if p and (REPO / p).is_file())


@pytest.fixture(scope="module")
def tracked() -> list[str]:
    return _tracked_files()


@pytest.fixture(scope="module")
def dists(tmp_path_factory: pytest.TempPathFactory, tracked: list[str]) -> dict[str, Path]:
    """sdist and wheel built from a copy of the tracked files."""
    root = tmp_path_factory.mktemp("packaging")
    src = root / "src"
    for rel in tracked:
        target = src / rel
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(REPO / rel, target)
    out = root / "dist"
    _run([sys.executable, "-m", "build", "--outdir", out, src], cwd=root, timeout=900)
    sdists = sorted(out.glob("*.tar.gz"))
    wheels = sorted(out.glob("*.whl"))
    assert len(sdists) == 1 and len(wheels) == 1, sorted(p.name for p in out.iterdir())
    return {"sdist": sdists[0], "wheel": wheels[0], "root": root}


@pytest.fixture(scope="module")
def wheel_names(dists: dict[str, Path]) -> list[str]:
    with zipfile.ZipFile(dists["wheel"]) as whl:
        return whl.namelist()


@pytest.fixture(scope="module")
def venv(dists: dict[str, Path]) -> Iterator[Path]:
    """A fresh virtual environment with the wheel and its dependencies installed; yields its bin/.

    Removed afterwards: it holds about 1.2 GB (pinocchio, example-robot-data), and pytest keeps
    the temporary folders of the last three runs.
    """
    root = dists["root"]
    env_dir = root / "venv"
    _run([sys.executable, "-m", "venv", env_dir], cwd=root, timeout=300)
    bin_dir = env_dir / ("Scripts" if os.name == "nt" else "bin")
    # --no-compile: byte-compiling the ~1 GB of dependencies would double the install time.
    _run([bin_dir / "python", "-m", "pip", "install", "--no-compile", dists["wheel"]], cwd=root, timeout=1500)
    yield bin_dir
    shutil.rmtree(env_dir, ignore_errors=True)


@pytest.fixture(scope="module")
def elsewhere(dists: dict[str, Path]) -> Path:
    """A working folder outside the checkout, so nothing can be imported from the source tree."""
    path = dists["root"] / "elsewhere"
    path.mkdir(exist_ok=True)
    return path


def _version_literal() -> str:
    """The one version literal: ``__version__ = "..."`` in kinengine/__init__.py."""
    tree = ast.parse((REPO / "kinengine" / "__init__.py").read_text(encoding="utf-8"))
    for node in tree.body:
        if (
            isinstance(node, ast.Assign)
            and len(node.targets) == 1
            and isinstance(node.targets[0], ast.Name)
            and node.targets[0].id == "__version__"
        ):
            assert isinstance(node.value, ast.Constant) and isinstance(node.value.value, str)
            return node.value.value
    raise AssertionError("kinengine/__init__.py has no __version__ literal")


def test_version_has_a_single_source() -> None:
    assert _version_literal() == kinengine.__version__
    pyproject = (REPO / "pyproject.toml").read_text(encoding="utf-8")
    project = re.search(r"^\[project\]\n(.*?)(?=^\[)", pyproject, re.MULTILINE | re.DOTALL)
    assert project is not None
    assert re.search(r'^dynamic\s*=\s*\[[^\]]*"version"', project.group(1), re.MULTILINE)
    assert not re.search(r"^version\s*=", project.group(1), re.MULTILINE), "[project] writes a version"
    assert re.search(r'^version\s*=\s*\{\s*attr\s*=\s*"kinengine.__version__"', pyproject, re.MULTILINE)


def test_twine_check_strict(dists: dict[str, Path]) -> None:
    _run(
        [sys.executable, "-m", "twine", "check", "--strict", dists["sdist"], dists["wheel"]],
        cwd=dists["root"],
        timeout=300,
    )


def test_file_names_carry_the_version(dists: dict[str, Path]) -> None:
    v = kinengine.__version__
    assert dists["sdist"].name == f"kinengine-{v}.tar.gz"
    wheel = dists["wheel"].name
    with zipfile.ZipFile(dists["wheel"]) as whl:
        compiled = any(_is_accelerator(n) for n in whl.namelist())
    if compiled:  # the optional C accelerator was built: a wheel for this interpreter and platform
        tag = f"cp{sys.version_info.major}{sys.version_info.minor}"
        assert re.fullmatch(rf"kinengine-{re.escape(v)}-{tag}-{tag}-\w+\.whl", wheel), wheel
    else:
        assert wheel == f"kinengine-{v}-py3-none-any.whl"


ACCELERATORS = ("kinengine/model/fastcall", "kinengine/kinematics/chainkernel")
"""The optional C extensions (without the platform suffix)."""


def _is_accelerator(name: str, module: str = ACCELERATORS[0]) -> bool:
    return re.fullmatch(rf"{module}\.[^/]*(\.so|\.pyd)", name) is not None


def _can_compile() -> bool:
    headers = Path(sysconfig.get_paths()["include"], "Python.h").exists()
    return headers and shutil.which(os.environ.get("CC", "cc")) is not None


def test_wheel_metadata(dists: dict[str, Path], wheel_names: list[str]) -> None:
    v = kinengine.__version__
    with zipfile.ZipFile(dists["wheel"]) as whl:
        metadata = whl.read(f"kinengine-{v}.dist-info/METADATA").decode()
        entry_points = whl.read(f"kinengine-{v}.dist-info/entry_points.txt").decode()
        licenses = [
            n for n in wheel_names if n.startswith(f"kinengine-{v}.dist-info/") and n.endswith("LICENSE")
        ]
        assert len(licenses) == 1, wheel_names
        assert whl.read(licenses[0]) == (REPO / "LICENSE").read_bytes()
    assert re.search(rf"^Version: {re.escape(v)}$", metadata, re.MULTILINE)
    assert re.search(r"^Name: kinengine$", metadata, re.MULTILINE)
    assert "BSD-3-Clause" in metadata
    assert re.search(r"^kinengine\s*=", entry_points, re.MULTILINE), entry_points


def test_wheel_contents(wheel_names: list[str], tracked: list[str]) -> None:
    names = set(wheel_names)
    for required in (
        "kinengine/__init__.py",
        "kinengine/py.typed",
        "kinengine/robots/abb_irb120/abb_irb120.urdf",
        "kinengine/robots/abb_irb120/meshes/collision/link_1.stl",  # the collision meshes and their license
        "kinengine/robots/abb_irb120/meshes/collision/LICENSE",
        *(f"{module}.pyi" for module in ACCELERATORS),
    ):
        assert required in names
    if _can_compile():  # pip builds the optional C accelerator where it can
        for module in ACCELERATORS:
            assert any(_is_accelerator(n, module) for n in names), sorted(n for n in names if ".so" in n)
    assert {"abb_irb120", "planar_3dof", "scara"} <= set(SHIPPED_ROBOTS)
    for robot in SHIPPED_ROBOTS:
        assert f"kinengine/robots/{robot}/{robot}.urdf" in names
        assert f"kinengine/robots/{robot}/README.md" in names
    # Every tracked module of the package is installed: a subpackage missing from
    # [tool.setuptools] packages in pyproject.toml shows up here by name.
    modules = [p for p in tracked if p.startswith("kinengine/") and p.endswith(".py")]
    missing = sorted(set(modules) - names)
    assert not missing, f"tracked modules not in the wheel (add their package to pyproject.toml): {missing}"
    # Nothing but the package and its metadata.
    for name in names:
        top = name.split("/", 1)[0]
        assert top == "kinengine" or (top.startswith("kinengine-") and top.endswith(".dist-info")), name
        assert not name.lower().endswith(".png"), name
        assert not re.match(r"kinengine/(tests|benchmarks|docs)/", name), name


def test_shipped_robot_readmes_state_their_license(dists: dict[str, Path]) -> None:
    with zipfile.ZipFile(dists["wheel"]) as whl:
        for robot in SHIPPED_ROBOTS:
            text = whl.read(f"kinengine/robots/{robot}/README.md").decode()
            assert re.search(r"^## License$", text, re.MULTILINE), robot
            assert "BSD-3-Clause" in text, robot


def test_sdist_contents(dists: dict[str, Path], tracked: list[str]) -> None:
    v = kinengine.__version__
    prefix = f"kinengine-{v}/"
    with tarfile.open(dists["sdist"]) as sdist:
        names = {m.name.removeprefix(prefix) for m in sdist.getmembers() if m.isfile()}
        pkg_info = sdist.extractfile(prefix + "PKG-INFO")
        assert pkg_info is not None
        assert re.search(rf"^Version: {re.escape(v)}$", pkg_info.read().decode(), re.MULTILINE)
    for required in ("LICENSE", "README.md", "pyproject.toml"):
        assert required in names
    for robot in SHIPPED_ROBOTS:
        assert f"robots/{robot}/{robot}.urdf" in names
    missing = sorted(p for p in tracked if p.startswith("kinengine/") and p not in names)
    assert not missing, f"tracked package files not in the sdist: {missing}"


def test_installed_kinengine_is_the_wheel(venv: Path, elsewhere: Path) -> None:
    proc = _run(
        [venv / "python", "-c", "import kinengine; print(kinengine.__file__)"], cwd=elsewhere, timeout=120
    )
    installed = Path(proc.stdout.strip()).resolve()
    assert installed.is_relative_to(venv.parent.resolve()), installed
    assert not installed.is_relative_to(REPO), installed


def test_installed_wheel_runs_the_accelerator_it_ships(
    venv: Path, elsewhere: Path, wheel_names: list[str]
) -> None:
    code = (
        "from kinengine.model import accelerator; from kinengine.kinematics import compiler; "
        "print(accelerator.AVAILABLE, compiler.KERNEL is not None)"
    )
    proc = _run([venv / "python", "-c", code], cwd=elsewhere, timeout=120)
    shipped = [str(any(_is_accelerator(n, module) for n in wheel_names)) for module in ACCELERATORS]
    assert proc.stdout.split() == shipped


def test_installed_version(venv: Path, elsewhere: Path) -> None:
    proc = _run([venv / "kinengine", "--version"], cwd=elsewhere, timeout=120)
    version, accelerator = proc.stdout.splitlines()
    assert version == f"kinengine {kinengine.__version__}"
    # on, or off and why (tests/test_accelerator_status.py)
    assert accelerator.startswith("accelerator: "), accelerator


def test_installed_list(venv: Path, elsewhere: Path) -> None:
    proc = _run([venv / "kinengine", "list"], cwd=elsewhere, timeout=120)
    names = set(proc.stdout.split())
    # The shipped robots come from the wheel's package data, ur5 from the example-robot-data dependency.
    assert set(SHIPPED_ROBOTS) <= names, proc.stdout
    assert "ur5" in names, proc.stdout


_NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)")  # plain decimals, as numpy prints them here


def _printed_pose(stdout: str) -> list[list[str]]:
    """The four rows of numbers (as printed) that follow the line introducing T."""
    lines = stdout.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("T"))
    rows = []
    for line in lines[start + 1 :]:
        if not line.strip():
            break
        rows.append(_NUMBER.findall(line))
    assert len(rows) == 4 and all(len(r) == 4 for r in rows), stdout
    return rows


def test_installed_pose_matches_the_library(venv: Path, elsewhere: Path) -> None:
    proc = _run([venv / "kinengine", "pose", "abb_irb120"], cwd=elsewhere, timeout=300)
    assert "tool0" in proc.stdout
    rows = _printed_pose(proc.stdout)
    robot = kinengine.load("abb_irb120")
    expected = robot.frame_pose(robot.neutral(), "tool0")
    assert np.allclose(expected[:3, 3], [0.374, 0.0, 0.630], atol=1e-12)  # the README's check figure
    # numpy prints an array with one precision, trailing zeros stripped: the most decimals shown
    # bound the rounding of every entry.
    decimals = max(len(token.split(".")[1]) if "." in token else 0 for row in rows for token in row)
    tolerance = 0.5 * 10.0**-decimals + 1e-12
    printed = np.array([[float(token) for token in row] for row in rows])
    assert np.abs(printed - expected).max() <= tolerance, (printed, expected, decimals)
