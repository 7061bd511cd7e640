"""The compiled inverse kinematics of output-driven motions (pkm_pin.output_kernel)
against the Python reference (trajectory._OutputDriver.position_reference) and
Pinocchio (issue 26)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from test_trajectory import ROOT, _output_case, model

import pkm_pin
from pkm_pin import output_kernel as ok
from pkm_pin import trajectory as tr
from pkm_pin import tree_kernel as tk
from pkm_pin.builders import MECHANISMS


def _cassie_case():
    """The Cassie-like knee's output driven by z (rising 4 cm) and pitch (±0.1 rad)."""
    cm, q0 = model("cassie_knee")
    c0 = tr._OutputCoordinates(cm).values(q0)
    t = np.linspace(0.0, 2.0, 21)
    V = np.c_[c0[2] + 0.02 * (1 - np.cos(np.pi * t)), c0[4] + 0.1 * np.sin(np.pi * t)]
    return cm, q0, tr.OutputMotion(t, V, ("z", "pitch"))


def _stewart_pose_case():
    """The Stewart driven by its full 6D output pose (every coordinate moving)."""
    cm, q0 = tr.closure_model_of(MECHANISMS["stewart"]().build())
    c0 = tr._OutputCoordinates(cm).values(q0)
    t = np.linspace(0.0, 2.0, 21)
    s = np.sin(np.pi * t)[:, None]
    return cm, q0, tr.OutputMotion(t, c0 + s * np.array([0.02, -0.01, 0.03, 0.05, -0.04,
                                                         0.1]))


def _five_bar_case():
    """models/loops/five_bar.urdf's output driven by x, y (1 cm sweeps)."""
    link = pkm_pin.load_mechanism(ROOT / "models/loops/five_bar.urdf")
    cm, q0 = link.model, link.home_assembly.q
    c0 = tr._OutputCoordinates(cm).values(q0)
    t = np.linspace(0.0, 2.0, 21)
    V = np.c_[c0[0] + 0.01 * np.sin(np.pi * t), c0[1] + 0.01 * (1 - np.cos(np.pi * t))]
    return cm, q0, tr.OutputMotion(t, V, ("x", "y"))


def _case(name):
    if name == "five_bar":
        return _five_bar_case()
    if name == "cassie_knee":
        return _cassie_case()
    if name == "stewart_6d":
        return _stewart_pose_case()
    return _output_case(name)[:3]


@pytest.mark.parametrize("name", ["five_bar", "5bar_linkage", "cassie_knee", "stewart",
                                  "stewart_6d"])
def test_output_rows_match_pinocchio(name):
    """At five perturbed configurations the compiled closure and coordinate rows equal
    the closure model's residual and Jacobian and the reference's coordinates and
    ``K = [J_p; E⁻¹ J_ω]`` (divided by the coordinate units) to 1e-12."""
    cm, q0, _ = _case(name)
    kern = tk.tree_kernel(cm)
    oc = tr._OutputCoordinates(cm)
    sel = np.arange(6, dtype=np.int64)
    scales = oc.scales.copy()
    rng = np.random.default_rng(3)
    n0 = len(cm.closure_residual(q0))
    for _ in range(5):
        q = pin.integrate(cm.tree, q0, 0.05 * rng.standard_normal(cm.nv))
        c_ref, K = oc.rates(q)
        target = c_ref + 0.01 * rng.standard_normal(6)
        e, H, c = np.empty(n0 + 6), np.empty((n0 + 6, cm.nv)), np.empty(6)
        ok.output_rows_compiled(kern, q, sel, target, scales, e, H, c)
        assert np.allclose(c, c_ref, rtol=0, atol=1e-12)
        assert np.allclose(e[:n0], cm.closure_residual(q), rtol=0, atol=1e-12)
        assert np.allclose(H[:n0], cm.closure_jacobian(q), rtol=0, atol=1e-12)
        assert np.allclose(e[n0:], tr.coordinate_errors_of(c_ref, target, sel) / scales,
                           rtol=0, atol=1e-12)
        assert np.allclose(H[n0:], K / scales[:, None], rtol=0, atol=1e-12)


