"""Motion/force transmission indices and statics (issue 18): closed forms of the 3-RPR,
the Stewart platform and the five-bar derived here by hand, zeros at the singular poses
the project finds, invariance under units and rigid motions, actuator efforts against
the Plücker-line statics and finite differences of virtual work."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest
from helpers import shipped_mechanisms

from pkm_pin import InputError, SingularityError, screws
from pkm_pin.builders import MECHANISMS, five_bar
from pkm_pin.builders.pinned import elbow_angles
from pkm_pin.builders.planar import rpr3_type2_pose, rrr3_stretched_pose
from pkm_pin.builders.spatial import stewart_default_points, upu3_constraint_singular_pose
from pkm_pin.transmission import (
    local_transmission_index,
    nearest_point,
    output_twists,
    payload_wrench,
    power_coefficient,
    transmission_indices,
)

mechanism = shipped_mechanisms()
DELTA = np.block([[np.zeros((3, 3)), np.eye(3)], [np.eye(3), np.zeros((3, 3))]])
#: A rigid motion of the whole mechanism (as tests/test_invariance.py).
MOVE = pin.SE3(pin.rpy.rpyToMatrix(0.7, -1.1, 2.3), np.array([100.0, -60.0, 75.0]))


def moved(design, M: pin.SE3 = MOVE):
    """The design with every leg base and the home pose moved by ``M``."""
    return replace(design, legs=[replace(leg, base=M * leg.base) for leg in design.legs],
                   home=M * design.home)


def line(p, s):
    """Unit line (s; p × s), by hand."""
    s = np.asarray(s, float) / np.linalg.norm(s)
    return np.r_[s, np.cross(p, s)]


# --------------------------------------------------------------- array functions
def test_power_coefficient_of_a_force_on_a_translation_is_the_cosine():
    """A force against a translation: |cos| of the angle between them, at any point."""
    f, v = np.array([1.0, 2.0, 0.5]), np.array([-0.3, 1.0, 2.0])
    w = np.r_[f, np.cross([3.0, -1.0, 2.0], f)]
    t = np.r_[np.zeros(3), v]
    expected = abs(f @ v) / np.linalg.norm(f) / np.linalg.norm(v)
    for point in ([0, 0, 0], [5.0, 1.0, -2.0]):
        assert power_coefficient(w, t, point, 1.0) == pytest.approx(expected, rel=1e-12)


def test_power_coefficient_of_a_force_on_a_rotation_is_the_pressure_angle_cosine():
    """A force applied at P against a rotation about an axis: |f̂ · v_P| / |v_P| (the
    distance-based normalisation: d_max = distance from P to the axis); a point given
    off the wrench's axis is first projected onto it."""
    P, f = np.array([0.3, 0.4, 0.0]), np.array([np.cos(0.3), np.sin(0.3), 0.0])
    w = line(P, f)
    t = np.r_[[0, 0, 1.0], np.zeros(3)]  # rotation about z through the origin
    vP = np.cross([0, 0, 1.0], P)
    expected = abs(f @ vP) / np.linalg.norm(vP)
    off = P + 0.2 * np.array([-f[1], f[0], 0.0])
    for point in (P, off):
        assert power_coefficient(w, t, point, 1.0) == pytest.approx(expected, rel=1e-12)


def test_power_coefficient_of_a_couple_is_the_cosine_with_the_rotation():
    """A couple against a rotation: |m̂·ω̂|; against a translation: 0."""
    m, omega = np.array([0.0, 1.0, 1.0]), np.array([1.0, 1.0, 0.0])
    w, t = np.r_[np.zeros(3), m], np.r_[omega, [2.0, 0.0, 0.0]]
    assert power_coefficient(w, t, np.zeros(3), 1.0) == pytest.approx(0.5, rel=1e-12)
    assert power_coefficient(w, np.r_[np.zeros(3), omega], np.zeros(3), 1.0) == 0.0


