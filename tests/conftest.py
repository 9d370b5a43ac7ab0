"""Fixtures shared by the test modules: the shipped ABB IRB 120 and the mixed test chain."""

from __future__ import annotations

import pytest
from custom_robots import mixed_chain_urdf

import kinengine


@pytest.fixture(scope="session")
def abb():
    return kinengine.load("abb_irb120")


@pytest.fixture(scope="session")
def mixed():
    """Revolute, continuous, prismatic, fixed and mimic joints in one chain (tests/custom_robots.py)."""
    return kinengine.load_urdf_string(mixed_chain_urdf())
