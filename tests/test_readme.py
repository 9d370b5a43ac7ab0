"""The README stays true: its Python examples run, and CI runs its test command verbatim."""

from __future__ import annotations

import ast
from pathlib import Path
import re

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def _python_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", README, flags=re.S)


def _runnable(block: str) -> bool:
    """Blocks that name undefined example inputs (C, omega, ...) are illustrations, not scripts."""
    return "import kinengine" in block or "kinengine.load" in block


@pytest.mark.parametrize("block", [b for b in _python_blocks() if _runnable(b)],
                         ids=lambda b: b.strip().splitlines()[0][:40])
def test_readme_python_examples_run(block, recwarn):
    """Statement by statement; a statement may raise only if its line's comment names the exception."""
    import kinengine

    namespace = {"np": np, "kinengine": kinengine}
    lines = block.splitlines()
    for statement in ast.parse(block).body:
        source = "\n".join(lines[statement.lineno - 1:statement.end_lineno])
        try:
            exec(compile(ast.Module([statement], []), "README.md", "exec"), namespace)
        except Exception as exc:
            assert type(exc).__name__ in source, f"README line {source!r} raised {type(exc).__name__}: {exc}"


def test_ci_runs_the_readme_test_command_verbatim():
    commands = re.search(r"```bash\n(.*?)\n(.*?)\n```", README, flags=re.S)
    assert commands, "the README must open with a bash block of two commands"
    install_and_run, install_and_test = commands.group(1), commands.group(2)
    assert "kinengine" in install_and_run and "pip install ." in install_and_run
    assert install_and_test in (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert README.index("```bash") < 200, "the two commands must be the README's first lines"
