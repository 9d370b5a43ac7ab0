"""Load a file of examples/ as a module (examples are scripts, not a package)."""

from __future__ import annotations

import importlib.util
import sys
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def load_example(name: str) -> ModuleType:
    """examples/<name>.py executed as module ``name`` (registered in sys.modules for its dataclasses)."""
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses look their module up while the file executes
    spec.loader.exec_module(module)
    return module


def example_module(name: str) -> Iterator[ModuleType]:
    """Yield :func:`load_example` of ``name``, and unregister it afterwards (a fixture's body: ``yield from``)."""
    try:
        yield load_example(name)
    finally:
        sys.modules.pop(name, None)
