"""Generic sensitivity to URDF parameters: names, selection, finite differences, compatibility."""

from __future__ import annotations

import numpy as np
import pytest

from pkm_pin import InputError, PkmError, screws
from pkm_pin.builders import delta, orthoglide_quasi, rps3, stewart
from pkm_pin.mechanism import Assembly, Mechanism
from pkm_pin.sensitivity import (
    parameter_names,
    perturb,
    select_parameters,
    sensitivity,
)

#: Step of the central differences (the FK is solved to 1e-12; truncation ~ EPS²).
EPS = 1e-5
#: Accepted |analytic − finite difference| per column entry (observed ≤ 2e-10).
FD_TOL = 1e-8


@pytest.fixture(scope="module")
def ortho():
    """Quasi-orthogonal Orthoglide at a random (seeded) assembly away from home."""
    mech = orthoglide_quasi().build()
    rng = np.random.default_rng(11)
    qa = mech.home_assembly.q_actuated + rng.uniform(-0.1, 0.1, 3)
    return mech, mech.forward_kinematics(qa)


def _finite_difference(mech, assembly, name: str) -> np.ndarray:
    """Central difference of the platform twist for one parameter, FK at fixed q_a."""
    out = []
    for sign in (1.0, -1.0):
        m2 = perturb(mech, {name: sign * EPS})
        guess = Assembly(m2, assembly.pose, [q.copy() for q in assembly.leg_q])
        b = m2.forward_kinematics(assembly.q_actuated, guess)
        out.append(screws.log(b.pose * assembly.pose.inverse()))
    return (out[0] - out[1]) / (2 * EPS)


# ====================================================================== names
def test_parameter_names_cover_origins_axes_bases_and_anchors(ortho):
    """Names of the issue exist; axis components parallel to the axis are left out."""
    names = parameter_names(ortho[0])
    for n in ("legx/Pa2/origin.x", "legx/Pa2/origin.roll", "legx/R1/axis.rx", "legx/base.y",
              "legx/anchor.yaw", "legz/tip_fixed/origin.pitch", "legy/P/axis.ry"):
        assert n in names
    assert "legx/R1/axis.rz" not in names  # R1 turns about z
    # per leg: base 6, six joints (tip_fixed included) × 6 origin components, axes: 3 for
    # the tilted (unaligned) P, 2 for each of R1, Pa1, Pa2, R2; anchor 6
    assert len(names) == len(set(names)) == 3 * (6 + 6 * 6 + (3 + 4 * 2) + 6)


def test_selection_by_name_prefix_and_glob(ortho):
    """Selection keeps pattern order, accepts prefixes and globs, and rejects unknown names."""
    mech = ortho[0]
    assert select_parameters(mech, "legx/R1/axis") == ["legx/R1/axis.rx", "legx/R1/axis.ry"]
    assert select_parameters(mech, ["legz/base.x", "*/Pa2/origin.x"]) == [
        "legz/base.x", "legx/Pa2/origin.x", "legy/Pa2/origin.x", "legz/Pa2/origin.x"]
    assert len(select_parameters(mech, "legy")) == len(parameter_names(mech)) // 3
    with pytest.raises(InputError, match="no parameter matches"):
        select_parameters(mech, "legx/R9/origin.x")


# ======================================================== finite differences
def test_every_compatible_orthoglide_parameter_matches_finite_differences(ortho):
    """All 6 × n columns of the compatible parameters equal central differences of the FK."""
    mech, a = ortho
    sens = sensitivity(mech, a)
    names = [n for n in sens.parameters if n not in sens.incompatible]
    assert len(names) == 102
    worst = max(np.max(np.abs(_finite_difference(mech, a, n) - sens.column(n))) for n in names)
    assert worst < FD_TOL