def test_power_coefficient_is_bounded_and_frame_and_scale_invariant():
    """λ ∈ [0, 1] and unchanged by a rigid motion of everything, the scales of the
    screws and the units (lengths × 1000)."""
    rng = np.random.default_rng(3)
    W, T = rng.normal(size=(200, 6)), rng.normal(size=(200, 6))
    P = nearest_point(W, T)[0]
    lam = power_coefficient(W, T, P, 1.0)
    assert np.all((lam >= 0) & (lam <= 1))
    M = pin.SE3(pin.rpy.rpyToMatrix(*rng.normal(size=3)), 50 * rng.normal(size=3))
    X = screws.adjoint(M)
    lam2 = power_coefficient(2.5 * W @ X.T, -0.3 * T @ X.T, P @ M.rotation.T + M.translation,
                             1.0)
    np.testing.assert_allclose(lam2, lam, atol=1e-9)
    k = np.r_[np.ones(3), 1000.0 * np.ones(3)]  # moments and velocities in mm
    np.testing.assert_allclose(power_coefficient(W * k, T * k, 1000 * P, 1000.0), lam,
                               atol=1e-9)


def test_nearest_point_of_intersecting_lines_is_their_intersection():
    """Two lines through a common point: the point and the sine of their angle."""
    X = np.array([0.2, -1.0, 3.0])
    p, sin = nearest_point(line(X, [1, 0, 0]), line(X, [1, 1, 0]))
    np.testing.assert_allclose(p, X, atol=1e-12)
    assert sin == pytest.approx(np.sqrt(0.5))


def test_output_twists_are_reciprocal_to_the_other_wrenches():
    """Each output twist lies in the platform basis and is reciprocal to every other
    actuation wrench (square, and fewer actuators: a zero row, OTI 0)."""
    rng = np.random.default_rng(0)
    A, P = rng.normal(size=(4, 6)), rng.normal(size=(4, 6))
    T = output_twists(A, P, 1.3)
    for i in range(4):
        np.testing.assert_allclose(np.delete(A, i, 0) @ DELTA @ T[i], 0, atol=1e-12)
        coef = np.linalg.lstsq(P.T, T[i], rcond=None)[0]
        np.testing.assert_allclose(P.T @ coef, T[i], atol=1e-12)
    T2 = output_twists(A[:2], P[:3], 1.3)  # 2 actuators, 3 DOF: never controlled
    assert np.all(T2 == 0)
    assert np.isnan(output_twists(A, P[:3], 1.3)).all()  # redundant actuation


# --------------------------------------------------------------------- 3-RPR
def rpr3_lines(pose: pin.SE3, scale: float = 1.0):
    """Actuation wrench lines (point, direction) of the 3-RPR, by hand: legs A and C
    (prismatic) along the leg through the platform pivot; leg B (base revolute) normal
    to the leg through B2 (the design's geometry: pivots on the x axis, platform
    triangle of circumradius 0.4)."""
    base = scale * np.array([[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0]])
    a = np.radians([210.0, 90.0, 330.0])
    plat = scale * 0.4 * np.column_stack([np.cos(a), np.zeros(3), np.sin(a)])
    out = []
    for i in range(3):
        P = pose.act(plat[i])
        d = P - base[i]
        if i == 1:
            d = np.array([-d[2], 0.0, d[0]])
        out.append((P, d / np.linalg.norm(d)))
    return out


def rpr3_oti(pose: pin.SE3, scale: float = 1.0) -> np.ndarray:
    """OTI_i = dist(I_jk, line_i) / |P_i − I_jk|: locking the other two actuators leaves
    the rotation about I_jk, the intersection of their lines (xz-plane)."""
    L = rpr3_lines(pose, scale)
    out = []
    for i in range(3):
        (pj, dj), (pk, dk) = [L[j] for j in range(3) if j != i]
        M = np.array([[dj[0], -dk[0]], [dj[2], -dk[2]]])
        s = np.linalg.solve(M, (pk - pj)[[0, 2]])[0]
        I = pj + s * dj
        P, d = L[i]
        r = P - I
        out.append(abs(r[0] * d[2] - r[2] * d[0]) / np.linalg.norm(r))
    return np.array(out)


