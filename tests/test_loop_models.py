"""The closed-loop models of models/loops/: closed-form assemblies checked through the
ClosureModel API (residual, Jacobian, mobility, redundancy, output twists); every model
is assembled at q = 0 in its intended mode, and ``LinkageAssembly.q`` is a configuration
of Pinocchio's own model of the file.

The models write their home pose into the joint origins, so a joint's value is its angle
from home: the closed forms below give absolute angles and subtract the home's."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from pkm_pin import load_mechanism
from pkm_pin.builders.loops import CASSIE_POINTS, LOOP_MODELS, five_bar, four_bar
from pkm_pin.model import read_extended_urdf, read_mjcf

LOOPS = Path(__file__).resolve().parents[1] / "models" / "loops"
GEPETTO = Path(__file__).resolve().parents[1] / "tests" / "data" / "gepetto"


def load(name: str):
    return read_extended_urdf(LOOPS / f"{name}.urdf")


def set_joint(model, q: np.ndarray, name: str, value) -> None:
    """Write ``value`` (a float, or a configuration vector) into joint ``name`` of ``q``."""
    joint = model.tree.joints[model.tree.getJointId(name)]
    q[joint.idx_q:joint.idx_q + joint.nq] = value


def assert_jacobian_matches_fd(model, q: np.ndarray, eps: float = 1e-7) -> None:
    """closure_jacobian equals central differences of closure_residual along pin.integrate."""
    J = model.closure_jacobian(q)
    fd = np.zeros_like(J)
    for k in range(model.nv):
        dv = np.zeros(model.nv)
        dv[k] = eps
        fd[:, k] = (model.closure_residual(pin.integrate(model.tree, q, dv))
                    - model.closure_residual(pin.integrate(model.tree, q, -dv))) / (2 * eps)
    assert np.allclose(J, fd, atol=1e-6 * max(1.0, np.abs(J).max()))


def test_committed_files_equal_the_builders_output():
    """models/loops/ holds exactly what pkm_pin.builders.loops writes."""
    for build in LOOP_MODELS.values():
        model = build()
        assert (LOOPS / f"{model.name}.urdf").read_text() == model.urdf
        assert (LOOPS / f"{model.name}.yaml").read_text() == model.yaml
        if model.mjcf is not None:
            assert (LOOPS / f"{model.name}.xml").read_text() == model.mjcf


# ----------------------------------------------------------------------------- four-bar
A, B, C, D = 0.03, 0.09, 0.07, 0.10  # crank, coupler, rocker, ground [m]


def four_bar_closed_form(theta2: float) -> tuple[float, float, float]:
    """(θ3 coupler, θ4 rocker, μ transmission angle), absolute angles from +x, elbow up.

    f² = a² + d² − 2ad cos θ2 (crank end B to rocker pivot O4);
    transmission angle: cos μ = (b² + c² − f²) / (2bc);
    θ4 = atan2(−B_y, d − B_x)… written as the circle intersection below.
    """
    Bp = A * np.array([math.cos(theta2), math.sin(theta2)])
    O4 = np.array([D, 0.0])
    f = np.linalg.norm(O4 - Bp)
    mu = math.acos((B ** 2 + C ** 2 - f ** 2) / (2 * B * C))
    # C point: at distance b from B and c from O4, left of B→O4 (elbow up)
    a = (B ** 2 - C ** 2 + f ** 2) / (2 * f)
    u = (O4 - Bp) / f
    Cp = Bp + a * u + math.sqrt(B ** 2 - a ** 2) * np.array([-u[1], u[0]])
    theta3 = math.atan2(*(Cp - Bp)[::-1])
    theta4 = math.atan2(*(Cp - O4)[::-1])
    return theta3, theta4, mu


FOUR_BAR_HOME = math.pi / 3  # crank angle of q = 0


def four_bar_q(theta2: float) -> np.ndarray:
    """The configuration (crank, coupler, rocker values from home) at crank angle θ2."""
    def absolute(t2):
        t3, t4, _ = four_bar_closed_form(t2)
        return np.array([t2, t3 - t2, t4])
    return absolute(theta2) - absolute(FOUR_BAR_HOME)


@pytest.mark.parametrize("theta2", [0.0, 0.7, 2.0, 3.5, 5.5])
def test_four_bar_closes_at_the_closed_form_angles(theta2):
    """Residual 0, mobility 1, one redundant row (planar point), transmission angle."""
    model = load("four_bar")
    assert min(A, B, C, D) + max(A, B, C, D) < sum((A, B, C, D)) - min(A, B, C, D) - max(
        A, B, C, D)  # Grashof, crank shortest: crank-rocker
    _, _, mu = four_bar_closed_form(theta2)
    q = four_bar_q(theta2)
    assert np.abs(model.closure_residual(q)).max() < 1e-12
    assert model.mobility(q) == 1 and model.redundant_constraints(q) == 1
    assert_jacobian_matches_fd(model, q)
    data = model.tree.createData()
    pin.framesForwardKinematics(model.tree, data, q)
    coupler = data.oMf[model.tree.getFrameId("coupler")].rotation[:, 0]
    rocker = data.oMf[model.tree.getFrameId("rocker")].rotation[:, 0]
    assert math.acos(abs(coupler @ rocker)) == pytest.approx(min(mu, math.pi - mu), abs=1e-9)


def test_four_bar_rocker_rate_and_output_twist():
    """The rocker turns about O4 at ω4/ω2 = a sin(θ3 − θ2) / (c sin(θ3 − θ4))."""
    model = load("four_bar")
    theta2 = 1.1
    theta3, theta4, _ = four_bar_closed_form(theta2)
    q = four_bar_q(theta2)
    null = np.linalg.svd(model.closure_jacobian(q))[2][-1]
    ratio = null[2] / null[0]
    assert ratio == pytest.approx(A * math.sin(theta3 - theta2) / (C * math.sin(theta3 - theta4)),
                                  rel=1e-9)
    (twist,) = model.output_twists(q)
    twist = twist / twist[2]
    assert np.allclose(twist, [0, 0, 1, 0, -D, 0], atol=1e-12)  # rotation about z at O4


def test_four_bar_mjcf_is_the_urdf_model():
    """The MJCF (assembled at qpos0 = 0, the URDF's home) closes at the same closed form."""
    urdf, mjcf = load("four_bar"), read_mjcf(LOOPS / "four_bar.xml")
    assert mjcf.actuated == ("crank_joint",) and mjcf.output == "rocker"
    assert not mjcf.reference.any()
    assert np.abs(mjcf.closure_residual(mjcf.reference)).max() < 1e-12
    for theta2 in (0.3, 2.5):
        q = four_bar_q(theta2)
        assert np.abs(mjcf.closure_residual(q)).max() < 1e-12
        assert mjcf.mobility(q) == urdf.mobility(q) == 1


# ----------------------------------------------------------------------------- five-bar
E, L1, L2 = 0.05, 0.10, 0.12  # half base, proximal, distal [m]


def five_bar_q(P, elbows=(1.0, -1.0)) -> np.ndarray:
    """Closed-form inverse kinematics: q = (mot1, free1, mot2, free2) with the tip at P."""
    q = []
    for x, sign in zip((-E, E), elbows):
        Ap = np.array([x, 0.0])
        d = np.linalg.norm(P - Ap)
        # the elbow C: |C − A| = l1, |P − C| = l2; angle at A by the law of cosines
        base = math.atan2(P[1] - Ap[1], P[0] - Ap[0])
        t1 = base + sign * math.acos((L1 ** 2 + d ** 2 - L2 ** 2) / (2 * L1 * d))
        Cp = Ap + L1 * np.array([math.cos(t1), math.sin(t1)])
        t2 = math.atan2(P[1] - Cp[1], P[0] - Cp[0])
        q += [t1, t2 - t1]
    return np.array(q)


FIVE_BAR_HOME = np.array([0.0, 0.15])  # tip at q = 0


def five_bar_rel(q_absolute: np.ndarray) -> np.ndarray:
    """Joint values from home of the absolute angles (mot1, free1, mot2, free2)."""
    return q_absolute - five_bar_q(FIVE_BAR_HOME)


def passive_rank(model, q) -> int:
    """Rank of the closure Jacobian's passive columns (free1, free2), in-plane rows."""
    J = model.closure_jacobian(q)[:2][:, [1, 3]]
    s = np.linalg.svd(J, compute_uv=False)
    return int(np.sum(s > 1e-9 * np.linalg.svd(model.closure_jacobian(q)[:2],
                                                  compute_uv=False)[0]))


def tip_velocity_rank(model, q) -> int:
    """Rank of the tip's planar velocity over the motions the closures allow."""
    N = np.linalg.svd(model.closure_jacobian(q))[2][2:].T  # rank 2: null space is 2-D
    Jo = model.output_jacobian(q)
    data = model.tree.createData()
    pin.framesForwardKinematics(model.tree, data, q)
    p = data.oMf[model.tree.getFrameId("effector")].translation
    v = Jo[3:] + np.cross(Jo[:3].T, p).T  # velocity of the tip point: v_O + ω × p
    s = np.linalg.svd(v[:2] @ N, compute_uv=False)
    return int(np.sum(s > 1e-9 * s[0]))


def test_five_bar_regular_configuration():
    """Tip at (0.02, 0.15): residual 0, mobility 2, 1 redundant row, full passive and tip ranks."""
    model = load("five_bar")
    assert model.output_point  # output_point: true in five_bar.yaml
    q = five_bar_rel(five_bar_q(np.array([0.02, 0.15])))
    assert np.abs(model.closure_residual(q)).max() < 1e-12
    assert model.mobility(q) == 2 and model.redundant_constraints(q) == 1
    assert passive_rank(model, q) == 2 and tip_velocity_rank(model, q) == 2
    assert_jacobian_matches_fd(model, q)


def test_five_bar_singularities_in_closed_form():
    """Type II (parallel): both distal links on the line y = l1 sin θ1 with
    cos θ1 = (e − l2)/l1, θ2 = π − θ1, the distal angles 0 and π: the passive columns lose
    rank. Type I (serial): leg 1 stretched, P = A1 + (l1 + l2)(cos 60°, sin 60°): the tip
    can only move across leg 1 (tip velocity rank 1) and a motion of the actuators leaves
    it still."""
    model = load("five_bar")
    t1 = math.acos((E - L2) / L1)
    q2 = five_bar_rel(np.array([t1, -t1, math.pi - t1, t1]))  # distal 1 at 0, distal 2 at π
    assert np.abs(model.closure_residual(q2)).max() < 1e-12
    assert model.mobility(q2) == 2 and passive_rank(model, q2) == 1
    phi = math.pi / 3
    P = np.array([-E, 0.0]) + (L1 + L2) * np.array([math.cos(phi), math.sin(phi)])
    q1 = five_bar_q(P)
    assert q1[1] == pytest.approx(0.0, abs=1e-7)  # leg 1 stretched…
    q1[:2] = phi, 0.0  # …exactly (acos near 1 loses half the digits)
    q1 = five_bar_rel(q1)
    assert np.abs(model.closure_residual(q1)).max() < 1e-12
    assert model.mobility(q1) == 2 and tip_velocity_rank(model, q1) == 1
    assert passive_rank(model, q1) == 2


def test_five_bar_mjcf_is_the_urdf_model():
    """The MJCF closes at qpos0 = 0 (tip at (0, 0.15), the URDF's home) and at the same
    closed form; an MJCF has no output_point key (load it with point=True)."""
    mjcf = read_mjcf(LOOPS / "five_bar.xml")
    assert mjcf.actuated == ("mot1", "mot2") and mjcf.output == "effector"
    assert [c.kind for c in mjcf.closures] == ["point"] and not mjcf.output_point
    assert np.abs(mjcf.closure_residual(mjcf.reference)).max() < 1e-12
    q = five_bar_rel(five_bar_q(np.array([0.03, 0.17])))
    assert np.abs(mjcf.closure_residual(q)).max() < 1e-12
    assert mjcf.mobility(q) == 2


def test_builders_take_other_dimensions():
    """A longer coupler and a wider five-bar still give assembled MJCF files."""
    assert "0.11" in four_bar(coupler=0.11).urdf
    assert "0.14" in five_bar(half_base=0.07).urdf


# -------------------------------------------------------------------------------- ankle
H, R, W = 0.30, 0.05, 0.04  # rod, crank, half spacing [m]


def ankle_q(model, roll: float, pitch: float) -> np.ndarray:
    """Closed form: foot at R_x(roll) R_y(pitch); crank angle u of each motor from
    A cos u + B sin u = C, A = 2 r D_x, B = −2 r D_z, C = h² − r² − |D|², D = F − motor;
    rods by the rotation taking (0, 0, −1) to the rod direction, in the crank frame."""
    q = model.reference.copy()
    set_joint(model, q, "ankle_X", roll)
    set_joint(model, q, "ankle_Y", pitch)
    foot = pin.utils.rotate("x", roll) @ pin.utils.rotate("y", pitch)
    for i, y in ((1, W), (2, -W)):
        F = foot @ np.array([-R, y, 0.0])
        Dv = F - np.array([0.0, y, H])
        a_, b_, c_ = 2 * R * Dv[0], -2 * R * Dv[2], H ** 2 - R ** 2 - Dv @ Dv
        base, half = math.atan2(b_, a_), math.acos(c_ / math.hypot(a_, b_))
        u = min((base + half, base - half), key=lambda t: abs(math.remainder(t, 2 * math.pi)))
        crank = pin.utils.rotate("y", u)
        Cp = np.array([0.0, y, H]) + crank @ np.array([-R, 0.0, 0.0])
        rod = crank.T @ (F - Cp) / H
        quat = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, -1.0]), rod)
        set_joint(model, q, f"motor_{i}", u)
        set_joint(model, q, f"rod_{i}_ball", quat.coeffs())
    return q


