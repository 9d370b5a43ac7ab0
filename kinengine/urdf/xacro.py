"""Expanding a xacro file into URDF text without a ROS installation.

Owns :func:`expand_xacro`. The macro processor is the PyPI ``xacro`` package
(ROS's own, pinned); this module only feeds it: ``$(find pkg)`` goes through
:func:`.packages.resolve_package`, every file it reads (includes, ``load_yaml``) is opened
without blocking by :func:`.source.read_bytes_once` (a FIFO or device is refused), size-checked
and refused if it holds a DTD or entity declaration (it is parsed by :func:`.safe_xml.parse_xml`
first), its messages become ``UserWarning``s, its errors one-line
:class:`~kinengine.errors.URDFError`s, and its module-level state is reset on each call under a lock.
The expansion is bounded by ``Limits.max_macro_calls``, ``Limits.max_bytes`` (the text macro calls
add, estimated as they are made) and ``Limits.max_xacro_seconds``
(:class:`~kinengine.errors.ResourceLimitError` naming the bound). The text returned is still to be
parsed by :func:`.parser.parse_urdf`.

Trust model: xacro itself evaluates ``${...}`` and ``$(eval ...)`` with Python's ``eval``, which a
file can turn into running any command. By default its two evaluation points are replaced by the
restricted evaluator of :mod:`.xacro_eval` (the ``simpleeval`` package narrowed to xacro's
allow-list); ``trust_xacro=True`` keeps xacro's own evaluation for files you would build with ROS
anyway, in a child process (:mod:`.xacro_trusted`) stopped after ``Limits.max_xacro_seconds``, so
that even one Python expression that does not finish (``9**9**9``) is bounded. Either way
``$(env ...)``, ``$(optenv ...)`` and ``load_yaml`` read the environment and files.
"""

from __future__ import annotations

import contextlib
import os
import re
import stat
import threading
import warnings
import xml.dom.minidom
import xml.parsers.expat
from collections.abc import Iterator, Mapping
from pathlib import Path
from types import ModuleType

from ..errors import KinematicsError, OptionError, ResourceLimitError, URDFError
from .limits import LIMITS, Limits
from .packages import resolve_package
from .safe_xml import parse_xml
from .xacro_budget import Budget, MacroStack, failing_file, read_file

XACRO_REQUIREMENT = "xacro==2.1.1"
_LOCK = threading.Lock()  # xacro keeps its file stack, arguments and symbols in module globals
_XACRO_NS = "http://www.ros.org/wiki/xacro"


def expand_xacro(
    path: str | os.PathLike[str],
    *,
    args: Mapping[str, str] | None = None,
    packages: Mapping[str, str | os.PathLike[str]] | None = None,
    limits: Limits = LIMITS,
    trust_xacro: bool = False,
) -> str:
    """The URDF text (str) that xacro file ``path`` expands to; URDFError (one line) otherwise.

    ``args`` sets ``xacro:arg`` values (as ``xacro file name:=value`` does; values are
    converted with ``str``); ``packages`` maps ROS package names to folders for
    ``$(find pkg)``, which is otherwise resolved from ``ROS_PACKAGE_PATH`` and then the
    folders above ``path`` (see :func:`.packages.resolve_package`). Expressions are evaluated by
    the restricted evaluator of :mod:`.xacro_eval` unless ``trust_xacro=True`` (xacro's own Python
    ``eval``, run in a child process stopped after ``limits.max_xacro_seconds``: only for files you
    would build with ROS). Refused: a missing
    argument, an unknown macro, an undefined property or block, an expression outside the
    allow-list, an unreadable, non-regular or malformed file, a DTD or entity declaration in any
    file read, a file (or all files together) over ``limits.max_bytes`` bytes, and a result whose
    root is not a named ``<robot>`` with at least one ``<link>`` (e.g. a file that only defines
    macros); ResourceLimitError: more than ``limits.max_macro_calls`` macro calls, more than
    ``limits.max_bytes`` bytes of expanded text, more than ``limits.max_xacro_seconds`` seconds.
    xacro's warnings (e.g. an unknown attribute) are re-issued as ``UserWarning``.
    Thread-safe: calls are serialized.
    """
    try:
        source = os.fsdecode(os.fspath(path))
    except TypeError:
        raise URDFError(f"expected a path to a .xacro file, got {type(path).__name__}") from None
    mappings = _arguments(args, source)
    if packages is not None and not isinstance(packages, Mapping):
        raise URDFError(
            f"packages= takes a mapping of package name to folder, got {type(packages).__name__}",
            source=source,
        )
    if not isinstance(limits, Limits):
        raise OptionError(f"limits= takes a kinengine.urdf.Limits, got {type(limits).__name__}")
    if not isinstance(trust_xacro, bool):
        raise OptionError(f"trust_xacro= takes True or False, got {trust_xacro!r}")
    try:
        info = os.stat(source)
    except (OSError, ValueError) as exc:
        reason = getattr(exc, "strerror", None) or exc
        raise URDFError(f"cannot open the file: {reason}", source=source) from None
    if not stat.S_ISREG(info.st_mode):
        raise URDFError("not a regular file", source=source)
    try:
        import xacro
    except ImportError:
        raise URDFError(
            f"expanding xacro files needs the xacro package: pip install {XACRO_REQUIREMENT}", source=source
        ) from None
    if trust_xacro:  # xacro's own eval: in a child process, stopped after the time bound
        from .xacro_trusted import run_trusted

        text, messages = run_trusted(source, mappings, packages, limits)
    else:
        text, messages = expand_in_process(xacro, source, mappings, packages, limits, trust_xacro)
    for message in dict.fromkeys(messages):
        warnings.warn(f"{source}: xacro: {message}", UserWarning, stacklevel=2)
    _check_result(text, source, limits)
    return text


