"""kinengine.urdf: strict and safe parsing, structural validation, limits, Pinocchio agreement.

Every refusal asserts the exact type URDFError, a message fragment and, where the
element is known, its line. Values are checked against the URDF text itself,
yourdfpy (an independent parser), scipy's rotations and Pinocchio's own parse of
the original files.
"""

from __future__ import annotations

import dataclasses
import importlib.metadata
import math
import os
import threading
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yourdfpy
from hypothesis import HealthCheck, given, settings
from scipy.spatial.transform import Rotation
from urdf_strategies import random_urdfs

from kinengine.errors import KinematicsError, URDFError
from kinengine.model import build_pinocchio_model, check_pinocchio_model
from kinengine.urdf import LIMITS, Limits, RobotDescription, parse_urdf, read_urdf_file

LIMIT = '<limit lower="-1" upper="1" effort="2" velocity="3"/>'
AXIS_Z = '<axis xyz="0 0 1"/>'
_ERD = importlib.metadata.distribution("example-robot-data")
ERD_FILES = sorted((Path(f.locate()) for f in _ERD.files if str(f).endswith(".urdf")), key=lambda p: p.name)
ERD_ROOT = Path(_ERD.locate_file("cmeel.prefix/share/example-robot-data/robots"))
AGREEMENT_ROBOTS = (
    "ur_description/urdf/ur5_robot.urdf",
    "panda_description/urdf/panda.urdf",
    "baxter_description/urdf/baxter.urdf",
    "kinova_description/robots/kinova.urdf",
    "talos_data/robots/talos_left_arm.urdf",
)


# -- URDF builders -----------------------------------------------------------------------------------
def joint_xml(name: str, parent: str, child: str, kind: str = "revolute", body: str = LIMIT + AXIS_Z) -> str:
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>{body}</joint>'
    )


def robot_xml(links: list[str], joints: list[str], name: str = "test") -> str:
    """<robot> on line 1, then one line per link, then one line per joint."""
    lines = [f'<robot name="{name}">'] + [f'<link name="{n}"/>' for n in links] + joints + ["</robot>"]
    return "\n".join(lines) + "\n"


def chain_urdf(n: int, kind: str = "revolute", body: str = '<origin xyz="0 0 0.1"/>' + AXIS_Z + LIMIT) -> str:
    """Links l0..ln, joints j1..jn (j_i: l_{i-1} -> l_i)."""
    return robot_xml(
        [f"l{i}" for i in range(n + 1)],
        [joint_xml(f"j{i}", f"l{i - 1}", f"l{i}", kind, body) for i in range(1, n + 1)],
    )


def one_joint(body: str, kind: str = "revolute") -> str:
    """Links base (line 2) and tip (line 3), joint 'j' on line 4."""
    return robot_xml(["base", "tip"], [joint_xml("j", "base", "tip", kind, body)])


def refused(
    document: str | bytes, match: str, *, line: int | None = None, limits: Limits = LIMITS
) -> URDFError:
    with pytest.raises(URDFError, match=match) as info:
        parse_urdf(document, limits=limits)
    assert type(info.value) is URDFError
    if line is not None:
        assert info.value.line == line
    return info.value


def without_lines(d: RobotDescription) -> tuple:
    """The description minus source, lines and warnings; velocity/effort None as 0.0.

    to_xml() writes None velocity and effort as 0.0, because urdfdom (inside
    Pinocchio) requires both attributes on every <limit>.
    """
    joints = tuple(
        dataclasses.replace(j, line=None, velocity=j.velocity or 0.0, effort=j.effort or 0.0)
        for j in d.joints
    )
    return d.name, d.root, tuple(dataclasses.replace(x, line=None) for x in d.links), joints


def in_thread(function, timeout: float = 60.0):
    """function() run in a daemon thread; its result or exception, or 'hung' if it did not return."""
    box: list = []

    def run() -> None:
        try:
            box.append(function())
        except BaseException as exc:
            box.append(exc)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(timeout)
    return box[0] if box else "hung"


# -- safe XML ----------------------------------------------------------------------------------------
def test_str_and_bytes_give_the_same_description():
    text = chain_urdf(3)
    assert parse_urdf(text) == parse_urdf(text.encode()) == parse_urdf(bytearray(text.encode()))


def test_str_with_an_encoding_declaration_is_read_as_the_text_it_is():
    body = robot_xml(["bäse", "tip"], [joint_xml("jé", "bäse", "tip")], name="robøt")
    for declaration in (
        '<?xml version="1.0" encoding="ISO-8859-1"?>\n',
        "<?xml version='1.0' encoding='UTF-16'?>\n",
    ):
        d = parse_urdf(declaration + body)
        assert (d.name, d.root, d.joints[0].name) == ("robøt", "bäse", "jé")
    latin = parse_urdf(('<?xml version="1.0" encoding="ISO-8859-1"?>\n' + body).encode("latin-1"))
    utf16 = parse_urdf(('<?xml version="1.0" encoding="UTF-16"?>\n' + body).encode("utf-16"))
    assert latin.joints[0].name == utf16.joints[0].name == "jé"


