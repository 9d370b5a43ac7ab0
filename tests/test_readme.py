"""The README and the documentation site stay true: their Python examples run, and CI runs the
README's test command (in its quick and slow steps).

README blocks run one by one, each in a fresh namespace. A docs page's blocks run top to bottom in one
namespace (a later block may use an earlier block's names), in a temporary working directory. In both,
statement by statement: a statement may raise only if its own lines name the exception it raises.
"""

from __future__ import annotations

import ast
import importlib.util
import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
DOCS = ROOT / "docs"

# Pages whose examples need an optional extra: skipped, saying which, when it is not installed.
PAGE_NEEDS = {
    "viewer.md": ("viser", "kinengine[view]"),
    "ik.md": ("eaik", "kinengine[ik]"),
    "workspace.md": ("distributed", "kinengine[scale]"),
}


def _python_blocks(text: str) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)


def _runnable(block: str) -> bool:
    """Blocks that name undefined example inputs (C, omega, ...) are illustrations, not scripts."""
    return "import kinengine" in block or "kinengine.load" in block


def _run_block(block: str, namespace: dict, where: str) -> None:
    lines = block.splitlines()
    for statement in ast.parse(block).body:
        source = "\n".join(lines[statement.lineno - 1 : statement.end_lineno])
        raised = None
        try:
            exec(compile(ast.Module([statement], []), where, "exec"), namespace)
        except Exception as exc:
            raised = exc
        if raised is not None:
            name = type(raised).__name__
            assert name in source, f"{where} line {source!r} raised {name}: {raised}"


@pytest.mark.parametrize(
    "block", [b for b in _python_blocks(README) if _runnable(b)], ids=lambda b: b.strip().splitlines()[0][:40]
)
def test_readme_python_examples_run(block, recwarn, tmp_path, monkeypatch):
    """Statement by statement; a statement may raise only if its line's comment names the exception."""
    import kinengine

    monkeypatch.chdir(tmp_path)
    _run_block(block, {"np": np, "kinengine": kinengine}, "README.md")


def _pages_with_examples() -> list[str]:
    return sorted(p.name for p in DOCS.glob("*.md") if _python_blocks(p.read_text(encoding="utf-8")))


@pytest.mark.parametrize("page", _pages_with_examples())
def test_docs_python_examples_run(page, recwarn, tmp_path, monkeypatch):
    """Every ```python block of a docs page, top to bottom in one namespace, as a reader would paste them."""
    if page in PAGE_NEEDS and importlib.util.find_spec(PAGE_NEEDS[page][0]) is None:
        module, extra = PAGE_NEEDS[page]
        pytest.skip(f"{page} needs {module}, from the optional extra: pip install '{extra}'")
    import matplotlib

    matplotlib.use("Agg")  # pages that draw do so headless here
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    for block in _python_blocks((DOCS / page).read_text(encoding="utf-8")):
        _run_block(block, namespace, f"docs/{page}")


def test_ci_runs_the_readme_test_command_as_its_quick_and_slow_steps():
    """.ci/run installs as the README's test command does and runs its tests in two steps, the quick ones
    and the slow ones (marker ``slow``), which together are every test the README's command runs."""
    commands = re.search(r"```bash\n(.*?)\n(.*?)\n```", README, flags=re.S)
    assert commands, "the README must open with a bash block of two commands"
    install_and_run, install_and_test = commands.group(1), commands.group(2)
    assert "kinengine" in install_and_run and "pip install ." in install_and_run
    install, test = install_and_test.rsplit(" && ", 1)
    assert test == ".venv/bin/pytest -q"
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()
    assert install in ci
    assert ci[ci.index(install) + 1 :][:2] == [f'{test} -m "not slow"', f"{test} -m slow"]
    assert README.index("```bash") < 200, "the two commands must be the README's first lines"


def test_readme_is_short():
    """The README is what a newcomer reads first; the reference lives on the documentation site."""
    size = len(README.encode("utf-8"))
    assert size < 12 * 1024, f"README.md is {size} bytes; move detail to docs/"