def test_rpr3_indices_match_the_hand_derivation():
    """3-RPR: ITI = 1 (prismatic legs push along their lines; the revolute's force is
    normal to its leg at B2), OTI from the intersections of the other lines."""
    mech = mechanism("rpr3")
    for pose in (mech.home, pin.SE3(pin.rpy.rpyToMatrix(0, 0.4, 0), np.array([1.2, 0, 0.9]))):
        tr = mech.analyze(mech.assemble(pose)).transmission
        np.testing.assert_allclose(tr.iti, 1.0, atol=1e-12)
        np.testing.assert_allclose(tr.oti, rpr3_oti(pose), rtol=1e-9)
        assert tr.lti == pytest.approx(min(rpr3_oti(pose).min(), 1.0), rel=1e-9)
        np.testing.assert_allclose(tr.leg_cti, 1.0)  # planar: no leg can lose its plane


def test_rpr3_oti_vanishes_at_its_type_ii_pose():
    """At the type II pose (the three wrench lines concurrent) every OTI is 0; the
    constraints (planar, redundant) still transmit: CTI 1."""
    mech = mechanism("rpr3")
    an = mech.analyze(mech.assemble(rpr3_type2_pose()))
    assert an.singularity in ("II", "III")
    np.testing.assert_allclose(an.transmission.oti, 0.0, atol=1e-8)
    assert an.transmission.lti < 1e-8
    assert "OTI 0.00" in an.transmission.worst
    np.testing.assert_allclose(an.transmission.leg_cti, 1.0)


def test_rrr3_iti_vanishes_at_a_stretched_leg():
    """Type I of the 3-RRR (leg 1 stretched): ITI of leg 1 is 0, the others are not."""
    mech = mechanism("rrr3")
    tr = mech.analyze(mech.assemble(rrr3_stretched_pose())).transmission
    assert tr.iti[0] < 1e-7
    assert tr.iti[1:].min() > 0.1
    assert tr.worst.startswith(f"leg {mech.legs[0].name} transmits poorly: ITI 0.00")


