"""xacro expansion without ROS (kinengine.urdf.xacro) and ROS package lookup (kinengine.urdf.packages).

Every file under tests/data/xacro was written for these tests: each xacro is checked against a
URDF expanded by hand (tests/data/xacro/expected), to 1e-15 in every frame pose and Jacobian.
"""

from __future__ import annotations

import os
import threading
import warnings
from pathlib import Path

import numpy as np
import pytest

import kinengine
from kinengine.errors import ResourceLimitError, URDFError
from kinengine.urdf.packages import resolve_package, resolve_uri
from kinengine.urdf.xacro import expand_xacro

DATA = Path(__file__).parent / "data" / "xacro"
ARM = DATA / "ws" / "src" / "kin_arm" / "urdf" / "arm.urdf.xacro"
PARTS = DATA / "elsewhere" / "parts_pkg"  # package kin_parts, in a folder of another name
IRB = DATA / "irb_like_support" / "robots" / "irb_like.xacro"
ERRORS = DATA / "errors"


@pytest.fixture(autouse=True)
def no_ros_package_path(monkeypatch):
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)


def assert_same_model(text: str, expected: Path, rename=lambda name: name, samples: int = 5) -> None:
    """The model of ``text`` equals the hand-expanded ``expected`` (names mapped by ``rename``) to 1e-15."""
    robot = kinengine.load_urdf_string(text)
    reference = kinengine.load_urdf_string(expected.read_text())
    assert robot.joint_names == tuple(rename(n) for n in reference.joint_names)
    frames = [f for f in reference.frame_names if f != "universe"]
    assert sorted(robot.frame_names) == sorted(
        rename(f) if f != "universe" else f for f in reference.frame_names
    )
    rng = np.random.default_rng(13)
    for q in [reference.neutral()] + [reference.random_configuration(rng) for _ in range(samples)]:
        for frame in frames:
            np.testing.assert_allclose(
                robot.frame_pose(q, rename(frame)), reference.frame_pose(q, frame), rtol=0, atol=1e-15
            )
            np.testing.assert_allclose(
                robot.jacobian(q, rename(frame)), reference.jacobian(q, frame), rtol=0, atol=1e-15
            )


def assert_one_line(exc: pytest.ExceptionInfo, *fragments: str) -> str:
    message = str(exc.value)
    assert "\n" not in message, message
    for fragment in fragments:
        assert fragment in message, message
    return message


# --- expansion, through each of the three package sources --------------------------------------------


def test_packages_argument_resolves_find():
    """kin_parts through packages=, kin_arm through its own package.xml above the file."""
    text = expand_xacro(ARM, packages={"kin_parts": PARTS})
    assert "xacro" not in text and "$(" not in text and "${" not in text
    assert_same_model(text, DATA / "expected" / "arm.urdf")


def test_ros_package_path_resolves_find(monkeypatch):
    roots = [str(DATA / "no_such_folder"), str(DATA / "elsewhere")]
    monkeypatch.setenv("ROS_PACKAGE_PATH", os.pathsep.join(roots))
    assert_same_model(expand_xacro(str(ARM)), DATA / "expected" / "arm.urdf")


def test_own_tree_resolves_find_by_package_xml_and_by_folder_name():
    """irb_like_support by the package.xml above the wrapper, kin_common as a folder beside an ancestor."""
    assert_same_model(expand_xacro(IRB), DATA / "expected" / "irb_like.urdf")


def test_arguments_conditionals_and_math():
    text = expand_xacro(
        ARM,
        args={"upper_length": 0.6, "with_tool": "false", "prismatic_wrist": "true"},
        packages={"kin_parts": str(PARTS)},
    )
    assert_same_model(text, DATA / "expected" / "arm_prismatic_no_tool.urdf")


def test_rosindustrial_wrapper_with_a_prefix():
    text = expand_xacro(IRB, args={"prefix": "left_"})
    assert_same_model(
        text, DATA / "expected" / "irb_like.urdf", rename=lambda name: "left_" + name, samples=2
    )


def test_packages_argument_wins_over_the_environment_and_the_tree(monkeypatch, tmp_path):
    """A package.xml naming kin_parts first on ROS_PACKAGE_PATH, but packages= points elsewhere."""
    decoy = tmp_path / "decoy"
    decoy.mkdir()
    (decoy / "package.xml").write_text("<package><name>kin_parts</name></package>")
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path))
    assert resolve_package("kin_parts") == decoy
    assert resolve_package("kin_parts", packages={"kin_parts": PARTS}) == PARTS.resolve()


