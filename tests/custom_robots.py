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