@pytest.mark.parametrize("roll,pitch", [(0.0, 0.0), (0.0, 0.3), (0.2, 0.0), (-0.15, 0.25)])
def test_ankle_closes_at_the_closed_form_angles(roll, pitch):
    """Residual 0; mobility 4 = 2 DOF + 2 idle rod spins; no redundant row."""
    model = load("ankle")
    assert model.nv == 10 and model.actuated == ("motor_1", "motor_2")
    q = ankle_q(model, roll, pitch)
    assert np.abs(model.closure_residual(q)).max() < 1e-12
    assert model.mobility(q) == 4 and model.redundant_constraints(q) == 0
    assert_jacobian_matches_fd(model, q)


def test_ankle_pitch_turns_both_cranks_alike_and_foot_rotates_about_the_centre():
    """Pure pitch β: both cranks at β (a parallelogram); the foot's twists are the two
    rotations about axes through the ankle centre (zero moment about the origin)."""
    model = load("ankle")
    q = ankle_q(model, 0.0, 0.3)
    for i in (1, 2):
        joint = model.tree.joints[model.tree.getJointId(f"motor_{i}")]
        assert q[joint.idx_q] == pytest.approx(0.3, abs=1e-12)
    twists = model.output_twists(q)
    assert twists.shape == (2, 6) and np.allclose(twists[:, 3:], 0, atol=1e-12)


