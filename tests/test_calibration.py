"""Calibration: errors injected into the quasi-orthogonal Orthoglide are recovered."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from pkm_pin import InputError
from pkm_pin.builders import orthoglide_quasi
from pkm_pin.calibration import calibrate, identifiable
from pkm_pin.sensitivity import perturb

#: The paper's parameters: L_i (bar length), phi_i (axis tilt, minus P/axis.ry), dd_i.
PAPER = [f"leg{a}/{p}" for a in "xyz" for p in ("Pa2/origin.x", "P/axis.ry", "P/origin.z")]
#: Same effect as legx/P/origin.z (shift along the same direction), a zero column, and an
#: error the overconstrained machine cannot absorb.
EXTRA = ["legx/R1/origin.z", "legx/tip_fixed/origin.yaw", "legx/R1/axis.rx"]


@pytest.fixture(scope="module")
def setup():
    """Nominal model, true errors, the true machine and 25 seeded sample actuations."""
    mech = orthoglide_quasi().build()
    rng = np.random.default_rng(21)
    true = {n: float(rng.normal(0.0, 2e-3)) for n in PAPER}
    truth = perturb(mech, true)
    home = mech.home_assembly.q_actuated
    qs = [home + rng.uniform(-0.2, 0.2, 3) for _ in range(25)]
    poses = [truth.forward_kinematics(q).pose for q in qs]
    return mech, true, qs, poses, rng


def test_errors_are_recovered_from_noisy_positions(setup):
    """With 1 µm position noise the 9 paper parameters come back within 4σ; σ is small."""
    mech, true, qs, poses, _ = setup
    rng = np.random.default_rng(22)
    samples = [(q, p.translation + rng.normal(0.0, 1e-6, 3)) for q, p in zip(qs, poses)]
    res = calibrate(mech, samples, PAPER + EXTRA)
    assert res.converged
    assert res.parameters == PAPER
    assert res.unidentifiable == ["legx/R1/origin.z", "legx/tip_fixed/origin.yaw"]
    assert res.incompatible == ["legx/R1/axis.rx"]
    for n in PAPER:
        assert abs(res.errors[n] - true[n]) < 4 * res.std[n], n
        assert res.std[n] < 1e-4
    assert res.residual_before > 1e-3
    assert res.residual_after < 3e-6  # ≈ √3 µm of noise


def test_noise_free_full_poses_are_fitted_exactly(setup):
    """Exact pose measurements (SE3) give the injected errors to 1e-9 and a zero residual."""
    mech, true, qs, poses, _ = setup
    res = calibrate(mech, list(zip(qs, poses)), PAPER)
    for n in PAPER:
        assert abs(res.errors[n] - true[n]) < 1e-9, n
    assert res.residual_after < 1e-10


def test_identifiable_keeps_the_first_of_dependent_columns():
    """Gram–Schmidt in column order drops zero columns and later dependent ones."""
    J = np.array([[1.0, 2.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0], [1.0, 2.0, 0.0, 1.0]])
    assert identifiable(J).tolist() == [True, False, False, True]


def test_malformed_samples_are_rejected(setup):
    """A sample that is not a pair or has the wrong number of actuated values is an InputError."""
    mech = setup[0]
    with pytest.raises(InputError):
        calibrate(mech, [np.zeros(3)], PAPER)
    with pytest.raises(InputError):
        calibrate(mech, [(np.zeros(2), pin.SE3.Identity())], PAPER)
    with pytest.raises(InputError):
        calibrate(mech, [], PAPER)
