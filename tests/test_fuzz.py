"""Hardened inputs: malformed mechanism files, URDF text and API arguments end in a
PkmError (one line from the CLI), never in another exception.

Property-based (hypothesis, derandomised so that every run draws the same examples):
mutations of a shipped mechanism file (keys deleted or renamed, values of the wrong type,
truncations, random text and bytes) and of a shipped leg URDF (elements and attributes
deleted, renamed, duplicated, given absurd values) go through the public loaders and
through ``pkm-pin check`` / ``pkm-pin analyze`` in-process; NaN, inf and wrong shapes go
to the public API calls. The tests at the end pin down specific inputs that the
fuzzing found escaping as other exceptions (overlong paths, non-numeric and non-finite
arguments, far targets); each states the error that such an input must give.
"""

from __future__ import annotations

import contextlib
import io
import re
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from helpers import MODELS
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from pkm_pin import InputError, Leg, MechanismFileError, PkmError, UrdfError, load_mechanism, screws
from pkm_pin.builders import MECHANISMS
from pkm_pin.cli import main

#: The shipped 3-RPR file with absolute URDF paths (so that a copy loads from anywhere).
BASE_TOML = (MODELS / "mechanisms" / "rpr3.toml").read_text().replace(
    '"../urdf/', f'"{MODELS / "urdf"}/')
BASE_URDF = (MODELS / "urdf" / "rpr_leg_a.urdf").read_text()

FUZZ = settings(max_examples=50, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
#: The API-argument properties: every public call, 15 examples each (module fixture).
API_FUZZ = settings(max_examples=15, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])


