"""Shared fixtures: the example-robot-data legs (loaded once per session), and the
hypothesis profile of every run.

Shared plain functions (shipped-model caches, random states and platform twists,
finite-difference Jacobians, screw-span oracles, model paths) are in ``helpers.py``,
imported as ``from helpers import ...``.
"""

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


# CI runs on a fresh machine: property tests must be reproducible there. Tests that set
# their own `settings` keep their example counts; every run explores the same examples.
from hypothesis import settings as _settings  # noqa: E402

_settings.register_profile("pkm_pin", derandomize=True, deadline=None)
_settings.load_profile("pkm_pin")


def pytest_addoption(parser):
    """``--fuzz-examples N``: hypothesis examples per fuzz test of ``tests/fuzz`` (the
    default keeps the whole fuzz run under a minute; a long run passes thousands);
    ``--fuzz-seed S``: other examples than the fixed ones (rounds of a long run)."""
    parser.addoption("--fuzz-examples", type=int, default=None,
                     help="examples per reader in tests/fuzz (default: a small CI budget)")
    parser.addoption("--fuzz-seed", type=int, default=None,
                     help="draw the tests/fuzz examples from this seed (default: the fixed, "
                          "derandomised examples): successive rounds of a long run differ")
