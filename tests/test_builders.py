"""Tests of pkm_pin.builders: URDF writer, designs, the mechanisms and the committed models."""

from __future__ import annotations

import math
import re
import subprocess
import sys

import numpy as np
import pinocchio as pin
import pytest

try:
    import tomllib
except ImportError:  # Python 3.10
    import tomli as tomllib

from helpers import MECHANISM_DIR, MODELS

from pkm_pin import InputError, Leg, screws
from pkm_pin.builders import (
    DESCRIPTIONS,
    MECHANISMS,
    JointSpec,
    chain_urdf,
    rpr3_type2_pose,
    rpr3_wrench_lines,
    rrr3_elbow_signs,
    rrr3_stretched_pose,
    stewart,
    upu3_constraint_singular_pose,
)

NAMES = sorted(MECHANISMS)

#: Rank of one leg's joint twists at home.
LEG_RANK = {"rpr3": 3, "rrr3": 3, "stewart": 6, "delta": 4, "upu3": 5, "rps3": 5,
            "prs3": 5, "agile_eye": 3, "orthoglide": 4, "orthoglide_quasi": 4}
#: Mobility of the platform (6 − rank of the union of the legs' constraint wrenches).
MOBILITY = {"rpr3": 3, "rrr3": 3, "stewart": 6, "delta": 3, "upu3": 3, "rps3": 3,
            "prs3": 3, "agile_eye": 3, "orthoglide": 3, "orthoglide_quasi": 3}
#: Number of legs.
N_LEGS = {"rpr3": 3, "rrr3": 3, "stewart": 6, "delta": 3, "upu3": 3, "rps3": 3,
          "prs3": 3, "agile_eye": 3, "orthoglide": 3, "orthoglide_quasi": 3}

#: Smallest relative singular value of the actuation wrenches accepted as "far from
#: a singularity" at home (the actual values are 0.13 to 0.31).
WELL_CONDITIONED = 0.1


@pytest.fixture(scope="module")
def designs():
    return {name: MECHANISMS[name]() for name in NAMES}


@pytest.fixture(scope="module")
def designs_mm():
    return {name: MECHANISMS[name](scale=1000.0) for name in NAMES}


# ------------------------------------------------------------------------ helpers
def _length(legs) -> float:
    """Characteristic length of a mechanism: mean characteristic length of its legs."""
    return float(np.mean([leg.characteristic_length for leg in legs]))


def _pose_error(a: pin.SE3, b: pin.SE3, length: float) -> float:
    """Relative distance of two placements: translation / length + rotation angle."""
    d = a.inverse() * b
    return np.linalg.norm(d.translation) / length + np.linalg.norm(pin.log3(d.rotation))


def _solve_all(design, pose, q_start=None):
    legs = design.legs_built()
    sols = [leg.solve(pose * ld.anchor, q)
            for leg, ld, q in zip(legs, design.legs, q_start or design.home_q)]
    return legs, sols


def _wrench_systems(legs, qs, length):
    """Union of the legs' constraint wrenches, and of the wrenches reciprocal to the
    passive joints (constraint + actuation), stacked."""
    constraint, actuation = [], []
    for leg, q in zip(legs, qs):
        T = leg.motion_twists(q)
        constraint.append(screws.reciprocal(T, length))
        actuation.append(screws.reciprocal(T[leg.passive_v], length))
    return np.vstack(constraint), np.vstack(actuation)


def _relative_smallest_singular_value(W, length) -> float:
    H = W.copy()
    H[:, 3:] /= length
    H /= np.linalg.norm(H, axis=1)[:, None]
    sv = np.linalg.svd(H, compute_uv=False)
    return float(sv[5] / sv[0]) if sv.size >= 6 else 0.0