# ------------------------------------------------------------------- Stewart
def stewart_lines(pose: pin.SE3, scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Unit leg lines (6 × 6, rows (s_i; S_i × s_i)) and platform points S_i, by hand."""
    base, plat = stewart_default_points(scale)
    S = np.array([pose.act(p) for p in plat])
    return np.array([line(S[i], S[i] - base[i]) for i in range(6)]), S


def test_stewart_indices_match_the_plucker_lines():
    """Stewart: ITI = 1 (prismatic actuation along the leg); OTI_i = |ŝ_i · v_Si| /
    |v_Si| for the twist t_i with L_j ∘ t_i = δ_ij (only leg i changes length)."""
    mech = mechanism("stewart")
    for pose in (mech.home, pin.SE3(pin.rpy.rpyToMatrix(0.1, -0.05, 0.2),
                                    mech.home.translation + [0.1, -0.05, 0.08])):
        Lines, S = stewart_lines(pose)
        T = np.linalg.inv(Lines @ DELTA)  # columns: t_i
        oti = []
        for i in range(6):
            w, v = T[:3, i], T[3:, i]
            vS = v + np.cross(w, S[i])
            oti.append(abs(Lines[i, :3] @ vS) / np.linalg.norm(vS))
        tr = mech.analyze(mech.assemble(pose)).transmission
        np.testing.assert_allclose(tr.iti, 1.0, atol=1e-12)
        np.testing.assert_allclose(tr.oti, oti, rtol=1e-9)
        assert tr.lti == pytest.approx(min(oti), rel=1e-9)


def test_stewart_actuator_efforts_are_the_plucker_statics():
    """Leg forces f with Σ f_i L_i = w (unit leg lines) are the actuator efforts."""
    mech = mechanism("stewart")
    rng = np.random.default_rng(5)
    pose = pin.SE3(pin.rpy.rpyToMatrix(0.05, 0.1, -0.1), mech.home.translation + [0, 0.1, 0])
    an = mech.analyze(mech.assemble(pose))
    Lines, _ = stewart_lines(pose)
    for _ in range(3):
        w = rng.normal(size=6) * [100, 100, 100, 30, 30, 30]
        np.testing.assert_allclose(an.actuator_efforts(w), np.linalg.solve(Lines.T, w),
                                   rtol=1e-9, atol=1e-9)
    assert an.constraint_forces(w).shape == (0,)


def test_stewart_payload_is_shared_equally_at_home():
    """A payload at the centre of the symmetric home pose loads the six legs equally:
    f_i = m g / (6 cos β_i) in compression."""
    mech = mechanism("stewart")
    an = mech.analyze()
    Lines, _ = stewart_lines(mech.home)
    tau = an.actuator_efforts(-payload_wrench(12.0, mech.home.translation))
    np.testing.assert_allclose(tau, 12.0 * 9.81 / (6 * Lines[:, 2]), rtol=1e-9)
    np.testing.assert_allclose(payload_wrench(2.0, [1.0, 0, 0], [0, 0, -10.0]),
                               [0, 0, -20.0, 0, 20.0, 0])


# ------------------------------------------------------------------ five-bar
def five_bar_q(point, elbows=(-1, 1)):
    """Configuration (L/R1, L/R2, R/R1, R/R2) of the default five-bar with its pin at
    ``point`` (half base 0.1, proximal 0.2, distal 0.25)."""
    qL = elbow_angles(np.array([-0.1, 0.0]), point, 0.2, 0.25, elbows[0])
    qR = elbow_angles(np.array([0.1, 0.0]), point, 0.2, 0.25, elbows[1])
    return np.r_[qL, qR]


def five_bar_indices(link, q):
    """ITI, OTI through the array functions, from the arrays LinkageAnalysis exposes."""
    an = link.analyze(q)
    kin = link.model.kinematics(q)
    cols = list(link.model.actuated_v)
    J = kin.joint_twists
    p_in = np.array([nearest_point(an.A[k], J[c + 1])[0] for k, c in enumerate(cols)])
    p_out = np.tile(an.reference_point, (len(cols), 1))
    return transmission_indices(an.A, J[cols], an.platform_twists, p_in, p_out,
                                an.length)


def five_bar_closed_form(q):
    """|sin γ_i| (proximal vs distal link of leg i), |sin ψ| (between the distal links)."""
    out, distal = [], []
    for x, (q1, q2) in ((-0.1, q[:2]), (0.1, q[2:])):
        u = np.array([np.cos(q1), np.sin(q1)])
        d = np.array([np.cos(q1 + q2), np.sin(q1 + q2)])
        out.append(abs(u[0] * d[1] - u[1] * d[0]))
        distal.append(d)
    (a, b) = distal
    return np.array(out), abs(a[0] * b[1] - a[1] * b[0])


@pytest.fixture(scope="module")
def link():
    return five_bar().build()


def test_five_bar_matches_its_closed_forms(link):
    """Five-bar: ITI_i = |sin γ_i|, OTI = |sin ψ| for both legs, LTI their minimum."""
    for point in ((0.0, 0.3), (0.08, 0.25), (-0.1, 0.38)):
        q = five_bar_q(np.array(point))
        iti, oti = five_bar_indices(link, q)
        iti_ref, oti_ref = five_bar_closed_form(q)
        np.testing.assert_allclose(iti, iti_ref, rtol=1e-9)
        np.testing.assert_allclose(oti, oti_ref, rtol=1e-9)
        assert local_transmission_index(iti, oti) == pytest.approx(
            min(iti_ref.min(), oti_ref), rel=1e-9)


def test_five_bar_indices_vanish_at_its_singularities(link):
    """Left leg stretched: its ITI is 0; distal links aligned (pin midway between the
    elbows at (∓0.25, h)): both OTIs are 0."""
    phi = np.radians(70.0)
    q = five_bar_q(np.array([-0.1, 0.0]) + 0.45 * np.array([np.cos(phi), np.sin(phi)]))
    iti, _ = five_bar_indices(link, q)
    assert iti[0] < 1e-7 and iti[1] > 0.1
    h = np.sqrt(0.2 ** 2 - 0.15 ** 2)
    q = five_bar_q(np.array([0.0, h]))
    assert np.allclose([np.cos(q[0] + q[1]), np.cos(q[2] + q[3])], [1, -1], atol=1e-9)
    _, oti = five_bar_indices(link, q)
    np.testing.assert_allclose(oti, 0.0, atol=1e-7)


# ------------------------------------------------- lower mobility, invariance
def test_upu3_constraint_index_vanishes_at_its_constraint_singularity():
    """3-UPU: CTI > 0 at home, 0 where the three constraint couples are dependent."""
    mech = mechanism("upu3")
    assert mech.analyze().transmission.cti > 0.5
    an = mech.analyze(mech.assemble(upu3_constraint_singular_pose()))
    np.testing.assert_allclose(an.transmission.leg_cti, 0.0, atol=1e-7)
    assert "transmits poorly" in an.transmission.worst


NAMES = ("rpr3", "rrr3", "stewart", "upu3", "rps3", "delta")


@pytest.mark.parametrize("name", NAMES)
def test_indices_do_not_depend_on_units_or_on_where_the_mechanism_stands(name):
    """ITI, OTI, CTI in [0, 1], the same in millimetres and moved 100 m and turned."""
    design = MECHANISMS[name]()
    mech = mechanism(name)
    a = mech.analyze().transmission
    b = mechanism(name, 1000.0).analyze().transmission
    far = moved(design).build()
    c = far.analyze().transmission
    for x in (a, b, c):
        for v in (x.iti, x.oti, x.leg_cti):
            assert np.all((v >= 0) & (v <= 1))
    for other in (b, c):
        np.testing.assert_allclose(other.iti, a.iti, atol=1e-8)
        np.testing.assert_allclose(other.oti, a.oti, atol=1e-8)
        np.testing.assert_allclose(other.leg_cti, a.leg_cti, atol=1e-8)


# ------------------------------------------------------------------- statics
@pytest.mark.parametrize("name", ("rpr3", "stewart", "upu3", "rps3", "delta"))
def test_actuator_efforts_satisfy_virtual_work(name):
    """τ · δq_a = w ∘ δt for a small actuated step (central differences of forward
    kinematics), and w = Aᵀ B⁻¹ τ + Cᵀ μ."""
    mech = mechanism(name)
    an = mech.analyze()
    rng = np.random.default_rng(11)
    L = mech.characteristic_length
    w = rng.normal(size=6) * np.r_[np.ones(3), L * np.ones(3)]
    tau = an.actuator_efforts(w)
    mu = an.constraint_forces(w)
    np.testing.assert_allclose(an.A.T @ (tau / np.diag(an.B)) + an.constraint_wrenches.T @ mu,
                               w, atol=1e-9 * np.abs(w).max())
    q0 = an.assembly.q_actuated
    dq = 1e-5 * mech.actuated_scales * rng.normal(size=len(q0))
    M0 = an.assembly.pose
    plus = mech.forward_kinematics(q0 + dq).pose
    minus = mech.forward_kinematics(q0 - dq).pose
    dt = 0.5 * (pin.log6(plus * M0.inverse()).vector - pin.log6(minus * M0.inverse()).vector)
    dt = screws.from_pinocchio(dt)  # (δθ; δp_O)
    power = w @ DELTA @ dt
    assert tau @ dq == pytest.approx(power, rel=1e-6, abs=1e-9 * np.abs(tau) @ np.abs(dq))


def test_statics_refuse_type_ii_and_bad_input():
    """At a type II pose the efforts are undefined; a wrench must have 6 numbers."""
    mech = mechanism("rpr3")
    an = mech.analyze(mech.assemble(rpr3_type2_pose()))
    with pytest.raises(SingularityError):
        an.actuator_efforts(np.ones(6))
    with pytest.raises(SingularityError):
        an.velocity_ellipsoid()
    with pytest.raises(InputError):
        mech.analyze().actuator_efforts(np.ones(5))


@pytest.mark.parametrize("name", ("rpr3", "stewart", "delta"))
def test_ellipsoids_are_dual_and_unit_invariant(name):
    """Velocity semi-axes σ_k: the actuated rates of the twist σ_k t_k have unit
    homogenised norm; force semi-axes are 1/σ_k; both the same in millimetres."""
    mech = mechanism(name)
    an = mech.analyze()
    ve, fe = an.velocity_ellipsoid(), an.force_ellipsoid()
    np.testing.assert_allclose(fe.semi_axes, 1.0 / ve.semi_axes[::-1], rtol=1e-12)
    prismatic = np.linalg.norm(an.actuated_twists[:, :3], axis=1) == 0
    for s, t in zip(ve.semi_axes, ve.axes):
        qd = an.inverse_velocity(s * t) / np.where(prismatic, an.length, 1.0)
        assert np.linalg.norm(qd) == pytest.approx(1.0, rel=1e-9)
    # the force axes are dual to the velocity axes: w_k ∘ t_j = δ_kj L (homogenised)
    G = fe.axes[::-1] @ DELTA @ ve.axes.T / an.length
    np.testing.assert_allclose(np.abs(G), np.eye(len(G)), atol=1e-9)
    mm = mechanism(name, 1000.0).analyze()
    np.testing.assert_allclose(mm.velocity_ellipsoid().semi_axes, ve.semi_axes, rtol=1e-8)


# -------------------------------------------------------------------- sweeps
def test_sweep_lti_equals_the_analysis():
    """The sweep's lti column (transmission=True) is Analysis.transmission.lti at each
    pose (nan by default: it costs the sweep 20–30 µs a pose)."""
    from pkm_pin import sweep

    mech = mechanism("stewart")
    h = mech.home
    x0 = np.r_[h.translation, pin.rpy.matrixToRpy(h.rotation)]
    X = np.array([x0 + [a, b, 0, 0, 0, c] for a in (-0.1, 0, 0.1) for b in (-0.1, 0.1)
                  for c in (0.0, 0.2)])
    res = mech.sweep(X, transmission=True)
    assert res.ok.all()
    for x, value in zip(X, res.lti):
        pose = pin.SE3(pin.rpy.rpyToMatrix(*x[3:]), x[:3])
        assert value == pytest.approx(mech.analyze(mech.assemble(pose)).transmission.lti,
                                      rel=1e-9)
    assert "lti" in res.arrays()
    assert np.isnan(sweep.sweep(mech, X).lti).all()


def _pose(x):
    return pin.SE3(pin.rpy.rpyToMatrix(*x[3:]), x[:3])


def test_sweep_cti_equals_the_analysis_near_the_upu3_constraint_singularity():
    """The sweep's cti column (transmission=True) is Analysis.transmission.cti at each
    pose to 1e-9 on the 3-UPU as it descends to its constraint-singular pose (z = 0),
    where it falls to 0 (and nan by default)."""
    mech = mechanism("upu3")
    T = upu3_constraint_singular_pose()
    x0 = np.r_[T.translation, pin.rpy.matrixToRpy(T.rotation)]
    X = np.array([x0 + [dx, dy, z, 0, 0, 0] for dx in (-0.05, 0.0, 0.05) for dy in (0.0, 0.03)
                  for z in (0.8, 0.3, 0.05, 0.005, 1e-4, 0.0)])
    res = mech.sweep(X, transmission=True)
    assert res.ok.all()
    for x, cti, lti in zip(X, res.cti, res.lti):
        t = mech.analyze(mech.assemble(_pose(x))).transmission
        assert cti == pytest.approx(t.cti, abs=1e-9) and lti == pytest.approx(t.lti, abs=1e-9)
    z = X[:, 2] - x0[2]
    assert np.all(res.cti[z == 0.0] < 1e-7) and np.all(res.cti[z == 0.8] > 0.5)
    assert np.all(np.diff(res.cti.reshape(6, 6)[:, 1:], axis=1) < 0)  # falls with z
    assert "cti" in res.arrays() and np.isnan(mech.sweep(X[:3]).cti).all()


def test_sweep_cti_equals_the_analysis_on_the_3rps():
    """3-RPS (one constraint force a leg): the sweep's cti is the analysis' at each
    completed pose of a small orientation workspace, within [0, 1]."""
    mech = mechanism("rps3")
    z = mech.home.translation[2]
    poses = [mech.complete_pose({"z": z + dz, "roll": r, "pitch": p})
             for dz in (-0.05, 0.05) for r in (-0.2, 0.0, 0.2) for p in (-0.1, 0.15)]
    res = mech.sweep(poses, transmission=True)
    assert res.ok.all() and np.all((res.cti >= 0) & (res.cti <= 1))
    for pose, cti in zip(poses, res.cti):
        assert cti == pytest.approx(mech.analyze(mech.assemble(pose)).transmission.cti,
                                    abs=1e-9)


def test_worst_efforts_over_poses_is_the_largest_per_pose_effort():
    """transmission.worst_efforts: the per-actuator maximum of |τ| over the poses, each
    τ being Analysis.actuator_efforts at that pose (a payload held by a Stewart)."""
    from pkm_pin.transmission import payload_wrench, worst_efforts

    mech = mechanism("stewart")
    h = mech.home
    poses = [pin.SE3(h.rotation, h.translation + [dx, 0.0, 0.0]) for dx in (-0.1, 0.0, 0.1)]
    w = -payload_wrench(10.0, h.translation)
    out = worst_efforts(mech, poses, w)
    per_pose = np.array([mech.analyze(mech.assemble(p)).actuator_efforts(w) for p in poses])
    np.testing.assert_allclose(out["efforts"], per_pose, rtol=1e-9)
    np.testing.assert_allclose(out["worst"], np.abs(per_pose).max(axis=0), rtol=1e-12)
    np.testing.assert_array_equal(out["pose_index"], np.abs(per_pose).argmax(axis=0))
    assert out["failures"] == []


# ------------------------------------------------------- general linkages (CTI)
def _linkage_and_assemblies(name, design=None):
    from test_invariance import poses

    from pkm_pin.linkage import Linkage
    from pkm_pin.model.closure_model import configuration, from_mechanism

    mech = mechanism(name) if design is None else design.build()
    link = Linkage(from_mechanism(mech))
    return mech, link, [(mech.assemble(p), configuration) for p in poses(mech, n=3)]


@pytest.mark.parametrize("name", sorted(MECHANISMS))
def test_linkage_cti_equals_the_platform_cti(name):
    """Every shipped mechanism read as a linkage (its tree plus one weld per leg): the
    linkage's CTI per actuator side is Analysis.transmission's per leg, at home and at two
    poses of forward kinematics (1e-9): the generalisation is the platform definition."""
    mech, link, assemblies = _linkage_and_assemblies(name)
    for a, configuration in assemblies:
        tl, tp = link.transmission(configuration(mech, a)), mech.analyze(a).transmission
        np.testing.assert_allclose(tl.leg_cti, tp.leg_cti, atol=1e-9)
        assert tl.cti == pytest.approx(tp.cti, abs=1e-9)
    # the caller's analysis of the same configuration gives the same indices; another
    # configuration's is refused
    q = configuration(mech, assemblies[-1][0])
    given = link.transmission(q, analysis=link.analyze(q))
    tl = link.transmission(q)
    for field in ("iti", "oti", "leg_cti"):
        np.testing.assert_array_equal(getattr(given, field), getattr(tl, field))
    assert given.lti == tl.lti or (np.isnan(given.lti) and np.isnan(tl.lti))
    other = link.analyze(configuration(mech, assemblies[0][0]))
    if not np.array_equal(other.q, q):
        with pytest.raises(InputError, match="not this linkage's analysis"):
            link.transmission(q, analysis=other)


def test_linkage_cti_vanishes_at_the_upu3_constraint_singularity():
    """3-UPU as a linkage: its CTI falls to 0 as the platform descends to the
    constraint-singular pose, equal to the platform's all the way."""
    from pkm_pin.linkage import Linkage
    from pkm_pin.model.closure_model import configuration, from_mechanism

    mech = mechanism("upu3")
    link = Linkage(from_mechanism(mech))
    T = upu3_constraint_singular_pose()
    values = []
    for dz in (0.3, 0.05, 1e-3, 0.0):
        a = mech.assemble(pin.SE3(T.rotation, T.translation + [0.0, 0.0, dz]))
        tr = link.transmission(configuration(mech, a))
        assert tr.cti == pytest.approx(mech.analyze(a).transmission.cti, abs=1e-9)
        values.append(tr.cti)
    assert values[0] > 0.5 and np.all(np.diff(values) < 0) and values[-1] < 1e-7
    assert not tr.good and "transmits poorly" in tr.worst


def test_linkage_cti_does_not_depend_on_units_or_on_where_the_linkage_stands():
    """3-UPU as a linkage in millimetres and moved 100 m and turned: the same CTI per
    side at home and at two poses of forward kinematics."""
    from pkm_pin.linkage import Linkage
    from pkm_pin.model.closure_model import configuration, from_mechanism

    mech, link, assemblies = _linkage_and_assemblies("upu3")
    mm = mechanism("upu3", 1000.0)
    far = moved(MECHANISMS["upu3"]()).build()
    link_mm, link_far = Linkage(from_mechanism(mm)), Linkage(from_mechanism(far))
    for a, _ in assemblies:
        ref = link.transmission(configuration(mech, a)).leg_cti
        p_mm = pin.SE3(a.pose.rotation, 1000.0 * a.pose.translation)
        got_mm = link_mm.transmission(configuration(mm, mm.assemble(p_mm))).leg_cti
        got_far = link_far.transmission(configuration(far, far.assemble(MOVE * a.pose))
                                        ).leg_cti
        assert np.all((ref > 0) & (ref < 1))
        np.testing.assert_allclose(got_mm, ref, atol=1e-9)
        np.testing.assert_allclose(got_far, ref, atol=1e-9)


@pytest.mark.parametrize("name", sorted(MECHANISMS))
def test_platform_and_linkage_readings_give_the_same_transmission(name):
    """Analysis.transmission and Linkage.transmission of the same mechanism (tree +
    closures) agree. The input point is the same rule in both (the first revolute after
    the actuator, passing sliders, with the joint's own line where joints mimic it: a
    Delta's elbow — the platform reading used the parallelogram's mimic-summed column,
    a translation, and gave the Delta ITI 0.37 instead of 0.99), and so is the output
    point (the last rotation of the leg). The transmission wrench is reciprocal to the
    leg's passive freedoms as its end body sees them (a parallelogram's mimicking joints
    included) in both: the linkage reading used the joints' own lines and was 1e-3 off
    on the quasi-Orthoglide."""
    from pkm_pin.linkage import Linkage
    from pkm_pin.model.closure_model import configuration

    mech = MECHANISMS[name]().build()
    tr = mech.home_analysis.transmission
    tl = Linkage(mech.closure_model).transmission(configuration(mech, mech.home_assembly))
    np.testing.assert_allclose(tl.iti, tr.iti, atol=1e-9)
    np.testing.assert_allclose(tl.oti, tr.oti, atol=1e-9)
    assert tl.cti == pytest.approx(tr.cti, abs=1e-9)
    res = mech.sweep([mech.home], transmission=True)
    assert res.lti[0] == pytest.approx(tr.lti, abs=1e-9)


def test_delta_iti_is_the_elbow_transmission_angle():
    """The Delta's ITI: the force along the forearm (the parallelogram's bars) against
    the elbow's velocity, perpendicular to the upper arm about the actuated axis u:
    |f̂ · v̂| with v = u × (E − B), E the elbow (the joint after R1), B on R1's axis."""
    mech = MECHANISMS["delta"]().build()
    a = mech.home_assembly
    tr = mech.analyze(a).transmission
    for k, leg in enumerate(mech.legs):
        data = leg.model.createData()
        pin.framesForwardKinematics(leg.model, data, a.leg_q[k])
        B = (leg.base * data.oMi[1]).translation  # R1 (actuated)
        u = (leg.base * data.oMi[1]).rotation @ np.array([0.0, 1.0, 0.0])
        E = (leg.base * data.oMi[2]).translation  # R2: the elbow
        # the forearm runs from the elbow bar to the platform bar: along R3's x axis
        forearm = (leg.base * data.oMi[3]).rotation @ np.array([1.0, 0.0, 0.0])
        v = np.cross(u, E - B)
        expected = abs(forearm @ v) / np.linalg.norm(v)
        assert tr.iti[k] == pytest.approx(expected, abs=1e-9)