# ------------------------------------------------------------------------ Cassie-like leg
def _ry(theta: float) -> np.ndarray:
    return pin.utils.rotate("y", theta)


def _ang(v) -> float:
    """Rotation about +y taking x̂ to the direction of v (in the xz-plane)."""
    return math.atan2(-v[2], v[0])


def _circle(p0, r0, p1, r1, near) -> np.ndarray:
    """The point of the xz-plane at r0 from p0 and r1 from p1, nearest to ``near``."""
    d = np.linalg.norm(p1 - p0)
    a = (r0 ** 2 - r1 ** 2 + d ** 2) / (2 * d)
    u = (p1 - p0) / d
    n = np.cross(u, [0.0, 1.0, 0.0])
    h = math.sqrt(r0 ** 2 - a ** 2)
    return min((p0 + a * u + h * n, p0 + a * u - h * n), key=lambda x: np.linalg.norm(x - near))


def cassie_q(model, alpha: float, beta: float) -> np.ndarray:
    """Closed form by three circle intersections: knee from the knee-drive four-bar, tarsus
    from the achilles four-bar, foot from the plantar four-bar (module CASSIE_POINTS)."""
    p = {k: np.array([v[0], 0.0, v[1]]) for k, v in CASSIE_POINTS.items()}
    K, M, A0, Q0, Hh, T0, E0 = (p[k] for k in ("knee", "knee_motor", "knee_crank_end",
                                               "knee_drive", "achilles", "tarsus", "heel"))
    P0, B0, F0, G0 = (p[k] for k in ("foot_motor", "foot_crank_end", "foot", "toe"))
    Ap = M + _ry(alpha) @ (A0 - M)
    Q = _circle(K, np.linalg.norm(Q0 - K), Ap, np.linalg.norm(Q0 - A0), Q0)
    kappa = _ang(Q - K) - _ang(Q0 - K)
    T = K + _ry(kappa) @ (T0 - K)
    Eh = _circle(T, np.linalg.norm(E0 - T0), Hh, np.linalg.norm(E0 - Hh),
                 K + _ry(kappa) @ (E0 - K))
    tau = _ang(Eh - T) - _ang(E0 - T0)
    F = T + _ry(tau) @ (F0 - T0)
    Pp = K + _ry(kappa) @ (P0 - K)
    Bp = Pp + _ry(kappa + beta) @ (B0 - P0)
    G = _circle(F, np.linalg.norm(G0 - F0), Bp, np.linalg.norm(G0 - B0), F + _ry(tau) @ (G0 - F0))
    phi = _ang(G - F) - _ang(G0 - F0)
    values = {"knee": kappa, "tarsus_joint": tau - kappa, "foot_joint": phi - tau,
              "knee_motor": alpha, "knee_rod_joint": _ang(Q - Ap) - _ang(Q0 - A0) - alpha,
              "achilles": _ang(Eh - Hh) - _ang(E0 - Hh), "foot_motor": beta,
              "plantar_rod_joint": _ang(G - Bp) - _ang(G0 - B0) - (kappa + beta)}
    q = model.reference.copy()
    for name, value in values.items():
        set_joint(model, q, name, value)
    return q