def _run_cli(argv: list[str]) -> tuple[int, str, str]:
    """Run ``pkm-pin`` in-process; return (status, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(argv)
    return status, out.getvalue(), err.getvalue()


def _assert_cli_fails_cleanly_or_succeeds(argv: list[str]) -> int:
    """The command succeeds (0, 1 for check warnings) or prints one error line with 2."""
    status, _, err = _run_cli(argv)
    assert status in (0, 1, 2)
    if status == 2:
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("pkm-pin: error:"), err
    return status


# ------------------------------------------------------------ mechanism files
#: Values of the wrong type, shape or range for any key of a mechanism file.
WRONG_VALUES = [
    '"text"', "true", "1", "-1.5", "[]", "[1, 2]", '["a", "b"]', "{}", "{ xyz = [1] }",
    "nan", "inf", "-inf", "1e308", "[nan, 0, 0]", "[inf, 0.0, 0.0]", "[[1, 2, 3]]",
    '"../urdf/missing.urdf"', '""', "{ xyz = [0, 0, 0], rpy = [0, 0, nan] }",
    '{ xyz = "a" }', "[1e308, 1e308, 1e308]", "[0, 0, 0, 0]", '["A1", "A1"]', '["A0"]',
    '["A2", "A1"]', '"tip "', '"A1"', "1979-05-27T07:32:00Z", "[true, false, true]",
    '{ rpy = [0, 1e300, 0] }', "[-1e9, 0, 0]", "0x10",
]
KEY = re.compile(r"^(\s*)([A-Za-z_]+)(\s*=\s*)(.*)$")
NUMBER = re.compile(r"-?\d+\.\d+(e-?\d+)?")


@st.composite
def malformed_toml(draw) -> str:
    """A shipped mechanism file with 1–3 random mutations."""
    text = BASE_TOML
    for _ in range(draw(st.integers(1, 3))):
        lines = text.splitlines()
        op = draw(st.sampled_from(["delete", "rename", "retype", "truncate", "insert",
                                   "duplicate", "number"]))
        if not lines:
            break
        i = draw(st.integers(0, len(lines) - 1))
        m = KEY.match(lines[i])
        if op == "delete":
            del lines[i]
        elif op == "duplicate":
            lines.insert(i, lines[i])
        elif op == "rename" and m:
            new = draw(st.sampled_from(["nme", "legs", "Tip", "urdff", "home", "anchor",
                                        "base", "xyz", "home_q", "q"])
                       | st.from_regex(r"[a-z_]{1,8}", fullmatch=True))
            lines[i] = m.group(1) + new + m.group(3) + m.group(4)
        elif op == "retype" and m:
            lines[i] = m.group(1) + m.group(2) + m.group(3) + draw(st.sampled_from(WRONG_VALUES))
        elif op == "number":
            numbers = list(NUMBER.finditer(text))
            if not numbers:
                continue
            k = draw(st.integers(0, len(numbers) - 1))
            value = repr(draw(st.floats(allow_nan=True, allow_infinity=True)))
            a, b = numbers[k].span()
            text = text[:a] + value + text[b:]
            continue
        elif op == "truncate":
            text = text[:draw(st.integers(0, len(text)))]
            continue
        elif op == "insert":
            k = draw(st.integers(0, len(text)))
            text = text[:k] + draw(st.text(max_size=12)) + text[k:]
            continue
        text = "\n".join(lines)
    return text


def _write(folder: str, name: str, data: str | bytes) -> str:
    path = Path(folder) / name
    if isinstance(data, bytes):
        path.write_bytes(data)
    else:
        path.write_text(data, encoding="utf-8", errors="surrogatepass")
    return str(path)


@FUZZ
@given(malformed_toml())
def test_malformed_mechanism_files_raise_mechanism_file_errors(text):
    """A mutated mechanism file loads or raises MechanismFileError; check/analyze give one line."""
    with tempfile.TemporaryDirectory() as folder:
        path = _write(folder, "m.toml", text)
        try:
            load_mechanism(path)
        except MechanismFileError:
            pass
        status = _assert_cli_fails_cleanly_or_succeeds(["check", path])
        if status != 2:  # it loads: analyze at home must fail cleanly or succeed
            _assert_cli_fails_cleanly_or_succeeds(["analyze", path, "--json"])


@FUZZ
@given(st.one_of(st.binary(max_size=200),
                 st.builds(lambda k, junk: BASE_TOML.encode()[:k] + junk,
                           st.integers(0, len(BASE_TOML)), st.binary(min_size=1, max_size=40))))
def test_random_bytes_are_refused_in_one_line(data):
    """Random bytes, or a valid file cut and followed by random bytes, give one error line."""
    with tempfile.TemporaryDirectory() as folder:
        path = _write(folder, "m.toml", data)
        with pytest.raises(MechanismFileError):
            load_mechanism(path)
        assert _assert_cli_fails_cleanly_or_succeeds(["check", path]) == 2


# ----------------------------------------------------------------- URDF text
#: Absurd attribute values.
WRONG_ATTRIBUTES = ["", "nan", "inf", "-inf", "1 2", "abc", "-1", "1e400", "0 0 0", "0 0 0 0",
                    "tip", "A0", "A1", "base", "revolute", "prismatic", "floating", "planar",
                    "fixed", "continuous", "spherical", "-inf 0 0", "1e308 1e308 1e308", "0 0 nan",
                    "1e-300 0 0"]
TAGS = ["link", "joint", "origin", "axis", "limit", "parent", "child", "mimic", "robot",
        "frame", "visual", "inertial", "x"]


@st.composite
def malformed_urdf(draw) -> str:
    """A shipped leg URDF with 1–3 structural mutations, then maybe a text mutation."""
    root = ET.fromstring(BASE_URDF)
    for _ in range(draw(st.integers(1, 3))):
        parents = [(p, c) for p in root.iter() for c in p]
        if not parents:
            break
        parent, element = draw(st.sampled_from(parents))
        op = draw(st.sampled_from(["remove", "drop_attribute", "set_attribute", "rename",
                                   "duplicate", "add_attribute"]))
        if op == "remove":
            parent.remove(element)
        elif op == "drop_attribute" and element.attrib:
            del element.attrib[draw(st.sampled_from(sorted(element.attrib)))]
        elif op == "set_attribute" and element.attrib:
            key = draw(st.sampled_from(sorted(element.attrib)))
            element.set(key, draw(st.sampled_from(WRONG_ATTRIBUTES) | st.text(max_size=8)))
        elif op == "add_attribute":
            element.set(draw(st.sampled_from(["name", "type", "xyz", "rpy", "link", "joint",
                                              "lower", "upper", "multiplier", "offset"])),
                        draw(st.sampled_from(WRONG_ATTRIBUTES)))
        elif op == "rename":
            element.tag = draw(st.sampled_from(TAGS))
        elif op == "duplicate":
            parent.append(ET.fromstring(ET.tostring(element)))
    text = ET.tostring(root, encoding="unicode")
    text_op = draw(st.sampled_from(["none", "none", "truncate", "insert"]))
    if text_op == "truncate":
        text = text[:draw(st.integers(1, len(text)))]
    elif text_op == "insert":
        k = draw(st.integers(1, len(text)))
        text = text[:k] + draw(st.text(max_size=10)) + text[k:]
    return text


@FUZZ
@given(malformed_urdf())
def test_malformed_urdf_text_raises_pkm_errors(text):
    """A mutated leg URDF builds a leg (usable at neutral) or raises a PkmError."""
    try:
        leg = Leg.from_urdf(text, "tip", ("A1",))
    except PkmError:
        return
    q = leg.neutral()
    assert np.all(np.isfinite(leg.jacobian(q)))
    assert np.all(np.isfinite(leg.tip_placement(q).homogeneous))


@settings(max_examples=30, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(malformed_urdf())
def test_malformed_urdf_in_a_mechanism_file_is_one_cli_line(text):
    """A mechanism file whose leg A points to a mutated URDF: one error line or success."""
    with tempfile.TemporaryDirectory() as folder:
        urdf_path = _write(folder, "leg_a.urdf", text)
        toml = BASE_TOML.replace(f'"{MODELS / "urdf"}/rpr_leg_a.urdf"', f'"{urdf_path}"')
        path = _write(folder, "m.toml", toml)
        _assert_cli_fails_cleanly_or_succeeds(["check", path])


# ------------------------------------------------------------------- API calls
@pytest.fixture(scope="module")
def rpr3():
    """The shipped 3-RPR, its home analysis and its first leg."""
    mech = MECHANISMS["rpr3"]().build()
    return mech, mech.home_analysis, mech.legs[0]


#: Public calls that take one array: (call given (mech, analysis, leg) and the array,
#: the shape they expect, shapes they also accept).
API_CALLS = {
    "Mechanism.assemble": (lambda m, a, l, x: m.assemble(x), (6,), [(4, 4)]),
    "Mechanism.analyze": (lambda m, a, l, x: m.analyze(x), (6,), [(4, 4)]),
    "Mechanism.inverse_kinematics": (lambda m, a, l, x: m.inverse_kinematics(x), (6,), [(4, 4)]),
    "Mechanism.forward_kinematics": (lambda m, a, l, x: m.forward_kinematics(x), (3,), []),
    # a 0-d array: test_a_scalar_is_refused_by_sweep
    "Mechanism.sweep": (lambda m, a, l, x: m.sweep(x), (2, 6), ["(k, 6)", ()]),
    "Analysis.forward_velocity": (lambda m, a, l, x: a.forward_velocity(x), (3,), []),
    "Analysis.inverse_velocity": (lambda m, a, l, x: a.inverse_velocity(x), (6,), [(1, 6)]),
    "Analysis.passive_rates": (lambda m, a, l, x: a.passive_rates(x), (6,), [(1, 6)]),
    "Leg.tip_placement": (lambda m, a, l, x: l.tip_placement(x), (3,), []),
    "Leg.jacobian": (lambda m, a, l, x: l.jacobian(x), (3,), []),
    "screws.line": (lambda m, a, l, x: screws.line(x, [0.0, 0.0, 1.0]), (3,), []),
    # (k, 6) with k != 1: test_screws_exp_takes_exactly_one_twist
    "screws.exp": (lambda m, a, l, x: screws.exp(x), (6,), ["(k, 6)"]),
    "screws.rank": (lambda m, a, l, x: screws.rank(x), (3, 6), ["(k, 6)", (6,)]),
}


def _accepted(shape: tuple, good: tuple, also: list) -> bool:
    if shape == good or shape in also:
        return True
    return "(k, 6)" in also and len(shape) == 2 and shape[1] == 6


@st.composite
def with_non_finite(draw, shape: tuple) -> np.ndarray:
    """An array of ``shape`` with finite values but one NaN or ±inf."""
    x = draw(hnp.arrays(float, shape, elements=st.floats(-2.0, 2.0)))
    index = tuple(draw(st.integers(0, n - 1)) for n in shape)
    x[index] = draw(st.sampled_from([np.nan, np.inf, -np.inf]))
    return x


@pytest.mark.parametrize("name", sorted(API_CALLS))
@API_FUZZ
@given(data=st.data())
def test_non_finite_arguments_are_refused_as_not_finite(rpr3, name, data):
    """NaN or inf in an API argument is an InputError that says it must be finite."""
    call, shape, _ = API_CALLS[name]
    x = data.draw(with_non_finite(shape))
    with pytest.raises(InputError, match="finite"):
        call(*rpr3, x)


@pytest.mark.parametrize("name", sorted(API_CALLS))
@API_FUZZ
@given(data=st.data())
def test_wrong_shapes_are_refused_with_the_shape(rpr3, name, data):
    """An API argument of the wrong shape is an InputError that names the shape."""
    call, good, also = API_CALLS[name]
    shape = data.draw(hnp.array_shapes(min_dims=0, max_dims=3, min_side=0, max_side=7)
                      .filter(lambda s: not _accepted(s, good, also)))
    x = data.draw(hnp.arrays(float, shape, elements=st.floats(-2.0, 2.0)))
    with pytest.raises(InputError, match="shape"):
        call(*rpr3, x)


# --------------------------------------------------- inputs found by the fuzzing
def test_overlong_urdf_path_is_a_urdf_error():
    """A non-XML URDF source too long for a file name is a UrdfError, not the OSError
    (ENAMETOOLONG) of asking the file system whether it is a file."""
    with pytest.raises(UrdfError):
        Leg.from_urdf("x" * 300, "tip")


def test_overlong_urdf_path_in_a_mechanism_file_is_one_cli_line(tmp_path):
    """A mechanism file whose urdf key is 300 characters long gives one error line and
    status 2 from ``pkm-pin check``."""
    path = _write(str(tmp_path), "m.toml",
                  BASE_TOML.replace(f'"{MODELS / "urdf"}/rpr_leg_a.urdf"', '"' + "z" * 300 + '"'))
    assert _assert_cli_fails_cleanly_or_succeeds(["check", path]) == 2


def test_overlong_mechanism_path_is_a_mechanism_file_error():
    """A mechanism path too long for a file name is a MechanismFileError, not the
    OSError of asking the file system whether it is a file."""
    with pytest.raises(MechanismFileError):
        load_mechanism("y" * 300)


def test_crosscheck_of_a_3rpr_with_other_actuators_does_not_crash(tmp_path):
    """A '3-RPR' whose leg A is not actuated is analysed (status 0) or refused in one
    line (status 2): the cross-check against the paper's formulas, which assume the
    paper's three actuators, must not crash on it."""
    path = _write(str(tmp_path), "m.toml", BASE_TOML.replace('actuated = ["A1"]', "actuated = []"))
    assert _assert_cli_fails_cleanly_or_succeeds(["analyze", path]) in (0, 2)


