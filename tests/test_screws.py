"""Tests of pkm_pin.screws: axis-first screw algebra (seed 000, sections 1-3).

Screws are axis-first ``(s; s0)`` about the world origin. Random geometry comes from
hypothesis (bounded boxes, moderate example counts) or from seeded numpy generators.
Rank properties are tested on integer-grid geometry, whose Plücker coordinates are
integers: such systems are either exactly dependent or well conditioned, so the
expected rank is computed exactly (rational Gaussian elimination), independently of
the SVD under test.

Seed 000: Michalková & Guldan, see docs/references.md.
"""

from __future__ import annotations

from fractions import Fraction

import helpers
import numpy as np
import pinocchio as pin
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from pkm_pin import InputError, screws
from pkm_pin.screws import DELTA

SETTINGS = settings(
    max_examples=50, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)

# ------------------------------------------------------------------ strategies
coord = st.floats(-2.0, 2.0, allow_nan=False, allow_infinity=False)
points = st.tuples(coord, coord, coord).map(np.array)
screw6 = st.tuples(*(6 * [st.floats(-5.0, 5.0, allow_nan=False)])).map(np.array)


@st.composite
def unit_directions(draw):
    """Unit vectors from spherical angles (no rejection, no zero vector)."""
    theta = draw(st.floats(0.0, np.pi))
    phi = draw(st.floats(0.0, 2.0 * np.pi))
    return np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


directions = unit_directions()