@pytest.mark.parametrize("alpha,beta", [(0.0, 0.0), (0.25, -0.2), (-0.2, 0.3)])
def test_cassie_knee_three_loops_close_in_closed_form(alpha, beta):
    """Three point closures, 8 joints: residual 0, mobility 2, 3 redundant (planar) rows."""
    model = load("cassie_knee")
    assert len(model.closures) == 3 and model.nv == 8
    assert set(model.actuated) == {"knee_motor", "foot_motor"}
    q = cassie_q(model, alpha, beta)
    assert np.abs(model.closure_residual(q)).max() < 1e-12
    assert model.mobility(q) == 2 and model.redundant_constraints(q) == 3
    assert_jacobian_matches_fd(model, q)
    if alpha:
        assert abs(q[model.tree.joints[model.tree.getJointId("knee")].idx_q]) > 0.05


# -------------------------------------------------------------------------------- Delta
RB, RP, LA, LB = 0.20, 0.05, 0.20, 0.45  # base, platform radius, arm, forearm [m]
DELTA_HOME = (0.0, 0.0, -0.35)  # platform at q = 0


def delta_q(model, p) -> np.ndarray:
    """:func:`delta_absolute` less its value at home (joint values from home; the
    platform's free flyer is its displacement from home)."""
    q = delta_absolute(model, p) - delta_absolute(model, DELTA_HOME)
    q[-4:] = 0.0, 0.0, 0.0, 1.0
    return q


