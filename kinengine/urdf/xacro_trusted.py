"""A trusted xacro expansion (``trust_xacro=True``), run in a child process so that its time bound holds.

xacro's own evaluation is Python's ``eval``: one expression such as ``9**9**9`` runs in C for hours and
no check between evaluations can stop it. So :func:`run_trusted` expands the file in
a child Python process (request and answer as JSON on stdin and stdout) and stops
that process after ``Limits.max_xacro_seconds`` plus :data:`MARGIN_SECONDS` (its start-up):
:class:`~kinengine.errors.ResourceLimitError`. The child bounds its own address space to
``Limits.max_xacro_memory`` (``RLIMIT_AS``, where the OS has it), applies every other bound itself and
sends its kinengine error back, raised here with the same class and message.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import subprocess
import sys
from collections.abc import Callable, Mapping
from pathlib import Path

from ..errors import KinematicsError, OptionError, ResourceLimitError, URDFError
from .limits import Limits

MARGIN_SECONDS = 5.0
"""[s] the child's start-up, allowed on top of ``Limits.max_xacro_seconds``."""
_ERRORS: dict[str, type[KinematicsError]] = {
    "URDFError": URDFError,
    "ResourceLimitError": ResourceLimitError,
    "OptionError": OptionError,
}


def run_trusted(
    source: str,
    mappings: dict[str, str],
    packages: Mapping[str, str | os.PathLike[str]] | None,
    limits: Limits,
) -> tuple[str, list[str]]:
    """(the expanded text, xacro's messages) of ``source`` expanded with xacro's own evaluation in a child
    process; its kinengine error, or ResourceLimitError when it outlives the time bound."""
    request = {
        "source": source,
        "args": mappings,
        "packages": None if packages is None else {str(k): os.fspath(v) for k, v in packages.items()},
        "limits": dataclasses.asdict(limits),
        "cwd": os.getcwd(),
    }
    root = str(Path(__file__).resolve().parents[2])  # the folder holding the kinengine package
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (root, os.environ.get("PYTHONPATH")) if p)}
    try:
        done = subprocess.run(
            [
                sys.executable,
                "-c",
                "import sys; sys.path.insert(0, sys.argv[1]); "
                "from kinengine.urdf.xacro import expand_in_process; "
                "from kinengine.urdf.xacro_trusted import serve; serve(expand_in_process)",
                root,
            ],
            input=json.dumps(request),
            capture_output=True,
            text=True,
            timeout=limits.max_xacro_seconds + MARGIN_SECONDS,
            env=env,
        )
    except subprocess.TimeoutExpired:
        raise ResourceLimitError(
            f"{source}: the trusted xacro expansion takes more than Limits.max_xacro_seconds = "
            f"{limits.max_xacro_seconds:g} s (an expression that does not finish, e.g. 9**9**9?); it was "
            "stopped. Without trust_xacro=True kinengine's evaluator refuses such expressions"
        ) from None
    except OSError as exc:
        raise URDFError(f"cannot start the trusted xacro expansion: {exc}", source=source) from None
    lines = done.stdout.splitlines()
    try:
        reply = json.loads(lines[-1])
    except (IndexError, ValueError):
        last = (done.stderr.strip().splitlines() or ["no message"])[-1]
        raise URDFError(
            f"the trusted xacro expansion ended without an answer (exit status {done.returncode}: {last})",
            source=source,
        ) from None
    if "error" in reply:
        raise _ERRORS.get(reply["error"], URDFError)(reply["message"])
    return reply["text"], list(reply["messages"])


def serve(expand: Callable[..., tuple[str, list[str]]]) -> None:
    """The child: one request on stdin, expanded by ``expand`` (:func:`.xacro.expand_in_process`), one
    JSON line on stdout."""
    request = json.load(sys.stdin)
    os.chdir(request["cwd"])
    limits = Limits(**request["limits"])
    try:
        import resource
    except ImportError:  # Windows: no RLIMIT_AS; the time bound still holds
        pass
    else:
        hard = resource.getrlimit(resource.RLIMIT_AS)[1]
        bound = (
            limits.max_xacro_memory if hard == resource.RLIM_INFINITY else min(hard, limits.max_xacro_memory)
        )
        with contextlib.suppress(ValueError, OSError):  # a system that refuses the bound: time still holds
            resource.setrlimit(resource.RLIMIT_AS, (bound, bound))
    try:
        import xacro

        text, messages = expand(xacro, request["source"], request["args"], request["packages"], limits, True)
        reply: dict[str, object] = {"text": text, "messages": messages}
    except KinematicsError as exc:
        reply = {"error": type(exc).__name__, "message": str(exc)}
    except MemoryError:  # within the RLIMIT_AS bound: the bound is what ran out
        message = (
            f"{request['source']}: the trusted xacro expansion needs more than Limits.max_xacro_memory = "
            f"{limits.max_xacro_memory} bytes; pass kinengine.load(..., limits=Limits(max_xacro_memory=...)) "
            "if the file is meant to be that large"
        )
        reply = {"error": "ResourceLimitError", "message": message}
    sys.stdout.write("\n" + json.dumps(reply) + "\n")


__all__ = ["MARGIN_SECONDS", "run_trusted", "serve"]
