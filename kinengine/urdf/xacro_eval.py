"""The restricted evaluator of xacro expressions: the safe default of :func:`.xacro.expand_xacro`.

xacro evaluates ``${...}`` and ``$(eval ...)`` with Python's ``eval`` (builtins removed, names
starting with ``__`` refused). That is no sandbox: its ``python.type`` / ``python.vars`` helpers build
such names from strings and walk from any object to ``os.system``. So, unless the caller passes
``trust_xacro=True``, :func:`.xacro.expand_xacro` replaces xacro's two evaluation points,
``xacro.safe_eval`` (every ``${...}``: attributes, text, property values, macro arguments,
conditions, yaml units) and ``xacro.substitution_args._eval`` (``$(eval ...)``), by
:meth:`XacroEvaluator.expression` and :meth:`XacroEvaluator.substitution`. They parse the text
with :mod:`ast` and walk it with the maintained ``simpleeval`` package (no ``eval`` of text, powers,
shifts, string and list sizes bounded): chosen over an evaluator written here so that its review and
fixes are shared; this module only narrows it to xacro's allow-list and bounds what it leaves open.

Allowed: literals; names of properties, macro parameters and ``xacro:arg`` values; arithmetic,
comparisons, ``and``/``or``/``not``, ``a if c else b``; subscripts and slices; list, tuple, dict and
set displays and comprehensions (at most ``xacro_bounds.MAX_ITEMS`` elements); calls of xacro's math
functions and constants (``pi``, ``radians``, ``sin``, ``sqrt``, ... directly or as ``math.*``),
``xacro.*`` (``load_yaml``, ``arg``, ``tokenize``, ``dotify``, ``abs_filename``, ``message``,
``warning``, ``error``, ``fatal``), ``load_yaml``, ``len``, ``min``, ``max``, ``abs``, ``round``,
``int``, ``float``, ``str``, ``bool``, ``list``, ``tuple``, ``dict``, ``set`` and ``range`` (at most
``xacro_bounds.MAX_ITEMS`` long); dotted access into an included file's namespace and into ``load_yaml``
data; the string methods in ``xacro_bounds.STRING_METHODS``.
Refused with a :class:`~kinengine.errors.URDFError` naming the file, line and expression: any other
name (``python``, ``type``, ``vars``, ...), attribute, call or syntax (``lambda``, f-strings, ``%``
formatting of strings, walrus), a name or attribute with a leading ``_``, an integer of more than
``xacro_bounds.MAX_INT_BITS`` bits, a result whose text would exceed ``xacro_bounds.MAX_TEXT``
characters. Math functions whose cost grows with their argument (``factorial``, ``comb``, ``perm``, ``prod``,
``lcm``) are left out.
"""

from __future__ import annotations

import ast
from collections.abc import Callable, Mapping
from typing import Any

import simpleeval

from ..errors import URDFError
from .xacro_bounds import (
    FUNCTIONS,
    MATH,
    MAX_TEXT,
    OPERATORS,
    STRING_METHODS,
    XACRO_NAMES,
    Refused,
    check_int,
    text_size,
)


class _Namespace:
    """``math`` or ``xacro`` in an expression: its allow-listed functions by name, nothing else."""

    def __init__(self, name: str, members: Mapping[str, object]) -> None:
        self.name, self.members = name, dict(members)


class _Evaluator(simpleeval.EvalWithCompoundTypes):
    """simpleeval with xacro's names, attribute rules and no f-strings."""

    def __init__(self, names: Mapping[str, object] | Callable[[ast.Name], object], functions: dict) -> None:
        super().__init__(operators=dict(OPERATORS), functions=functions, names=names)
        for node in (ast.JoinedStr, ast.FormattedValue):
            self.nodes.pop(node, None)

    def _eval_name(self, node: ast.Name) -> object:
        if node.id.startswith("_"):
            raise Refused(f"the name {node.id!r} (a leading '_')")
        return super()._eval_name(node)

    def _eval_call(self, node: ast.Call) -> object:
        if isinstance(node.func, ast.Name) and node.func.id not in self.functions:
            raise Refused(f"a call of {node.func.id}()")
        if not isinstance(node.func, (ast.Name, ast.Attribute)):
            raise Refused(f"a call of {ast.unparse(node.func)!r}")
        return super()._eval_call(node)

    def _eval_attribute(self, node: ast.Attribute) -> object:
        if node.attr.startswith("_"):
            raise Refused(f"the attribute {node.attr!r} (a leading '_')")
        owner = self._eval(node.value)
        if isinstance(owner, _Namespace):
            if node.attr not in owner.members:
                raise Refused(f"{owner.name}.{node.attr}")
            return owner.members[node.attr]
        import xacro

        if isinstance(owner, xacro.NameSpace):  # an included file's properties, not xacro's globals
            return scoped(owner, node.attr, xacro)
        if isinstance(owner, xacro.YamlDictWrapper):
            return owner[node.attr]  # a yaml key
        if isinstance(owner, str) and node.attr in STRING_METHODS:
            return getattr(owner, node.attr)
        raise Refused(f"the attribute .{node.attr} of a {type(owner).__name__}")

    def _eval(self, node: ast.AST) -> object:
        return check_int(super()._eval(node))


