"""Reports (pkm_pin.report): readable twist bases in words, JSON data, Markdown."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pkm_pin import screws
from pkm_pin.builders import MECHANISMS
from pkm_pin.report import (
    BasisScrew,
    markdown,
    readable_basis,
    readable_directions,
    report_data,
    text,
)


@pytest.fixture(scope="module")
def analyses():
    """Home analysis of every shipped mechanism, by registry name."""
    return {name: build().build().home_analysis for name, build in MECHANISMS.items()}


def _rebuilt(b: BasisScrew) -> np.ndarray:
    """The screw rebuilt from its direction, point and pitch."""
    if b.kind == "couple":
        return np.r_[np.zeros(3), b.direction]
    return screws.screw(b.point, b.direction, b.pitch)


@pytest.mark.parametrize("name", sorted(MECHANISMS))
def test_readable_basis_spans_the_platform_twist_system(analyses, name):
    """The readable basis spans exactly the platform twists, couples first."""
    an = analyses[name]
    basis = readable_basis(an.platform_twists, an.assembly.pose.translation, an.length,
                           an.translations)
    S = np.array([b.screw for b in basis])
    assert len(basis) == an.dof
    assert screws.rank(S, an.length) == an.dof
    assert np.all(screws.contains(an.platform_twists, S, an.length))
    kinds = [b.kind for b in basis]
    assert kinds == sorted(kinds, key=lambda k: k != "couple")
    assert kinds.count("couple") == an.translations


@pytest.mark.parametrize("name", sorted(MECHANISMS))
def test_direction_point_and_pitch_rebuild_each_screw(analyses, name):
    """Each basis screw equals the screw rebuilt from its direction, point and pitch."""
    an = analyses[name]
    for system in (an.platform_twists, an.constraint_wrenches):
        for b in readable_basis(system, an.assembly.pose.translation, an.length):
            assert np.allclose(_rebuilt(b), b.screw, atol=1e-9)


def test_3rpr_twists_in_words(analyses):
    """3-RPR at home: translations along x and z, rotation about y through the centre."""
    words = [b["words"] for b in report_data(analyses["rpr3"])["motion_basis"]]
    assert words == ["pure translation along (1, 0, 0)", "pure translation along (0, 0, 1)",
                     "rotation about an axis through (0.8, 0, 0.6) along (0, 1, 0)"]


def test_stewart_twists_are_translations_then_rotations_through_the_centre(analyses):
    """Gough–Stewart at home: three translations, then rotations about x, y, z through it."""
    basis = report_data(analyses["stewart"])["motion_basis"]
    assert [b["kind"] for b in basis] == ["couple"] * 3 + ["line"] * 3
    centre = analyses["stewart"].assembly.pose.translation
    for b, axis in zip(basis[3:], np.eye(3)):
        assert np.allclose(b["point"], centre) and np.allclose(b["direction"], axis)
        assert b["words"].startswith("rotation about an axis through (0, 0, 1) along")


def test_a_screw_of_finite_pitch_is_named_with_its_pitch():
    """A twist with ω·v ≠ 0 is described as a screw of its pitch, its axis found."""
    s = screws.screw([1.0, 2.0, 0.0], [0.0, 0.0, 1.0], 0.25)
    (b,) = readable_basis(s[None], [1.0, 2.0, 3.0], 1.0)
    assert b.kind == "screw" and b.pitch == pytest.approx(0.25)
    assert b.words() == "screw of pitch 0.25 m/rad about an axis through (1, 2, 3) along (0, 0, 1)"
    assert b.words(wrench=True).startswith("wrench of pitch 0.25")


def test_wrenches_are_named_as_forces_and_moments():
    """As wrenches, a line is a force through a point and a couple a pure moment."""
    W = np.array([screws.line([0, 0, 1], [1, 0, 0]), screws.couple([0, 0, 2])])
    basis = readable_basis(W, [0.0, 0.0, 1.0], 1.0)
    assert [b.words(wrench=True) for b in basis] == [
        "pure moment about (0, 0, 1)", "force along (1, 0, 0) through (0, 0, 1)"]


@settings(max_examples=40, deadline=None, derandomize=True)
@given(st.lists(st.lists(st.floats(-1, 1), min_size=3, max_size=3), min_size=1, max_size=3))
def test_readable_directions_are_an_orthonormal_basis_of_the_same_span(rows):
    """readable_directions returns an orthonormal basis of the span of its rows."""
    Q = np.array(rows)
    D = readable_directions(Q)
    top = np.linalg.norm(Q, 2)
    rank = np.linalg.matrix_rank(Q, tol=1e-9 * top) if top > 0 else 0
    assert D.shape == (rank, 3)
    assert np.allclose(D @ D.T, np.eye(rank), atol=1e-9)
    residual = Q - Q @ D.T @ D if rank else Q
    assert np.all(np.abs(residual) <= 1e-7 * top)


def test_world_axes_are_preferred_when_the_span_contains_them():
    """A plane containing the y axis gets y as a basis direction, signed positive."""
    D = readable_directions(np.array([[0.0, -3.0, 0.0], [1.0, 1.0, 1.0]]))
    assert np.allclose(D[0], [0.0, 1.0, 0.0])


def test_report_data_is_json_and_keeps_the_analysis_numbers(analyses):
    """report_data is JSON-serialisable and repeats dof, A, B and the indices."""
    an = analyses["rps3"]
    data = json.loads(json.dumps(report_data(an, plots=["a.png"])))
    assert data["dof"] == an.dof and data["motion_type"] == "1T2R"
    assert np.allclose(data["A"], an.A) and np.allclose(data["B"], an.B)
    assert data["indices"] == pytest.approx({**an.indices, **an.motion_indices})
    assert data["plots"] == ["a.png"] and data["crosscheck"] is None


def test_markdown_has_every_section_and_the_crosscheck_table(analyses):
    """The Markdown report has pose, mobility, actuation, singularity and cross-check."""
    text = markdown(analyses["rpr3"], plots=["m_singularity.png"])
    for heading in ("# 3-RPR", "## Pose", "## Mobility", "## Actuation", "## Singularity",
                    "## Cross-check against the hand-written formulas", "## Plots"):
        assert heading in text
    assert "| forward_velocity |" in text
    assert "rotation about an axis through (0.8, 0, 0.6) along (0, 1, 0)" in text
    assert "![m_singularity](m_singularity.png)" in text


def test_markdown_says_when_no_formulas_exist(analyses):
    """A mechanism without hand-written formulas says so instead of a table."""
    text = markdown(analyses["delta"])
    assert "No hand-written formulas exist for this mechanism." in text
    assert "pure moment about (1, 0, 0)" in text  # Delta: the three constraint couples


def test_report_gives_the_transmission_indices_in_words():
    """analyze's data, text and Markdown carry ITI/OTI/LTI/CTI and the weakest in words
    (issue 18): equal to Analysis.transmission."""
    from pkm_pin.builders import MECHANISMS
    from pkm_pin.report import markdown, report_data, text

    an = MECHANISMS["rpr3"]().build().home_analysis
    tr = an.transmission
    data = report_data(an)
    assert data["transmission"]["lti"] == pytest.approx(tr.lti, rel=1e-12)
    assert data["transmission"]["words"] == tr.worst == "leg B transmits poorly: OTI 0.59"
    assert "transmission       LTI = 0.587, CTI = 1: leg B transmits poorly" in text(data)
    assert "## Motion/force transmission" in markdown(an, data=data)
    # an index that is not defined (nan: redundant actuation) is None in the data (JSON
    # has no nan) and "n/a" / "—" in words, in the platform's report and the linkage's
    from dataclasses import replace

    from pkm_pin.report import transmission_data

    odd = transmission_data(replace(tr, oti=np.r_[np.nan, tr.oti[1:]], lti=np.nan))
    assert odd["oti"][0] is None and odd["lti"] is None
    assert odd["iti"] == data["transmission"]["iti"]
    json.dumps(odd, allow_nan=False)
    data["transmission"] = odd
    assert "transmission       LTI = n/a, CTI = 1:" in text(data)
    assert "LTI = n/a (good transmission" in markdown(an, data=data)


def test_text_says_the_idle_motions_one_sentence_each(analyses):
    """The text report names the idle motions right under the DOF (none for the 3-RPS;
    a mechanism with some gets one line per motion under their count)."""
    data = report_data(analyses["rps3"])
    lines = text(data).splitlines()
    k = next(i for i, x in enumerate(lines) if x.startswith("DOF "))
    assert lines[k + 1] == "idle motions       none"
    data["idle_motions"] = ["leg 1 spins about the line through its two spherical joints",
                            "leg 2 spins about the line through its two spherical joints"]
    data["idle_dof"] = 2
    lines = text(data).splitlines()
    k = lines.index("idle motions       2 (with every actuated joint locked):")
    assert lines[k + 1:k + 3] == [f"    {m}" for m in data["idle_motions"]]
