"""The declared dependency ranges hold what the code was run with."""

from __future__ import annotations

from importlib.metadata import requires, version

import pytest
from packaging.requirements import Requirement

from pkm_pin import compiling


def _declared(name: str) -> Requirement:
    for line in requires("pkm_pin") or ():
        req = Requirement(line)
        if req.name == name and req.marker is None:
            return req
    raise AssertionError(f"{name} is not a declared dependency of pkm_pin")


@pytest.mark.parametrize("name", ["pin", "numba", "numpy"])
def test_installed_versions_are_inside_the_declared_ranges(name):
    """Each installed core dependency satisfies pkm_pin's declared range."""
    req = _declared(name)
    assert req.specifier.contains(version(name), prereleases=True), (name, str(req))


def test_bounded_where_private_internals_are_read():
    """numba, whose private cache layout compiling.py reads, has an upper bound, and
    Pinocchio is pinned to the 4.x API the code calls."""
    assert any(s.operator == "<" for s in _declared("numba").specifier)
    pin = _declared("pin").specifier
    assert pin.contains("4.1.0") and not pin.contains("3.9.0") and not pin.contains("5.0.0")
    assert compiling.install_stamp()
