"""Small URDFs of our own making that exercise every joint type kinengine supports.

``mixed_chain_urdf()``: revolute, continuous, prismatic and fixed joints, a branch, and a
mimic joint (with multiplier and offset) following a revolute leader.
"""

from __future__ import annotations


def mixed_chain_urdf(name: str = "mixed") -> str:
    return f"""<?xml version="1.0"?>
<robot name="{name}">
  <link name="base"/>
  <link name="l1"/><link name="l2"/><link name="l3"/><link name="l4"/><link name="tip"/>
  <link name="finger_a"/><link name="finger_b"/><link name="side"/>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.3" rpy="0.1 -0.2 0.3"/><axis xyz="0 0 1"/>
    <limit lower="-2.5" upper="2.5" effort="10" velocity="2"/>
  </joint>
  <joint name="spin" type="continuous">
    <parent link="l1"/><child link="l2"/>
    <origin xyz="0.2 0.05 0.1" rpy="0 0.4 0"/><axis xyz="0 1 0"/>
    <limit effort="10" velocity="2"/>
  </joint>
  <joint name="slide" type="prismatic">
    <parent link="l2"/><child link="l3"/>
    <origin xyz="0.1 0 0.25" rpy="0.3 0 0"/><axis xyz="0.6 0 0.8"/>
    <limit lower="-0.1" upper="0.3" effort="10" velocity="1"/>
  </joint>
  <joint name="wrist" type="revolute">
    <parent link="l3"/><child link="l4"/>
    <origin xyz="0 0.1 0.05" rpy="0 0 0.5"/><axis xyz="1 0 0"/>
    <limit lower="-1.5" upper="1.5" effort="10" velocity="2"/>
  </joint>
  <joint name="tip_fixed" type="fixed">
    <parent link="l4"/><child link="tip"/>
    <origin xyz="0.05 0 0.12" rpy="0.2 0.1 -0.3"/>
  </joint>
  <joint name="finger_a_joint" type="revolute">
    <parent link="tip"/><child link="finger_a"/>
    <origin xyz="0 0.03 0.04"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <joint name="finger_b_joint" type="revolute">
    <parent link="tip"/><child link="finger_b"/>
    <origin xyz="0 -0.03 0.04"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="1" velocity="1"/>
    <mimic joint="finger_a_joint" multiplier="-1.5" offset="0.2"/>
  </joint>
  <joint name="side_joint" type="prismatic">
    <parent link="l1"/><child link="side"/>
    <origin xyz="0 0.2 0" rpy="0 0 1.0"/><axis xyz="0 0 1"/>
    <limit lower="0" upper="0.5" effort="1" velocity="1"/>
  </joint>
</robot>
"""


# -- the URDF features of issue 12, one small robot each (shapes seen in vendor files) ---------------------
_LIMIT = '<limit lower="-1.5" upper="1.5" effort="10" velocity="2"/>'
_FREE = '<limit effort="10" velocity="2"/>'


def _joint(name: str, kind: str, parent: str, child: str, inner: str = "") -> str:
    return (
        f'  <joint name="{name}" type="{kind}">\n    <parent link="{parent}"/><child link="{child}"/>{inner}\n'
        "  </joint>\n"
    )


def _robot(name: str, links: str, *joints: str, extra: str = "", attributes: str = "") -> str:
    return (
        f'<?xml version="1.0"?>\n<robot name="{name}"{attributes}>\n'
        + "".join(f'  <link name="{n}"/>\n' for n in links.split())
        + "".join(joints)
        + extra
        + "</robot>\n"
    )