def _perpendicular(s: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to the unit vector ``s``."""
    helper = np.eye(3)[np.argmin(np.abs(s))]
    p = np.cross(s, helper)
    return p / np.linalg.norm(p)


def _rotate(v: np.ndarray, k: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues rotation of ``v`` about the unit axis ``k`` (hand-written)."""
    return (v * np.cos(angle) + np.cross(k, v) * np.sin(angle)
            + k * k.dot(v) * (1.0 - np.cos(angle)))


@st.composite
def placements(draw):
    """Random SE3 (rotation vector in a box, translation in a box)."""
    rv = np.array(draw(st.tuples(coord, coord, coord))) * 1.5
    return pin.SE3(pin.exp3(rv), np.array(draw(st.tuples(coord, coord, coord))))


grid_point = st.tuples(*(3 * [st.integers(-3, 3)])).map(lambda t: np.array(t, dtype=float))
grid_dir = (
    st.tuples(*(3 * [st.integers(-2, 2)]))
    .filter(lambda t: any(t))
    .map(lambda t: np.array(t, dtype=float))
)


@st.composite
def grid_screw_rows(draw):
    """An unnormalised integer screw: line, couple or screw of integer pitch."""
    kind = draw(st.sampled_from(["line", "line", "line", "couple", "pitch"]))
    d = draw(grid_dir)
    if kind == "couple":
        return np.r_[np.zeros(3), d]
    r = draw(grid_point)
    h = draw(st.integers(-2, 2)) if kind == "pitch" else 0
    return np.r_[d, np.cross(r, d) + h * d]


@st.composite
def grid_systems(draw, min_size=0, max_size=7):
    """(k, 6) integer screw system, sometimes with deliberately dependent rows."""
    rows = draw(st.lists(grid_screw_rows(), min_size=min_size, max_size=max_size))
    S = np.array(rows, dtype=float).reshape(-1, 6)
    if S.shape[0] >= 2 and draw(st.booleans()):
        a, b = draw(st.integers(-2, 2)), draw(st.integers(-2, 2))
        combo = a * S[0] + b * S[1]
        if np.any(combo):
            S = np.vstack([S, combo])
    return S


def exact_rank(S: np.ndarray) -> int:
    """Rank of an integer-valued matrix by exact rational elimination."""
    rows = [[Fraction(int(round(x))) for x in r] for r in np.asarray(S)]
    rank, ncols = 0, 6
    for c in range(ncols):
        pivot = next((i for i in range(rank, len(rows)) if rows[i][c] != 0), None)
        if pivot is None:
            continue
        rows[rank], rows[pivot] = rows[pivot], rows[rank]
        for i in range(len(rows)):
            if i != rank and rows[i][c] != 0:
                f = rows[i][c] / rows[rank][c]
                rows[i] = [x - f * y for x, y in zip(rows[i], rows[rank])]
        rank += 1
    return rank


def spans_equal(A, B, length: float = 1.0, tol: float = 1e-8) -> bool:
    """Whether two screw systems span the same space.

    An oracle independent of :mod:`pkm_pin.screws`: moments divided by ``length``, rows
    normalised, ranks by numpy's SVD with a relative tolerance (rows below 1e-12 of the
    largest dropped first): :func:`helpers.spans_equal`.
    """
    return helpers.spans_equal(A, B, length, tol, relative_zero=True)


# A planar motion system in the xz-plane (normal y): rotation about y, translations x, z
# (seed 000, eq. 55), and its constraint wrenches (eq. 54) which have the same coordinates.
PLANAR_XZ = np.array([[0, 1, 0, 0, 0, 0], [0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 0, 1]], float)
PLANAR_YZ = np.array([[1, 0, 0, 0, 0, 0], [0, 0, 0, 0, 1, 0], [0, 0, 0, 0, 0, 1]], float)


# --------------------------------------------------------------- constructors
def test_line_matches_pluecker_formula():
    """A line through r along s is the unit screw (s; r × s)."""
    S = screws.line([1.0, 2.0, 3.0], [0.0, 0.0, 2.0])
    np.testing.assert_allclose(S, [0, 0, 1, 2, -1, 0], atol=1e-15)


def test_couple_is_unit_and_has_zero_direction_part():
    """A couple is (0; s) with unit s."""
    np.testing.assert_allclose(screws.couple([0, 3, 4]), [0, 0, 0, 0, 0.6, 0.8], atol=1e-15)


@SETTINGS
@given(points, directions)
def test_screw_of_pitch_zero_is_a_line_and_inf_a_couple(p, d):
    """screw(p, d, 0) is line(p, d) and screw(p, d, inf) is couple(d)."""
    np.testing.assert_allclose(screws.screw(p, d, 0.0), screws.line(p, d), atol=1e-14)
    np.testing.assert_allclose(screws.screw(p, d, np.inf), screws.couple(d), atol=1e-14)


@SETTINGS
@given(points, directions, st.floats(-3.0, 3.0))
def test_pitch_of_screw_round_trips(p, d, h):
    """pitch(screw(p, d, h)) equals h."""
    assert abs(screws.pitch(screws.screw(p, d, h)) - h) <= 1e-12 * (1 + np.linalg.norm(p))


@SETTINGS
@given(points, directions, st.floats(-3.0, 3.0), st.floats(0.1, 10.0))
def test_axis_round_trips(p, d, h, scale):
    """axis(k·screw(p, d, h)) is the point of the axis nearest the origin and d."""
    point, direction = screws.axis(scale * screws.screw(p, d, h))
    nearest = p - p.dot(d) * d
    np.testing.assert_allclose(point, nearest, atol=1e-12)
    np.testing.assert_allclose(direction, d, atol=1e-12)


@SETTINGS
@given(points, directions, st.floats(-3.0, 3.0), st.floats(0.1, 10.0), points)
def test_axis_point_nearest_a_point(p, d, h, scale, x):
    """axis_point_nearest(k·screw(p, d, h), x) is the foot of x on the axis (a point of
    the axis, x − it orthogonal to d); x itself for a couple; rows of a stack alike."""
    s = scale * screws.screw(p, d, h)
    got = screws.axis_point_nearest(s, x)
    np.testing.assert_allclose(got, p + (x - p).dot(d) * d, atol=1e-10 * (1 + abs(x).max()))
    np.testing.assert_allclose(screws.axis_point_nearest(screws.couple(d), x), x, atol=0)
    stack = np.stack([s, screws.couple(d), s])
    np.testing.assert_allclose(screws.axis_point_nearest(stack, x), [got, x, got], atol=0)


@SETTINGS
@given(directions, st.floats(0.1, 10.0))
def test_couple_has_infinite_pitch_and_axis_through_origin(d, scale):
    """A couple has pitch inf and its axis is returned through the origin."""
    c = scale * screws.couple(d)
    assert screws.pitch(c) == np.inf
    point, direction = screws.axis(c)
    np.testing.assert_allclose(point, 0.0, atol=0)
    np.testing.assert_allclose(direction, d, atol=1e-12)


def test_pitch_vectorised_over_rows():
    """pitch of a (k, 6) array gives one pitch per row (inf for couples)."""
    S = np.vstack([screws.screw([1, 2, 0], [0, 0, 1], 0.5), screws.couple([1, 0, 0]),
                   screws.line([0, 1, 0], [1, 1, 0])])
    h = screws.pitch(S)
    assert h.shape == (3,)
    np.testing.assert_allclose(h, [0.5, np.inf, 0.0], atol=1e-14)


@pytest.mark.parametrize(
    "call",
    [
        lambda: screws.line([0, 0, 0], [0, 0, 0]),
        lambda: screws.couple([0, 0, 0]),
        lambda: screws.screw([0, 0, 0], [0, 0, 0], 0.1),
        lambda: screws.line([np.nan, 0, 0], [1, 0, 0]),
        lambda: screws.line([0, 0, 0], [1, np.nan, 0]),
        lambda: screws.couple([np.nan, 1, 0]),
        lambda: screws.screw([0, 0, 0], [1, 0, 0], np.nan),
        lambda: screws.screw([0, np.inf, 0], [1, 0, 0], 0.1),
        lambda: screws.line([0, 0], [1, 0, 0]),
        lambda: screws.couple([1, 0, 0, 0]),
        lambda: screws.axis(np.zeros(6)),
        lambda: screws.rank(np.ones((2, 5))),
        lambda: screws.rank([[np.nan, 0, 0, 0, 0, 0]]),
        lambda: screws.reciprocal_product(np.ones(5), np.ones(6)),
        lambda: screws.rank(np.eye(6), length=0.0),
        lambda: screws.rank(np.eye(6), length=-1.0),
        lambda: screws.transform(np.ones(6), np.eye(4)),
    ],
    ids=[
        "line-zero-dir", "couple-zero-dir", "screw-zero-dir", "line-nan-point",
        "line-nan-dir", "couple-nan", "screw-nan-pitch", "screw-inf-point", "line-2d-point",
        "couple-4d", "axis-zero-screw", "rank-5-columns", "rank-nan", "product-5-coords",
        "zero-length", "negative-length", "transform-not-se3",
    ],
)
def test_bad_input_raises_input_error(call):
    """Zero directions, NaN/inf, wrong shapes and bad lengths raise InputError."""
    with pytest.raises(InputError):
        call()


# ---------------------------------------------------------- reciprocal product
@SETTINGS
@given(screw6, screw6)
def test_reciprocal_product_symmetric_and_equals_delta_form(a, b):
    """a ∘ b = b ∘ a = a @ DELTA @ b."""
    ab = screws.reciprocal_product(a, b)
    tol = 1e-12 * (1 + np.linalg.norm(a) * np.linalg.norm(b))
    assert abs(ab - screws.reciprocal_product(b, a)) <= tol
    assert abs(ab - a @ DELTA @ b) <= tol
    assert abs(ab - (a[:3] @ b[3:] + a[3:] @ b[:3])) <= tol


def test_reciprocal_product_broadcasts_over_rows():
    """The reciprocal product of (k, 6) arrays is taken row by row."""
    rng = np.random.default_rng(0)
    A, B = rng.normal(size=(4, 6)), rng.normal(size=(4, 6))
    np.testing.assert_allclose(screws.reciprocal_product(A, B),
                               np.einsum("ij,jk,ik->i", A, DELTA, B), rtol=1e-13, atol=1e-13)


def test_delta_is_a_symmetric_involution():
    """DELTA is symmetric, its own inverse and read-only."""
    np.testing.assert_array_equal(DELTA, DELTA.T)
    np.testing.assert_array_equal(DELTA @ DELTA, np.eye(6))
    with pytest.raises(ValueError):
        DELTA[0, 0] = 1.0


@SETTINGS
@given(
    points, directions, st.floats(0.3, np.pi - 0.3), st.floats(0, 2 * np.pi),
    st.floats(-3, 3), st.floats(-3, 3),
    st.one_of(st.just(0.0), st.floats(0.1, 3.0), st.floats(-3.0, -0.1)),
)
def test_two_lines_reciprocal_iff_coplanar(r1, s1, angle, spin, t, u, d):
    """Two non-parallel lines have product −d·sin(angle): zero iff they meet (d = 0)."""
    # s2 makes the angle `angle` with s1; the common normal n; line 2 is offset by d along n.
    k = _rotate(_perpendicular(s1), s1, spin)
    s2 = _rotate(s1, k, angle)
    n = np.cross(s1, s2) / np.linalg.norm(np.cross(s1, s2))
    r2 = r1 + t * s1 + u * s2 + d * n
    product = screws.reciprocal_product(screws.line(r1, s1), screws.line(r2, s2))
    assert abs(product - (-d * np.sin(angle))) <= 1e-12 * (1 + np.linalg.norm(r2))
    if d == 0.0:
        assert abs(product) <= 1e-12 * (1 + np.linalg.norm(r2))
    else:
        assert abs(product) >= 0.1 * np.sin(0.3) * 0.99


@SETTINGS
@given(points, points, directions, st.sampled_from([1.0, -1.0]))
def test_parallel_lines_are_reciprocal(r1, r2, s, sign):
    """Two parallel lines (coplanar) have zero reciprocal product."""
    product = screws.reciprocal_product(screws.line(r1, s), screws.line(r2, sign * s))
    assert abs(product) <= 1e-12 * (1 + np.linalg.norm(r1) + np.linalg.norm(r2))


@SETTINGS
@given(points, directions, directions)
def test_line_and_couple_reciprocal_iff_perpendicular(r, s, c):
    """line(r, s) ∘ couple(c) = s·c: zero iff the couple is perpendicular to the line."""
    product = screws.reciprocal_product(screws.line(r, s), screws.couple(c))
    assert abs(product - s.dot(c)) <= 1e-13
    c_perp = _perpendicular(s)
    assert abs(screws.reciprocal_product(screws.line(r, s), screws.couple(c_perp))) <= 1e-13
    c_oblique = (s + c_perp) / np.sqrt(2)
    assert abs(screws.reciprocal_product(screws.line(r, s), screws.couple(c_oblique))
               - 1 / np.sqrt(2)) <= 1e-13


@SETTINGS
@given(directions, directions)
def test_two_couples_are_always_reciprocal(c1, c2):
    """Any two couples are reciprocal."""
    assert screws.reciprocal_product(screws.couple(c1), screws.couple(c2)) == 0.0


# -------------------------------------------------------------- rank and spans
# Grid geometry has unit scale: the algebra is tested with ``length=1.0`` given, and the
# default (estimated) length separately below.
GRID_L = 1.0


@SETTINGS
@given(grid_systems())
def test_rank_matches_exact_rank(S):
    """rank(S) equals the exact rank of the integer Plücker matrix."""
    assert screws.rank(S, GRID_L) == exact_rank(S)
    assert screws.rank(S) == exact_rank(S)


@SETTINGS
@given(grid_systems())
def test_reciprocal_has_complementary_dimension_and_is_reciprocal(S):
    """reciprocal(S) has 6 − rank(S) independent rows, each reciprocal to every row of S."""
    R = screws.reciprocal(S, GRID_L)
    r = exact_rank(S)
    assert R.shape == (6 - r, 6)
    assert screws.rank(R, GRID_L) == 6 - r
    if S.shape[0] and R.shape[0]:
        scale = np.linalg.norm(S, axis=1)[:, None] * np.linalg.norm(R, axis=1)[None, :]
        assert np.all(np.abs(S @ DELTA @ R.T) <= 1e-10 * scale)


def _assert_same_system(X, S):
    """``X`` spans ``S`` (oracle) and, both non-empty, each contains the other
    (:func:`pkm_pin.screws.contains` at the grid length)."""
    assert spans_equal(X, S)
    if S.shape[0] and X.shape[0]:
        assert np.all(screws.contains(X, S, GRID_L))
        assert np.all(screws.contains(S, X, GRID_L))


@SETTINGS
@given(grid_systems())
def test_reciprocal_of_reciprocal_spans_original(S):
    """reciprocal(reciprocal(S)) spans the same system as S."""
    RR = screws.reciprocal(screws.reciprocal(S, GRID_L), GRID_L)
    assert RR.shape[0] == exact_rank(S)
    _assert_same_system(RR, S)


@SETTINGS
@given(grid_systems())
def test_basis_is_independent_and_spans(S):
    """basis(S) has rank(S) rows that span S."""
    B = screws.basis(S, GRID_L)
    assert B.shape == (exact_rank(S), 6)
    _assert_same_system(B, S)


@SETTINGS
@given(grid_systems())
@example(np.array([[0, 1, 1, 0, 0, 0], [0, 0, 1, 0, 0, 0]], float))  # lines through O
@example(np.array([[0, 0, 0, 0, 1, 1], [0, 0, 0, 0, 0, 1]], float))  # two couples
def test_default_length_ranks_of_computed_systems_are_right(S):
    """With the length estimated, rank, reciprocal and basis of computed (round-off
    carrying) systems still have the exact dimensions."""
    r = exact_rank(S)
    R = screws.reciprocal(S)
    assert R.shape[0] == 6 - r
    assert screws.rank(R) == 6 - r
    assert screws.reciprocal(R).shape[0] == r
    assert screws.rank(screws.basis(S)) == r


def test_characteristic_length_ignores_round_off():
    """Round-off in computed screws does not set the characteristic length: lines through
    the origin with 1e-16 moments give 1.0, a couple with a 1e-17 direction part is no
    axis 1e17 m away."""
    s = 1 / np.sqrt(2)
    through_origin = np.array([[0, 0, 1, 0, 0, 0], [0, 0, 0, 1, 0, 0],
                               [-s, s, 0, 0, -4.5e-17, -1.0e-16],
                               [-s, -s, 0, 0, -2.6e-16, 7.5e-17]])
    assert 0.1 <= screws.characteristic_length(through_origin) <= 10.0
    assert screws.rank(through_origin) == 4
    noisy_couple = np.vstack([screws.line([1, 0, 0], [0, 0, 1]), [1e-17, 0, 0, 0, 1, 0]])
    assert 0.1 <= screws.characteristic_length(noisy_couple) <= 10.0
    assert screws.rank(np.vstack([noisy_couple, screws.couple([0, 0, 1])])) == 3


def test_reciprocal_of_empty_system_is_everything():
    """The reciprocal of no screw is the whole 6-dimensional space."""
    R = screws.reciprocal(np.zeros((0, 6)))
    assert R.shape == (6, 6)
    assert screws.rank(R) == 6


def test_reciprocal_of_single_line_contains_lines_meeting_it():
    """The 5-system reciprocal to a line contains every line meeting it and every
    line parallel to it, and no line skew to it."""
    rng = np.random.default_rng(1)
    L0 = screws.line([1.0, 0.5, 0.0], [0.0, 0.0, 1.0])
    R = screws.reciprocal(L0)
    assert R.shape == (5, 6)
    for _ in range(10):
        meet = np.array([1.0, 0.5, rng.uniform(-2, 2)])
        assert screws.contains(R, screws.line(meet, rng.normal(size=3)))
        assert screws.contains(R, screws.line(rng.normal(size=3), [0, 0, 1]))
    assert not screws.contains(R, screws.line([0, 0, 0], [0, 1, 0]))  # skew, distance 1


# The degenerate line configurations of line geometry, with their known ranks.
def _concurrent(n):
    rng = np.random.default_rng(n)
    c = np.array([0.3, -0.2, 0.5])
    return np.array([screws.line(c, rng.normal(size=3)) for _ in range(n)])


def _planar_pencil(n):
    c = np.array([0.3, -0.2, 0.0])
    return np.array([screws.line(c, [np.cos(a), np.sin(a), 0]) for a in np.linspace(0, 3, n)])


def _coplanar(n):
    rng = np.random.default_rng(10 + n)
    return np.array([screws.line(np.r_[rng.normal(size=2), 0.4],
                                 np.r_[rng.normal(size=2), 0.0]) for _ in range(n)])


def _parallel_in_space(n):
    rng = np.random.default_rng(20 + n)
    return np.array([screws.line(rng.normal(size=3), [1, 2, 2]) for _ in range(n)])


def _parallel_coplanar(n):
    return np.array([screws.line([0.1, k, 0.7], [1, 0, 0]) for k in range(n)])


def _regulus(n):
    """Lines of one ruling of the hyperboloid x² + y² − z² = 1: a 3-system."""
    out = []
    for t in np.linspace(0.0, 5.0, n):
        p = np.array([np.cos(t), np.sin(t), 0.0])
        out.append(screws.line(p, [-np.sin(t), np.cos(t), 1.0]))
    return np.array(out)


def _general(n):
    rng = np.random.default_rng(30 + n)
    return np.array([screws.line(rng.normal(size=3), rng.normal(size=3)) for _ in range(n)])


def _gough_stewart_central():
    """Six legs of a Stewart platform at its home pose, all directions through a
    common point on the axis (the platform shrunk to a point): a 3-system."""
    base = [np.array([np.cos(a), np.sin(a), 0.0]) for a in np.deg2rad([0, 60, 120, 180, 240, 300])]
    apex = np.array([0.0, 0.0, 1.0])
    return np.array([screws.line(b, apex - b) for b in base])


DEGENERATE = [
    ("concurrent-5", _concurrent(5), 3),
    ("planar-pencil-4", _planar_pencil(4), 2),
    ("coplanar-5", _coplanar(5), 3),
    ("parallel-space-5", _parallel_in_space(5), 3),
    ("parallel-coplanar-4", _parallel_coplanar(4), 2),
    ("regulus-6", _regulus(6), 3),
    ("general-4", _general(4), 4),
    ("general-7", _general(7), 6),
    ("stewart-central", _gough_stewart_central(), 3),
    ("planar-motion", PLANAR_XZ, 3),
]


@pytest.mark.parametrize("S, expected", [(s, r) for _, s, r in DEGENERATE],
                         ids=[n for n, _, _ in DEGENERATE])
@pytest.mark.parametrize("scale", [1.0, 1e3, 1e-3])
def test_ranks_of_special_line_systems_are_unit_invariant(S, expected, scale):
    """Special line systems have their textbook rank, whether in m, mm or km."""
    S_scaled = S.copy()
    S_scaled[:, 3:] *= scale  # scaling the geometry scales the moments
    assert screws.rank(S_scaled) == expected
    assert screws.reciprocal(S_scaled).shape == (6 - expected, 6)


@SETTINGS
@given(grid_systems(), st.sampled_from([1e3, 1e-3, 25.4]))
def test_ranks_unchanged_when_geometry_scaled(S, k):
    """Scaling the geometry (m to mm, to km, to inches) does not change the rank."""
    S_k = S.copy()
    S_k[:, 3:] *= k
    assert screws.rank(S_k) == screws.rank(S) == exact_rank(S)
    L = screws.characteristic_length(S)
    assert screws.rank(S_k, length=k * L) == exact_rank(S)
    assert screws.reciprocal(S_k).shape[0] == 6 - exact_rank(S)


@st.composite
def offset_lines(draw):
    """(line, distance of its axis from the origin), the distance in [0.05, 2]."""
    d = draw(directions)
    u = _rotate(_perpendicular(d), d, draw(st.floats(0, 2 * np.pi)))
    rho = draw(st.floats(0.05, 2.0))
    t = draw(st.floats(-2.0, 2.0))
    return rho * u + t * d, d, rho


@SETTINGS
@given(st.lists(offset_lines(), min_size=1, max_size=7), st.floats(1e-3, 1e3))
def test_characteristic_length_is_median_axis_distance_and_scales(lines, k):
    """characteristic_length is the median distance of the axes from the origin, and
    scaling the geometry by k scales it by k."""
    S = np.array([screws.line(p, d) for p, d, _ in lines])
    expected = float(np.median([rho for _, _, rho in lines]))
    assert abs(screws.characteristic_length(S) - expected) <= 1e-12 * expected
    S_k = np.array([screws.line(k * p, d) for p, d, _ in lines])
    assert abs(screws.characteristic_length(S_k) - k * expected) <= 1e-12 * k * expected


def test_characteristic_length_ignores_couples_and_origin_lines():
    """Couples do not count; only axes through the origin (or none) give 1.0."""
    S = np.array([screws.line([1, 0, 0], [0, 0, 1]), screws.line([0, 2, 0], [1, 0, 0]),
                  screws.line([0, 0, 10], [0, 1, 0]), screws.couple([1, 0, 0]),
                  screws.couple([0, 1, 1])])
    assert abs(screws.characteristic_length(S) - 2.0) <= 1e-12
    assert screws.characteristic_length(screws.couple([0, 1, 0])) == 1.0
    assert screws.characteristic_length(screws.line([0, 0, 0], [1, 2, 3])) == 1.0


# ------------------------------------------------------ union and intersection
def test_intersection_of_two_planar_motion_systems_is_common_translation():
    """Planar motions in xz and in yz share only the translation along z."""
    common = screws.intersection(PLANAR_XZ, PLANAR_YZ)
    assert common.shape == (1, 6)
    assert screws.contains(common, [0, 0, 0, 0, 0, 1])
    np.testing.assert_allclose(np.abs(common[0]) / np.linalg.norm(common[0]),
                               [0, 0, 0, 0, 0, 1], atol=1e-12)


def test_union_of_two_planar_motion_systems_has_dimension_five():
    """Planar motions in xz and in yz together span a 5-system lacking rotation about z."""
    U = screws.union(PLANAR_XZ, PLANAR_YZ)
    assert U.shape == (5, 6)
    assert not screws.contains(U, [0, 0, 1, 0, 0, 0])
    assert np.all(screws.contains(U, np.vstack([PLANAR_XZ, PLANAR_YZ])))


def test_planar_motion_constraint_system_is_eq_54():
    """The constraint wrenches of planar motion in xz are (0 1 0|0 0 0), (0 0 0|1 0 0),
    (0 0 0|0 0 1) (seed 000, eq. 54)."""
    W = screws.reciprocal(PLANAR_XZ)
    assert W.shape == (3, 6)
    assert spans_equal(W, PLANAR_XZ)  # eq. 54 and eq. 55 have the same coordinates


def test_planar_motion_about_any_pivot_is_the_same_system():
    """A rotation about y through any point of the plane is in the planar system (55)."""
    rng = np.random.default_rng(2)
    pivots = np.c_[rng.uniform(-3, 3, 5), np.zeros(5), rng.uniform(-3, 3, 5)]
    lines = np.array([screws.line(p, [0, 1, 0]) for p in pivots])
    assert np.all(screws.contains(PLANAR_XZ, lines))
    assert spans_equal(lines[:2].tolist() + [screws.couple([1, 0, 0])], PLANAR_XZ)


def _rpr3_hand_twists(seed: int) -> list[np.ndarray]:
    """Hand-written twists of the three 3-RPR legs (eq. 50-52, unit prismatics)."""
    rng = np.random.default_rng(seed)
    y = np.array([0.0, 1.0, 0.0])
    legs = []
    for base_x in (0.0, 1.2, 2.0):
        b = np.array([base_x, 0.0, 0.0])
        a, L = rng.uniform(0.3, 2.8), rng.uniform(0.5, 2.0)
        d = np.array([np.cos(a), 0.0, np.sin(a)])
        p = b + L * d
        legs.append(np.array([np.r_[y, np.cross(b, y)], np.r_[np.zeros(3), d],
                              np.r_[y, np.cross(p, y)]]))
    return legs


@pytest.mark.parametrize("seed", [3, 4, 5])
def test_seed000_3rpr_hand_twists_intersect_in_planar_system(seed):
    """Hand-written 3-RPR leg twists intersect in (55); their constraints are (54)."""
    legs = _rpr3_hand_twists(seed)
    L = 1.0
    for T in legs:
        assert screws.rank(T, L) == 3
    assert spans_equal(screws.intersection(*legs, length=L), PLANAR_XZ)
    constraints = screws.union(*[screws.reciprocal(T, L) for T in legs], length=L)
    assert constraints.shape == (3, 6)
    assert spans_equal(constraints, PLANAR_XZ)  # (54): union of identical leg systems
    assert spans_equal(screws.reciprocal(constraints, L), PLANAR_XZ)  # mobility 3


@pytest.mark.parametrize("seed", [3, 4, 5])
def test_seed000_3rpr_mobility_procedure_with_default_lengths(seed):
    """The seed-000 procedure with every length left to its default (leg twists →
    reciprocal → union → reciprocal) gives the 3-dimensional systems (54) and (55)."""
    legs = _rpr3_hand_twists(seed)
    assert spans_equal(screws.intersection(*legs), PLANAR_XZ)
    constraints = screws.union(*[screws.reciprocal(T) for T in legs])
    assert constraints.shape == (3, 6)
    assert spans_equal(constraints, PLANAR_XZ)
    platform = screws.reciprocal(constraints)
    assert platform.shape == (3, 6)
    assert spans_equal(platform, PLANAR_XZ)


@SETTINGS
@given(grid_systems(min_size=1))
def test_intersection_with_itself_spans_itself(S):
    """intersection(S, S) spans S."""
    assert spans_equal(screws.intersection(S, S, length=GRID_L), S)
    assert spans_equal(screws.intersection(S, S), S)


@SETTINGS
@given(grid_systems(), grid_systems())
def test_union_and_intersection_dimensions_obey_grassmann(A, B):
    """dim(A ∪ B) = rank of the stacked rows and dim A + dim B = dim(A ∪ B) + dim(A ∩ B)."""
    stacked = np.vstack([A, B])
    U = screws.union(A, B, length=GRID_L)
    I = screws.intersection(A, B, length=GRID_L)
    assert U.shape[0] == exact_rank(stacked)
    assert exact_rank(A) + exact_rank(B) == U.shape[0] + I.shape[0]
    assert spans_equal(U, stacked)
    if I.shape[0]:
        assert spans_equal(np.vstack([A, I]), A)
        assert spans_equal(np.vstack([B, I]), B)


def test_union_and_intersection_of_nothing():
    """union() is the empty system and intersection() the whole space."""
    assert screws.union().shape == (0, 6)
    assert screws.intersection().shape == (6, 6)


# ---------------------------------------------------------------------- contains
def test_contains_linear_combinations_and_rejects_outsiders():
    """contains accepts combinations of the rows and rejects a screw outside the span."""
    rng = np.random.default_rng(4)
    S = np.array([screws.line(rng.normal(size=3), rng.normal(size=3)) for _ in range(3)])
    combos = rng.normal(size=(5, 3)) @ S
    assert np.all(screws.contains(S, combos))
    outsider = screws.reciprocal(S)[0] @ DELTA  # Δ maps the reciprocal complement out
    assert not screws.contains(S, outsider)
    result = screws.contains(S, np.vstack([combos[0], outsider]))
    assert result.dtype == bool and result.tolist() == [True, False]
    assert screws.contains(S, combos[0]) is True


def test_contains_in_empty_system_only_zero():
    """The empty system contains no non-zero screw."""
    assert not screws.contains(np.zeros((0, 6)), [1, 0, 0, 0, 0, 0])


# ------------------------------------------------------------- Pinocchio bridge
@SETTINGS
@given(screw6)
def test_from_and_to_pinocchio_are_inverse(x):
    """to_pinocchio and from_pinocchio undo each other."""
    np.testing.assert_array_equal(screws.from_pinocchio(screws.to_pinocchio(x)), x)
    np.testing.assert_array_equal(screws.to_pinocchio(screws.from_pinocchio(x)), x)


@SETTINGS
@given(points, points)
def test_from_pinocchio_matches_motion_parts(v, w):
    """from_pinocchio(Motion(v, ω)) is (ω; v) and to_pinocchio((ω; v)) is Motion's vector."""
    m = pin.Motion(v, w)
    np.testing.assert_array_equal(screws.from_pinocchio(m), np.r_[m.angular, m.linear])
    np.testing.assert_array_equal(screws.from_pinocchio(m.vector), np.r_[w, v])
    np.testing.assert_array_equal(screws.to_pinocchio(np.r_[w, v]), m.vector)


@SETTINGS
@given(points, points, points, points)
def test_power_of_pinocchio_force_on_motion_is_reciprocal_product(v, w, f, tau):
    """A pin.Force converted by from_pinocchio is the axis-first wrench (f; m_O): its
    reciprocal product with the converted pin.Motion is the power f·v + τ·ω."""
    motion, force = pin.Motion(v, w), pin.Force(f, tau)
    power = float(motion.vector @ force.vector)
    twist, wrench = screws.from_pinocchio(motion), screws.from_pinocchio(force)
    assert abs(screws.reciprocal_product(twist, wrench) - power) <= 1e-12 * (1 + abs(power))
    np.testing.assert_array_equal(wrench, np.r_[f, tau])


def test_from_pinocchio_swaps_jacobian_rows():
    """A 6×n Pinocchio Jacobian becomes a 6×n axis-first one with its row blocks swapped."""
    J = np.arange(24.0).reshape(6, 4)
    out = screws.from_pinocchio(J)
    assert out.shape == (6, 4)
    np.testing.assert_array_equal(out[:3], J[3:])
    np.testing.assert_array_equal(out[3:], J[:3])
    np.testing.assert_array_equal(screws.to_pinocchio(out), J)


@SETTINGS
@given(screw6, placements())
def test_transform_equals_pinocchio_act_on_motion(t, M):
    """transform(twist, aMb) equals Pinocchio's aMb.act on the Motion, converted."""
    expected = screws.from_pinocchio(M.act(pin.Motion(screws.to_pinocchio(t))))
    np.testing.assert_allclose(screws.transform(t, M), expected, atol=1e-12 * (1 + abs(t).max()))


@SETTINGS
@given(screw6, placements())
def test_transform_equals_pinocchio_act_on_force(wrench, M):
    """transform(wrench, aMb) equals aMb.act on pin.Force(f, m) (already force-first)."""
    acted = M.act(pin.Force(wrench[:3], wrench[3:]))
    expected = np.r_[acted.linear, acted.angular]
    np.testing.assert_allclose(screws.transform(wrench, M), expected,
                               atol=1e-12 * (1 + abs(wrench).max()))


@SETTINGS
@given(points, directions, placements())
def test_transform_moves_a_line_rigidly(p, d, M):
    """transform(line(p, d), M) is the line through M·p along R·d."""
    np.testing.assert_allclose(screws.transform(screws.line(p, d), M),
                               screws.line(M.act(p), M.rotation @ d), atol=1e-12)


@SETTINGS
@given(screw6, screw6, placements())
def test_transform_preserves_reciprocal_product(a, b, M):
    """transform preserves the reciprocal product (a ∘ b is frame independent)."""
    before = screws.reciprocal_product(a, b)
    after = screws.reciprocal_product(screws.transform(a, M), screws.transform(b, M))
    assert abs(after - before) <= 1e-10 * (1 + np.linalg.norm(a) * np.linalg.norm(b))


@SETTINGS
@given(placements(), placements())
def test_transform_composes_like_placements(M1, M2):
    """transform(transform(S, M1), M2) = transform(S, M2 * M1), shapes kept."""
    S = np.random.default_rng(5).normal(size=(4, 6))
    np.testing.assert_allclose(screws.transform(screws.transform(S, M1), M2),
                               screws.transform(S, M2 * M1), atol=1e-11)
    assert screws.transform(S[0], M1).shape == (6,)
    assert screws.transform(S, M1).shape == (4, 6)


def test_adjoint_matches_pinocchio_action_matrix_reordered():
    """adjoint(M) is Pinocchio's M.action with both row and column blocks swapped."""
    M = pin.SE3(pin.exp3(np.array([0.3, -0.4, 1.1])), np.array([0.5, -1.0, 2.0]))
    swap = np.r_[3:6, 0:3]
    np.testing.assert_allclose(screws.adjoint(M), M.action[np.ix_(swap, swap)], atol=1e-15)


# -------------------------------------------------------------------- exp / log
@SETTINGS
@given(st.tuples(*(3 * [st.floats(-1.7, 1.7)])).map(np.array), points)
def test_log_of_exp_round_trips(w, v):
    """log(exp(t)) = t for rotation angles below π."""
    t = np.r_[w, v]
    np.testing.assert_allclose(screws.log(screws.exp(t)), t, atol=1e-9)


@SETTINGS
@given(placements())
def test_exp_of_log_round_trips(M):
    """exp(log(M)) = M."""
    assert screws.exp(screws.log(M)).isApprox(M, 1e-9)


@SETTINGS
@given(points, directions, st.floats(-3.0, 3.0), st.floats(-2.0, 2.0))
def test_exp_of_rotation_twist_fixes_its_axis(p, d, angle, t):
    """exp(θ · line(p, d)) rotates by θ about the line: points of the line stay put."""
    D = screws.exp(angle * screws.line(p, d))
    on_axis = p + t * d
    np.testing.assert_allclose(D.act(on_axis), on_axis, atol=1e-12)
    np.testing.assert_allclose(D.rotation @ d, d, atol=1e-12)
    x = _perpendicular(d)
    np.testing.assert_allclose((D.rotation @ x).dot(x), np.cos(angle), atol=1e-12)
    np.testing.assert_allclose(np.cross(x, D.rotation @ x), np.sin(angle) * d, atol=1e-12)


@SETTINGS
@given(directions, st.floats(-3.0, 3.0))
def test_exp_of_couple_is_a_translation(d, dist):
    """exp(dist · couple(d)) translates by dist · d without rotating."""
    D = screws.exp(dist * screws.couple(d))
    np.testing.assert_allclose(D.rotation, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(D.translation, dist * d, atol=1e-14)


@SETTINGS
@given(points, directions, st.floats(-3.0, 3.0), st.floats(-2.0, 2.0))
def test_exp_of_screw_advances_pitch_times_angle(p, d, h, angle):
    """exp(θ · screw(p, d, h)) moves points of the axis by h·θ along it."""
    D = screws.exp(angle * screws.screw(p, d, h))
    np.testing.assert_allclose(D.act(p), p + h * angle * d, atol=1e-11)


def test_about_a_point_is_the_translated_frame_and_from_point_undoes_it():
    """screws.about(S, p): the screws written about p — the same numbers as transforming
    into a frame at p with the world's axes; for a line, the moment about a point on it
    is zero. screws.from_point is its inverse, batched over poses too."""
    rng = np.random.default_rng(3)
    S, p = rng.normal(size=(4, 6)), rng.normal(size=3)
    np.testing.assert_allclose(screws.about(S, p),
                               screws.transform(S, pin.SE3(np.eye(3), -p)), atol=1e-15)
    line = np.r_[[0.0, 0.0, 1.0], np.cross(p, [0.0, 0.0, 1.0])]  # through p along z
    np.testing.assert_allclose(screws.about(line, p)[3:], 0.0, atol=1e-15)
    B, P = rng.normal(size=(2, 5, 6)), rng.normal(size=(2, 3))
    np.testing.assert_allclose(screws.from_point(screws.about(B, P), P), B, atol=1e-14)
    np.testing.assert_allclose(screws.about(B, P)[1], screws.about(B[1], P[1]), atol=1e-15)


def test_cross_equals_numpy_cross_with_broadcasting():
    """screws.cross gives numpy.cross's numbers for vectors, stacks and broadcasts."""
    rng = np.random.default_rng(3)
    for sa, sb in (((3,), (3,)), ((5, 3), (3,)), ((4, 1, 3), (2, 3)), ((7, 3), (7, 3))):
        a, b = rng.normal(size=sa), rng.normal(size=sb)
        np.testing.assert_allclose(screws.cross(a, b), np.cross(a, b), rtol=0, atol=1e-15)
