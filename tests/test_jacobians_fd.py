"""Every geometric Jacobian column equals central finite differences of the frame pose.

Covers every shipped robot, every example-robot-data robot of the catalog and robots of our own
making (continuous, prismatic, mimic), in all three references, for every frame.
"""

from __future__ import annotations

import numpy as np
import pytest
from custom_robots import mixed_chain_urdf
from finite_differences import assert_close_relative, pose_jacobian_fd

import kinengine

REFERENCES = ("local_world_aligned", "local", "world")


def _robots():
    yield from ((name, lambda name=name: kinengine.load(name)) for name in kinengine.available_robots())
    yield "mixed_chain", lambda: kinengine.load_urdf_string(mixed_chain_urdf())


@pytest.mark.parametrize("name,make", list(_robots()), ids=lambda v: v if isinstance(v, str) else "")
def test_jacobian_matches_finite_differences_for_every_frame(name, make):
    robot = make()
    rng = np.random.default_rng(7)
    frames = robot.frame_names
    if len(frames) > 24:  # big robots: a seeded subset, always including the end effector
        frames = [robot.end_effector] + list(rng.choice(frames, 23, replace=False))
    for q in (robot.random_configuration(rng), robot.random_configuration(rng)):
        for frame in frames:
            for reference in REFERENCES:
                J = robot.jacobian(q, frame, reference)
                J_fd = pose_jacobian_fd(lambda x: robot.frame_pose(x, frame), q, reference)
                assert_close_relative(J, J_fd, 1e-6, f"{name} {frame} {reference}")


def test_references_are_related_by_the_documented_formulas():
    robot = kinengine.load_urdf_string(mixed_chain_urdf())
    q = robot.random_configuration(3)
    T = robot.frame_pose(q, "tip")
    C, p = T[:3, :3], T[:3, 3]
    J_lwa = robot.jacobian(q, "tip", "local_world_aligned")
    J_local = robot.jacobian(q, "tip", "local")
    J_world = robot.jacobian(q, "tip", "world")
    np.testing.assert_allclose(J_local[:3], C.T @ J_lwa[:3], rtol=0, atol=1e-12)
    np.testing.assert_allclose(J_local[3:], C.T @ J_lwa[3:], rtol=0, atol=1e-12)
    np.testing.assert_allclose(J_world[:3], J_lwa[:3] - np.cross(J_lwa[3:].T, p).T, rtol=0, atol=1e-12)
    np.testing.assert_allclose(J_world[3:], J_lwa[3:], rtol=0, atol=1e-12)


def test_mimic_joint_moves_with_its_leader_in_the_leader_column():
    robot = kinengine.load_urdf_string(mixed_chain_urdf())
    assert "finger_b_joint" not in robot.joint_names
    k = robot.joint_names.index("finger_a_joint")
    q = robot.random_configuration(5)
    # finger_b rotates about its y axis by -1.5 * q_a + 0.2: its angular velocity column is -1.5 n_b
    J = robot.jacobian(q, "finger_b", "local")
    np.testing.assert_allclose(J[3:, k], [0.0, -1.5, 0.0], rtol=0, atol=1e-12)
    q0 = q.copy()
    q0[k] = 0.0
    C_tip = robot.frame_pose(q0, "tip")[:3, :3]
    C_b = robot.frame_pose(q0, "finger_b")[:3, :3]
    angle = 0.2  # the offset at q_a = 0: rotation about y by 0.2
    expected = C_tip @ np.array(
        [[np.cos(angle), 0, np.sin(angle)], [0, 1, 0], [-np.sin(angle), 0, np.cos(angle)]]
    )
    np.testing.assert_allclose(C_b, expected, rtol=0, atol=1e-12)
