"""Assembly modes (pkm_pin.modes): homotopy for distance legs, multistart otherwise.

Dietmaier's platform: P. Dietmaier, "The Stewart-Gough platform of general geometry can
have 40 real postures", ARK 1998 (pkm_pin.builders.dietmaier).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from helpers import shipped_mechanisms

from pkm_pin.builders.dietmaier import (
    DIETMAIER_BASE,
    DIETMAIER_LENGTHS,
    DIETMAIER_PLATFORM,
    dietmaier,
)
from pkm_pin.errors import ForwardKinematicsError, InputError
from pkm_pin.modes import AssemblyModes, distance_legs, stewart_gough_postures

mech = shipped_mechanisms()


@pytest.fixture(scope="module")
def platform():
    """Dietmaier's 6-UPS platform, built once."""
    return dietmaier().build()


@pytest.fixture(scope="module")
def postures(platform):
    """Its assembly modes at Dietmaier's leg lengths."""
    return platform.forward_kinematics_all(DIETMAIER_LENGTHS)


def leg_lengths(pose: pin.SE3) -> np.ndarray:
    """Distances |R b_i + t − a_i| in closed form."""
    ends = DIETMAIER_PLATFORM @ pose.rotation.T + pose.translation
    return np.linalg.norm(ends - DIETMAIER_BASE, axis=1)


def test_dietmaier_forty_real_postures(platform, postures):
    """All 40 real postures are found, proven complete (128 paths: 40 finite, 88 on the
    exceptional set), each closing to 1e-12 with the leg lengths to 1e-12, distinct."""
    assert isinstance(postures, AssemblyModes)
    assert postures.method == "homotopy" and postures.complete
    assert len(postures) == 40
    c = postures.counts
    assert c["paths"] == 128 and c["finite"] == 40 and c["real"] == 40
    assert c["at_infinity"] == 88 and c["failed"] == 0 and c["outside_limits"] == 0
    L = platform.characteristic_length
    for a in postures:
        assert a.residual <= 1e-12
        np.testing.assert_allclose(a.q_actuated, DIETMAIER_LENGTHS, atol=1e-12)
        np.testing.assert_allclose(leg_lengths(a.pose), DIETMAIER_LENGTHS, atol=1e-12)
        assert all(leg.within_limits(q) for leg, q in zip(platform.legs, a.leg_q))
    for i in range(40):
        for j in range(i):
            e = pin.log6(postures[i].pose.actInv(postures[j].pose)).vector
            assert np.max(np.abs(np.r_[e[:3] / L, e[3:]])) > 1e-6


def test_dietmaier_homotopy_alone_and_invariance():
    """The bare homotopy (no mechanism) gives the same 40 postures, and in millimetres
    with the base moved and turned it gives them moved and scaled."""
    ref = stewart_gough_postures(DIETMAIER_BASE, DIETMAIER_PLATFORM, DIETMAIER_LENGTHS)
    assert ref.complete and len(ref.poses) == 40
    M = pin.SE3(pin.exp3(np.array([0.3, -0.2, 0.5])), np.array([100.0, -50.0, 20.0]))
    base = 1000.0 * (DIETMAIER_BASE @ M.rotation.T + M.translation)
    moved = stewart_gough_postures(base, 1000.0 * DIETMAIER_PLATFORM,
                                   1000.0 * DIETMAIER_LENGTHS, seed=5)
    assert moved.complete and len(moved.poses) == 40
    want = np.array(sorted(tuple(np.round(1000.0 * (M * p).translation, 4)) for p in ref.poses))
    got = np.array(sorted(tuple(np.round(p.translation, 4)) for p in moved.poses))
    np.testing.assert_allclose(got, want, atol=2e-3)


