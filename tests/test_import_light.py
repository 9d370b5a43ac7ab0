"""``import kinengine; kinengine.load(name)`` stays light: the modules that only some calls need (inverse
kinematics, the QP solver and its backends, xacro, model editing, plotting, example-robot-data's package
metadata) are imported on first use, and every public name still resolves to the object it names.
Speed itself is measured by benchmarks/import_time.py, never asserted here."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

import kinengine
from kinengine.urdf import parse_urdf

# Not imported by `import kinengine; kinengine.load("abb_irb120")`.
HEAVY = [
    "qpsolvers",
    "scipy",
    "matplotlib",
    "tqdm",
    "rich",
    "xacro",
    "xml.dom.minidom",
    "importlib.metadata",
    "urllib.request",
    "xml.sax.saxutils",
    "email",
    "ssl",
    "concurrent.futures.thread",
    "kinengine.control.ik",
    "kinengine.control.ik_batch",
    "kinengine.control.qp",
    "kinengine.control.pose_error",
    "kinengine.control.task",
    "kinengine.control.task_frame",
    "kinengine.control.frame_task",
    "kinengine.model.editing",
    "kinengine.urdf.xacro",
    "kinengine.presentation",
    "kinengine.cli",
]


def _modules_after(code: str) -> set[str]:
    script = f"import json, sys\n{code}\nprint(json.dumps(sorted(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", script], check=True, capture_output=True, text=True)
    return set(json.loads(out.stdout.splitlines()[-1]))


@pytest.mark.slow
def test_loading_a_shipped_robot_imports_none_of_the_heavy_modules():
    loaded = _modules_after("import kinengine; kinengine.load('abb_irb120')")
    assert "kinengine.robot" in loaded and "pinocchio" in loaded
    assert sorted(m for m in HEAVY if m in loaded) == []


@pytest.mark.slow
def test_the_lazy_names_are_imported_on_first_use():
    loaded = _modules_after(
        "import kinengine\nfrom kinengine import DifferentialIK, IKBatchResult\nassert kinengine.pose_error"
    )
    assert {"kinengine.control.qp", "kinengine.control.ik_batch", "kinengine.control.pose_error"} <= loaded


@pytest.mark.parametrize("name", kinengine.__all__)
def test_every_public_name_resolves_to_its_object(name):
    from kinengine.control import frame_task, ik, ik_batch, manipulability, pose_error, qp, task
    from kinengine.robot import Robot

    expected = {
        "DifferentialIK": qp.DifferentialIK,
        "PoseTarget": qp.PoseTarget,
        "PostureTarget": qp.PostureTarget,
        "FrameTask": frame_task.FrameTask,
        "IKResult": ik.IKResult,
        "IKBatchResult": ik_batch.IKBatchResult,
        "SingularityReport": manipulability.SingularityReport,
        "Task": task.Task,
        "pose_error": pose_error.pose_error,
        "Robot": Robot,
    }
    value = getattr(kinengine, name)
    assert name in dir(kinengine)
    if name in expected:
        assert value is expected[name]
    elif name == "__version__":
        assert isinstance(value, str)
    elif name == "ACCELERATED":
        from kinengine.model import accelerator

        assert value is accelerator.AVAILABLE and value is (accelerator.native is not None)
    else:
        assert getattr(value, "__name__", None) == name
        assert value.__module__.startswith("kinengine.")


def test_from_import_star_and_unknown_names():
    namespace: dict[str, object] = {}
    exec("from kinengine import *", namespace)
    assert set(kinengine.__all__) <= set(namespace)
    with pytest.raises(AttributeError, match="no attribute 'not_a_name'"):
        kinengine.not_a_name  # noqa: B018


def test_the_facade_reaches_the_lazily_imported_inverse_kinematics():
    robot = kinengine.load("abb_irb120")
    q = robot.neutral() + 0.1
    result = robot.inverse_kinematics(robot.frame_pose(q), q0=q)
    assert isinstance(result, kinengine.IKResult) and result.success
    assert abs(robot.frame_pose(result.q) - robot.frame_pose(q)).max() < 1e-6


def test_the_regenerated_urdf_escapes_every_name_without_the_xml_sax_import():
    """to_xml (on the load path) quotes names through lxml's serializer, not xml.sax.saxutils (which imports
    urllib.request, http, ssl and email): names with &, <, >, quotes, tab, newline and carriage return
    come back unchanged from a parse of the regenerated text."""
    urdf = (
        '<robot name="a&amp;b &quot;q&quot; it&apos;s"><link name="base &lt;0&gt;"/>'
        '<link name="tab&#9;nl&#10;cr&#13;"/><joint name="j &quot;1&quot;" type="revolute">'
        '<parent link="base &lt;0&gt;"/><child link="tab&#9;nl&#10;cr&#13;"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>'
    )
    description = parse_urdf(urdf)
    assert description.name == 'a&b "q" it\'s'
    assert [link.name for link in description.links] == ["base <0>", "tab\tnl\ncr\r"]
    again = parse_urdf(description.to_xml())
    assert again.to_xml() == description.to_xml()
    assert [j.name for j in again.joints] == ['j "1"'] and again.joints[0].child == "tab\tnl\ncr\r"