def test_input_that_is_not_text_or_not_unicode_is_refused():
    refused(None, "str or bytes")  # type: ignore[arg-type]
    refused(chain_urdf(1).replace("test", "te\ud800st"), "not valid Unicode")


def test_broken_xml_reports_lxml_reason_and_line():
    text = robot_xml(["a", "b"], ['<joint name="j" type="fixed"><parent link="a"/><child link="b"/></link>'])
    error = refused(text, "not well-formed XML: Opening and ending tag mismatch: joint", line=4)
    assert "column" in str(error)


def test_truncated_file_is_refused_not_read_as_a_smaller_robot():
    text = chain_urdf(5)
    cut = text.index("</joint>", text.index('name="j3"')) + len("</joint>")
    refused(text[:cut], "Premature end of data in tag robot", line=10)
    refused(text[: cut - 3], "not well-formed XML", line=10)


def test_root_must_be_robot():
    refused(
        '<model name="m">\n<link name="a"/>\n</model>', r"root element is <model>, expected <robot>", line=1
    )
    # a default namespace on <robot> is accepted, as urdfdom does (tests/test_urdf_features.py)
    assert parse_urdf('<robot xmlns="http://example.com/urdf" name="r"><link name="a"/></robot>').root == "a"


def test_robot_needs_a_name():
    refused('<robot>\n<link name="a"/>\n</robot>', "<robot> has no 'name' attribute", line=1)


@pytest.mark.parametrize("prefix", ["", '<?xml version="1.0"?>\n<!-- a <robot> in a comment -->\n'])
def test_external_entity_is_refused_without_opening_the_file(tmp_path, prefix):
    fifo = tmp_path / "secret"  # opening a FIFO for reading blocks until a writer comes: a read would hang
    os.mkfifo(fifo)
    text = (
        f'{prefix}<!DOCTYPE robot [<!ENTITY x SYSTEM "file://{fifo}">]>\n'
        '<robot name="&x;"><link name="a">&x;</link></robot>'
    )
    outcome = in_thread(lambda: parse_urdf(text), timeout=30)
    assert type(outcome) is URDFError, outcome
    assert "DOCTYPE" in str(outcome) or "external entity 'x'" in str(outcome)
    passwd = (
        '<!DOCTYPE r [<!ENTITY x SYSTEM "file:///etc/passwd">]>\n<robot name="r"><link name="&x;"/></robot>'
    )
    error = refused(passwd, r"<!DOCTYPE> is not allowed", line=1)
    assert "root:" not in str(error)


def test_billion_laughs_is_refused_before_libxml2_sees_it():
    entities = ['<!ENTITY lol0 "lol">'] + [f'<!ENTITY lol{i} "{f"&lol{i - 1};" * 10}">' for i in range(1, 10)]
    text = f'<?xml version="1.0"?>\n<!DOCTYPE robot [\n{chr(10).join(entities)}\n]>\n<robot name="&lol9;"/>'
    refused(text, r"<!DOCTYPE> is not allowed.*entity", line=2)
    refused('<!DOCTYPE robot SYSTEM "http://example.com/robot.dtd">\n<robot name="r"/>', "DOCTYPE", line=1)
    hidden = '<!-- <robot> --><!DOCTYPE robot [<!ENTITY a "b">]><robot name="&a;"><link name="l"/></robot>'
    refused(hidden, r"<!DOCTYPE> is not allowed")
    refused('<robot name="r"><link name="&undefined;"/></robot>', "Entity 'undefined' not defined")


def test_the_reference_reads_yourdfpy_strictly_without_meshes_or_entities(tmp_path):
    # the issue: yourdfpy recovers malformed XML, resolves external entities with lxml < 6.1 and opens
    # mesh paths relative to the URDF; kinengine.reference parses strictly first and never loads meshes
    from lxml import etree

    from kinengine.reference import ReferenceKinematics

    assert etree.LXML_VERSION >= (6, 1)
    secret = tmp_path / "secret.txt"
    secret.write_text("SECRET-CONTENT")
    xxe = (
        f'<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY s SYSTEM "file://{secret}">]>\n'
        '<robot name="&s;"><link name="a"/></robot>'
    )
    outcome = in_thread(lambda: ReferenceKinematics.from_urdf_string(xxe))
    assert type(outcome) is URDFError and "SECRET" not in str(outcome), outcome
    fifo = tmp_path / "mesh.stl"
    os.mkfifo(fifo)  # opening it for reading would block forever
    mesh = f'<visual><geometry><mesh filename="{fifo}"/></geometry></visual>'
    relative = '<collision><geometry><mesh filename="../../mesh.stl"/></geometry></collision>'
    text = one_joint(LIMIT + AXIS_Z).replace(
        '<link name="tip"/>', f'<link name="tip">{mesh}{relative}</link>'
    )
    reference = in_thread(lambda: ReferenceKinematics.from_urdf_string(text, joint_names=("j",)))
    assert isinstance(reference, ReferenceKinematics), reference
    assert isinstance(in_thread(lambda: parse_urdf(text)), RobotDescription)
    truncated = one_joint(LIMIT + AXIS_Z)[:-40]
    assert type(in_thread(lambda: ReferenceKinematics.from_urdf_string(truncated))) is URDFError


