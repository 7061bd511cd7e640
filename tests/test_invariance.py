"""Answers that do not depend on where the world origin is, nor on how joint frames are
written (issue 17, items 1 and 2).

* Every shipped mechanism moved 100 m and turned arbitrarily has the same DOF, motion
  type, class and indices, its actuation wrenches are the moved ones (covariant rows of
  A), B is the same, and forward kinematics gives the moved pose; its reading as a
  general linkage (one tree plus closures) gives the same indices too.
* The agile eye written with every joint frame at the centre (three concurrent
  revolutes, one actuated: not a spherical joint) equals the one written with offset
  frames, and both are isotropic at home.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest

from pkm_pin import screws
from pkm_pin.builders import MECHANISMS
from pkm_pin.builders.spatial import agile_eye
from pkm_pin.linkage import Linkage
from pkm_pin.model.closure_model import configuration, from_mechanism

#: A rigid motion of the whole mechanism: 100 m away, turned about a skew axis.
MOVE = pin.SE3(pin.rpy.rpyToMatrix(0.7, -1.1, 2.3), np.array([100.0, -60.0, 75.0]))


def moved(design, M: pin.SE3 = MOVE):
    """The design with every leg base and the home pose moved by ``M`` (the anchors, the
    tip frames in the platform frame, are unchanged)."""
    legs = [replace(leg, base=M * leg.base) for leg in design.legs]
    return replace(design, legs=legs, home=M * design.home)


def same_span(X, Y, L: float) -> bool:
    """Rows of X and Y (screws about one point) span the same space, decided on the
    homogenised rows' projectors."""
    if X.shape != Y.shape:
        return False
    if not len(X):
        return True
    Qx = np.linalg.qr(screws.homogenise(np.atleast_2d(X), L).T)[0]
    Qy = np.linalg.qr(screws.homogenise(np.atleast_2d(Y), L).T)[0]
    return np.allclose(Qx @ Qx.T, Qy @ Qy.T, atol=1e-8)


def poses(mech, n: int = 3, size: float = 0.03) -> list[pin.SE3]:
    """Home and the poses of forward kinematics at actuated values near home's (on the
    motion manifold, parasitic motions included)."""
    q0 = mech.home_assembly.q_actuated
    rng = np.random.default_rng(1)
    scales = mech.actuated_scales
    return [mech.home] + [mech.forward_kinematics(q0 + size * scales * rng.normal(size=len(q0))
                                                  ).pose for _ in range(n - 1)]


@pytest.fixture(scope="module", params=sorted(MECHANISMS))
def pair(request):
    design = MECHANISMS[request.param]()
    return design.build(), moved(design).build()


def test_indices_classes_and_jacobians_do_not_depend_on_the_world_frame(pair):
    mech, far = pair
    for pose in poses(mech):
        a = mech.analyze(mech.assemble(pose))
        b = far.analyze(far.assemble(MOVE * pose))
        assert (b.dof, b.motion_type, b.redundant_constraints, b.singularity) == (
            a.dof, a.motion_type, a.redundant_constraints, a.singularity)
        for key, value in a.indices.items():
            assert b.indices[key] == pytest.approx(value, rel=1e-8, abs=1e-12), key
        L = mech.characteristic_length
        # covariant actuation wrenches: the moved mechanism's rows are the moved rows
        np.testing.assert_allclose(b.A, screws.transform(a.A, MOVE), atol=1e-8 * max(1, L))
        np.testing.assert_allclose(b.B, a.B, atol=1e-9 * L)
        # the twist and wrench systems move with the mechanism
        about = pin.SE3(np.eye(3), -b.centre)
        for X, Y in ((b.platform_twists, a.platform_twists),
                     (b.constraint_wrenches, a.constraint_wrenches)):
            assert same_span(screws.transform(X, about),
                             screws.transform(screws.transform(Y, MOVE), about), L)
        assert b.constraint_singular == a.constraint_singular


