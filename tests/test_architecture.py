"""The package's import graph, read from the source with ast, obeys kinengine/layers.py: no cycles,
no lower layer importing a higher one, the CLI on the public API only, the reference independent of
the Pinocchio path, no import of another module's private names, no module below the facade naming the
facade's Robot (not even for the type checker: they type against a Protocol), and a docstring in every
module that says what it owns."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from kinengine.layers import INDEPENDENT, LAYERS, PUBLIC_API, layer_of

PACKAGE = Path(__file__).resolve().parent.parent / "kinengine"


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _resolve(module: str, is_package: bool, level: int, target: str | None) -> str:
    """The absolute module of a (possibly relative) import in ``module``."""
    if level == 0:
        return target or ""
    base = module.split(".") if is_package else module.split(".")[:-1]
    base = base[: len(base) - (level - 1)]
    return ".".join(base + ([target] if target else []))


def _imports(path: Path) -> list[tuple[str, str | None, int, bool]]:
    """(imported module, imported name or None, line, under TYPE_CHECKING) of every kinengine import."""
    module, is_package = _module_name(path), path.name == "__init__.py"
    tree = ast.parse(path.read_text(encoding="utf-8"))
    type_checking: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            type_checking.update(id(n) for n in ast.walk(node))
    found = []
    for node in ast.walk(tree):
        guarded = id(node) in type_checking
        if isinstance(node, ast.Import):
            found += [
                (a.name, None, node.lineno, guarded) for a in node.names if a.name.startswith("kinengine")
            ]
        elif isinstance(node, ast.ImportFrom):
            target = _resolve(module, is_package, node.level, node.module)
            if not target.startswith("kinengine"):
                continue
            for alias in node.names:
                submodule = f"{target}.{alias.name}"
                if (PACKAGE.parent / Path(*submodule.split("."))).with_suffix(".py").exists() or (
                    PACKAGE.parent / Path(*submodule.split(".")) / "__init__.py"
                ).exists():
                    found.append((submodule, None, node.lineno, guarded))  # `from . import batch`
                else:
                    found.append((target, alias.name, node.lineno, guarded))
    return found


MODULES = {(_module_name(p)): p for p in sorted(PACKAGE.rglob("*.py"))}
GRAPH = {name: _imports(path) for name, path in MODULES.items()}


def test_every_module_belongs_to_a_layer():
    for name in MODULES:
        layer_of(name)


@pytest.mark.parametrize("name", sorted(MODULES))
def test_no_module_imports_a_higher_layer(name):
    mine = layer_of(name)
    for target, _, line, type_only in GRAPH[name]:
        if type_only or (target == "kinengine" and name.startswith("kinengine.cli")):
            continue  # an import under TYPE_CHECKING names a type for the checker; nothing runs
        theirs = layer_of(target)
        assert theirs <= mine, (
            f"{name}:{line} imports {target} ({LAYERS[theirs][0]}), a higher layer than {LAYERS[mine][0]}"
        )


@pytest.mark.parametrize("name", sorted(n for n in MODULES if n.startswith("kinengine.cli")))
def test_the_command_line_uses_only_the_public_api(name):
    for target, _, line, _ in GRAPH[name]:
        if target.startswith("kinengine.cli"):
            continue
        assert any(target == p or (p != "kinengine" and target.startswith(p + ".")) for p in PUBLIC_API), (
            f"{name}:{line} imports {target}, which is not public API"
        )


def test_the_reference_is_independent_of_the_pinocchio_path():
    for name in MODULES:
        if any(name == p or name.startswith(p + ".") for p in INDEPENDENT):
            for target, _, line, _ in GRAPH[name]:
                assert target == "kinengine.errors" or any(target.startswith(p) for p in INDEPENDENT), (
                    f"{name}:{line} imports {target}"
                )
            source = MODULES[name].read_text(encoding="utf-8")
            assert "import pinocchio" not in source


@pytest.mark.parametrize("name", sorted(MODULES))
def test_no_module_imports_private_names_of_another(name):
    for target, imported, line, _ in GRAPH[name]:
        if imported is not None and imported.startswith("_") and not imported.startswith("__"):
            assert target == name, f"{name}:{line} imports the private name {imported} from {target}"


def test_no_private_attribute_reaches_into_a_robot():
    """The Robot is a facade: no other module reads its private members."""
    for name, path in MODULES.items():
        if name == "kinengine.robot":
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.Attribute)
                and isinstance(node.value, ast.Name)
                and node.value.id in ("robot", "self_robot")
                and node.attr.startswith("_")
            ):
                pytest.fail(f"{name}:{node.lineno} reads robot.{node.attr}")


def test_there_are_no_import_cycles():
    edges = {
        name: {t for t, _, _, guarded in GRAPH[name] if not guarded and t in MODULES and t != name}
        for name in MODULES
    }
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(edges[node]):
            if state.get(nxt) == 1:
                cycle = stack[stack.index(nxt) :] + [nxt]
                # a package's __init__ importing its own submodules is not a cycle of the design
                # (whichever module the search entered the cycle by)
                package = min(cycle, key=len)
                if not all(c == package or c.startswith(package + ".") for c in cycle):
                    pytest.fail("import cycle: " + " -> ".join(cycle))
            elif nxt not in state:
                visit(nxt)
        stack.pop()
        state[node] = 2

    for name in sorted(edges):
        if name not in state:
            visit(name)


@pytest.mark.parametrize("name", sorted(MODULES))
def test_no_module_below_the_facade_imports_the_robot(name):
    """Lower layers take a Protocol (e.g. kinengine.control.robot_like.RobotLike), not the facade's Robot:
    an import under TYPE_CHECKING counts too (a type-level dependency on a higher layer)."""
    if layer_of(name) >= layer_of("kinengine.robot"):
        return
    for target, _, line, _ in GRAPH[name]:
        assert target != "kinengine.robot", f"{name}:{line} imports kinengine.robot"


@pytest.mark.parametrize("name", sorted(MODULES))
def test_modules_say_what_they_own(name):
    path = MODULES[name]
    source = path.read_text(encoding="utf-8")
    if source.strip():
        assert ast.get_docstring(ast.parse(source)), f"{path} opens with no docstring"