def expand_in_process(
    xacro: ModuleType,
    source: str,
    mappings: dict[str, str],
    packages: Mapping[str, str | os.PathLike[str]] | None,
    limits: Limits,
    trusted: bool,
) -> tuple[str, list[str]]:
    """(the expanded text, xacro's messages) of ``source``, expanded in this process."""
    messages: list[str] = []
    budget = Budget(limits)
    with _LOCK, _xacro_hooks(xacro, packages, budget, messages, trusted):
        try:
            xacro.init_stacks(source)
            setattr(xacro, "macrostack", MacroStack(budget))  # noqa: B010 (each macro xacro expands is pushed)
            document = xacro.parse(None, source)
            xacro.process_doc(document, mappings=mappings, verbosity=0)
            text = document.documentElement.toprettyxml(indent="  ")  # as the xacro command writes it
        except KinematicsError:
            raise
        except RecursionError:
            raise URDFError(
                "xacro error: macros nested too deeply (a macro that calls itself?)", source=source
            ) from None
        except Exception as exc:  # xacro raises XacroException, and lets anything from eval() through
            if _caused_by_memory_error(exc):  # wrapped by xacro; a trusted child reports it against its bound
                if trusted:
                    raise MemoryError from None
                raise ResourceLimitError(
                    f"{failing_file(source)}: the xacro expansion ran out of memory"
                ) from None
            raise _translate(exc, source) from None
    return text, messages


def _causes(exc: BaseException) -> Iterator[BaseException]:
    """``exc`` and what it wraps, 64 deep at most (xacro wraps errors of $(...) in XacroException.exc)."""
    seen: object = exc
    for _ in range(64):
        if not isinstance(seen, BaseException):
            return
        yield seen
        seen = getattr(seen, "exc", None) or seen.__cause__ or seen.__context__


def _caused_by_memory_error(exc: BaseException) -> bool:
    return any(isinstance(seen, MemoryError) for seen in _causes(exc))


def _arguments(args: object, source: str) -> dict[str, str]:
    if args is None:
        return {}
    if not isinstance(args, Mapping):
        raise URDFError(
            f"args= takes a mapping of xacro argument name to value, got {type(args).__name__}", source=source
        )
    for key in args:
        if not isinstance(key, str) or not key:
            raise URDFError(f"xacro argument names are non-empty strings, got {key!r}", source=source)
    return {key: str(value) for key, value in args.items()}