def test_non_finite_analysis_tolerances_are_refused(rpr3):
    """A non-finite or negative rtol / singular_tol is an InputError saying it must be
    finite or positive (with rtol=nan the 3-RPR would otherwise report 6 DOF)."""
    mech = rpr3[0]
    for options in ({"rtol": np.nan}, {"singular_tol": np.inf}, {"rtol": -1.0}):
        with pytest.raises(InputError, match="finite|positive"):
            mech.analyze(None, **options).dof


def test_non_numeric_arguments_are_input_errors(rpr3):
    """Text or objects where numbers are expected (a pose, actuated coordinates, a leg
    configuration, screws) are InputErrors, not the ValueError / TypeError of numpy's
    float conversion."""
    mech, analysis, leg = rpr3
    calls = [lambda: mech.assemble("abc"), lambda: mech.assemble([object()] * 6),
             lambda: mech.forward_kinematics(["a", "b", "c"]),
             lambda: leg.tip_placement([None, {}, 1]), lambda: screws.rank("screws")]
    for call in calls:
        with pytest.raises(InputError):
            call()


def test_non_finite_screws_in_the_reciprocal_product_are_refused():
    """reciprocal_product refuses a NaN screw with an InputError saying it must be finite
    (rather than returning nan)."""
    with pytest.raises(InputError, match="finite"):
        screws.reciprocal_product([np.nan, 0, 0, 0, 0, 0], [0, 0, 1, 0, 0, 0])