def delta_absolute(model, p) -> np.ndarray:
    """Closed-form inverse kinematics of the 3-RUU Delta for the platform at ``p``
    (orientation identity): per leg, A cos θ + B sin θ = C with X = W_x − R,
    A = −2 X La, B = 2 W_z La, C = Lb² − X² − La² − W_y² − W_z²; elbow U from the
    forearm direction d: sin β2 = d_y, θ + β1 = atan2(−d_z, d_x); wrist U = the inverse."""
    q = model.reference.copy()
    set_joint(model, q, "platform_joint", np.r_[p, 0, 0, 0, 1])
    for i in range(1, 4):
        phi = 2 * math.pi * (i - 1) / 3
        Wl = pin.utils.rotate("z", -phi) @ np.asarray(p) + np.array([RP, 0, 0])
        X = Wl[0] - RB
        a_, b_ = -2 * X * LA, 2 * Wl[2] * LA
        c_ = LB ** 2 - X ** 2 - LA ** 2 - Wl[1] ** 2 - Wl[2] ** 2
        theta = math.atan2(b_, a_) + math.acos(c_ / math.hypot(a_, b_))
        Ep = np.array([RB + LA * math.cos(theta), 0.0, -LA * math.sin(theta)])
        d = (Wl - Ep) / LB
        beta2, total = math.asin(d[1]), math.atan2(-d[2], d[0])
        for name, value in ((f"hip_{i}", theta), (f"elbow_{i}_1", total - theta),
                            (f"elbow_{i}_2", beta2), (f"wrist_{i}_1", -beta2),
                            (f"wrist_{i}_2", -total)):
            set_joint(model, q, name, value)
    return q