@contextlib.contextmanager
def _xacro_hooks(
    xacro: ModuleType,
    packages: Mapping[str, str | os.PathLike[str]] | None,
    budget: Budget,
    messages: list[str],
    trusted: bool,
) -> Iterator[None]:
    """xacro with fresh global state, our file reader, package finder, message sink, budget and
    (unless ``trusted``) evaluator."""
    from xacro import color
    from xacro import substitution_args as subst

    limits = budget.limits
    trusted_eval = xacro.safe_eval

    def find(name: str) -> str:
        stack = getattr(xacro, "filestack", None) or [None]
        start = Path(stack[-1]).parent if stack[-1] else None
        return str(resolve_package(name, packages=packages, start=start))

    def parse(inp: object, filename: str | None = None) -> object:
        budget.tick()
        if inp is not None:
            return xml.dom.minidom.parseString(inp) if isinstance(inp, str) else inp
        name = os.path.join(xacro.root_dir, str(filename))
        data = read_file(name, budget, limits, xacro)
        parse_xml(data, source=str(filename), limits=limits)  # refuses DTDs, entities, bad or oversized XML
        budget.texts[str(filename)] = data.decode("utf-8", "replace")
        return xml.dom.minidom.parseString(data)

    def load_yaml(filename: str) -> object:
        import yaml

        for unit in xacro.ConstructUnits:
            yaml.SafeLoader.add_constructor(unit.value.tag, unit.constructor)
        filename = xacro.abs_filename_spec(filename)
        xacro.filestack.append(filename)
        try:
            data = read_file(filename, budget, limits, xacro, pop=False)
            return xacro.YamlListWrapper.wrap(yaml.safe_load(data))
        finally:
            xacro.filestack.pop()
            xacro.all_includes.append(filename)

    def timed_eval(expr: str, globals: object, locals: object = None) -> object:
        budget.tick()
        return trusted_eval(expr, globals, locals)

    def message(msg: object, *args: object, **kwargs: object) -> None:
        messages.append(" ".join(str(a) for a in (msg, *args)).replace("\n", " "))

    first = [(xacro, "load_yaml", load_yaml)]  # before create_global_symbols(), which exposes it
    originals = [(module, name, getattr(module, name)) for module, name, _ in first]
    for module, name, value in first:
        setattr(module, name, value)
    try:
        patches = [
            (xacro, "parse", parse),
            (xacro, "print_location", lambda: None),
            (xacro, "message", message),
            (color, "message", message),
            (subst, "_eval_find", find),
            (xacro, "root_dir", os.curdir),
            (xacro, "verbosity", 0),
            (xacro, "all_includes", []),
            (xacro, "filestack", None),
            (xacro, "macrostack", None),
            (xacro, "_global_symbols", xacro.create_global_symbols()),  # eval() can mutate the old ones
        ]
    except BaseException:
        for module, name, value in originals:
            setattr(module, name, value)
        raise
    originals += [(module, name, getattr(module, name)) for module, name, _ in patches]
    original_find = subst._eval_dict.get("find")
    for module, name, value in patches:
        setattr(module, name, value)
    subst._eval_dict["find"] = find
    if trusted:
        originals.append((xacro, "safe_eval", trusted_eval))
        setattr(xacro, "safe_eval", timed_eval)  # noqa: B010 (mypy: the module's attributes are unknown)
    else:
        from .xacro_eval import XacroEvaluator

        evaluator = XacroEvaluator(xacro, budget.locate, budget.tick)
        originals += [(xacro, "safe_eval", trusted_eval), (subst, "_eval", subst._eval)]
        setattr(xacro, "safe_eval", evaluator.expression)  # noqa: B010
        subst._eval = evaluator.substitution
    xacro.substitution_args_context.clear()
    try:
        yield
    finally:
        for module, name, value in reversed(originals):
            setattr(module, name, value)
        subst._eval_dict["find"] = original_find
        xacro.substitution_args_context.clear()


_PATTERNS = (  # (what xacro says, how kinengine says it)
    (
        re.compile(r"Undefined substitution argument (\S+)"),
        r"missing xacro argument '\1': pass args={'\1': ...} (CLI: \1:=value) or give its "
        r"xacro:arg a default",
    ),
    (re.compile(r"unknown macro name: (\S+)"), r"unknown xacro macro <\1> (not defined nor included)"),
    (re.compile(r"name '(.+?)' is not defined"), r"undefined xacro property or name '\1'"),
)


def _translate(exc: BaseException, source: str) -> URDFError:
    """One URDFError for whatever xacro raised: a wrapped URDFError as is, else its message on one line."""
    wrapped = next((seen for seen in _causes(exc) if isinstance(seen, URDFError)), None)
    if wrapped is not None:
        return wrapped
    file = failing_file(source)
    if isinstance(exc, xml.parsers.expat.ExpatError):
        return URDFError(f"not well-formed XML: {exc}", source=file)
    text = " ".join(str(exc).split()) or type(exc).__name__
    for pattern, replacement in _PATTERNS:
        found = pattern.search(text)
        if found:
            return URDFError(f"{found.expand(replacement)} ({text})", source=file)
    return URDFError(f"xacro error: {text}", source=file)


def _check_result(text: str, source: str, limits: Limits) -> None:
    size = len(text.encode("utf-8"))
    if size > limits.max_bytes:
        raise URDFError(
            f"the expanded URDF is {size} bytes, more than Limits.max_bytes = {limits.max_bytes}",
            source=source,
        )
    root = parse_xml(text, source=source, limits=limits)
    if root.tag != "robot":
        raise URDFError(
            f"the expansion's root element is <{root.tag}>, expected <robot name=...>", source=source
        )
    if not root.get("name") or root.find("link") is None:
        missing = "no <link>" if root.get("name") else "a <robot> without a name"
        raise URDFError(
            f"the expansion has {missing}: a file that only defines macros (e.g. *_macro.xacro) "
            "is meant to be included by a xacro that calls them; expand that one",
            source=source,
        )
