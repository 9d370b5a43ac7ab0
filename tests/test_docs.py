"""The documentation site builds without a warning, and user-facing text cites its theory properly.

`mkdocs build --strict` fails on a broken link or anchor, a page missing from the navigation, a
mkdocstrings reference that does not resolve or a docstring griffe cannot parse; it needs the [docs]
extra (pip install '.[docs]').
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow  # mkdocs build --strict

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.skipif(
    importlib.util.find_spec("mkdocs") is None or importlib.util.find_spec("mkdocstrings") is None,
    reason="mkdocs and mkdocstrings are not installed: pip install '.[docs]'",
)
def test_mkdocs_build_strict(tmp_path):
    site = tmp_path / "site"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "mkdocs",
            "build",
            "--strict",
            "--config-file",
            str(ROOT / "mkdocs.yml"),
            "--site-dir",
            str(site),
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},
    )
    assert result.returncode == 0, f"mkdocs build --strict failed:\n{result.stdout}\n{result.stderr}"
    for page in ("api", "cli", "conventions", "robots"):
        assert (site / page / "index.html").is_file(), page
    cli = (site / "cli" / "index.html").read_text(encoding="utf-8")
    assert "kinengine pose" in cli and "--rotation" in cli, "the CLI reference is generated from the parser"
    api = (site / "api" / "index.html").read_text(encoding="utf-8")
    assert "frame_pose" in api and "analytic_jacobian" in api, "the API reference renders the Robot"


def _user_facing_files() -> list[Path]:
    """The package's code (docstrings, CLI help, error messages), the README, the docs and the shipped robots
    (their READMEs and URDF comments travel inside the wheel)."""
    return sorted(
        [
            *ROOT.glob("kinengine/**/*.py"),
            ROOT / "README.md",
            *ROOT.glob("docs/**/*.md"),
            *ROOT.glob("robots/*/*.md"),
            *ROOT.glob("robots/*/*.urdf"),
        ]
    )


# Internal names for the theory that a user has never seen. A random seed or an IK seed is fine.
_FORBIDDEN = re.compile(r"the seed\b|(?<!of )\bcourse\b|seed eq|seed's|\(seed [0-9]|seed 2\.", re.I)


def test_theory_is_cited_by_its_name():
    """Cite "Robot Dynamics lecture notes, ETH Zurich, section 2.8", never "the seed" or "the course"."""
    found = [
        f"{path.relative_to(ROOT)}:{number}: {line.strip()}"
        for path in _user_facing_files()
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        if _FORBIDDEN.search(line)
    ]
    assert not found, "user-facing text names the theory by an internal name:\n" + "\n".join(found)


def test_api_reference_covers_the_public_api():
    """Every name `from kinengine import *` gives has its entry on the API reference page."""
    import kinengine

    page = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    entries = {line.removeprefix("::: ").strip() for line in page.splitlines() if line.startswith("::: ")}
    missing = [
        name for name in kinengine.__all__ if name != "__version__" and f"kinengine.{name}" not in entries
    ]
    assert not missing, f"docs/api.md lacks `::: kinengine.NAME` for {missing}"