# --------------------------------------------------------------------- URDF writer
def test_chain_urdf_writes_mimic_limits_and_tip():
    """A written chain keeps its mimic (yourdfpy's writer drops it), limits and tip."""
    xml = chain_urdf("demo", [
        JointSpec("a", axis=(0, 1, 0), lower=-1.0, upper=2.0),
        JointSpec("b", xyz=(0.5, 0, 0), axis=(0, 1, 0), mimic=("a", -1.0, 0.0)),
        JointSpec("c", "prismatic", axis=(0, 0, 1), lower=0.1, upper=0.9),
    ], tip="flange", tip_xyz=(0, 0, 0.25), tip_rpy=(0.1, 0.2, 0.3))
    assert '<mimic joint="a" multiplier="-1.0" offset="0.0"/>' in xml
    leg = Leg.from_urdf(xml, "flange")
    assert leg.joint_names == ["a", "c"]
    assert np.allclose(leg.lower, [-1.0, 0.1]) and np.allclose(leg.upper, [2.0, 0.9])
    T = leg.tip_placement(np.array([0.7, 0.4]))
    expected = (pin.SE3(pin.rpy.rpyToMatrix(0, 0.7, 0), np.zeros(3))
                * pin.SE3(np.eye(3), np.array([0.5, 0, 0]))
                * pin.SE3(pin.rpy.rpyToMatrix(0, -0.7, 0), np.zeros(3))
                * pin.SE3(np.eye(3), np.array([0, 0, 0.4]))
                * pin.SE3(pin.rpy.rpyToMatrix(0.1, 0.2, 0.3), np.array([0, 0, 0.25])))
    assert _pose_error(T, expected, 1.0) < 1e-12


def test_joint_spec_rejects_bad_type_and_limits():
    """A joint spec with an unknown type or inverted limits raises InputError."""
    with pytest.raises(InputError):
        JointSpec("x", "spherical")
    with pytest.raises(InputError):
        JointSpec("x", "prismatic", lower=1.0, upper=0.0)


# ------------------------------------------------------------------- every design
def test_registry_has_descriptions():
    """Every registry entry has a one-line description."""
    assert set(DESCRIPTIONS) == set(MECHANISMS)
    assert all(d and "\n" not in d for d in DESCRIPTIONS.values())


@pytest.mark.parametrize("name", NAMES)
def test_legs_load_from_urdf(designs, name):
    """The generated URDF of every leg loads with Leg.from_urdf, with its actuated joint."""
    d = designs[name]
    assert len(d.legs) == N_LEGS[name]
    for ld in d.legs:
        leg = Leg.from_urdf(ld.urdf, ld.tip, ld.actuated, ld.base, ld.name)
        assert leg.actuated == ld.actuated and len(leg.actuated) == 1


@pytest.mark.parametrize("name", NAMES)
def test_home_assembles(designs, name):
    """At home every leg's tip placement equals home * anchor to 1e-12."""
    d = designs[name]
    legs = d.legs_built()
    L = _length(legs)
    for leg, ld, q in zip(legs, d.legs, d.home_q):
        assert _pose_error(leg.tip_placement(q), d.home * ld.anchor, L) < 1e-12


@pytest.mark.parametrize("name", NAMES)
def test_home_inside_limits_and_away_from_gimbal_lock(designs, name):
    """Home joint values lie strictly inside the limits; spherical groups have |middle| < π/4."""
    d = designs[name]
    for leg, q in zip(d.legs_built(), d.home_q):
        lo, up = leg._bounds
        margin = 0.05 * (up - lo)
        assert np.all(q >= lo + margin) and np.all(q <= up - margin)
        for group in leg.spherical_groups:
            assert abs(q[group[1]]) < math.pi / 4


@pytest.mark.parametrize("name", NAMES)
def test_leg_ik_converges_from_perturbed_home(designs, name):
    """leg.solve(home * anchor) converges from a perturbed home configuration."""
    d = designs[name]
    rng = np.random.default_rng(7)
    for leg, ld, q in zip(d.legs_built(), d.legs, d.home_q):
        q0 = leg.clip(q + rng.uniform(-0.05, 0.05, q.shape))
        sol = leg.solve(d.home * ld.anchor, q0)
        assert sol.converged
        assert leg.within_limits(sol.q)
        assert np.allclose(sol.q, q, atol=1e-6)


@pytest.mark.parametrize("name", NAMES)
def test_leg_twist_rank_at_home(designs, name):
    """Each leg's joint twists at home have the expected rank."""
    d = designs[name]
    for leg, q in zip(d.legs_built(), d.home_q):
        assert screws.rank(leg.joint_twists(q), leg.characteristic_length) == LEG_RANK[name]


@pytest.mark.parametrize("name", NAMES)
def test_mobility_and_no_singularity_at_home(designs, name):
    """At home the mobility is as expected and the actuation wrenches are well conditioned."""
    d = designs[name]
    legs = d.legs_built()
    L = _length(legs)
    constraint, actuation = _wrench_systems(legs, d.home_q, L)
    assert 6 - screws.rank(constraint, L) == MOBILITY[name]
    assert screws.rank(actuation, L) == 6
    assert _relative_smallest_singular_value(actuation, L) > WELL_CONDITIONED