@pytest.mark.parametrize("p", [(0.0, 0.0, -0.35), (0.03, -0.02, -0.38), (-0.05, 0.04, -0.3)])
def test_delta_closes_in_closed_form_and_translates(p):
    """Three welds: residual 0, mobility 3, no redundancy, output twists pure translations."""
    model = load("delta_loops")
    assert model.nv == 21 and model.actuated == ("hip_1", "hip_2", "hip_3")
    q = delta_q(model, p)
    assert np.abs(model.closure_residual(q)).max() < 1e-12
    assert model.mobility(q) == 3 and model.redundant_constraints(q) == 0
    twists = model.output_twists(q)
    assert twists.shape == (3, 6) and np.allclose(twists[:, :3], 0, atol=1e-10)
    assert_jacobian_matches_fd(model, q)


# ------------------------------------------------------------ the home assembly, q order
def frame_placement(model, q: np.ndarray, name: str) -> pin.SE3:
    data = model.tree.createData()
    pin.framesForwardKinematics(model.tree, data, q)
    return data.oMf[model.tree.getFrameId(name)]


def planar_angle(M: pin.SE3) -> float:
    """Angle from +x of a frame's x axis in the xy-plane."""
    return math.atan2(M.rotation[1, 0], M.rotation[0, 0])


def check_four_bar_home(model, q) -> None:
    """Crank at π/3, coupler and rocker at the closed-form angles (elbow up)."""
    t3, t4, _ = four_bar_closed_form(FOUR_BAR_HOME)
    for frame, angle in (("crank", FOUR_BAR_HOME), ("coupler", t3), ("rocker", t4)):
        assert planar_angle(frame_placement(model, q, frame)) == pytest.approx(angle, abs=1e-9)


def check_five_bar_home(model, q) -> None:
    """Tip at (0, 0.15), both elbows out at the closed-form angles."""
    t = five_bar_q(FIVE_BAR_HOME)
    assert frame_placement(model, q, "effector").translation == pytest.approx(
        [0.0, 0.15, 0.0], abs=1e-12)
    for i, body in enumerate(("proximal1", "distal1", "proximal2", "distal2")):
        expected = t[i] if i % 2 == 0 else t[i - 1] + t[i]
        assert math.remainder(planar_angle(frame_placement(model, q, body)) - expected,
                              2 * math.pi) == pytest.approx(0.0, abs=1e-9)


def check_delta_home(model, q) -> None:
    """Platform at (0, 0, −0.35), unrotated; every hip at the closed-form angle."""
    M = frame_placement(model, q, "platform")
    assert M.translation == pytest.approx(DELTA_HOME, abs=1e-12)
    assert np.allclose(M.rotation, np.eye(3), atol=1e-12)
    absolute = delta_absolute(model, DELTA_HOME)
    for i in range(1, 4):
        phi = 2 * math.pi * (i - 1) / 3
        arm = pin.utils.rotate("z", -phi) @ frame_placement(model, q, f"arm_{i}").rotation[:, 0]
        theta = absolute[model.tree.joints[model.tree.getJointId(f"hip_{i}")].idx_q]
        assert math.atan2(-arm[2], arm[0]) == pytest.approx(theta, abs=1e-9)


def check_cassie_home(model, q) -> None:
    """The closure points and the foot at CASSIE_POINTS (the closed form at α = β = 0)."""
    for frame, point in (("knee_drive_point", "knee_drive"), ("heel_point", "heel"),
                         ("toe_point", "toe"), ("foot", "foot")):
        x, z = CASSIE_POINTS[point]
        assert frame_placement(model, q, frame).translation == pytest.approx([x, 0, z],
                                                                              abs=1e-12)
    assert np.allclose(q, cassie_q(model, 0.0, 0.0), atol=1e-12)


def check_ankle_home(model, q) -> None:
    """Foot flat, cranks level, rods vertical: the closed form at roll = pitch = 0."""
    assert np.allclose(frame_placement(model, q, "foot").rotation, np.eye(3), atol=1e-12)
    assert np.allclose(q, ankle_q(model, 0.0, 0.0), atol=1e-12)


HOMES = [("four_bar.urdf", {}, "1R", check_four_bar_home),
         ("four_bar.xml", {}, "1R", check_four_bar_home),
         ("five_bar.urdf", {}, "2T", check_five_bar_home),
         ("five_bar.xml", {"point": True}, "2T", check_five_bar_home),
         ("five_bar.xml", {}, "1T1R", check_five_bar_home),
         ("delta_loops.urdf", {}, "3T", check_delta_home),
         ("cassie_knee.urdf", {}, "1T1R", check_cassie_home),
         ("ankle.urdf", {}, "2R", check_ankle_home)]


