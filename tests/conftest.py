"""Shared fixtures: the example-robot-data legs (loaded once per session)."""

from __future__ import annotations

import pytest

from pkm_pin import Leg


@pytest.fixture(scope="session")
def ur5() -> Leg:
    """UR5 from example-robot-data, tip ``tool0``, every joint actuated."""
    return Leg.from_example_robot_data("ur5", "tool0")


@pytest.fixture(scope="session")
def panda() -> Leg:
    """Franka Panda from example-robot-data, tip ``panda_link8`` (the arm only)."""
    return Leg.from_example_robot_data("panda", "panda_link8")
