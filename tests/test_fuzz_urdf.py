"""Mutation fuzzing of kinengine.load_urdf_string: accept a model the reference agrees with, or refuse.

Valid URDFs (random trees from ``urdf_strategies.random_urdfs`` and the texts of the
shipped robots and of Panda, which has a mimic finger) are mutated: elements dropped,
duplicated, moved or renamed; attributes dropped or corrupted (NaN, inf, text, huge and
subnormal numbers, wrong counts, other elements' names); the raw text truncated or spliced.
For every mutant, ``kinengine.load_urdf_string`` must either raise a KinematicsError or
return a Robot whose frame poses T_IF (root link frame, [m]) equal those of the independent
reference (``kinengine.reference``: yourdfpy + numpy) for every frame, at random q. Any
other exception fails the test. Only the kinematic part of a URDF is mutated; visuals,
collisions and materials, which kinengine ignores, stay valid.
"""

from __future__ import annotations

import copy
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from lxml import etree
from urdf_strategies import random_urdfs

import kinengine
from kinengine.model import catalog_entry, shipped_robots_dir
from kinengine.reference import ReferenceKinematics

pytestmark = pytest.mark.slow  # hypothesis over mutated URDFs

SEED_TEXTS = tuple(p.read_text(encoding="utf-8") for p in sorted(shipped_robots_dir().glob("*/*.urdf"))) + (
    catalog_entry("panda").path.read_text(encoding="utf-8"),
)
IGNORED_SUBTREES = ("visual", "collision", "material", "gazebo", "transmission")
TAGS = (
    "robot",
    "link",
    "joint",
    "origin",
    "axis",
    "limit",
    "mimic",
    "parent",
    "child",
    "inertial",
    "mass",
    "inertia",
    "calibration",
    "dynamics",
    "safety_controller",
)
ATTRIBUTES = {  # attributes a corruption may also add where they are absent
    "robot": ("name",),
    "link": ("name",),
    "joint": ("name", "type"),
    "origin": ("xyz", "rpy"),
    "axis": ("xyz",),
    "limit": ("lower", "upper", "effort", "velocity"),
    "mimic": ("joint", "multiplier", "offset"),
    "parent": ("link",),
    "child": ("link",),
    "mass": ("value",),
    "inertia": ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"),
}
BAD_NUMBERS = (
    "nan",
    "NaN",
    "-nan",
    "inf",
    "-Infinity",
    "1e400",
    "-1e400",
    "1e308",
    "-1e308",
    "1e300",
    "1e-320",
    "5e-324",
    "0",
    "-0",
    "1e-9",
    "abc",
    "",
    "0x1A",
    "1_0",
    "\u0661",
    "1.5.2",
    "+.5",
    "5.",
    "1e",
    "--1",
    "3.0e+2",
    " 7 ",
    "1,5",
    "\uff11",
)
BAD_VALUES = (
    "",
    " ",
    "1 2",
    "1 2 3 4",
    "0 0 0",
    "nan nan nan",
    "a b c",
    "1e308 1e308 1e308",
    "1e-320 0 0",
    "0 0 1e-10",
    "\t1\n2  3 ",
    "1\u00a02\u00a03",
    "x" * 5000,
    "revolute",
    "continuous",
    "prismatic",
    "fixed",
    "floating",
    "planar",
    "spherical",
    "REVOLUTE",
)
SPLICES = ("<", "&", "\x00", "\ud800", "</joint>", "<link name='x'/>")  # break the XML wherever they land
JOINT_TYPES = (
    "revolute",
    "continuous",
    "prismatic",
    "fixed",
    "floating",
    "planar",
    "spherical",
    "",
    "Revolute",
)


def kinematic_elements(root: etree._Element) -> list[etree._Element]:
    """The elements a mutation may touch: everything outside visual/collision/material subtrees."""
    return [
        e
        for e in root.iter()
        if isinstance(e.tag, str) and not any(a.tag in IGNORED_SUBTREES for a in (e, *e.iterancestors()))
    ]


def names(root: etree._Element) -> list[str]:
    return [e.get("name") for e in root.iter("link", "joint") if e.get("name")]