def test_expansion_leaves_xacro_state_clean_and_is_thread_safe():
    import xacro

    # as it found it (another user of xacro in this process, e.g. Robotics Toolbox's URDF loader in the
    # benchmark's peers, leaves filestack at [None])
    before = (xacro.filestack, list(xacro.all_includes), dict(xacro.substitution_args_context))
    results: list[str] = []

    def expand():
        results.append(expand_xacro(IRB))

    threads = [threading.Thread(target=expand) for _ in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert len(set(results)) == 1 and len(results) == 4
    assert (xacro.filestack, xacro.all_includes, xacro.substitution_args_context) == before


def test_xacro_warnings_become_user_warnings(capsys):
    with pytest.warns(UserWarning, match="unknown attribute.*colour"):
        text = expand_xacro(ERRORS / "emits_warning.xacro")
    assert 'xyz="0 0 0.3"' in text
    assert capsys.readouterr() == ("", "")


# --- errors: one line each, nothing printed ------------------------------------------------------------


@pytest.mark.parametrize(
    "name, fragments",
    [
        ("needs_arg.xacro", ["missing xacro argument 'ur_type'", "args="]),
        ("unknown_macro.xacro", ["unknown xacro macro <xacro:no_such_arm>"]),
        ("undefined_property.xacro", ["undefined xacro property", "lower_length"]),
        ("malformed.xacro", ["malformed.xacro:4", "not well-formed XML"]),
        ("includes_doctype.xacro", ["doctype_part.xacro:2", "<!DOCTYPE> is not allowed"]),
        ("calls_fatal.xacro", ["unsupported robot variant"]),
    ],
)
def test_xacro_errors_are_one_line(name, fragments, capsys):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(URDFError) as exc:
            expand_xacro(ERRORS / name)
    assert_one_line(exc, *fragments)
    assert capsys.readouterr() == ("", "")


def test_macro_only_file_is_refused():
    with pytest.raises(URDFError) as exc:
        expand_xacro(IRB.parent / "irb_like_macro.xacro")
    assert_one_line(exc, "only defines macros", "irb_like_macro.xacro")


def test_unresolved_package_names_it_and_the_places_searched(monkeypatch, capsys):
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(DATA / "elsewhere"))
    with pytest.raises(URDFError) as exc:
        expand_xacro(ERRORS / "finds_missing_package.xacro", packages={"kin_parts": PARTS})
    assert_one_line(
        exc,
        "'kin_no_such_package' not found",
        "packages= ('kin_parts')",
        f"ROS_PACKAGE_PATH ({DATA / 'elsewhere'})",
        f"the folders above '{ERRORS}'",
        "--package kin_no_such_package=",
        "ROS_PACKAGE_PATH",
    )
    assert capsys.readouterr() == ("", "")


def test_a_package_missing_from_every_source_is_refused():
    """kin_parts is only reachable through packages= or ROS_PACKAGE_PATH."""
    with pytest.raises(URDFError) as exc:
        expand_xacro(ARM)
    assert_one_line(exc, "'kin_parts' not found", "ROS_PACKAGE_PATH (unset)")


@pytest.mark.parametrize(
    "path, fragment",
    [
        (DATA / "no_such_file.xacro", "cannot open the file"),
        (DATA, "not a regular file"),
    ],
)
def test_unreadable_input_is_refused(path, fragment):
    with pytest.raises(URDFError) as exc:
        expand_xacro(path)
    assert_one_line(exc, fragment)


def test_packages_entry_that_is_not_a_folder():
    with pytest.raises(URDFError) as exc:
        expand_xacro(ARM, packages={"kin_parts": DATA / "nowhere"})
    assert_one_line(exc, "packages= maps ROS package 'kin_parts'", "not a folder")


def test_exponential_macro_is_stopped_by_the_macro_call_budget(tmp_path):
    """2**39 links; the budget is Limits.max_macro_calls (lowered here: xacro needs ~1 s per 10,000)."""
    levels = "\n".join(
        f'<xacro:macro name="m{i}"><xacro:m{i - 1}/><xacro:m{i - 1}/></xacro:macro>' for i in range(1, 40)
    )
    (tmp_path / "bomb.xacro").write_text(
        '<robot name="bomb" xmlns:xacro="http://www.ros.org/wiki/xacro">'
        f'<xacro:macro name="m0"><link name="l"/></xacro:macro>{levels}<xacro:m39/></robot>'
    )
    with pytest.raises(ResourceLimitError) as exc:
        expand_xacro(tmp_path / "bomb.xacro", limits=kinengine.urdf.Limits(max_macro_calls=2000))
    assert_one_line(exc, "more than Limits.max_macro_calls = 2000 macro calls")


# --- package lookup and URIs ---------------------------------------------------------------------------


def test_package_uri_resolves_to_a_mesh_file():
    mesh = resolve_uri("package://irb_like_support/meshes/x.stl", start=IRB.parent)
    assert mesh == (DATA / "irb_like_support" / "meshes" / "x.stl").resolve()
    assert mesh.read_text().startswith("solid x")
    assert resolve_uri("package://kin_parts/urdf/parts.xacro", packages={"kin_parts": PARTS}).is_file()


def test_file_and_relative_uris():
    assert resolve_uri(f"file://{IRB}") == IRB
    assert resolve_uri("file:///tmp/a%20b.stl") == Path("/tmp/a b.stl")
    assert resolve_uri("../meshes/x.stl", start=IRB) == DATA / "irb_like_support" / "meshes" / "x.stl"
    for bad in ("http://example.com/x.stl", "file://otherhost/x.stl", "package://", "package://pkg"):
        with pytest.raises(URDFError):
            resolve_uri(bad)


def test_package_names_cannot_escape(tmp_path):
    for bad in ("..", "a/b", "", "../etc"):
        with pytest.raises(URDFError) as exc:
            resolve_package(bad, start=tmp_path)
        assert_one_line(exc, "not a ROS package name")


def test_package_xml_name_in_a_comment_is_ignored(monkeypatch):
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(DATA / "elsewhere"))
    assert resolve_package("kin_parts") == PARTS.resolve()
    with pytest.raises(URDFError) as exc:
        resolve_package("not_this")
    assert_one_line(exc, "'not_this' not found", "no file's folders")
