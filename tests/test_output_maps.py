"""Statics, ellipsoids and singular directions written once (pkm_pin.output_maps) for
both backends: the per-leg engine's Analysis and the general elimination's
LinkageAnalysis give the same machine the same efforts and ellipsoids, and on linkages
that have no legs the answers are checked by virtual work and against the forward
velocity map (issue 24: every capability on every mechanism)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from linkage_models import four_bar, four_bar_dead_centre

import pkm_pin
from pkm_pin import screws
from pkm_pin.errors import InputError, SingularityError
from pkm_pin.linkage import Linkage

MODELS = Path(__file__).resolve().parents[1] / "models"
DETECTED = ["loops/four_bar.urdf", "loops/delta_loops.urdf", "loops/five_bar.xml"]


def _random_motion(an, rng):
    """Random actuated rates and the output twist they give."""
    qd = rng.normal(size=an.A.shape[0])
    return qd, an.forward_velocity(qd)


@pytest.mark.parametrize("name", DETECTED)
def test_both_backends_give_the_machine_the_same_statics_and_ellipsoids(name):
    """Actuator efforts agree to 1e-9 between the general elimination and the legs
    engine, each balancing the wrench with its actuation and constraint wrenches; with
    the legs' characteristic length the homogenised ellipsoids agree too (their
    semi-axes are in units of L)."""
    general = pkm_pin.load_mechanism(MODELS / name, backend="general")
    legs = pkm_pin.load_mechanism(MODELS / name, backend="legs")
    ga, la = general.home_analysis, legs.home_analysis
    rng = np.random.default_rng(3)
    for _ in range(3):
        w = rng.normal(size=6)
        np.testing.assert_allclose(ga.actuator_efforts(w), la.actuator_efforts(w),
                                   rtol=1e-9, atol=1e-12)
        for an in (ga, la):  # w = Aᵀ λ + Cᵀ μ in each (the split depends on A's rows)
            lam = an.actuator_efforts(w) / np.diag(an.B)
            np.testing.assert_allclose(lam @ an.A + an.constraint_forces(w)
                                       @ an.constraint_wrenches, w, atol=1e-9)
    same_length = Linkage(dataclasses.replace(general.model,
                                              length=legs.characteristic_length))
    sa = same_length.analyze(general.home_assembly.q)
    for g, l in ((sa.velocity_ellipsoid(), la.velocity_ellipsoid()),
                 (sa.force_ellipsoid(), la.force_ellipsoid())):
        np.testing.assert_allclose(g.semi_axes, l.semi_axes, rtol=1e-9)


@pytest.mark.parametrize("name", ["loops/cassie_knee.urdf", "loops/five_bar.urdf",
                                  "loops/four_bar.urdf"])
def test_linkage_efforts_do_the_virtual_work_of_the_wrench(name):
    """For every motion, τ · q̇_a = w ∘ t (t the output twist of q̇_a): the efforts of
    a linkage that has no legs (Cassie's knee, the five-bar's point output)."""
    an = pkm_pin.load_mechanism(MODELS / name, backend="general").home_analysis
    rng = np.random.default_rng(7)
    for _ in range(4):
        w = rng.normal(size=6)
        tau = an.actuator_efforts(w)
        qd, t = _random_motion(an, rng)
        assert tau @ qd == pytest.approx(screws.reciprocal_product(w, t), rel=1e-8, abs=1e-12)


@pytest.mark.parametrize("name", ["loops/cassie_knee.urdf", "loops/five_bar.urdf",
                                  "loops/delta_loops.urdf"])
def test_linkage_velocity_ellipsoid_is_the_forward_map(name):
    """Semi-axes: the singular values of the forward map from homogenised actuated rates
    (prismatic / L) to homogenised output twists about the centre, computed column by
    column with forward_velocity; the force ellipsoid's are their inverses."""
    an = pkm_pin.load_mechanism(MODELS / name, backend="general").home_analysis
    L, n = an.length, an.A.shape[0]
    scale = np.where(an.actuated_prismatic, L, 1.0)
    T = np.column_stack([screws.homogenised_about(an.forward_velocity(np.eye(n)[j] * scale[j])
                                                  [None], an.centre, L)[0]
                         for j in range(n)])
    sv = np.linalg.svd(T, compute_uv=False)
    vel, force = an.velocity_ellipsoid(), an.force_ellipsoid()
    np.testing.assert_allclose(vel.semi_axes, sv, rtol=1e-9)
    np.testing.assert_allclose(force.semi_axes, 1.0 / sv[::-1], rtol=1e-9)
    for axis, s in zip(vel.axes, vel.semi_axes):  # each axis a unit output twist
        h = screws.homogenised_about(axis[None], an.centre, L)[0]
        assert np.linalg.norm(h) == pytest.approx(1.0, rel=1e-9)
        assert an._contains(axis)


