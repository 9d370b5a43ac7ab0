"""Recognizing a floating-base description: a humanoid, legged or flying robot whose root link is a free body.

kinengine models are fixed-base: a URDF without a floating joint means its root link is fixed in the
world (the inertial frame I of the Robot Dynamics lecture notes, ETH Zurich, section 2.8), and that is
how such a file is loaded. For a robot that walks or flies this is a choice the user should see, so
:func:`floating_base_note` recognizes one from the words in its link and joint names (hip, knee, ankle,
foot, leg, pelvis, thigh, calf; ANYmal's HAA/HFE/KFE), rotors (rotor, propeller, flying) or wheels
(base_footprint, wheel, caster) and says so in one sentence. Arms, hands and grippers use none of these words,
but for "prop" in a gripper's part (Interbotix arms' ``gripper_prop_link``), which does not count.
"""

from __future__ import annotations

import re

from ..urdf import RobotDescription

LEGGED_WORDS = frozenset(
    {
        "hip",
        "knee",
        "ankle",
        "foot",
        "feet",
        "leg",
        "legs",
        "pelvis",
        "thigh",
        "calf",
        "shin",
        "sole",
        "haa",
        "hfe",
        "kfe",
    }
)
FLYING_WORDS = frozenset({"rotor", "propeller", "prop", "flying", "quadrotor", "multirotor", "drone"})
MOBILE_WORDS = frozenset({"footprint", "wheel", "caster"})
GRIPPER_WORDS = frozenset({"gripper", "finger", "hand", "jaw"})
"""A name with one of these is a gripper's part: its "prop" is not a propeller."""
_WORD = re.compile(r"[A-Z]+(?![a-z])|[A-Z]?[a-z]+|[0-9]+")


def name_words(name: str) -> set[str]:
    """Lower-case words of a snake_case, kebab-case or CamelCase name:
    'LKneePitch' -> {'l', 'knee', 'pitch'}."""
    return {w.lower() for w in _WORD.findall(name)}


def floating_base_note(description: RobotDescription) -> str | None:
    """One sentence saying the root link is held fixed, if the description looks like a floating-base robot
    (legs, rotors or wheels named in its links or joints); None otherwise."""
    words: set[str] = set()
    for name in [link.name for link in description.links] + [joint.name for joint in description.joints]:
        parts = name_words(name)
        words |= parts - {"prop"} if parts & GRIPPER_WORDS else parts
    for kind, vocabulary in (
        ("a legged or humanoid robot", LEGGED_WORDS),
        ("a flying robot", FLYING_WORDS),
        ("a mobile robot", MOBILE_WORDS),
    ):
        found = sorted(words & vocabulary)
        if found:
            return (
                f"{description.name!r} looks like {kind} (its names mention {', '.join(found[:3])}); "
                f"it is loaded with its root link {description.root!r} held fixed: poses are given in that "
                f"link's frame and the base's own motion is not a coordinate"
            )
    return None


__all__ = [
    "FLYING_WORDS",
    "GRIPPER_WORDS",
    "LEGGED_WORDS",
    "MOBILE_WORDS",
    "floating_base_note",
    "name_words",
]