def test_document_size_is_bounded_before_parsing():
    big = '<robot name="r"><link name="a"/>' + " " * LIMITS.max_bytes + "</robot>"
    refused(big, f"more than Limits.max_bytes = {LIMITS.max_bytes}")
    refused(big.encode(), f"more than Limits.max_bytes = {LIMITS.max_bytes}")
    refused(chain_urdf(2), "more than Limits.max_bytes = 100", limits=Limits(max_bytes=100))
    refused(chain_urdf(2), "markup tags, more than Limits.max_tags = 10", limits=Limits(max_tags=10))


def test_nesting_depth_is_bounded_in_any_thread():
    nested = "<a>" * 100 + "</a>" * 100
    text = f'<robot name="r">\n<link name="l">{nested}</link>\n</robot>'
    refused(text, f"nested deeper than Limits.max_depth = {LIMITS.max_depth}", line=2)
    very_deep = f'<robot name="r"><link name="l">{"<a>" * 5000}{"</a>" * 5000}</link></robot>'
    outcome = in_thread(lambda: parse_urdf(very_deep))
    assert type(outcome) is URDFError and "depth" in str(outcome)


def test_attribute_length_and_name_length_are_bounded():
    text = one_joint(LIMIT + f'<axis xyz="0 0 1" comment="{"x" * 5000}"/>')
    refused(text, "attribute 'comment' has 5000 characters, more than Limits.max_attribute_length", line=4)
    long_name = "n" * (LIMITS.max_name_length + 1)
    refused(robot_xml([long_name], []), "more than Limits.max_name_length", line=2)


# -- model size limits -----------------------------------------------------------------------------------
def test_ten_thousand_joint_chain_is_refused_in_the_main_thread_and_in_a_worker():
    text = chain_urdf(10_000)
    refused(text, "the robot has 10001 links, more than Limits.max_links = 4096")
    outcome = in_thread(lambda: parse_urdf(text))
    assert type(outcome) is URDFError and "Limits.max_links" in str(outcome)


def test_tree_depth_is_bounded_even_for_fixed_joints():
    # Pinocchio's recursive C++ parser crashes the process on deep chains (see Limits.max_tree_depth)
    text = chain_urdf(LIMITS.max_tree_depth + 1, kind="fixed", body="")
    refused(
        text,
        "link 'l129' is more than Limits.max_tree_depth = 128 joints below the root 'l0'",
        line=2 + 130 + 128,
    )
    assert len(parse_urdf(chain_urdf(LIMITS.max_tree_depth, kind="fixed", body="")).joints) == 128


def test_ten_thousand_joint_chain_with_raised_limits_needs_no_recursion():
    text = chain_urdf(10_000)
    big = Limits(max_links=10_001, max_joints=10_000, max_movable_joints=10_000, max_tree_depth=10_000)
    previous = threading.stack_size(256 * 1024)  # a recursive tree walk would overflow this
    try:
        outcome = in_thread(lambda: parse_urdf(text, limits=big))
    finally:
        threading.stack_size(previous)
    assert isinstance(outcome, RobotDescription), outcome
    assert [j.name for j in outcome.joints] == [f"j{i}" for i in range(1, 10_001)]
    assert outcome.links[-1].name == "l10000"


def test_movable_joints_are_counted_separately_from_fixed_ones():
    n = LIMITS.max_movable_joints
    refused(chain_urdf(n + 1), f"{n + 1} movable joints, more than Limits.max_movable_joints = {n}")
    star = robot_xml(
        ["base"] + [f"l{i}" for i in range(300)],
        [joint_xml(f"j{i}", "base", f"l{i}", "fixed", "") for i in range(300)],
    )
    fixed = parse_urdf(star)
    assert len(fixed.joints) == 300 and fixed.movable_joints == ()
    refused(chain_urdf(5), "6 links, more than Limits.max_links = 5", limits=Limits(max_links=5))
    refused(chain_urdf(5), "5 joints, more than Limits.max_joints = 4", limits=Limits(max_joints=4))


def test_load_takes_raised_limits_and_refuses_anything_but_a_limits_object(tmp_path):
    import kinengine

    text = chain_urdf(LIMITS.max_movable_joints + 1)
    with pytest.raises(
        URDFError,
        match="129 movable joints, more than Limits.max_movable_joints = 128; pass "
        r"parse_urdf\(..., limits=Limits\(max_movable_joints=...\)\)",
    ):
        kinengine.load_urdf_string(text)
    bigger = Limits(max_movable_joints=129, max_tree_depth=129)
    assert kinengine.load_urdf_string(text, limits=bigger).dof == 129
    path = tmp_path / "chain.urdf"
    path.write_text(text)
    assert kinengine.load(path, limits=bigger).dof == 129
    with pytest.raises(URDFError, match="chain.urdf.*129 movable joints"):
        kinengine.load(path)
    with pytest.raises(URDFError, match="more than Limits.max_links = 5"):
        kinengine.load("abb_irb120", limits=Limits(max_links=5))
    with pytest.raises(
        kinengine.OptionError, match=r"limits= takes a kinengine.urdf.Limits \(.*\), got dict"
    ):
        kinengine.load_urdf_string(chain_urdf(2), limits={"max_links": 10})