def test_a_scalar_is_refused_by_sweep(rpr3):
    """Mechanism.sweep of a 0-d array is an InputError naming the shape, not a
    TypeError."""
    with pytest.raises(InputError, match="shape"):
        rpr3[0].sweep(np.array(0.0))


def test_screws_exp_takes_exactly_one_twist():
    """screws.exp of a (k, 6) array with k != 1 is an InputError naming the shape: a
    (2, 6) array does not silently use its first row, a (0, 6) array raises no
    IndexError."""
    for shape in [(2, 6), (0, 6)]:
        with pytest.raises(InputError, match="shape"):
            screws.exp(np.zeros(shape))


def test_a_far_target_is_an_unconverged_leg_solution(rpr3):
    """Leg.solve of a finite target 1e12 m away returns a non-converged solution, as its
    docstring promises, and raises no LinAlgError (a mechanism file with base
    xyz = [1e16, 0, 0] reaches this case through Mechanism.home_assembly)."""
    leg = rpr3[2]
    assert not leg.solve(pin.SE3(np.eye(3), np.array([1e12, 0.0, 0.0]))).converged


def test_non_finite_leg_targets_are_refused(rpr3):
    """Leg.solve refuses a target placement containing NaN with an InputError saying it
    must be finite (rather than returning a non-converged solution with residual nan)."""
    leg = rpr3[2]
    with pytest.raises(InputError, match="finite"):
        leg.solve(pin.SE3(np.eye(3), np.array([np.nan, 0.0, 0.0])))