def test_rpy_matches_pinocchio_on_both_branches():
    """matrix_to_rpy equals pin.rpy.matrixToRpy on random rotations and at pitch
    5e-4 and 1e-6 from ±π/2 (roll and yaw still apart) to 1e-9."""
    rng = np.random.default_rng(0)
    rots = [pin.rpy.rpyToMatrix(*rng.uniform(-3, 3, 3)) for _ in range(20)]
    rots += [pin.rpy.rpyToMatrix(0.3, s * (np.pi / 2 - d), -0.7) for s in (1, -1)
             for d in (5e-4, 1e-6)]
    out = np.empty(3)
    for R in rots:
        ok.matrix_to_rpy(R, out)
        assert np.allclose(out, pin.rpy.matrixToRpy(R), rtol=0, atol=1e-9)


@pytest.mark.parametrize("name", ["five_bar", "cassie_knee", "stewart", "stewart_6d", "rps3"])
def test_compiled_output_motion_equals_the_reference(name):
    """The output-driven motion states with the compiled inverse kinematics equal the
    Python reference's (tree_kernel.ENABLED off): q to 1e-9, v and a to 1e-8 of their
    size; every sample closes (1e-10) and meets its coordinates (1e-10)."""
    cm, q0, motion = _case(name)
    t = np.linspace(0.0, 2.0, 11)
    driver = tr._OutputDriver(cm, motion, q0)  # the compiled code ready (not plain calls)
    driver.position(q0, driver.targets(*motion(t[:1]))[0][0], 1e-12, compiled=True)
    try:
        tk.ENABLED = False
        (q1, v1, a1, *_), _ = tr.motion_states(cm, motion, t, q0)
    finally:
        tk.ENABLED = True
    (q2, v2, a2, *_), _ = tr.motion_states(cm, motion, t, q0)
    assert np.abs(q1 - q2).max() <= 1e-9
    assert np.abs(v1 - v2).max() <= 1e-8 * np.abs(v1).max()
    assert np.abs(a1 - a2).max() <= 1e-8 * np.abs(a1).max()
    oc = tr._OutputCoordinates(cm)
    given = [tr.POSE_COORDINATES.index(c) for c in motion.coordinates]
    C = motion(t)[0]
    for i in range(t.size):
        assert np.linalg.norm(cm.closure_residual(q2[i])) < 1e-10
        assert np.abs(tr.coordinate_errors_of(oc.values(q2[i])[given], C[i], given)).max() \
            < 1e-10


def test_idle_motion_model_per_sample_equals_the_reference():
    """The Gepetto 5-bar driven by y, z has an idle motion (its rows [J; K] have rank
    nv − 1), which its dynamics carries from sample to sample, so rounding differences
    of the two drivers grow along it over a trajectory. Per sample, from the same
    guess (the reference's states), both drivers close to the tolerance and land on the
    same configuration: 1e-11 (dimensionless) across the rows' range; along the idle
    direction, which no row fixes, the damped steps' rounding over a small damping moves
    each by ~1e-9, so 1e-8 there; a guess 0.05 off (dimensionless) too."""
    cm, q0, motion = _case("5bar_linkage")
    t = np.linspace(0.0, 2.0, 11)
    try:
        tk.ENABLED = False
        (q, v, a, *_), _ = tr.motion_states(cm, motion, t, q0)
    finally:
        tk.ENABLED = True
    driver = tr._OutputDriver(cm, motion, q0)
    C, _, _ = driver.targets(*motion(t))
    guesses = [pin.integrate(cm.tree, q[i - 1], v[i - 1] * 0.2 + 0.02 * a[i - 1])
               for i in range(1, t.size)]
    guesses.append(pin.integrate(cm.tree, q0, 0.05 * cm.velocity_units))
    for i, guess in zip(list(range(1, t.size)) + [5], guesses):
        qa, ra = driver.position(guess, C[i], 1e-12, compiled=True)
        qb, rb = driver.position(guess, C[i], 1e-12, compiled=False)
        assert ra <= 1e-12 and rb <= 1e-12
        d = pin.difference(cm.tree, qb, qa) / cm.velocity_units
        c, K = driver.oc.rates(qb)
        H = np.vstack([cm.closure_jacobian(qb), K[driver.rows] / driver.oc.scales[
            driver.rows, None]]) * cm.velocity_units
        _, sv, Vt = np.linalg.svd(H)
        rank = int(np.sum(sv > 1e-9 * sv[0]))
        assert rank == cm.nv - 1
        assert np.abs(Vt[:rank] @ d).max() <= 1e-11  # the determined part
        assert np.abs(qa - qb).max() <= 1e-8  # along the idle motion: LM's rounding / λ
