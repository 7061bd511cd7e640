"""pkm_pin.tolerances: one home for every tolerance; historical names are aliases."""

from __future__ import annotations

import ast
import importlib
import inspect
import re
from pathlib import Path

import pytest

from pkm_pin import tolerances
from pkm_pin.mechanism import Mechanism

PACKAGE = Path(tolerances.__file__).parent

#: The values the historical names had before they moved (they must not change).
HISTORICAL = {
    "screws.RTOL": 1e-9,
    "screws._ZERO_ROW": 1e-12,
    "analysis.SINGULAR_TOL": 1e-7,
    "serial.SINGULAR_TOL": 1e-9,
    "serial.TWIST_RTOL": 1e-9,
    "sensitivity.SINGULAR_TOL": 1e-9,
    "sensitivity.COMPATIBILITY_TOL": 1e-8,
    "calibration.IDENT_TOL": 1e-6,
    "sweep.SWEEP_TOL": 1e-12,
    "sweep.TRUST": 1e-7,
    "position.STEP": 0.05,
    "position.COMPILED_STEP": 0.2,
    "position.CONTINUATION_TOL": 1e-6,
    "position.INERTIA_TOL": 1e-2,
    "report._SNAP": 1e-9,
}


def test_every_alias_is_listed_with_its_historical_value():
    """The alias table covers the historical names, each keeping its value."""
    assert set(tolerances.ALIASES) == set(HISTORICAL)
    for old, new in tolerances.ALIASES.items():
        assert getattr(tolerances, new) == HISTORICAL[old], old


@pytest.mark.parametrize("old", sorted(HISTORICAL))
def test_historical_names_still_work(old):
    """``pkm_pin.<module>.<NAME>`` still exists and equals the constant of tolerances."""
    module, name = old.split(".")
    found = importlib.import_module(f"pkm_pin.{module}")
    value = getattr(found, name)
    assert value == getattr(tolerances, tolerances.ALIASES[old]) == HISTORICAL[old]


def test_distinct_concepts_have_distinct_names():
    """The two SINGULAR_TOL of the package (closeness indices, serial chains) are two
    constants of tolerances with their own names and values."""
    assert tolerances.CLOSENESS_SINGULAR_TOL == 1e-7
    assert tolerances.SERIAL_SINGULAR_TOL == 1e-9
    assert tolerances.SENSITIVITY_SINGULAR_TOL == 1e-9
    values = list(tolerances.ALIASES.values())
    assert len(values) == len(set(values))


def test_every_constant_is_documented():
    """Every upper-case constant of tolerances has a ``#:`` comment right above it."""
    lines = inspect.getsource(tolerances).splitlines()
    names = [n for n in vars(tolerances) if n.isupper() and not n.startswith("_")]
    for name in names:
        k = next(i for i, line in enumerate(lines) if line.startswith(f"{name} ="))
        assert lines[k - 1].startswith("#:"), name


def test_tolerances_imports_nothing_from_the_package():
    """Any module can import tolerances: it has no import of pkm_pin."""
    tree = ast.parse((PACKAGE / "tolerances.py").read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            assert node.module == "__future__", node.module
        assert not isinstance(node, ast.Import)


def test_damping():
    """The Levenberg–Marquardt damping is the floor plus the gain times r²."""
    assert tolerances.damping(0.0) == tolerances.DAMPING_FLOOR == 1e-10
    assert tolerances.damping(0.5) == 1e-10 + 1e-2 * 0.5 * 0.5
    assert tolerances.DAMPING_GAIN == 1e-2


def test_compiled_solvers_write_the_same_damping():
    """The compiled solvers' shared policy (newton.py) writes the damping out once for
    their compiled code (numba's cache follows its own file only): ``DAMPING_FLOOR +
    DAMPING_GAIN r²``; no other module writes a damping of its own."""
    def damping_expressions(name):
        source = (PACKAGE / name).read_text()
        return re.findall(r"lam = ([0-9.e+-]+) \+ ([0-9.e+-]+) \* (\w+) \* \3\b", source)

    found = damping_expressions("newton.py")
    assert len(found) == 1
    for name in ("solve.py", "tree_kernel.py", "kernels.py", "leg.py", "position.py",
                 "sweep.py"):
        assert not damping_expressions(name)
    for floor, gain, _ in found:
        assert float(floor) == tolerances.DAMPING_FLOOR
        assert float(gain) == tolerances.DAMPING_GAIN


@pytest.mark.parametrize("module", ["assembly", "position", "sensitivity", "sweep",
                                    "calibration", "leg", "serial", "tolerances"])
def test_solver_modules_do_not_import_mechanism(module):
    """position, sensitivity, sweep, calibration (and what they build on) never import
    pkm_pin.mechanism, at the top or inside a function (no import circle)."""
    tree = ast.parse((PACKAGE / f"{module}.py").read_text())
    typing_only = {id(child) for node in ast.walk(tree)
                   if isinstance(node, ast.If) and getattr(node.test, "id", "") == "TYPE_CHECKING"
                   for child in ast.walk(node)}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 1 and node.module == "mechanism":
            assert id(node) in typing_only, f"{module} imports pkm_pin.mechanism"


def test_mechanism_is_no_mixin():
    """Mechanism inherits from nothing; its position, sensitivity and sweep methods are
    thin wrappers of module functions of the same names."""
    assert Mechanism.__mro__ == (Mechanism, object)
    for name, module in (("forward_kinematics", "position"),
                         ("forward_kinematics_all", "position"),
                         ("inverse_kinematics", "position"),
                         ("inverse_kinematics_all", "position"),
                         ("sensitivity", "sensitivity"), ("sweep", "sweep")):
        function = getattr(importlib.import_module(f"pkm_pin.{module}"), name)
        method = getattr(Mechanism, name)
        assert f":func:`pkm_pin.{module}.{name}`" in method.__doc__
        params = list(inspect.signature(function).parameters)
        assert params[0] == "mech"
        assert params[1:] == list(inspect.signature(method).parameters)[1:]