@st.composite
def corrupt_value(draw: st.DrawFn, root: etree._Element, old: str | None) -> str:
    """A whole bad value, one bad token swapped into a number list, or another element's name."""
    form = draw(st.sampled_from(("whole", "token", "name")))
    if form == "token" and old and old.split():
        tokens = old.split()
        tokens[draw(st.integers(0, len(tokens) - 1))] = draw(st.sampled_from(BAD_NUMBERS))
        return " ".join(tokens)
    if form == "name" and names(root):
        return draw(st.sampled_from(names(root) + ["missing_link", "universe"]))
    return draw(st.sampled_from(BAD_VALUES + BAD_NUMBERS))


@st.composite
def mutate(draw: st.DrawFn, root: etree._Element) -> None:
    """One mutation of ``root``, in place."""
    elements = kinematic_elements(root)
    target = draw(st.sampled_from(elements))
    kind = draw(
        st.sampled_from(
            (
                "drop",
                "duplicate",
                "move",
                "retag",
                "drop_attribute",
                "corrupt",
                "corrupt",
                "corrupt",
                "joint_type",
            )
        )
    )
    parent = target.getparent()
    if kind == "drop" and parent is not None:
        parent.remove(target)
    elif kind == "duplicate" and parent is not None:
        target.addnext(copy.deepcopy(target))
    elif kind == "move" and parent is not None:
        destination = draw(
            st.sampled_from([e for e in elements if e is not target and target not in e.iterancestors()])
        )
        destination.append(target)
    elif kind == "retag":
        target.tag = draw(st.sampled_from(TAGS))
    elif kind == "drop_attribute" and target.attrib:
        del target.attrib[draw(st.sampled_from(sorted(target.attrib)))]
    elif kind == "joint_type":
        joints = root.findall("joint")
        if joints:
            draw(st.sampled_from(joints)).set("type", draw(st.sampled_from(JOINT_TYPES)))
    else:
        candidates = sorted(set(target.attrib) | set(ATTRIBUTES.get(target.tag, ())))
        if candidates:
            attribute = draw(st.sampled_from(candidates))
            target.set(attribute, draw(corrupt_value(root, target.get(attribute))))


@st.composite
def mutated_urdfs(draw: st.DrawFn) -> str:
    """A valid URDF after 1 to 3 mutations, sometimes truncated or spliced with markup that breaks the XML."""
    base = draw(st.one_of(random_urdfs(max_links=6), st.sampled_from(SEED_TEXTS)))
    root = etree.fromstring(base.encode("utf-8"))  # our own valid texts: no hostile markup here
    for _ in range(draw(st.integers(1, 3))):
        draw(mutate(root))
    text = etree.tostring(root, encoding="unicode")
    raw = draw(st.sampled_from(("none", "none", "none", "none", "truncate", "splice")))
    if raw == "truncate":
        text = text[: draw(st.integers(0, len(text) - 1))]
    elif raw == "splice":
        at = draw(st.integers(0, len(text)))
        text = text[:at] + draw(st.sampled_from(SPLICES)) + text[at:]
    return text


