"""The public API is typed for a reader and a type checker: no parameter or return of a public function or
Robot method is annotated ``object`` or ``Any``, and no public method hides its options in ``**kwargs``."""

from __future__ import annotations

import inspect
import re

import pytest

import kinengine

PUBLIC_CLASSES = [kinengine.Robot, kinengine.Task, kinengine.DifferentialIK]
FUNCTIONS = [getattr(kinengine, n) for n in kinengine.__all__ if inspect.isfunction(getattr(kinengine, n))]
METHODS = [
    (cls.__name__, name, member)
    for cls in PUBLIC_CLASSES
    for name, member in inspect.getmembers(cls, inspect.isfunction)
    if not name.startswith("_")
]
VAGUE = re.compile(r"(^|[\[\] ,|(])(object|Any|typing\.Any)($|[\[\] ,|)])")


def _annotations(function):
    return {
        name: str(p.annotation)
        for name, p in inspect.signature(function).parameters.items()
        if p.annotation is not inspect.Parameter.empty and name != "self"
    } | {"return": str(inspect.signature(function).return_annotation)}


@pytest.mark.parametrize(
    "owner, name, function",
    METHODS + [("kinengine", f.__name__, f) for f in FUNCTIONS],
    ids=lambda v: v if isinstance(v, str) else "",
)
def test_no_vague_annotations_and_no_hidden_options(owner, name, function):
    signature = inspect.signature(function)
    for parameter in signature.parameters.values():
        assert parameter.kind is not inspect.Parameter.VAR_KEYWORD, f"{owner}.{name} takes **{parameter.name}"
        if parameter.name != "self":
            assert parameter.annotation is not inspect.Parameter.empty, (
                f"{owner}.{name}({parameter.name}) untyped"
            )
    for where, text in _annotations(function).items():
        assert not VAGUE.search(text), f"{owner}.{name}: {where} is annotated {text!r}"


def test_the_methods_checked_cover_the_robot():
    names = {name for owner, name, _ in METHODS if owner == "Robot"}
    assert {
        "frame_pose",
        "jacobian",
        "kinematics",
        "analytic_jacobian",
        "inverse_kinematics",
        "task",
        "relative_jacobian",
        "with_frame",
        "locked",
        "view",
        "plot",
    } <= names
