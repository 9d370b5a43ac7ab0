"""Hypothesis strategies for random, valid URDF texts of fixed-base kinematic trees.

``random_urdfs(max_links=8)`` draws a branching tree of links with random origins
(xyz [m], rpy [rad]), random unit axes (cardinal ones too, which Pinocchio builds as
special joint models), every supported joint type (revolute, continuous, prismatic,
fixed), limits with lower < upper, and mimic joints (multiplier, offset) of every shape
kinengine accepts: a mimic joint of any movable type following a leader of any movable
type (a continuous joint following a revolute one, a prismatic one following a revolute
one), before or after its leader in tree order, and mimics of mimics (chains, composed
by the loader). Joint elements appear in shuffled file order and joint names are shuffled,
so file order, name order and tree order all differ. Floats are written with ``repr`` so
every parser reads the same doubles.

Acyclic by construction: the movable joints are visited in a random order and each one is
either independent or follows a joint visited before it in that order (which may itself be
a mimic joint); that order is unrelated to the tree order.
"""

from __future__ import annotations

import math

from hypothesis import strategies as st

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed")
CARDINAL_AXES = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0), (0.0, 0.0, -1.0), (-1.0, 0.0, 0.0))


def _floats(lo: float, hi: float) -> st.SearchStrategy[float]:
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False, allow_subnormal=False)


def _v(values: tuple[float, ...]) -> str:
    return " ".join(repr(float(v)) for v in values)


@st.composite
def unit_axes(draw: st.DrawFn) -> tuple[float, float, float]:
    """A unit 3-vector: one of a few cardinal axes, or a random direction."""
    if draw(st.booleans()):
        return draw(st.sampled_from(CARDINAL_AXES))
    v = draw(
        st.tuples(_floats(-1, 1), _floats(-1, 1), _floats(-1, 1)).filter(
            lambda v: math.fsum(x * x for x in v) > 0.01
        )
    )
    norm = math.sqrt(math.fsum(x * x for x in v))
    return (v[0] / norm, v[1] / norm, v[2] / norm)


def _origin(draw: st.DrawFn) -> str:
    """An <origin> element, sometimes omitted or without rpy (the defaults are zero)."""
    form = draw(st.sampled_from(("full", "full", "full", "xyz", "none")))
    if form == "none":
        return ""
    xyz = draw(st.tuples(*[_floats(-1, 1)] * 3))
    if form == "xyz":
        return f'<origin xyz="{_v(xyz)}"/>'
    rpy = draw(st.tuples(*[_floats(-math.pi, math.pi)] * 3))
    return f'<origin xyz="{_v(xyz)}" rpy="{_v(rpy)}"/>'


@st.composite
def random_urdfs(draw: st.DrawFn, max_links: int = 8) -> str:
    """URDF text of a random valid tree with 1..max_links links (0..max_links-1 joints)."""
    n = draw(st.integers(1, max_links))
    parents = [draw(st.integers(0, i)) for i in range(n - 1)]  # joint i: link parents[i] -> link i + 1
    link_ids = draw(st.permutations(range(n)))
    joint_ids = draw(st.permutations(range(n - 1)))
    links = [f"link_{k}" for k in link_ids]
    names = [f"joint_{k}" for k in joint_ids]
    types = [draw(st.sampled_from(JOINT_TYPES)) for _ in range(n - 1)]

    mimic: dict[int, str] = {}
    movable = [i for i in range(n - 1) if types[i] != "fixed"]
    seen: list[int] = []  # movable joints visited so far in a random order: the possible leaders
    for i in draw(st.permutations(movable)):
        if seen and draw(st.integers(0, 2)) == 0:
            leader = names[draw(st.sampled_from(seen))]
            multiplier, offset = draw(_floats(-2, 2)), draw(_floats(-1, 1))
            mimic[i] = f'<mimic joint="{leader}" multiplier="{multiplier!r}" offset="{offset!r}"/>'
        seen.append(i)

    elements = [
        f'<joint name="{names[i]}" type="{types[i]}">'
        f'<parent link="{links[parents[i]]}"/><child link="{links[i + 1]}"/>{_origin(draw)}'
        + _motion_elements(draw, types[i])
        + mimic.get(i, "")
        + "</joint>"
        for i in range(n - 1)
    ]
    order = draw(st.permutations(range(n - 1)))
    body = "\n  ".join(
        [f'<link name="{name}"/>' for name in draw(st.permutations(links))] + [elements[i] for i in order]
    )
    return f'<?xml version="1.0"?>\n<robot name="random">\n  {body}\n</robot>\n'


def _motion_elements(draw: st.DrawFn, kind: str) -> str:
    """<axis> (sometimes omitted: default x) and <limit> of a joint of type ``kind``."""
    if kind == "fixed":
        return ""
    axis = "" if draw(st.integers(0, 5)) == 0 else f'<axis xyz="{_v(draw(unit_axes()))}"/>'
    if kind == "continuous":
        return axis + '<limit effort="10" velocity="2"/>'
    lower = draw(_floats(-3, 2.5))
    upper = lower + draw(_floats(0.05, 3))
    return axis + f'<limit lower="{lower!r}" upper="{upper!r}" effort="10" velocity="2"/>'