MIMIC_SHAPES = {
    # the balancer piston of an ABB IRB 6600 / FANUC M-900: a continuous joint following a revolute one
    "continuous_follows_revolute": _robot(
        "balancer",
        "base arm tool0 piston rod",
        _joint(
            "lift",
            "revolute",
            "base",
            "arm",
            f'<origin xyz="0 0 0.4" rpy="0 0.2 0"/><axis xyz="0 1 0"/>{_LIMIT}',
        ),
        _joint("tool_fixed", "fixed", "arm", "tool0", '<origin xyz="0.6 0 0.1"/>'),
        _joint(
            "balancer",
            "continuous",
            "base",
            "piston",
            f'<origin xyz="-0.1 0.1 0.3" rpy="0.3 0 0"/><axis xyz="0 1 0"/>{_FREE}'
            '<mimic joint="lift" multiplier="-1" offset="0.3"/>',
        ),
        _joint("rod_fixed", "fixed", "piston", "rod", '<origin xyz="0 0 0.35"/>'),
    ),
    # ABB IRB 6700 cylinder_joint, Kinova Gen3 lite: the mimic joint sorts before its leader among siblings
    "mimic_before_leader": _robot(
        "before",
        "base cylinder cyl_tip arm tool0",
        _joint(
            "b_arm_joint", "revolute", "base", "arm", f'<origin xyz="0 0 0.3"/><axis xyz="0 1 0"/>{_LIMIT}'
        ),
        _joint(
            "a_cylinder_joint",
            "revolute",
            "base",
            "cylinder",
            f'<origin xyz="0.1 0 0.2" rpy="0 0 0.4"/><axis xyz="0 1 0"/>{_LIMIT}'
            '<mimic joint="b_arm_joint" multiplier="0.8" offset="-0.2"/>',
        ),
        _joint("cyl_fixed", "fixed", "cylinder", "cyl_tip", '<origin xyz="0 0 0.25"/>'),
        _joint("tool_fixed", "fixed", "arm", "tool0", '<origin xyz="0.5 0 0"/>'),
    ),
    # Inspire FTP hands: a finger whose distal joints mimic the joint before them
    "mimic_of_mimic": _robot(
        "finger",
        "palm p1 p2 p3 tip",
        _joint(
            "proximal", "revolute", "palm", "p1", f'<origin xyz="0 0.02 0.1"/><axis xyz="1 0 0"/>{_LIMIT}'
        ),
        _joint(
            "middle",
            "revolute",
            "p1",
            "p2",
            f'<origin xyz="0 0 0.05" rpy="0.1 0 0"/><axis xyz="1 0 0"/>{_LIMIT}'
            '<mimic joint="proximal" multiplier="1.2" offset="0.1"/>',
        ),
        _joint(
            "distal",
            "revolute",
            "p2",
            "p3",
            f'<origin xyz="0 0 0.04"/><axis xyz="0.8 0.6 0"/>{_LIMIT}'
            '<mimic joint="middle" multiplier="0.8" offset="-0.2"/>',
        ),
        _joint("tip_fixed", "fixed", "p3", "tip", '<origin xyz="0 0.01 0.03"/>'),
    ),
    # a crank driving a slider: a prismatic joint following a revolute one, with an offset
    "prismatic_follows_revolute": _robot(
        "crank",
        "base crank slider tool0",
        _joint(
            "crank_joint",
            "revolute",
            "base",
            "crank",
            f'<origin xyz="0 0 0.2" rpy="0.2 0 0"/><axis xyz="0 0 1"/>{_LIMIT}',
        ),
        _joint(
            "slider_joint",
            "prismatic",
            "crank",
            "slider",
            '<origin xyz="0.1 0 0.05"/><axis xyz="1 0 0"/><limit lower="-0.1" upper="0.2" effort="1" velocity="1"/>'
            '<mimic joint="crank_joint" multiplier="0.05" offset="0.01"/>',
        ),
        _joint("tool_fixed", "fixed", "slider", "tool0", '<origin xyz="0 0.03 0.02" rpy="0 0.3 0"/>'),
    ),
}
"""name -> URDF text of a small robot with one mimic shape (see the comments)."""


def mimic_chain_urdf(name: str = "mimic_chain") -> str:
    """Every mimic shape in one tree: an independent continuous joint leading a revolute mimic, a continuous
    mimic of a revolute joint, a mimic sorted before its leader, a chain of three mimics (a prismatic one
    last, following a revolute mimic), all with multipliers and offsets, below a 2-dof arm."""
    return _robot(
        name,
        "base l1 l2 l3 tool0 a_link b_link c_link d_link spinner follower",
        _joint(
            "shoulder",
            "revolute",
            "base",
            "l1",
            f'<origin xyz="0 0 0.3" rpy="0.1 -0.2 0.3"/><axis xyz="0 0 1"/>{_LIMIT}',
        ),
        _joint("elbow", "revolute", "l1", "l2", f'<origin xyz="0.2 0.05 0.1"/><axis xyz="0 1 0"/>{_LIMIT}'),
        _joint(
            "wrist",
            "continuous",
            "l2",
            "l3",
            f'<origin xyz="0.3 0 0" rpy="0 0.4 0"/><axis xyz="1 0 0"/>{_FREE}',
        ),
        _joint("tool_fixed", "fixed", "l3", "tool0", '<origin xyz="0.05 0 0.02"/>'),
        # siblings below l3, sorted by name: a_ (mimic of z_), then b_, c_ (mimics of mimics), then z_
        _joint(
            "a_mimic",
            "revolute",
            "l3",
            "a_link",
            f'<origin xyz="0 0.04 0.05"/><axis xyz="0 0 1"/>{_LIMIT}'
            '<mimic joint="z_leader" multiplier="-0.5" offset="0.2"/>',
        ),
        _joint(
            "b_mimic",
            "revolute",
            "a_link",
            "b_link",
            f'<origin xyz="0 0.03 0"/><axis xyz="0 0.6 0.8"/>{_LIMIT}'
            '<mimic joint="a_mimic" multiplier="1.5" offset="-0.1"/>',
        ),
        _joint(
            "c_mimic",
            "prismatic",
            "b_link",
            "c_link",
            '<origin xyz="0 0.02 0.01"/><axis xyz="0 1 0"/>'
            '<limit lower="-1" upper="1" effort="1" velocity="1"/><mimic joint="b_mimic" multiplier="0.1" offset="0.02"/>',
        ),
        _joint(
            "z_leader", "revolute", "l3", "d_link", f'<origin xyz="0 -0.04 0.05"/><axis xyz="0 0 1"/>{_LIMIT}'
        ),
        _joint(
            "spin_continuous",
            "continuous",
            "l2",
            "spinner",
            f'<origin xyz="0 0.1 0"/><axis xyz="0 1 0"/>{_FREE}'
            '<mimic joint="elbow" multiplier="2" offset="0.5"/>',
        ),
        _joint(
            "follow_wrist",
            "revolute",
            "spinner",
            "follower",
            f'<origin xyz="0 0.05 0"/><axis xyz="1 0 0"/>'
            f'{_LIMIT}<mimic joint="wrist" multiplier="-1" offset="0"/>',
        ),
    )