# -- joint types and structure ------------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["floating", "planar"])
def test_floating_and_planar_joints_are_refused_with_advice(kind):
    error = refused(one_joint("", kind=kind), f"fixed-base model cannot have a {kind} joint", line=4)
    assert "Remove the joint" in str(error) and "floating-base robot" in str(error)


def test_unknown_or_missing_joint_type_lists_the_supported_ones():
    supported = "supported types: revolute, continuous, prismatic, fixed"
    refused(one_joint("", kind="ball"), f"unsupported type 'ball'; {supported}", line=4)
    text = robot_xml(["a", "b"], ['<joint name="j"><parent link="a"/><child link="b"/></joint>'])
    refused(text, f"no type attribute; {supported}", line=4)


def test_names_must_be_unique():
    refused(robot_xml(["a", "b", "a"], []), r"link name 'a' is used twice \(lines 2 and 4\)", line=4)
    joints = [joint_xml("j", "a", "b"), joint_xml("j", "b", "c")]
    refused(robot_xml(["a", "b", "c"], joints), r"joint name 'j' is used twice \(lines 5 and 6\)", line=6)


def test_names_must_be_present_and_non_empty():
    refused(robot_xml([""], []), "<link> has an empty 'name' attribute", line=2)
    refused(robot_xml(["a", "b"], [joint_xml("", "a", "b")]), "<joint> has an empty 'name'", line=4)
    text = robot_xml(["a", "b"], ['<joint name="j" type="fixed"><parent link="a"/></joint>'])
    refused(text, "has no <child link=...> element", line=4)
    text = robot_xml(["a", "b"], ['<joint name="j" type="fixed"><parent/><child link="b"/></joint>'])
    refused(text, "<parent> has no 'link' attribute", line=4)


def test_joint_links_must_exist():
    refused(
        robot_xml(["base", "tip"], [joint_xml("j", "bsae", "tip")]),
        r"joint 'j': its parent link 'bsae' is not defined \(did you mean 'base'\?\)",
        line=4,
    )
    refused(
        robot_xml(["base", "tip"], [joint_xml("j", "base", "nowhere")]), "child link 'nowhere' is not defined"
    )


def test_a_link_cannot_have_two_parents():
    joints = [joint_xml("j1", "a", "c"), joint_xml("j2", "b", "c"), joint_xml("j0", "a", "b")]
    refused(robot_xml(["a", "b", "c"], joints), r"link 'c' already has parent joint 'j1' \(line 5\)", line=6)


def test_several_roots_are_named():
    joints = [joint_xml("j1", "a", "b")]
    refused(
        robot_xml(["a", "b", "c", "d"], joints), "the links form 3 separate trees, with roots 'a', 'c', 'd'"
    )


def test_cycles_are_refused():
    refused(
        robot_xml(["a", "b"], [joint_xml("j1", "a", "b"), joint_xml("j2", "b", "a")]),
        r"there is no root link: joints 'j\d', 'j\d' form a cycle",
    )
    joints = [
        joint_xml("j0", "root", "a"),
        joint_xml("j1", "b", "c"),
        joint_xml("j2", "c", "d"),
        joint_xml("j3", "d", "b"),
    ]
    refused(
        robot_xml(["root", "a", "b", "c", "d"], joints),
        r"not every link hangs from root 'root': "
        r"joints 'j1', 'j2', 'j3' form a cycle 'b' -> 'c' -> 'd' -> 'b'",
    )
    refused(robot_xml(["a", "b"], [joint_xml("j", "a", "a")]), "connects link 'a' to itself", line=4)


def test_a_robot_needs_a_link_and_may_have_no_joint():
    refused('<robot name="r"/>', "the robot has no <link>")
    lone = parse_urdf(robot_xml(["only"], []))
    assert (lone.root, lone.joints, lone.movable_joints) == ("only", (), ())


def test_xacro_macros_are_refused():
    text = (
        '<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">\n<link name="a"/>\n'
        '<xacro:include filename="arm.xacro"/>\n</robot>'
    )
    refused(text, "<xacro:include> is a xacro macro: expand the file first", line=3)


def test_a_repeated_singular_element_takes_the_first_one_with_a_warning():
    with pytest.warns(UserWarning, match=r"joint 'j'.*2 <origin> elements"):
        d = parse_urdf(one_joint('<origin xyz="1 0 0"/><origin xyz="0 1 0"/>' + LIMIT))
    assert d.joint("j").xyz == (1.0, 0.0, 0.0)