@pytest.mark.parametrize("name", NAMES)
def test_scale_1000_same_ranks_angles_lengths_times_1000(designs, designs_mm, name):
    """scale=1000 gives the same twist ranks and angles, and lengths multiplied by 1000."""
    d, mm = designs[name], designs_mm[name]
    assert np.allclose(mm.home.translation, 1000 * d.home.translation, rtol=1e-12, atol=1e-9)
    assert np.allclose(mm.home.rotation, d.home.rotation, atol=1e-12)
    for leg, leg_mm, ld, ld_mm, q, q_mm in zip(d.legs_built(), mm.legs_built(), d.legs, mm.legs,
                                               d.home_q, mm.home_q):
        prismatic = np.array([leg.model.joints[leg.model.getJointId(n)].shortname().endswith(
            ("PX", "PY", "PZ", "PrismaticUnaligned")) for n in leg.joint_names])
        assert np.allclose(q_mm[~prismatic], q[~prismatic], atol=1e-12)
        assert np.allclose(q_mm[prismatic], 1000 * q[prismatic], rtol=1e-12)
        assert np.allclose(leg_mm.lower[prismatic], 1000 * leg.lower[prismatic], rtol=1e-12)
        assert np.allclose(ld_mm.anchor.translation, 1000 * ld.anchor.translation, atol=1e-9)
        assert np.allclose(ld_mm.base.translation, 1000 * ld.base.translation, atol=1e-9)
        assert screws.rank(leg_mm.joint_twists(q_mm), leg_mm.characteristic_length) == \
            screws.rank(leg.joint_twists(q), leg.characteristic_length)


@pytest.mark.parametrize("name", NAMES)
def test_write_round_trip(designs, name, tmp_path):
    """write() produces valid TOML whose URDF paths exist and whose numbers reproduce the design."""
    d = designs[name]
    d.write(tmp_path)
    toml_path = tmp_path / "mechanisms" / f"{d.slug}.toml"
    data = tomllib.loads(toml_path.read_text())
    assert data["name"] == d.name and data["description"] == d.description
    assert len(data["legs"]) == len(d.legs)

    def se3(entry):
        return pin.SE3(pin.rpy.rpyToMatrix(np.array(entry["rpy"])), np.array(entry["xyz"]))

    L = _length(d.legs_built())
    for entry, ld, q in zip(data["legs"], d.legs, d.home_q):
        urdf = (toml_path.parent / entry["urdf"]).resolve()
        assert urdf.is_file() and urdf.read_text() == ld.urdf
        assert entry["name"] == ld.name and entry["tip"] == ld.tip
        assert tuple(entry["actuated"]) == ld.actuated
        assert _pose_error(se3(entry["base"]), ld.base, L) < 1e-14
        assert _pose_error(se3(entry["anchor"]), ld.anchor, L) < 1e-14
        assert entry["home_q"] == list(q)
    assert _pose_error(se3(data["home"]), d.home, L) < 1e-14


@pytest.mark.parametrize("name", NAMES)
def test_committed_models_are_current(designs, name, tmp_path):
    """The files under models/ equal what the builders generate now."""
    written = designs[name].write(tmp_path)
    for path in written:
        committed = MODELS / path.relative_to(tmp_path)
        assert committed.is_file(), f"{committed} missing: run python -m pkm_pin.builders"
        assert _same_up_to_rounding(committed.read_text(), path.read_text()), (
            f"{committed} is stale: run python -m pkm_pin.builders"
        )


_NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


def _same_up_to_rounding(a: str, b: str, atol: float = 1e-12) -> bool:
    """Equal text, numbers equal to ``atol`` (last-bit differences between numpy/BLAS builds)."""
    if _NUMBER.split(a) != _NUMBER.split(b):
        return False
    x = np.array([float(t) for t in _NUMBER.findall(a)])
    y = np.array([float(t) for t in _NUMBER.findall(b)])
    return x.shape == y.shape and bool(np.all(np.abs(x - y) <= atol * (1.0 + np.abs(y))))