def test_singular_directions_of_a_linkage_off_its_dead_centre():
    """1e-8 rad off the four-bar's extended dead centre: driven from the rocker (class
    II) the efforts and ellipsoids refuse, the uncontrolled twist is the crank's own
    rotation and the couple about the crank's pivot is not resisted; driven from the
    crank (class I) the lost actuated rate is the crank's."""
    theta2, dead = four_bar_dead_centre()
    crank_driven = Linkage(four_bar())
    rocker_driven = Linkage(four_bar(actuated=("rocker",), output="crank_body"))
    a = crank_driven.forward_kinematics([theta2 - 1e-8], dead + [0, 0.01, 0], starts=0)
    an, dn = crank_driven.analyze(a.q), rocker_driven.analyze(a.q)
    assert an.singularity == "I" and dn.singularity == "II"
    np.testing.assert_array_equal(an.lost_actuated_rates, [1.0])
    assert dn.lost_actuated_rates is None and an.uncontrolled_twist is None
    with pytest.raises(SingularityError, match="actuator efforts undefined"):
        dn.actuator_efforts(np.r_[0, 0, 0, 0, 0, 1.0])
    with pytest.raises(SingularityError, match="ellipsoids undefined"):
        dn.velocity_ellipsoid()
    # Compared as projectors onto the lines they span (sign-free), never as the vectors
    # an SVD happens to return: here the unit rows [A; C] are orthonormal (six equal
    # singular values; the singularity is in B), so no order of them may decide.
    def line(v):
        return np.outer(v, v) / (v @ v)

    H = screws.normalised_rows(screws.about(dn.full_jacobian, dn.centre), dn.length)
    np.testing.assert_allclose(np.linalg.svd(H, compute_uv=False), 1.0, atol=1e-9)
    t = dn.uncontrolled_twist
    crank_axis = dn.platform_twists[0]
    th, ch = (screws.homogenised_about(x[None], dn.centre, dn.length)[0]
              for x in (t, crank_axis))
    np.testing.assert_allclose(line(th), line(ch), atol=1e-9)
    assert np.linalg.norm(th) == pytest.approx(1.0, rel=1e-9)
    w = dn.unresisted_wrench  # the couple about the crank's pivot axis z, unit / L
    np.testing.assert_allclose(line(w), np.diag([0.0] * 5 + [1.0]), atol=1e-9)
    np.testing.assert_allclose(w[:5], 0.0, atol=1e-9)
    assert abs(w[5]) == pytest.approx(dn.length, rel=1e-9)
    assert abs(screws.reciprocal_product(w, t)) == pytest.approx(dn.length, rel=1e-9)
    wh = screws.homogenised_about(w[None], dn.centre, dn.length)[0]
    C = screws.normalised_rows(screws.about(dn.constraint_wrenches, dn.centre), dn.length)
    np.testing.assert_allclose(C @ wh, 0.0, atol=1e-9)  # none of it is a constraint's


def test_underactuated_output_refuses_ellipsoids_in_a_sentence():
    """The rigid-body four-bar output of a linkage with no actuator: no ellipsoid."""
    link = Linkage(four_bar(actuated=()))
    with pytest.raises(InputError, match="as many actuators as degrees of freedom"):
        link.home_analysis.velocity_ellipsoid()