def load_or_refuse(text: str) -> kinengine.Robot | None:
    """The Robot of ``text``, or None if kinengine refused it with a KinematicsError (anything else raises)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # non-unit axes are normalized with a warning
            return kinengine.load_urdf_string(text)
    except kinengine.KinematicsError:
        return None


def assert_reference_agrees(robot: kinengine.Robot, text: str, seed: int) -> None:
    """Every frame's T_IF equals the reference's at two random q (any angle, limits ignored)."""
    reference = ReferenceKinematics.from_urdf_string(text, joint_names=robot.joint_names)
    assert set(reference.frame_names) == set(robot.frame_names)
    qs = np.random.default_rng(seed).uniform(-np.pi, np.pi, size=(2, robot.dof))
    for frame in robot.frame_names:
        np.testing.assert_allclose(
            robot.frame_pose(qs, frame), reference.frame_pose(qs, frame), rtol=1e-12, atol=1e-9, err_msg=frame
        )


@settings(max_examples=1000, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(mutated_urdfs(), st.integers(0, 2**32 - 1))
def test_mutated_urdf_is_refused_or_agrees_with_the_reference(text, seed):
    robot = load_or_refuse(text)
    if robot is not None:
        assert_reference_agrees(robot, text, seed)


@pytest.mark.parametrize("text", SEED_TEXTS, ids=lambda t: t[t.index("<robot name=") + 13 :].split('"')[0])
def test_unmutated_seeds_are_accepted_and_agree(text):
    robot = load_or_refuse(text)
    assert robot is not None
    assert_reference_agrees(robot, text, seed=0)


# -- files the fuzzer found kinengine accepting although yourdfpy (and urdfdom) refuse them --------------
def joint(inner: str, kind: str = "revolute", name: str = "j", parent: str = "a") -> str:
    return (
        f'<robot name="r"><link name="a"/><link name="b"/><joint name="{name}" type="{kind}">'
        f'<parent link="{parent}"/><child link="b"/>{inner}</joint></robot>'
    )


LIMIT = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'


@pytest.mark.parametrize(
    "text, fragment",
    [
        (joint('<limit upper="--1" effort="1" velocity="1"/>', kind="continuous"), "'--1' is not a number"),
        (
            joint(LIMIT + '<safety_controller k_velocity="panda_hand_tcp"/>'),
            "'panda_hand_tcp' is not a number",
        ),
        (joint(LIMIT + '<calibration rising="0x1A"/>'), "'0x1A' is not a number"),
        # found by this fuzzer: a fixed joint's <limit>, <axis> and <mimic> are unused but still read by others
        (joint('<limit lower="0" upper="1" effort="" velocity="2"/>', kind="fixed"), "'' is not a number"),
        (joint('<mimic joint="j" multiplier="two"/>', kind="fixed"), "'two' is not a number"),
    ],
)
def test_numbers_yourdfpy_cannot_read_are_refused(text, fragment):
    with pytest.raises(kinengine.URDFError) as info:
        kinengine.load_urdf_string(text)
    assert fragment in str(info.value)
    with pytest.raises(kinengine.URDFError, match="yourdfpy could not read it"):
        ReferenceKinematics.from_urdf_string(text)


@pytest.mark.parametrize(
    "text, fragment",
    [
        (
            joint(LIMIT).replace('name="a"', 'name="universe"').replace('link="a"', 'link="universe"'),
            '<link name="universe">: the name is reserved',
        ),
        (joint(LIMIT, name="universe"), '<joint name="universe">: the name is reserved'),
        (joint(LIMIT + '<dynamics damping="nan" friction="0"/>'), "'nan' is not finite"),
    ],
)
def test_names_pinocchio_reserves_and_unused_non_finite_numbers_are_refused(text, fragment):
    # a link or joint named "universe" (found by this fuzzer) lost its frame next to Pinocchio's own
    with pytest.raises(kinengine.URDFError) as info:
        kinengine.load_urdf_string(text)
    assert fragment in str(info.value)


def test_axis_whose_squared_norm_overflows_is_refused_and_a_large_one_normalized():
    # found by this fuzzer: yourdfpy's np.linalg.norm and Pinocchio's Eigen normalize() overflow on such an
    # axis (Pinocchio then moves the child frame non-rigidly), so kinengine refuses what they cannot read
    with pytest.raises(kinengine.URDFError, match="squared norm overflows a double"):
        kinengine.load_urdf_string(joint(LIMIT + '<axis xyz="-1e308 0 1"/>'))
    text = joint(LIMIT + '<axis xyz="-1e150 0 1"/>')
    with pytest.warns(UserWarning, match="normalized to"):
        robot = kinengine.load_urdf_string(text)
    np.testing.assert_array_equal(robot.description.joints[0].axis, (-1.0, 0.0, 1e-150))
    assert_reference_agrees(robot, text, seed=0)


def test_a_fixed_joint_axis_must_be_three_numbers_and_may_be_zero():
    with pytest.raises(kinengine.URDFError, match=r'<axis xyz="0 0">'):
        kinengine.load_urdf_string(joint('<axis xyz="0 0"/>', kind="fixed"))
    robot = kinengine.load_urdf_string(joint('<axis xyz="0 0 0"/>', kind="fixed"))  # common in the wild
    assert robot.dof == 0