@pytest.mark.parametrize("name", NAMES)
def test_committed_file_loads_and_assembles_in_the_home_working_mode(designs, name):
    """load_mechanism on the committed TOML assembles at home with the design's joint values."""
    from pkm_pin import load_mechanism

    d = designs[name]
    mech = load_mechanism(MECHANISM_DIR / f"{d.slug}.toml")
    for q, q_design in zip(mech.home_assembly.leg_q, d.home_q):
        assert np.allclose(q, q_design, atol=1e-9)
    built = d.build()
    assert [leg.name for leg in built.legs] == [ld.name for ld in d.legs]


def test_main_regenerates_into_a_folder(tmp_path):
    """python -m pkm_pin.builders --out DIR writes every mechanism file and its URDFs."""
    subprocess.run([sys.executable, "-m", "pkm_pin.builders", "--out", str(tmp_path)],
                   check=True, capture_output=True)
    tomls = sorted(p.stem for p in (tmp_path / "mechanisms").glob("*.toml"))
    assert tomls == sorted(MECHANISMS[n]().slug for n in NAMES)
    for p in (tmp_path / "mechanisms").glob("*.toml"):
        for leg in tomllib.loads(p.read_text())["legs"]:
            assert (p.parent / leg["urdf"]).is_file()


# -------------------------------------------------------------------------- 3-RPR
def test_rpr3_twists_equal_hand_written_screws(designs):
    """3-RPR leg twists at home: y-lines at the base and platform pivots, a couple along the leg."""
    d = designs["rpr3"]
    for leg, ld, q in zip(d.legs_built(), d.legs, d.home_q):
        base = ld.base.translation
        pivot = (d.home * ld.anchor).translation
        expected = np.array([
            screws.line(base, [0, 1, 0]),
            screws.couple(pivot - base),
            screws.line(pivot, [0, 1, 0]),
        ])
        assert np.allclose(leg.joint_twists(q), expected, atol=1e-12)
        assert math.isclose(q[1], np.linalg.norm(pivot - base), rel_tol=1e-12)


def test_rpr3_paper_layout_and_actuation(designs):
    """The 3-RPR has the paper's base pivots and actuation, the platform above the base."""
    d = designs["rpr3"]
    assert [ld.actuated for ld in d.legs] == [("A1",), ("B0",), ("C1",)]
    assert np.allclose([ld.base.translation for ld in d.legs], [[0, 0, 0], [1, 0, 0], [2, 0, 0]])
    pivots = np.array([(d.home * ld.anchor).translation for ld in d.legs])
    assert np.all(pivots[:, 2] > 0) and np.allclose(pivots[:, 1], 0)
    for q, ld in zip(d.home_q, d.legs):  # the paper's leg angle alpha = -X0
        pivot = (d.home * ld.anchor).translation - ld.base.translation
        assert math.isclose(-q[0], math.atan2(pivot[2], pivot[0]), abs_tol=1e-12)


def _paper_det60(design, qs) -> float:
    """Determinant of the matrix of seed 000 (Michalková & Guldan, see docs/references.md)
    eq. (60), normalised by its row norms."""
    (alpha, _, _), (beta, L5, _), (gamma, _, _) = [(-q[0], q[1], q[2]) for q in qs]
    L3, L6 = 1.0, 1.0
    M = np.array([
        [0.0, math.cos(alpha), math.sin(alpha)],
        [L5 + L3 * math.cos(beta), math.sin(beta), -math.cos(beta)],
        [-(L3 + L6) * math.sin(gamma), math.cos(gamma), math.sin(gamma)],
    ])
    return float(np.linalg.det(M / np.linalg.norm(M, axis=1)[:, None]))


def test_rpr3_type2_pose_is_reachable_and_singular(designs):
    """At rpr3_type2_pose the legs assemble within limits and the actuation lines are concurrent."""
    d = designs["rpr3"]
    pose = rpr3_type2_pose()
    legs, sols = _solve_all(d, pose)
    assert all(s.converged and leg.within_limits(s.q) for leg, s in zip(legs, sols))
    qs = [s.q for s in sols]
    # the lines: leg A, leg C, and the normal to leg B at B2; they meet at one point
    pts = [(pose * ld.anchor).translation for ld in d.legs]
    dirs = [pts[0] - d.legs[0].base.translation,
            np.cross([0, 1, 0], pts[1] - d.legs[1].base.translation),
            pts[2] - d.legs[2].base.translation]
    meet = _intersection_xz(pts[0], dirs[0], pts[2], dirs[2])
    assert _distance_to_line(meet, pts[1], dirs[1]) < 1e-9
    assert abs(np.linalg.det(rpr3_wrench_lines(pose))) < 1e-12
    # Pinocchio path: the wrenches reciprocal to the passive joints lose rank
    L = _length(legs)
    _, actuation = _wrench_systems(legs, qs, L)
    assert screws.rank(actuation, L) == 5
    # the paper's eq. (60) vanishes there, not at home
    assert abs(_paper_det60(d, qs)) < 1e-12
    assert abs(_paper_det60(d, d.home_q)) > 0.1