# -- numbers ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "value, reason",
    [
        ("nan 0 0", "'nan' is not finite"),
        ("0 -inf 0", "'-inf' is not finite"),
        ("0 0 Infinity", "is not finite"),
        ("a b c", "'a' is not a number"),
        ("1 2", "expected three numbers separated by spaces, got 2"),
        ("1 2 3 4", "got 4"),
        ("1,2,3", "got 1"),
        ("", "got 0"),
        ("1_0 0 0", "'1_0' is not a number"),
        ("1e400 0 0", "'1e400' overflows a double"),
        ("0x1 0 0", "is not a number"),
        ("\u0663 0 0", "is not a number"),
    ],
)
@pytest.mark.parametrize("element, attribute", [("origin", "xyz"), ("origin", "rpy"), ("axis", "xyz")])
def test_vectors_need_three_finite_numbers(element, attribute, value, reason):
    body = f'<{element} {attribute}="{value}"/>' + LIMIT
    refused(one_joint(body), rf"joint 'j': <{element} {attribute}=\"{value}\">: .*{reason}", line=4)


def test_spec_defaults_for_origin_axis_and_limits():
    d = parse_urdf(one_joint('<origin xyz="1 2 3"/><limit effort="1"/>'))
    j = d.joints[0]
    assert (j.xyz, j.rpy, j.axis) == ((1.0, 2.0, 3.0), (0.0, 0.0, 0.0), (1.0, 0.0, 0.0))
    assert (j.lower, j.upper, j.effort, j.velocity) == (0.0, 0.0, 1.0, None)
    bare = parse_urdf(one_joint("", kind="continuous")).joints[0]
    assert (bare.xyz, bare.rpy) == ((0.0,) * 3, (0.0,) * 3)
    assert (bare.lower, bare.upper, bare.velocity) == (None, None, None)
    exact = parse_urdf(one_joint('<origin xyz=" 1e-3\t-2.5E+1\n.5 " rpy="-0 +1. 3.25"/>' + LIMIT)).joints[0]
    assert exact.xyz == (0.001, -25.0, 0.5) and exact.rpy == (0.0, 1.0, 3.25)


def test_zero_axis_is_refused():
    refused(
        one_joint('<axis xyz="0 0 0"/>' + LIMIT), r"<axis xyz=\"0 0 0\"> is zero; give a unit axis", line=4
    )
    refused(one_joint('<axis xyz="0 1e-12 0"/>', kind="continuous"), "give a unit axis")
    d = parse_urdf(one_joint('<axis xyz="0 0 0"/>', kind="fixed"))  # fixed joints have no axis
    assert d.joints[0].axis == (1.0, 0.0, 0.0)