def test_dietmaier_fk_from_nearby_guesses(platform, postures):
    """FK from a guess 1 cm / 1° away from each well-conditioned posture (type II index
    ≥ 3e-3: condition of A up to a few hundred) converges to that posture by direct
    Newton."""
    rng = np.random.default_rng(0)
    tried = 0
    for a in postures:
        w, v = rng.normal(size=3), rng.normal(size=3)
        if platform.analyze(a).indices["type_II"] < 3e-3:
            continue
        tried += 1
        w *= np.radians(1.0) / np.linalg.norm(w)
        v *= 0.01 / np.linalg.norm(v)
        guess = platform.assemble(pin.SE3(pin.exp3(w) @ a.pose.rotation,
                                          a.pose.translation + v), a)
        b = platform.forward_kinematics(DIETMAIER_LENGTHS, guess)
        e = pin.log6(b.pose.actInv(a.pose)).vector
        assert np.max(np.abs(e)) < 1e-9
        assert b.residual <= 1e-12
    assert tried >= 25


def test_distance_legs_recognised():
    """The 6-UPS models are distance constraints; the planar and 3-leg ones are not."""
    g = distance_legs(mech("stewart"))
    assert g is not None
    home = mech("stewart").home_assembly
    np.testing.assert_allclose(g.lengths(home.q_actuated), home.q_actuated, atol=1e-12)
    for name in ("rpr3", "rrr3", "rps3", "delta"):
        assert distance_legs(mech(name)) is None


def test_stewart_modes_complete_within_limits():
    """The shipped 6-UPS at home lengths: 8 real postures, 4 within the joint limits
    (the mirror images need U-joint angles beyond ±90°), proven complete, home first."""
    m = mech("stewart")
    qa = m.home_assembly.q_actuated
    modes = m.forward_kinematics_all(qa)
    assert modes.complete and modes.counts["real"] == 8
    assert len(modes) == 4 and modes.counts["outside_limits"] == 4
    L = m.characteristic_length
    e = pin.log6(modes[0].pose.actInv(m.home_assembly.pose)).vector
    assert np.max(np.abs(np.r_[e[:3] / L, e[3:]])) < 1e-10
    for a in modes:
        np.testing.assert_allclose(a.q_actuated, qa, atol=1e-12)
        assert a.residual <= 1e-12


def test_unreachable_targets_raise():
    """A 6-UPS target no posture reaches raises (proven by the homotopy), as does a
    3-RPS one (multistart, not proven); both say so, and quickly."""
    m = mech("stewart")
    far = m.home_assembly.q_actuated.copy()
    far[0] = 0.95 * m.legs[0]._bounds[1][2]
    far[1] = 0.35 * m.legs[1]._bounds[1][2]
    with pytest.raises(ForwardKinematicsError, match="unreachable.*proven"):
        m.forward_kinematics_all(far)
    r = mech("rps3")
    qa = r.home_assembly.q_actuated.copy()
    lo, up = r.legs[0]._bounds
    k = int(np.atleast_1d(r.legs[0].actuated_q)[0])
    qa[0], qa[1] = up[k], lo[k]
    with pytest.raises(ForwardKinematicsError, match="not proven"):
        r.forward_kinematics_all(qa)
    with pytest.raises(InputError):
        mech("rps3").forward_kinematics_all(qa, method="homotopy")


@pytest.mark.parametrize("name,count", [("rrr3", 2), ("rps3", 4), ("orthoglide_quasi", 2)])
def test_multistart_modes_at_home(name, count):
    """Multistart at home: the known number of modes, each valid and distinct, the home
    pose first, not claimed complete; the same seed gives the same list."""
    m = mech(name)
    qa = m.home_assembly.q_actuated
    modes = m.forward_kinematics_all(qa)
    assert modes.method == "multistart" and not modes.complete
    assert len(modes) == count
    L = m.characteristic_length
    e = pin.log6(modes[0].pose.actInv(m.home_assembly.pose)).vector
    assert np.max(np.abs(np.r_[e[:3] / L, e[3:]])) < 1e-9
    for a in modes:
        np.testing.assert_allclose(a.q_actuated, qa, atol=1e-10 * max(1.0, L))
        assert a.residual <= 1e-12
        assert all(leg.within_limits(q) for leg, q in zip(m.legs, a.leg_q))
    again = m.forward_kinematics_all(qa)
    for a, b in zip(modes, again):
        np.testing.assert_allclose(a.pose.homogeneous, b.pose.homogeneous, atol=1e-12)