def test_sweep_indices_do_not_depend_on_the_world_frame(pair):
    mech, far = pair
    P = poses(mech, n=4)
    r, s = mech.sweep(P), far.sweep([MOVE * p for p in P])
    assert r.ok.all() and s.ok.all()
    np.testing.assert_array_equal(r.singularity, s.singularity)
    for key in ("type_I", "type_II"):
        np.testing.assert_allclose(getattr(s, key), getattr(r, key), rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(s.det, r.det, rtol=1e-7, atol=1e-12)


def test_forward_kinematics_does_not_depend_on_the_world_frame(pair):
    mech, far = pair
    pose = poses(mech, n=2)[1]
    q = mech.assemble(pose).q_actuated
    a = mech.forward_kinematics(q)
    b = far.forward_kinematics(q)
    L = mech.characteristic_length
    np.testing.assert_allclose((MOVE * a.pose).homogeneous, b.pose.homogeneous,
                               atol=1e-8 * max(1.0, L))


def test_linkage_indices_do_not_depend_on_the_world_frame(pair):
    """The general-linkage reading of a shipped mechanism (its tree plus one weld per leg)
    gives the same seed-000 and general indices, DOF and class for the mechanism moved
    100 m and turned, at home and at three poses of forward kinematics."""
    mech, far = pair
    link, link_far = Linkage(from_mechanism(mech)), Linkage(from_mechanism(far))
    for pose in poses(mech, n=4):
        a = link.analyze(configuration(mech, mech.assemble(pose)))
        b = link_far.analyze(configuration(far, far.assemble(MOVE * pose)))
        assert (b.dof, b.output_dof, b.singularity) == (a.dof, a.output_dof, a.singularity)
        for key in ("type_I", "type_II", "condition_A", "forward", "inverse"):
            assert b.indices[key] == pytest.approx(a.indices[key], rel=1e-8, abs=1e-12), key


# ------------------------------------------------------------------------ agile eye
@pytest.fixture(scope="module")
def eyes():
    return agile_eye(centred=True).build(), agile_eye(centred=False).build()


def test_concurrent_revolutes_with_an_actuated_one_are_not_a_spherical_joint(eyes):
    centred, offset = eyes
    assert all(leg.spherical_groups == [] for leg in centred.legs + offset.legs)


def test_agile_eye_is_isotropic_at_home_whichever_way_its_frames_are_written(eyes):
    for mech in eyes:
        an = mech.home_analysis
        assert (an.motion_type, an.singularity) == ("3R", "none")
        # unit couples along the base axes, B = I: the isotropic home
        np.testing.assert_allclose(an.A, np.c_[np.zeros((3, 3)), np.eye(3)], atol=1e-12)
        np.testing.assert_allclose(an.B, np.eye(3), atol=1e-12)
        assert an.indices["condition_A"] == pytest.approx(1.0, abs=1e-12)


def test_agile_eye_centred_frames_equal_offset_frames_away_from_home(eyes):
    centred, offset = eyes
    for q in ([0.3, -0.2, 0.5], [-0.6, 0.4, 0.1]):
        a = centred.forward_kinematics(q)
        b = offset.forward_kinematics(q)
        np.testing.assert_allclose(a.pose.homogeneous, b.pose.homogeneous, atol=1e-10)
        x, y = centred.analyze(a), offset.analyze(b)
        assert (x.motion_type, x.singularity) == (y.motion_type, y.singularity) == ("3R", "none")
        np.testing.assert_allclose(x.A, y.A, atol=1e-10)
        np.testing.assert_allclose(x.B, y.B, atol=1e-10)
        for key in x.indices:
            assert x.indices[key] == pytest.approx(y.indices[key], rel=1e-9)
        # forward velocity against finite differences of forward kinematics
        h = 1e-6
        for k in range(3):
            dq = np.zeros(3)
            dq[k] = h
            p, m = offset.forward_kinematics(np.add(q, dq), b), offset.forward_kinematics(
                np.subtract(q, dq), b)
            fd = screws.from_pinocchio(pin.log6(p.pose * m.pose.inverse()).vector) / (2 * h)
            np.testing.assert_allclose(y.forward_velocity(dq / h), fd, atol=1e-7)


def test_sensitivity_does_not_depend_on_the_world_frame():
    """The pose error per parameter error of the moved Stewart platform is the moved one
    (a twist about the world origin, transformed), its compatibility the same. (The base
    placements' parameters are increments of world coordinates: they are not the same
    errors once the world is turned, so they are left out.)"""
    design = MECHANISMS["stewart"]()
    mech, far = design.build(), moved(design).build()
    a, b = mech.sensitivity(), far.sensitivity()
    assert a.parameters == b.parameters
    keep = ["/base." not in name for name in a.parameters]
    L = mech.characteristic_length
    np.testing.assert_allclose(b.matrix[:, keep], (screws.adjoint(MOVE) @ a.matrix)[:, keep],
                               atol=1e-7 * L)
    np.testing.assert_allclose(b.compatibility, a.compatibility, atol=1e-9)


def test_serial_index_does_not_depend_on_the_world_frame(ur5):
    """A serial arm's singularity index and inverse velocity: the same for the arm moved
    100 m and turned (its Jacobian homogenised about the tip point)."""
    far = replace(ur5, base=MOVE * ur5.base)
    for q in ([0.3, -1.2, 1.4, -0.6, 0.8, 0.7], [0.1, -0.4, 0.9, 0.2, 0.05, -0.3]):
        assert far.serial_singularity_index(q) == pytest.approx(
            ur5.serial_singularity_index(q), rel=1e-9)
        V = ur5.serial_jacobian(q) @ np.arange(1.0, 7.0)
        np.testing.assert_allclose(far.serial_inverse_velocity(q, screws.transform(V, MOVE)),
                                   ur5.serial_inverse_velocity(q, V), atol=1e-8)