@pytest.mark.parametrize("name,options,motion,check", HOMES,
                         ids=[f"{h[0]}{'-point' if h[1] else ''}" for h in HOMES])
def test_assemble_from_the_reference_keeps_the_intended_mode(name, options, motion, check):
    """Linkage.assemble() from the reference (q = 0: pinocchio.neutral; MJCF qpos0)
    stays at the home assembly: the closed-form angles, the intended motion type, no
    singularity."""
    link = load_mechanism(LOOPS / name, **options)
    assert np.array_equal(link.model.reference, pin.neutral(link.model.tree))  # q = 0
    assert np.abs(link.model.closure_residual(link.model.reference)).max() < 1e-13
    a = link.assemble()
    assert np.allclose(a.q, link.model.reference, atol=1e-12)
    check(link.model, a.q)
    an = link.analyze(a)
    assert an.motion_type == motion and an.singularity == "none"
    assert an.dof - an.idle_dof == len(link.actuated)


def test_five_bar_output_is_its_pin():
    """output_point: true makes the five-bar's effector a point (2T); point=False, or the
    key absent, analyses the distal link as a body (1T1R)."""
    assert load_mechanism(LOOPS / "five_bar.urdf").model.output_point
    body = load_mechanism(LOOPS / "five_bar.urdf", point=False)
    assert body.analyze(body.assemble()).motion_type == "1T1R"
    point = load_mechanism(LOOPS / "five_bar.xml", point=True)
    an = point.analyze(point.assemble())
    assert np.allclose(an.platform_twists[:, :3], 0.0) and an.A.shape == (2, 6)


URDF_TREES = [LOOPS / f"{n}.urdf" for n in ("four_bar", "five_bar", "cassie_knee",
                                             "delta_loops")]
URDF_TREES += [GEPETTO / n / "robot.urdf" for n in ("5bar_linkage", "5bar_linkage_iso3d")]


@pytest.mark.parametrize("path", URDF_TREES, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_assembly_q_is_pinocchios_urdf_configuration(path):
    """Assembly.q of a URDF without joint replacements, fed to a fresh
    pinocchio.buildModelFromUrdf model of the file, closes every closure pair."""
    link = load_mechanism(path)
    tree = link.model.tree
    a = link.assemble(pin.integrate(tree, link.model.reference, np.full(tree.nv, 0.05)))
    tree = pin.buildModelFromUrdf(str(path))
    assert list(tree.names) == list(link.model.tree.names) and tree.nq == a.q.size
    data = tree.createData()
    pin.framesForwardKinematics(tree, data, a.q)
    L = link.model.length
    for c in link.model.closures:
        Ma = data.oMf[tree.getFrameId(c.frame_a)] * c.placement_a
        Mb = data.oMf[tree.getFrameId(c.frame_b)] * c.placement_b
        M = Ma.actInv(Mb)
        assert np.linalg.norm(M.translation) / L < 1e-10
        if c.kind == "weld":
            assert np.linalg.norm(pin.log3(M.rotation)) < 1e-10


@pytest.mark.parametrize("name", ["four_bar", "five_bar"])
def test_assembly_q_is_pinocchios_mjcf_configuration(name):
    """Assembly.q of an MJCF, fed to Pinocchio's own model and constraint models of the
    file (pinocchio.buildModelAndLegacyConstraintsFromMJCF), closes every constraint."""
    path = LOOPS / f"{name}.xml"
    link = load_mechanism(path)
    a = link.forward_kinematics(np.full(len(link.actuated), 0.2), starts=4)
    tree, constraints = pin.buildModelAndLegacyConstraintsFromMJCF(str(path))
    assert list(tree.names) == list(link.model.tree.names)
    assert len(constraints) == len(link.model.closures)
    data = tree.createData()
    pin.forwardKinematics(tree, data, a.q)
    for c in constraints:
        assert str(c.type) == "CONTACT_3D"
        pa = (data.oMi[c.joint1_id] * c.joint1_placement).translation
        pb = (data.oMi[c.joint2_id] * c.joint2_placement).translation
        assert np.linalg.norm(pa - pb) < 1e-10
