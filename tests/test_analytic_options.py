"""One options object: every Robot method that takes the analytic options (position, rotation, rows,
singularity_threshold, on_singularity) declares the defaults of ``kinengine.analytic.options.DEFAULTS``,
so that no two of them can drift apart, and checks its values the same way."""

from __future__ import annotations

import dataclasses
import inspect

import numpy as np
import pytest

import kinengine
from kinengine.analytic.options import DEFAULTS, AnalyticOptions

OPTIONS = [field.name for field in dataclasses.fields(AnalyticOptions)]
ANALYTIC_METHODS = ["pose_parameters", "analytic_jacobian", "analytic_hessian", "task"]


@pytest.mark.parametrize("method", ANALYTIC_METHODS)
def test_the_analytic_methods_take_their_defaults_from_the_one_options_object(method):
    parameters = inspect.signature(getattr(kinengine.Robot, method)).parameters
    names = list(parameters)
    assert names[names.index("position") + 1] == "rotation"  # position, rotation: positional, in this order
    for option in OPTIONS:
        if option in parameters:
            assert parameters[option].default == getattr(DEFAULTS, option), f"{method}({option}=...)"


@pytest.fixture(scope="module")
def abb():
    return kinengine.load("abb_irb120")


@pytest.mark.parametrize(
    "options, error, message",
    [
        ({"rotation": "euler_abc"}, kinengine.ParameterizationError, "euler_abc"),
        ({"rows": ("x", "nope")}, kinengine.ParameterizationError, "nope"),
        ({"singularity_threshold": -1.0}, kinengine.OptionError, "singularity_threshold"),
    ],
)
@pytest.mark.parametrize("method", ["pose_parameters", "analytic_jacobian", "analytic_hessian", "task"])
def test_a_bad_option_is_the_same_error_from_every_method(abb, method, options, error, message):
    q = abb.neutral()
    call = getattr(abb, method)
    with pytest.raises(error, match=message):
        call(q, "tool0", **options) if method != "task" else call("tool0", **options)


def test_options_are_checked_before_the_frame_and_the_frames_before_q(abb):
    bad_q = np.full(abb.dof + 1, 0.1)
    for method in ANALYTIC_METHODS[:3]:
        with pytest.raises(kinengine.OptionError, match="singularity_threshold"):
            getattr(abb, method)(bad_q, "no_such_frame", singularity_threshold=-1.0)
        with pytest.raises(kinengine.FrameNotFoundError, match="no_such_frame"):
            getattr(abb, method)(bad_q, "no_such_frame")
    for method in ("pose_parameters", "analytic_jacobian"):
        with pytest.raises(kinengine.FrameNotFoundError, match="no_such_frame"):
            getattr(abb, method)(bad_q, "tool0", relative_to="no_such_frame")
        with pytest.raises(kinengine.ConfigurationError):
            getattr(abb, method)(bad_q, "tool0", relative_to="base_link")