def test_rpr3_concurrent_leg_lines_pose(designs):
    """At rpr3_type2_pose(actuated='PPP') the three leg lines (pivot to base) are concurrent."""
    d = designs["rpr3"]
    pose = rpr3_type2_pose(actuated="PPP")
    legs, sols = _solve_all(d, pose)
    assert all(s.converged and leg.within_limits(s.q) for leg, s in zip(legs, sols))
    pts = [(pose * ld.anchor).translation for ld in d.legs]
    bases = [ld.base.translation for ld in d.legs]
    meet = _intersection_xz(pts[0], pts[0] - bases[0], pts[2], pts[2] - bases[2])
    assert _distance_to_line(meet, pts[1], pts[1] - bases[1]) < 1e-9
    # three coplanar lines through one point span a pencil: rank 2 (3 at home)
    lines = np.array([screws.line(p, p - b) for p, b in zip(pts, bases)])
    assert screws.rank(lines, 1.0) == 2
    home_pts = [(d.home * ld.anchor).translation for ld in d.legs]
    assert screws.rank(np.array([screws.line(p, p - b) for p, b in zip(home_pts, bases)]),
                       1.0) == 3


def _intersection_xz(p1, d1, p2, d2) -> np.ndarray:
    """Intersection of two lines of the xz-plane."""
    A = np.array([[d1[0], -d2[0]], [d1[2], -d2[2]]])
    t = np.linalg.solve(A, [p2[0] - p1[0], p2[2] - p1[2]])
    return p1 + t[0] * d1


def _distance_to_line(x, p, d) -> float:
    d = d / np.linalg.norm(d)
    return float(np.linalg.norm(np.cross(x - p, d)))


# -------------------------------------------------------------------------- 3-RRR
def test_rrr3_home_working_mode_and_stretched_pose(designs):
    """3-RRR: elbows all +1 at home; at the stretched pose leg 1 has R2 = 0 and rank 2 (type I)."""
    d = designs["rrr3"]
    assert rrr3_elbow_signs(d.home_q) == (1, 1, 1)
    pose = rrr3_stretched_pose()
    legs, sols = _solve_all(d, pose)
    assert all(s.converged and leg.within_limits(s.q) for leg, s in zip(legs, sols))
    assert abs(sols[0].q[1]) < 1e-6
    assert screws.rank(legs[0].joint_twists(sols[0].q), legs[0].characteristic_length,
                       rtol=1e-6) == 2
    assert rrr3_elbow_signs([s.q for s in sols])[1:] == (1, 1)
    assert all(screws.rank(leg.joint_twists(s.q)) == 3 for leg, s in zip(legs[1:], sols[1:]))


# ------------------------------------------------------------------ Gough–Stewart
def test_stewart_twists_are_lines_through_joint_centres(designs):
    """UPS leg at home: U lines at the base point, P a couple along the leg, S lines at the top."""
    d = designs["stewart"]
    for leg, ld, q in zip(d.legs_built(), d.legs, d.home_q):
        b = ld.base.translation
        p = (d.home * ld.anchor).translation
        R = ld.base.rotation
        expected = np.array([screws.line(b, R[:, 0]), screws.line(b, R[:, 1]),
                             screws.couple(p - b), screws.line(p, R[:, 0]),
                             screws.line(p, R[:, 1]), screws.line(p, R[:, 2])])
        assert np.allclose(leg.joint_twists(q), expected, atol=1e-12)
        assert np.allclose(R[:, 2], (p - b) / np.linalg.norm(p - b), atol=1e-12)