def scoped(symbols: object, name: str, xacro: Any) -> object:
    """Property ``name`` of xacro's scopes ``symbols`` (a ``xacro.Table``, lazy values evaluated), never
    one of xacro's globals (its ``python``, ``math``, builtins: the root of every scope);
    NameError without one."""
    table = symbols
    while isinstance(table, xacro.Table):
        if dict.__contains__(table, name):
            return table[name]
        table = table.parent
    raise NameError(f"name '{name}' is not defined")


class XacroEvaluator:
    """The safe replacements of xacro's evaluation points for one expansion.

    ``xacro_module`` is the imported ``xacro`` package; ``locate(expression)`` returns the
    ``(file, line)`` an expression is written in (line None if unknown); ``tick()`` is called before
    each evaluation (the wall-time bound of the expansion).
    """

    def __init__(
        self,
        xacro_module: Any,
        locate: Callable[[str], tuple[str, int | None]],
        tick: Callable[[], None],
    ) -> None:
        self._xacro, self._locate, self._tick = xacro_module, locate, tick
        xacro_members = {}
        for name in XACRO_NAMES:
            member = xacro_module._global_symbols["xacro"].get(name)
            if member is not None:
                xacro_members[name] = member
        self._functions: dict[str, Callable[..., Any]] = {
            **{k: v for k, v in MATH.items() if callable(v)},
            **FUNCTIONS,
            "load_yaml": xacro_members["load_yaml"],
        }
        self._constants: dict[str, object] = {
            **{k: v for k, v in MATH.items() if not callable(v)},
            "True": True,
            "False": False,
            "math": _Namespace("math", MATH),
            "xacro": _Namespace("xacro", xacro_members),
        }

    def expression(self, expr: str, symbols: Mapping[str, object], locals: object = None) -> object:
        """The value of one ``${...}`` expression (the signature of ``xacro.safe_eval``)."""
        self._tick()
        xacro = self._xacro

        def lookup(name: str) -> object:
            try:
                return scoped(symbols, name, xacro)
            except NameError:
                pass
            if name in self._constants:
                return self._constants[name]
            if name in self._functions:
                return self._functions[name]
            if isinstance(symbols, Mapping) and name in symbols:
                raise Refused(f"the name {name!r}")
            raise NameError(f"name '{name}' is not defined")

        return self._run(expr, _Names(lookup), "${" + expr.strip() + "}")

    def substitution(self, expr: str, context: dict) -> str:
        """The text of one ``$(eval ...)`` (the signature of ``xacro.substitution_args._eval``)."""
        self._tick()
        from xacro import substitution_args as subst

        arguments = context.setdefault("arg", {})
        special = {
            "arg": lambda name: subst.convert_value(subst._eval_arg(name, args=arguments), "auto"),
            "dirname": lambda: subst._eval_dirname(context.get("filename")),
            "env": subst._eval_env,
            "optenv": subst._eval_optenv,
            "find": subst._eval_dict["find"],
        }

        def lookup(name: str) -> object:
            if name in ("true", "True"):
                return True
            if name in ("false", "False"):
                return False
            if name in special:
                return special[name]
            if name in self._constants and name not in ("math", "xacro"):
                return self._constants[name]
            if name in self._functions:
                return self._functions[name]
            if name in arguments:
                return subst.convert_value(arguments[name], "auto")
            raise NameError(f"name '{name}' is not defined")

        functions = {**self._functions, **special}
        return str(self._run(expr, _Names(lookup), f"$(eval {expr.strip()})", functions))

    def _run(self, expr: str, names: _Names, shown: str, functions: dict | None = None) -> object:
        evaluator = _Evaluator(names, dict(self._functions if functions is None else functions))
        try:
            value = evaluator.eval(expr.strip())
            if text_size(value) > MAX_TEXT:
                raise Refused(f"a result of more than {MAX_TEXT} characters")
            return value
        except NameError:
            raise
        except (simpleeval.InvalidExpression, SyntaxError) as exc:
            raise self._refusal(shown, exc) from None

    def _refusal(self, shown: str, exc: Exception) -> URDFError:
        file, line = self._locate(shown)
        if isinstance(exc, SyntaxError):
            what = f"not an expression ({exc.msg})"
        elif isinstance(exc, Refused):
            what = f"{exc} is not allowed"
        else:
            what = " ".join(str(exc).split())
        return URDFError(
            f"xacro expression {shown[:200]!r}: {what} by kinengine's safe xacro evaluator "
            "(see kinengine.urdf.xacro_eval); if you trust this file as you would to build it with ROS, "
            "load it with kinengine.load(..., trust_xacro=True) (CLI: --trust-xacro)",
            source=file,
            line=line,
        )


class _Names(Mapping[str, object]):
    """simpleeval's names: one lookup function, KeyError for simpleeval when it raises NameError."""

    def __init__(self, lookup: Callable[[str], object]) -> None:
        self._lookup = lookup

    def __getitem__(self, name: str) -> object:
        return self._lookup(name)

    def __iter__(self):  # type: ignore[no-untyped-def]
        return iter(())

    def __len__(self) -> int:
        return 0