@pytest.mark.parametrize("build", [stewart, delta, rps3], ids=["stewart", "delta", "rps3"])
def test_other_mechanisms_match_finite_differences(build):
    """Random parameters of a 6-UPS, a Delta and a 3-RPS (curved 1T2R) match central differences."""
    mech = build().build()
    rng = np.random.default_rng(12)
    qa = mech.home_assembly.q_actuated + rng.uniform(-0.02, 0.02, mech.n_actuated)
    a = mech.forward_kinematics(qa)
    sens = sensitivity(mech, a)
    names = [n for n in sens.parameters if n not in sens.incompatible]
    for k in rng.choice(len(names), 10, replace=False):
        fd = _finite_difference(mech, a, names[k])
        assert np.max(np.abs(fd - sens.column(names[k]))) < FD_TOL, names[k]


# ================================================================ compatibility
def test_non_overconstrained_stewart_has_no_incompatible_parameter():
    """Every URDF parameter error of the 6-UPS platform is absorbed (residual below 1e-12)."""
    mech = stewart().build()
    sens = sensitivity(mech)
    assert sens.incompatible == []
    assert np.max(sens.compatibility) < 1e-12


def test_orthoglide_tilting_a_revolute_is_incompatible(ortho):
    """Tilting R1 out of parallel with R2 cannot be absorbed; a finite such error does not move."""
    mech, a = ortho
    sens = sensitivity(mech, a, ["legx/R1/axis", "legx/P/axis", "legx/Pa2/origin.x"])
    assert sens.incompatible == ["legx/R1/axis.rx", "legx/R1/axis.ry"]
    assert np.all(sens.compatibility[2:] < 1e-12)
    bad = perturb(mech, {"legx/R1/axis.rx": 1e-3})
    with pytest.raises(PkmError):
        bad.forward_kinematics(a.q_actuated + 0.05)


def test_rotation_about_the_leg_revolute_has_no_effect(ortho):
    """A yaw error of the tip frame (about R2's axis) changes nothing: a zero column."""
    mech, a = ortho
    sens = sensitivity(mech, a, "legx/tip_fixed/origin.yaw")
    assert np.max(np.abs(sens.matrix)) < 1e-12
    assert sens.incompatible == []


# =================================================================== plumbing
def test_perturb_edits_urdf_base_and_anchor(ortho):
    """perturb() changes the URDF origin, the base and the anchor by the given amounts."""
    mech, _ = ortho
    m2 = perturb(mech, {"legy/Pa2/origin.x": 0.01, "legy/base.z": 0.02, "legz/anchor.x": -0.03})
    assert np.isclose(m2.legs[1].model.jointPlacements[4].translation[0],
                      mech.legs[1].model.jointPlacements[4].translation[0] + 0.01, atol=1e-15)
    assert np.allclose(m2.legs[1].base.translation - mech.legs[1].base.translation, [0, 0, 0.02])
    assert np.allclose(m2.anchors[2].translation - mech.anchors[2].translation, [-0.03, 0, 0])
    assert m2.legs[0] is mech.legs[0]


def test_method_defaults_to_home_and_matches_the_function(ortho):
    """Mechanism.sensitivity(mech) is the function at the home assembly."""
    mech, _ = ortho
    a = Mechanism.sensitivity(mech, parameters="legx/P")
    b = sensitivity(mech, mech.home_assembly, "legx/P")
    assert a.parameters == b.parameters and np.allclose(a.matrix, b.matrix, atol=0)


def test_length_columns_are_unit_invariant():
    """In millimetres, length columns are unchanged and angle columns' linear rows scale by 1000."""
    m, mm = orthoglide_quasi().build(), orthoglide_quasi(scale=1000.0).build()
    names = ["legx/Pa2/origin.x", "legy/P/origin.z", "legz/P/axis.ry"]
    s, smm = sensitivity(m, parameters=names), sensitivity(mm, parameters=names)
    assert np.allclose(smm.matrix[:, :2], s.matrix[:, :2], atol=1e-12)
    assert np.allclose(smm.matrix[3:, 2], 1000 * s.matrix[3:, 2], rtol=1e-9, atol=1e-9)