def test_stewart_with_given_points_assembles():
    """stewart() with arbitrary base and platform points assembles at the given home."""
    rng = np.random.default_rng(3)
    angles = np.sort(rng.uniform(0, 2 * np.pi, 6))
    base = np.column_stack([np.cos(angles), np.sin(angles), np.zeros(6)])
    plat = 0.6 * np.column_stack([np.cos(angles + 0.4), np.sin(angles + 0.4), np.zeros(6)])
    home = pin.SE3(pin.rpy.rpyToMatrix(0.05, -0.03, 0.1), np.array([0.02, -0.01, 0.9]))
    d = stewart(base, plat, home=home, name="6-SPS test", slug="sps_test",
                urdf_file="sps_test_leg.urdf")
    for leg, ld, q, pb, pp in zip(d.legs_built(), d.legs, d.home_q, base, plat):
        assert np.allclose(ld.base.translation, pb)
        assert np.allclose((d.home * ld.anchor).translation, home.act(pp), atol=1e-12)
        assert _pose_error(leg.tip_placement(q), d.home * ld.anchor, 1.0) < 1e-12


def test_stewart_rejects_points_of_wrong_shape():
    """stewart() with 5 points or with only base points raises InputError."""
    with pytest.raises(InputError):
        stewart(np.zeros((5, 3)), np.zeros((5, 3)))
    with pytest.raises(InputError):
        stewart(np.zeros((6, 3)))


# -------------------------------------------------------------------------- Delta
def test_delta_parallelogram_keeps_platform_orientation(designs):
    """Moving R2, R3 of a Delta leg only translates its tip; R1 and R6 turn it about u."""
    d = designs["delta"]
    leg = d.legs_built()[1]
    q = d.home_q[1]
    u = leg.base.rotation[:, 1]
    T0 = leg.tip_placement(q)
    T1 = leg.tip_placement(q + np.array([0.0, -0.3, 0.25, 0.0]))
    assert np.allclose(T1.rotation, T0.rotation, atol=1e-12)
    assert np.linalg.norm(T1.translation - T0.translation) > 0.05
    for k in (0, 3):
        dq = np.zeros(4)
        dq[k] = 0.3
        T2 = leg.tip_placement(q + dq)
        assert np.allclose(pin.log3(T2.rotation @ T0.rotation.T), 0.3 * u, atol=1e-12)
    assert d.home.translation[2] < 0 and np.allclose(d.home.rotation, np.eye(3))


# -------------------------------------------------------------------------- 3-UPU
def test_upu3_constraint_singular_pose(designs):
    """3-UPU: the three constraint couples have rank 3 at home and rank 2 at the singular pose."""
    d = designs["upu3"]
    legs = d.legs_built()
    L = _length(legs)

    def couples(qs):
        W = np.vstack([screws.reciprocal(leg.joint_twists(q), L) for leg, q in zip(legs, qs)])
        assert W.shape == (3, 6) and np.allclose(W[:, :3], 0, atol=1e-12)  # pure couples
        return W

    assert screws.rank(couples(d.home_q), L) == 3
    legs, sols = _solve_all(d, upu3_constraint_singular_pose())
    assert all(s.converged and leg.within_limits(s.q) for leg, s in zip(legs, sols))
    assert screws.rank(couples([s.q for s in sols]), L) == 2


def test_upu3_platform_u_axes_parallel_to_base(designs):
    """3-UPU at home: U4 is parallel to U1 and U3 to U2 (Tsai's condition for pure translation)."""
    d = designs["upu3"]
    for leg, q in zip(d.legs_built(), d.home_q):
        T = leg.joint_twists(q)
        assert np.allclose(np.cross(T[0, :3], T[4, :3]), 0, atol=1e-12)
        assert np.allclose(np.cross(T[1, :3], T[3, :3]), 0, atol=1e-12)


def test_special_poses_scale():
    """The special poses scale with scale=1000 (translations ×1000, same rotations)."""
    for f in (rpr3_type2_pose, rrr3_stretched_pose, upu3_constraint_singular_pose):
        a, b = f(), f(1000.0)
        assert np.allclose(b.translation, 1000 * a.translation, rtol=1e-9, atol=1e-9)
        assert np.allclose(b.rotation, a.rotation, atol=1e-12)
    assert upu3_constraint_singular_pose().isIdentity(1e-15)


def test_stale_check_tolerates_last_bits_only():
    a = 'xyz = [0.0, 0.4000000000000001]\n<origin xyz="1 2"/>'
    assert _same_up_to_rounding(a, 'xyz = [1.1e-16, 0.4]\n<origin xyz="1 2"/>')
    assert not _same_up_to_rounding(a, 'xyz = [0.0, 0.4000001]\n<origin xyz="1 2"/>')
    assert not _same_up_to_rounding(a, 'xyz = [0.0, 0.4000000000000001]\n<origin rpy="1 2"/>')