def test_non_unit_axis_is_normalized_with_a_warning():
    message = r"joint 'j': axis '3 0 4' has norm 5; normalized to \(0.6, 0, 0.8\)"
    with pytest.warns(UserWarning, match=message):
        d = parse_urdf(one_joint('<axis xyz="3 0 4"/>' + LIMIT))
    np.testing.assert_allclose(d.joints[0].axis, (0.6, 0.0, 0.8), rtol=0, atol=1e-15)
    assert math.hypot(*d.joints[0].axis) == pytest.approx(1.0, rel=0, abs=1e-15)
    assert len(d.warnings) == 1 and "normalized" in d.warnings[0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        unit = parse_urdf(one_joint('<axis xyz="0.6 0 -0.8"/>' + LIMIT))
    assert unit.joints[0].axis == (0.6, 0.0, -0.8) and unit.warnings == ()


def test_revolute_and_prismatic_joints_need_ordered_finite_limits():
    for kind in ("revolute", "prismatic"):
        refused(one_joint(AXIS_Z, kind=kind), f"a {kind} joint needs a <limit lower=... upper=...>", line=4)
    refused(
        one_joint('<limit lower="1" upper="-1"/>'), "lower limit 1.0 is greater than upper limit -1.0", line=4
    )
    refused(one_joint('<limit lower="nan" upper="1"/>'), r"<limit lower=\"nan\">: 'nan' is not finite")
    refused(one_joint('<limit lower="0" upper="1" velocity="fast"/>'), "'fast' is not a number")
    limit = '<limit lower="-0.5" upper="0.25" velocity="2" effort="30"/>'
    j = parse_urdf(one_joint(limit, kind="prismatic")).joints[0]
    assert (j.lower, j.upper, j.velocity, j.effort) == (-0.5, 0.25, 2.0, 30.0)


def test_continuous_joints_ignore_lower_and_upper():
    limit = '<limit lower="5" upper="-5" velocity="2" effort="1"/>'
    j = parse_urdf(one_joint(limit, kind="continuous")).joints[0]
    assert (j.lower, j.upper, j.velocity, j.effort) == (None, None, 2.0, 1.0)


# -- mimic joints -----------------------------------------------------------------------------------------
def _pinocchio_builds_mimic_joints() -> bool:
    """Whether this Pinocchio's URDF parser takes mimic=True (its own mimic joints; pin 3.4 has no such
    argument: kinengine never passes it, only the tests below that show what it does)."""
    try:
        pin.buildModelFromXML('<robot name="r"><link name="a"/></robot>', mimic=True)
    except TypeError:  # Boost.Python.ArgumentError: no overload with mimic=
        return False
    return True


PIN_MIMIC = _pinocchio_builds_mimic_joints()


def mimic_robot(
    mimic: str,
    leader_kind: str = "revolute",
    follower_kind: str = "revolute",
    leader: str = "a_leader",
    follower: str = "b_follower",
) -> str:
    """Links on lines 2-4, the leader joint on line 5, the follower (with ``mimic``) on line 6."""
    return robot_xml(
        ["base", "l1", "l2"],
        [
            joint_xml(leader, "base", "l1", leader_kind),
            joint_xml(follower, "base", "l2", follower_kind, LIMIT + AXIS_Z + mimic),
        ],
    )


def test_mimic_defaults_and_values():
    d = parse_urdf(mimic_robot('<mimic joint="a_leader"/>'))
    assert d.joint("b_follower").mimic.joint == "a_leader"
    assert (d.joint("b_follower").mimic.multiplier, d.joint("b_follower").mimic.offset) == (1.0, 0.0)
    text = mimic_robot('<mimic joint="a_leader" multiplier="-2.5" offset="0.125"/>')
    m = parse_urdf(text).joint("b_follower").mimic
    assert (m.multiplier, m.offset) == (-2.5, 0.125)
    assert [j.name for j in d.movable_joints] == ["a_leader"]


def test_mimic_rules():
    refused(
        mimic_robot('<mimic joint="a_ledaer"/>'),
        r"joint 'b_follower': mimics joint 'a_ledaer', which is not defined "
        r"\(did you mean 'a_leader'\?\)",
        line=6,
    )
    refused(mimic_robot('<mimic joint="b_follower"/>'), "mimics itself", line=6)
    refused(
        mimic_robot('<mimic joint="a_leader"/>', leader_kind="fixed"),
        "mimics joint 'a_leader', which is fixed",
    )
    refused(mimic_robot('<mimic joint="a_leader" multiplier="inf"/>'), "'inf' is not finite")
    refused(mimic_robot("<mimic/>"), "<mimic> has no 'joint' attribute")
    chained = robot_xml(
        ["base", "l1", "l2", "l3"],
        [
            joint_xml("a", "base", "l1"),
            joint_xml("b", "base", "l2", body=LIMIT + '<mimic joint="a"/>'),
            joint_xml("c", "base", "l3", body=LIMIT + '<mimic joint="b"/>'),
        ],
    )
    assert parse_urdf(chained).joint("c").mimic.joint == "b"  # a mimic of a mimic: composed by the model
    cycle = robot_xml(
        ["base", "l1", "l2", "l3"],
        [
            joint_xml("a", "base", "l1"),
            joint_xml("b", "base", "l2", body=LIMIT + '<mimic joint="c"/>'),
            joint_xml("c", "base", "l3", body=LIMIT + '<mimic joint="b"/>'),
        ],
    )
    refused(cycle, r"joint 'b': is part of a cycle of mimic joints 'b' -> 'c' -> 'b'")


def test_mimic_on_a_fixed_joint_is_ignored_with_a_warning():
    with pytest.warns(UserWarning, match=r"joint 'b_follower' is fixed: its <mimic> \(line 6\) is ignored"):
        d = parse_urdf(mimic_robot('<mimic joint="a_leader"/>', follower_kind="fixed"))
    assert d.joint("b_follower").mimic is None and len(d.warnings) == 1


@pytest.mark.parametrize(
    "leader_kind, follower_kind", [("continuous", "revolute"), ("revolute", "continuous")]
)
def test_mimic_pairs_of_any_revolute_kind_build_as_plain_joints(leader_kind, follower_kind):
    """Pinocchio 4.1's own mimic joints cannot pair continuous with revolute; kinengine's plain joints can."""
    text = mimic_robot('<mimic joint="a_leader" multiplier="2" offset="0.1"/>', leader_kind, follower_kind)
    if PIN_MIMIC:
        with pytest.raises(ValueError, match="configuration spaces have different sizes"):
            pin.buildModelFromXML(text, mimic=True)  # what the 0.1 design ran into
    model = build_pinocchio_model(parse_urdf(text))
    assert (model.nq, model.nv) == (2, 2)


def test_mimic_joint_ordered_before_its_leader_builds():
    text = mimic_robot('<mimic joint="b_leader"/>', leader="b_leader", follower="a_follower")
    text = text.replace("a_leader", "b_leader")
    if PIN_MIMIC:
        with pytest.raises(ValueError, match="mimic joint is not in the kinematic tree"):
            pin.buildModelFromXML(text, mimic=True)  # what the 0.1 design ran into
    assert list(build_pinocchio_model(parse_urdf(text)).names) == ["universe", "a_follower", "b_leader"]


# -- inertials --------------------------------------------------------------------------------------------
INERTIA = '<inertia ixx="0.1" ixy="0.01" ixz="-0.02" iyy="0.2" iyz="0.03" izz="0.3"/>'


def link_with(inertial: str) -> str:
    return f'<robot name="r">\n<link name="a">{inertial}</link>\n</robot>'


def test_inertial_values_and_absence():
    origin = '<origin xyz="0 0 0.5" rpy="0 1 0"/>'
    d = parse_urdf(link_with(f'<inertial>{origin}<mass value="2.5"/>{INERTIA}</inertial>'))
    i = d.links[0].inertial
    assert (i.mass, i.xyz, i.rpy) == (2.5, (0.0, 0.0, 0.5), (0.0, 1.0, 0.0))
    assert i.inertia == (0.1, 0.01, -0.02, 0.2, 0.03, 0.3)
    assert parse_urdf(link_with("")).links[0].inertial is None


def test_inertial_numbers_must_be_finite_and_complete():
    refused(
        link_with(f'<inertial><mass value="nan"/>{INERTIA}</inertial>'),
        r"link 'a': <mass value=\"nan\">",
        line=2,
    )
    refused(link_with(f'<inertial><mass value="-1"/>{INERTIA}</inertial>'), "mass -1.0 kg is negative")
    refused(link_with(f"<inertial>{INERTIA}</inertial>"), r"<inertial> needs <mass value=...>")
    refused(link_with('<inertial><mass value="1"/></inertial>'), "<inertial> needs <inertia ixx=...")
    no_iyz = INERTIA.replace(' iyz="0.03"', "")
    refused(link_with(f'<inertial><mass value="1"/>{no_iyz}</inertial>'), "<inertia> lacks iyz")
    refused(link_with(f'<inertial><mass value="1"/>{INERTIA.replace("0.3", "inf")}</inertial>'), "not finite")


# -- order, round trip, Pinocchio ------------------------------------------------------------------------
def test_joints_are_depth_first_with_siblings_sorted_by_name_like_pinocchio():
    joints = [
        joint_xml("z_first_in_file", "base", "z1"),
        joint_xml("m_child", "z1", "z2"),
        joint_xml("B_upper", "base", "b1"),
        joint_xml("a_lower", "base", "a1"),
        joint_xml("fixed_mid", "a1", "a2", "fixed", ""),
        joint_xml("c_under_fixed", "a2", "a3"),
    ]
    text = robot_xml(["base", "z1", "z2", "b1", "a1", "a2", "a3"], joints)
    d = parse_urdf(text)
    expected = ["B_upper", "a_lower", "fixed_mid", "c_under_fixed", "z_first_in_file", "m_child"]
    assert [j.name for j in d.joints] == expected  # byte order: upper case before lower case
    assert [link.name for link in d.links] == ["base"] + [d.joint(n).child for n in expected]
    assert list(pin.buildModelFromXML(text).names)[1:] == [n for n in expected if n != "fixed_mid"]


@pytest.mark.filterwarnings("ignore::UserWarning")  # talos_left_arm: <mimic> on fixed joints
@pytest.mark.parametrize("relative", AGREEMENT_ROBOTS)
def test_pinocchio_builds_the_description_exactly_as_it_builds_the_original(relative):
    path = ERD_ROOT / relative
    description = read_urdf_file(path)
    ours = build_pinocchio_model(description)
    theirs = pin.buildModelFromUrdf(str(path))  # mimic joints as plain joints, continuous as (cos, sin)
    assert list(ours.names) == list(theirs.names)
    assert ours.nq == ours.nv == theirs.nv == len([j for j in description.joints if j.movable])
    for a, b in zip(ours.jointPlacements, theirs.jointPlacements, strict=False):
        np.testing.assert_allclose(a.homogeneous, b.homogeneous, rtol=0, atol=1e-12)
    q = np.random.default_rng(0).uniform(-1, 1, ours.nq)
    q_theirs = (
        np.concatenate(
            [
                [q[i - 1]] if theirs.joints[i].nq == 1 else [np.cos(q[i - 1]), np.sin(q[i - 1])]
                for i in range(1, theirs.njoints)
            ]
        )
        if ours.nq
        else np.zeros(0)
    )
    data_ours, data_theirs = ours.createData(), theirs.createData()
    pin.forwardKinematics(ours, data_ours, q)
    pin.forwardKinematics(theirs, data_theirs, q_theirs)
    for a, b in zip(data_ours.oMi, data_theirs.oMi, strict=False):
        np.testing.assert_allclose(a.homogeneous, b.homogeneous, rtol=0, atol=1e-12)


def test_check_pinocchio_model_detects_a_model_that_disagrees():
    description = parse_urdf(chain_urdf(3))
    check_pinocchio_model(
        description, pin.buildModelFromXML(description.to_xml(), **({"mimic": True} if PIN_MIMIC else {}))
    )
    with pytest.raises(KinematicsError, match=r"Pinocchio built the joints \['j1', 'j2'\]"):
        check_pinocchio_model(description, pin.buildModelFromXML(chain_urdf(2)))
    continuous = pin.buildModelFromXML(chain_urdf(3).replace('"revolute"', '"continuous"'))
    with pytest.raises(KinematicsError, match=r"\(nq, nv\) = \(2, 1\).*expected \(1, 1\)"):
        check_pinocchio_model(description, continuous)


@pytest.mark.parametrize("path", ERD_FILES, ids=lambda p: p.name)
def test_every_example_robot_data_urdf_parses_or_is_refused_like_pinocchio_refuses_it(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # non-unit axes and mimic tags on fixed joints in some files
        try:
            description = read_urdf_file(path)
        except URDFError as error:
            assert type(error) is URDFError and str(path) in str(error)
            if "mimics joint" in str(error):  # Pinocchio without mimic joints never reads the reference
                return
            with pytest.raises(ValueError):  # Pinocchio's own parser refuses these files too
                pin.buildModelFromUrdf(str(path))
            return
    model = build_pinocchio_model(description)
    assert list(model.names) == list(pin.buildModelFromUrdf(str(path)).names)
    assert without_lines(parse_urdf(description.to_xml())) == without_lines(description)


@pytest.mark.parametrize(
    "relative",
    AGREEMENT_ROBOTS + ("romeo_description/urdf/romeo_laas_small.urdf", "pr2_description/urdf/pr2.urdf"),
)
def test_values_agree_with_yourdfpy(relative):
    path = ERD_ROOT / relative
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        description = read_urdf_file(path)
    other = yourdfpy.URDF.load(
        str(path), build_scene_graph=False, load_meshes=False, load_collision_meshes=False
    )
    assert {j.name for j in description.joints} == set(other.joint_map)
    for joint in description.joints:
        theirs = other.joint_map[joint.name]
        assert (joint.type, joint.parent, joint.child) == (theirs.type, theirs.parent, theirs.child)
        origin = np.eye(4)
        origin[:3, :3] = Rotation.from_euler("xyz", joint.rpy).as_matrix()  # URDF rpy: fixed-axis X, Y, Z
        origin[:3, 3] = joint.xyz
        np.testing.assert_allclose(
            origin, theirs.origin if theirs.origin is not None else np.eye(4), rtol=0, atol=1e-12
        )
        if not joint.movable:
            continue
        axis = np.asarray(theirs.axis if theirs.axis is not None else (1.0, 0.0, 0.0))
        np.testing.assert_allclose(joint.axis, axis / np.linalg.norm(axis), rtol=0, atol=1e-15)
        if joint.type != "continuous":
            assert (joint.lower, joint.upper) == (theirs.limit.lower or 0.0, theirs.limit.upper or 0.0)
        if joint.mimic is not None:
            assert (joint.mimic.joint, joint.mimic.multiplier, joint.mimic.offset) == (
                theirs.mimic.joint,
                theirs.mimic.multiplier or 1.0,
                theirs.mimic.offset or 0.0,
            )


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(random_urdfs(max_links=8))
def test_random_trees_round_trip_and_agree_with_pinocchio(text):
    description = parse_urdf(text)
    assert without_lines(parse_urdf(description.to_xml())) == without_lines(description)
    ours = build_pinocchio_model(description)
    check_pinocchio_model(description, ours)
    theirs = pin.buildModelFromXML(text)  # the original text: same joints, same placements
    assert list(theirs.names) == list(ours.names)
    for a, b in zip(ours.jointPlacements, theirs.jointPlacements, strict=False):
        np.testing.assert_allclose(a.homogeneous, b.homogeneous, rtol=0, atol=1e-12)


def test_parsing_in_worker_threads_gives_the_same_descriptions():
    texts = [chain_urdf(n) for n in range(1, 9)]
    expected = [parse_urdf(t) for t in texts]
    results: dict[int, object] = {}
    threads = [
        threading.Thread(target=lambda i=i: results.__setitem__(i, parse_urdf(texts[i % 8])))
        for i in range(32)
    ]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    assert all(results[i] == expected[i % 8] for i in range(32))


# -- files --------------------------------------------------------------------------------------------------
def test_read_urdf_file_matches_parse_urdf_and_names_the_file(tmp_path):
    path = tmp_path / "arm.urdf"
    path.write_text(chain_urdf(3), encoding="utf-8")
    from_file = read_urdf_file(path)
    assert from_file.source == str(path)
    assert without_lines(from_file) == without_lines(parse_urdf(chain_urdf(3)))
    path.write_text(chain_urdf(3).replace('lower="-1"', 'lower="x"'), encoding="utf-8")
    with pytest.raises(URDFError, match=rf"{path}:6, joint 'j1': <limit lower=\"x\">"):
        read_urdf_file(path)


def test_read_urdf_file_refuses_what_is_not_a_readable_regular_file(tmp_path):
    cases = [
        (tmp_path / "missing.urdf", "no such file"),
        (tmp_path, r"not a regular file \(a directory\)"),
        (Path("/dev/zero"), r"not a regular file \(a device, FIFO or socket\)"),
    ]
    for path, message in cases:
        with pytest.raises(URDFError, match=message) as info:
            read_urdf_file(path)
        assert type(info.value) is URDFError and str(path) in str(info.value)
    fifo = tmp_path / "pipe.urdf"
    os.mkfifo(fifo)
    outcome = in_thread(lambda: read_urdf_file(fifo), timeout=30)
    assert type(outcome) is URDFError and "FIFO" in str(outcome)
    big = tmp_path / "big.urdf"
    big.write_text(chain_urdf(3), encoding="utf-8")
    with pytest.raises(URDFError, match=rf"{big}: the file is \d+ bytes, more than Limits.max_bytes = 100"):
        read_urdf_file(big, limits=Limits(max_bytes=100))
    with pytest.raises(URDFError, match="cannot open the file: embedded null byte"):
        read_urdf_file(str(tmp_path / "a\0.urdf"))
    with pytest.raises(URDFError, match="path to a .urdf file, got int"):
        read_urdf_file(42)  # type: ignore[arg-type]