def robotiq_like_gripper_urdf() -> str:
    """A parallel gripper shaped like the vendor's Robotiq 2F-85: the leader finger_joint in [0, 0.8];
    the inner knuckles follow with multiplier 1 within [0, 0.8757] (narrowing nothing); the inner fingers
    follow with multiplier -1 but the file gives them [0, 0.8757] too, so only q = 0 would keep them
    in range: the narrowed leader range collapses to the single value [0, -0]."""
    finger = '<limit lower="0" upper="0.8757" effort="1000" velocity="2"/>'
    return _robot(
        "gripper_2f",
        "base left_outer left_inner_knuckle left_inner_finger right_outer right_inner_finger",
        _joint(
            "finger_joint",
            "revolute",
            "base",
            "left_outer",
            '<origin xyz="0 -0.0306 0.0549"/><axis xyz="1 0 0"/><limit lower="0" upper="0.8" effort="1000" '
            'velocity="2"/>',
        ),
        _joint(
            "left_inner_knuckle_joint",
            "revolute",
            "base",
            "left_inner_knuckle",
            f'<origin xyz="0 -0.0127 0.0614"/><axis xyz="1 0 0"/>{finger}<mimic joint="finger_joint" multiplier="1"/>',
        ),
        _joint(
            "left_inner_finger_joint",
            "revolute",
            "left_outer",
            "left_inner_finger",
            f'<origin xyz="0 0.0376 0.0430"/><axis xyz="1 0 0"/>{finger}'
            '<mimic joint="finger_joint" multiplier="-1" offset="0"/>',
        ),
        _joint(
            "right_outer_knuckle_joint",
            "revolute",
            "base",
            "right_outer",
            '<origin xyz="0 0.0306 0.0549" rpy="0 0 3.141592653589793"/><axis xyz="1 0 0"/>'
            '<limit lower="0" upper="0.81" effort="1000" velocity="2"/><mimic joint="finger_joint" multiplier="1"/>',
        ),
        _joint(
            "right_inner_finger_joint",
            "revolute",
            "right_outer",
            "right_inner_finger",
            f'<origin xyz="0 0.0376 0.0430"/><axis xyz="1 0 0"/>{finger}'
            '<mimic joint="right_outer_knuckle_joint" multiplier="-1"/>',
        ),
    )


def suction_cup_urdf() -> str:
    """A 0-dof end effector: only fixed joints (a flange, a cup and its tip)."""
    return _robot(
        "suction_cup",
        "flange cup cup_tip",
        _joint("cup_joint", "fixed", "flange", "cup", '<origin xyz="0 0 0.05" rpy="0 0 0.7"/>'),
        _joint("tip_joint", "fixed", "cup", "cup_tip", '<origin xyz="0.01 0 0.03" rpy="0.2 0 0"/>'),
    )


def single_joint_gripper_urdf() -> str:
    """A 1-dof gripper: one prismatic finger, the other mirroring it (a mimic joint, multiplier -1)."""
    finger = '<axis xyz="0 1 0"/><limit lower="0" upper="0.04" effort="20" velocity="0.2"/>'
    return _robot(
        "gripper_1dof",
        "hand left_finger right_finger tcp",
        _joint(
            "left_finger_joint",
            "prismatic",
            "hand",
            "left_finger",
            f'<origin xyz="0 0.01 0.06" rpy="0 0 0.1"/>{finger}',
        ),
        _joint(
            "right_finger_joint",
            "prismatic",
            "hand",
            "right_finger",
            f'<origin xyz="0 -0.01 0.06"/>{finger.replace("0 1 0", "0 -1 0")}'
            '<mimic joint="left_finger_joint"/>',
        ),
        _joint("tcp_joint", "fixed", "left_finger", "tcp", '<origin xyz="0 0 0.05"/>'),
    )


def single_revolute_urdf() -> str:
    """A 1-dof robot: one revolute joint (a rotary table) and a fixed tool."""
    return _robot(
        "rotary",
        "base table tool0",
        _joint(
            "table_joint",
            "revolute",
            "base",
            "table",
            f'<origin xyz="0 0 0.1" rpy="0.3 0 0"/><axis xyz="0 0 1"/>{_LIMIT}',
        ),
        _joint("tool_fixed", "fixed", "table", "tool0", '<origin xyz="0.2 0.05 0.1" rpy="0 0.5 0"/>'),
    )
