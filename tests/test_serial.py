"""Tests of pkm_pin.serial (SerialChain, the base class of Leg) and of the serial-chain builders.

Every derivative is checked against finite differences taken along the path
``q(t) = integrate(q, qd t + qdd t²/2)`` with ``pin.integrate``, on UR5 and Panda from
example-robot-data and on the seed 002 / seed 003 chains of ``models/urdf``.

Seed 002: anon., Polish, 1987; seed 003: Demidov 2025; see docs/references.md.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from helpers import URDF_DIR, fd_point, path_configuration, random_states, serial_model_path

from pkm_pin import FrameNotFound, InputError, Leg, SingularityError, screws
from pkm_pin.builders import serial_chains
from pkm_pin.serial import LinkScrew

SEED = 20240611
N_STATES = 5


# ------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def ur5() -> Leg:
    return Leg.from_example_robot_data("ur5")


@pytest.fixture(scope="module")
def panda() -> Leg:
    return Leg.from_example_robot_data("panda")


@pytest.fixture(scope="module")
def manipulator(tmp_path_factory) -> Leg:
    return Leg.from_urdf(serial_model_path("manipulator_seed002", tmp_path_factory), "tip")


@pytest.fixture(scope="module")
def chain_6r(tmp_path_factory) -> Leg:
    return Leg.from_urdf(serial_model_path("chain_6r_seed003", tmp_path_factory), "tip")


@pytest.fixture(scope="module")
def chain_rp(tmp_path_factory) -> Leg:
    return Leg.from_urdf(serial_model_path("chain_rprrrr_seed003", tmp_path_factory), "tip")


@pytest.fixture(scope="module")
def based_ur5() -> Leg:
    """UR5 on a tilted, shifted base (the base placement must enter every result)."""
    base = pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.5, 1.1), np.array([0.4, -0.2, 0.7]))
    return Leg.from_example_robot_data("ur5", base=base, name="ur5_based")


LEG_NAMES = ["ur5", "panda", "manipulator", "based_ur5", "chain_rp"]


@pytest.fixture(params=LEG_NAMES)
def leg(request) -> Leg:
    return request.getfixturevalue(request.param)


def _states(leg: Leg, n: int = N_STATES, seed: int = SEED):
    """Seeded random (q, qd, qdd) inside the joint limits, rates and accelerations in
    [-1, 1]."""
    return random_states(leg, n, seed)


def _moving_links(leg: Leg) -> list[str]:
    """Links carried by a movable joint (the root links are at rest)."""
    return [f.name for f in leg.model.frames
            if f.type == pin.FrameType.BODY and f.parentJoint > 0]


# ------------------------------------------------------------------------- builders
def test_generated_models_are_current():
    """The URDFs in models/urdf are exactly what write_serial_models produces now."""
    texts = {"chain_6r_seed003": serial_chains.chain_6r_seed003_urdf(),
             "chain_rprrrr_seed003": serial_chains.chain_rprrrr_seed003_urdf(),
             "manipulator_seed002": serial_chains.manipulator_seed002_urdf()}
    for key, text in texts.items():
        path = URDF_DIR / serial_chains.SERIAL_MODEL_FILES[key]
        assert path.is_file(), f"run write_serial_models('models') to create {path}"
        assert path.read_text() == text, f"{path} is stale: regenerate it"


def test_write_serial_models_writes_loadable_chains(tmp_path):
    """write_serial_models writes three URDFs that load as 6-DOF legs with a 'tip'."""
    paths = serial_chains.write_serial_models(tmp_path)
    assert [p.name for p in paths] == list(serial_chains.SERIAL_MODEL_FILES.values())
    for p in paths:
        assert p.parent == tmp_path / "urdf"
        assert Leg.from_urdf(p, "tip").nv == 6


def test_chain_6r_reproduces_seed003_example(chain_6r):
    """The 6R chain gives the paper's rotation 18.5° about (0.37, −0.711, 0.6) and
    displacement (−0.00178, 0.160, 0.067) m from the start to the target angles."""
    start = chain_6r.tip_placement(serial_chains.SEED003_START)
    target = chain_6r.tip_placement(serial_chains.SEED003_TARGET)
    rotvec = pin.log3(target.rotation @ start.rotation.T)
    angle = np.linalg.norm(rotvec)
    assert np.degrees(angle) == pytest.approx(18.5, abs=0.05)
    np.testing.assert_allclose(rotvec / angle, [0.37, -0.711, 0.6], atol=5e-3)
    np.testing.assert_allclose(target.translation - start.translation,
                               [-0.00178, 0.160, 0.067], atol=5e-4)
    assert target.rotation[0, 0] == pytest.approx(0.96, abs=5e-3)


def test_chain_6r_a11_corrected_formula(chain_6r):
    """a11 of the 6R chain equals the paper's product expansion with the corrected
    third bracket (cos φ1 cos φ2 sin φ3 − sin φ1 cos φ3) at random angles."""
    rng = np.random.default_rng(SEED)
    for _ in range(10):
        phi = rng.uniform(-np.pi, np.pi, 6)
        c, s = np.cos(phi), np.sin(phi)
        a11 = ((c[0] * c[1] * c[2] + s[0] * s[2]) * (c[3] * c[4] * c[5] + s[3] * s[5])
               + c[0] * s[1] * (s[3] * c[4] * c[5] - c[3] * s[5])
               + (c[0] * c[1] * s[2] - s[0] * c[2]) * s[4] * c[5])
        assert chain_6r.tip_placement(phi).rotation[0, 0] == pytest.approx(a11, abs=1e-12)


def test_chain_6r_axes_cross_at_right_angles_at_0_2_m(chain_6r):
    """Consecutive joint axes of the 6R chain are perpendicular with common normal 0.2 m."""
    q = np.random.default_rng(SEED).uniform(-np.pi, np.pi, 6)
    T = chain_6r.joint_twists(q)
    for a, b in zip(T[:-1], T[1:]):
        assert abs(a[:3] @ b[:3]) < 1e-12
        # distance of two perpendicular unit lines = |reciprocal product|
        assert abs(screws.reciprocal_product(a, b)) == pytest.approx(0.2, abs=1e-12)


def test_chain_rprrrr_second_pair_is_prismatic(chain_rp, chain_6r):
    """The seed 003 fig. 4 chain has a prismatic second pair along the 6R chain's second
    axis, and equals the 6R chain at S2 = 0, φ2 = 0."""
    q = np.random.default_rng(SEED).uniform(-1.0, 1.0, 6)
    q[1] = 0.0
    T = chain_rp.joint_twists(q)
    assert np.linalg.norm(T[1, :3]) == 0.0
    np.testing.assert_allclose(T[1, 3:], chain_6r.joint_twists(q)[1, :3], atol=1e-15)
    M1, M2 = chain_rp.tip_placement(q), chain_6r.tip_placement(q)
    assert np.linalg.norm(pin.log6(M1.actInv(M2)).vector) < 1e-14


def test_manipulator_seed002_structure(manipulator):
    """The seed 002 manipulator is R(z) R(x) P(y) and a spherical pair whose product of
    rotations is U4 = Rx(φ3) Rz(φ5) Ry(−φ4) of the paper."""
    assert manipulator.joint_names == ["phi1", "phi2", "s", "phi3", "phi5", "phi4"]
    assert manipulator.spherical_groups == [(3, 4, 5)]
    q = np.array([0.0, 0.0, 0.1, 0.3, -0.4, 0.7])
    T = manipulator.joint_twists(np.zeros(6))
    np.testing.assert_allclose(T[:3, :3], [[0, 0, 1], [1, 0, 0], [0, 0, 0]], atol=1e-15)
    np.testing.assert_allclose(T[2, 3:], [0, 1, 0], atol=1e-15)
    phi3, phi5, phi4 = q[3:]
    c3, s3, c4, s4, c5, s5 = (np.cos(phi3), np.sin(phi3), np.cos(phi4), np.sin(phi4),
                              np.cos(phi5), np.sin(phi5))
    U4 = np.array([[c4 * c5, -s5, -s4 * c5],
                   [c3 * c4 * s5 - s3 * s4, c3 * c5, -c4 * s3 - c3 * s4 * s5],
                   [c3 * s4 + s3 * c4 * s5, s3 * c5, c3 * c4 - s3 * s4 * s5]])
    np.testing.assert_allclose(manipulator.tip_placement(q).rotation, U4, atol=1e-14)
    # E = (0, BC + s + CD, AB) + U4 (0, DE, 0)
    d = serial_chains.SEED002_DIMENSIONS
    E = np.array([0.0, d["BC"] + q[2] + d["CD"], d["AB"]]) + U4 @ [0.0, d["DE"], 0.0]
    np.testing.assert_allclose(manipulator.tip_placement(q).translation, E, atol=1e-15)


# --------------------------------------------------------------------------- links
def test_link_names_are_body_frames(ur5):
    """link_names lists the BODY frames of the model, root first, tip included."""
    names = ur5.link_names
    assert names[0] == "world" and "tool0" in names and "wrist_3_joint" not in names
    assert len(names) == sum(f.type == pin.FrameType.BODY for f in ur5.model.frames)


def test_unknown_link_lists_the_links(ur5):
    """An unknown link raises FrameNotFound whose message lists the links."""
    with pytest.raises(FrameNotFound) as info:
        ur5.point_velocity("no_such_link", np.zeros(3), np.zeros(6), np.zeros(6))
    assert info.value.name == "no_such_link"
    assert "tool0" in info.value.frames and "'forearm_link'" in str(info.value)


def test_joint_frame_is_not_a_link(ur5):
    """A joint frame name (not a BODY frame) is rejected with FrameNotFound."""
    with pytest.raises(FrameNotFound):
        ur5.link_twist("wrist_3_joint", np.zeros(6), np.zeros(6))


@pytest.mark.parametrize("bad, message", [
    (np.zeros(5), "must have 6 values"),
    (np.full(6, np.nan), "must be finite"),
    (np.zeros((6, 1)), "must have 6 values"),
])
def test_bad_rates_raise_input_error(ur5, bad, message):
    """qd and qdd of the wrong shape or with NaN raise InputError naming the argument."""
    q = np.zeros(6)
    with pytest.raises(InputError, match=f"qd .*{message}"):
        ur5.link_twists(q, bad)
    with pytest.raises(InputError, match=f"qdd .*{message}"):
        ur5.point_acceleration("tool0", np.zeros(3), q, np.zeros(6), bad)


def test_bad_q_and_point_raise_input_error(ur5):
    """q of the wrong shape, a point without 3 finite values and a non-str link raise
    InputError."""
    with pytest.raises(InputError, match="q of leg 'ur5' must have 6 values"):
        ur5.point_velocity("tool0", np.zeros(3), np.zeros(7), np.zeros(6))
    with pytest.raises(InputError, match="point must have 3 components"):
        ur5.point_velocity("tool0", np.zeros(2), np.zeros(6), np.zeros(6))
    with pytest.raises(InputError, match="point must be finite"):
        ur5.point_velocity("tool0", [0, np.inf, 0], np.zeros(6), np.zeros(6))
    with pytest.raises(InputError, match="link name"):
        ur5.point_velocity(3, np.zeros(3), np.zeros(6), np.zeros(6))


def test_link_twists_match_finite_differences_of_placements(leg):
    """Every link twist equals log(M(h) M(−h)⁻¹)/(2h) of its world placement (rel. 1e-7)."""
    h = 1e-6
    for q, qd, qdd in _states(leg, 3):
        twists = leg.link_twists(q, qd)
        assert list(twists) == leg.link_names
        for link, twist in twists.items():
            D = leg.link_placement(link, path_configuration(leg, q, qd, qdd, h)) * \
                leg.link_placement(link, path_configuration(leg, q, qd, qdd, -h)).inverse()
            fd = screws.log(D) / (2 * h)
            scale = 1.0 + np.linalg.norm(twist)
            assert np.linalg.norm(twist - fd) < 1e-7 * scale, link
            np.testing.assert_array_equal(leg.link_twist(link, q, qd), twist)


def test_root_link_twist_is_zero(leg):
    """Links fixed to the root have a zero twist whatever the joint rates."""
    q, qd, _ = next(_states(leg, 1))
    twists = leg.link_twists(q, qd)
    for f in leg.model.frames:
        if f.type == pin.FrameType.BODY and f.parentJoint == 0:
            assert np.linalg.norm(twists[f.name]) == 0.0


def test_link_twists_are_partial_jacobian_sums(ur5):
    """The twist of the link of joint k is the sum of the first k joint twists times rates."""
    q, qd, _ = next(_states(ur5, 1))
    J = ur5.serial_jacobian(q)
    twists = ur5.link_twists(q, qd)
    links = ["shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link",
             "wrist_2_link", "wrist_3_link"]
    for k, link in enumerate(links, start=1):
        np.testing.assert_allclose(twists[link], J[:, :k] @ qd[:k], atol=1e-13)


# --------------------------------------------------------------------------- screws
def test_link_screws_match_screws_pitch_and_axis(leg):
    """Each link screw has the pitch and axis that screws.pitch/screws.axis give for the
    link twist (at the leg's characteristic length), to 1e-12."""
    L = leg.characteristic_length
    for q, qd, _ in _states(leg, 3):
        twists = leg.link_twists(q, qd)
        for link, sc in leg.link_screws(q, qd).items():
            assert isinstance(sc, LinkScrew) and sc.link == link
            t = twists[link]
            if np.linalg.norm(t) == 0.0:
                assert sc.at_rest and sc.point is None and sc.direction is None
                continue
            point, direction = screws.axis(t, length=L)
            assert sc.pitch == pytest.approx(screws.pitch(t, length=L), rel=1e-12, abs=1e-15)
            np.testing.assert_allclose(sc.point, point, atol=1e-12)
            np.testing.assert_allclose(sc.direction, direction, atol=1e-12)


def test_point_on_screw_axis_moves_along_it(leg):
    """A link point on its instantaneous screw axis moves with v = pitch ω (seed 002,
    the axis is the locus of minimum velocity), to 1e-10 relative."""
    for q, qd, _ in _states(leg, 2):
        twists = leg.link_twists(q, qd)
        for link, sc in leg.link_screws(q, qd).items():
            if sc.at_rest or np.isinf(sc.pitch):
                continue
            M = leg.link_placement(link, q)
            P = sc.point + 0.3 * sc.direction
            v = leg.point_velocity(link, M.actInv(P), q, qd)
            w = twists[link][:3]
            assert np.linalg.norm(v - sc.pitch * w) < 1e-10 * (1 + np.linalg.norm(v))


def test_revolute_link_screw_is_the_joint_axis(ur5):
    """With only the first joint moving, every moving link turns about that joint's axis
    with pitch 0 (the shoulder pan axis is the world z axis through the origin)."""
    q = next(_states(ur5, 1))[0]
    qd = np.zeros(6)
    qd[0] = 0.7
    for link in _moving_links(ur5):
        sc = ur5.link_screws(q, qd)[link]
        assert sc.pitch == pytest.approx(0.0, abs=1e-15)
        np.testing.assert_allclose(sc.direction, [0, 0, 1], atol=1e-15)
        np.testing.assert_allclose(sc.point, [0, 0, 0], atol=1e-12)


def test_prismatic_motion_has_infinite_pitch(manipulator):
    """With only the prismatic pair moving, the links after it translate: pitch inf,
    direction the slide axis, point the origin; the links before it are at rest."""
    q = next(_states(manipulator, 1))[0]
    qd = np.array([0.0, 0.0, 0.25, 0.0, 0.0, 0.0])
    axis = manipulator.joint_twists(q)[2, 3:]
    out = manipulator.link_screws(q, qd)
    for link in ("s_link", "phi3_link", "phi5_link", "phi4_link", "tip"):
        assert out[link].pitch == np.inf
        np.testing.assert_allclose(out[link].direction, axis, atol=1e-15)
        np.testing.assert_array_equal(out[link].point, np.zeros(3))
    for link in ("base", "phi1_link", "phi2_link"):
        assert out[link].at_rest


def test_link_screws_at_rest(manipulator):
    """With zero rates every link screw is at rest: point, direction and pitch None."""
    q = next(_states(manipulator, 1))[0]
    for sc in manipulator.link_screws(q, np.zeros(6)).values():
        assert sc.at_rest and sc.point is None and sc.direction is None and sc.pitch is None


def test_screw_of_cancelling_rates_is_at_rest(panda):
    """Panda joints 1 and 3 are coaxial at q2 = 0: opposite rates leave links 3… at rest
    (a round-off twist counts as zero, relative 1e-9 of the joint-rate scale)."""
    q = np.array([0.4, 0.0, -0.3, -1.5, 0.2, 1.2, 0.3])
    qd = np.array([0.7, 0.0, -0.7, 0.0, 0.0, 0.0, 0.0])
    out = panda.link_screws(q, qd)
    assert not out["panda_link2"].at_rest and out["panda_link2"].pitch == 0.0
    for link in ("panda_link3", "panda_link5", "panda_link8"):
        assert out[link].at_rest, link
    assert np.linalg.norm(panda.link_twist("panda_link8", q, qd)) < 1e-14


# --------------------------------------------------------------------------- points
def test_point_velocity_matches_finite_differences(leg):
    """The velocity of points of every moving link equals the central difference of the
    point's world position along q(t) (h = 1e-6, relative 1e-7)."""
    rng = np.random.default_rng(SEED + 1)
    for q, qd, qdd in _states(leg):
        for link in _moving_links(leg):
            p = rng.uniform(-0.3, 0.3, 3)
            v = leg.point_velocity(link, p, q, qd)
            v_fd, _ = fd_point(leg, link, p, q, qd, qdd, 1e-6)
            assert np.linalg.norm(v - v_fd) < 1e-7 * (1 + np.linalg.norm(v)), link


def test_point_acceleration_matches_finite_differences(leg):
    """The classical acceleration of points of every moving link equals the central
    second difference of the point's world position along q(t) (h = 1e-4, rel. 1e-6)."""
    rng = np.random.default_rng(SEED + 2)
    for q, qd, qdd in _states(leg):
        for link in _moving_links(leg):
            p = rng.uniform(-0.3, 0.3, 3)
            a = leg.point_acceleration(link, p, q, qd, qdd)
            _, a_fd = fd_point(leg, link, p, q, qd, qdd, 1e-4)
            assert np.linalg.norm(a - a_fd) < 1e-6 * (1 + np.linalg.norm(a)), link


def test_point_acceleration_has_coriolis_term(manipulator):
    """Constant rates of the first and prismatic pairs (qdd = 0) give the tip the
    Coriolis acceleration 2 ω × v_rel plus the centripetal term (seed 002, (43))."""
    q = np.zeros(6)
    q[2] = 0.1
    w, v = 0.8, 0.3
    qd = np.array([w, 0.0, v, 0.0, 0.0, 0.0])
    a = manipulator.point_acceleration("tip", np.zeros(3), q, qd, np.zeros(6))
    E = manipulator.tip_placement(q).translation
    omega, v_rel = np.array([0, 0, w]), np.array([0, v, 0])
    expected = 2 * np.cross(omega, v_rel) + np.cross(omega, np.cross(omega, E))
    np.testing.assert_allclose(a, expected, atol=1e-14)


def test_point_velocity_is_affine_in_the_point(panda):
    """v_P − v_Q = ω × (P − Q) for two points of the same link (rigid body, 1e-13)."""
    q, qd, _ = next(_states(panda, 1))
    link = "panda_link5"
    p, r = np.array([0.1, -0.2, 0.05]), np.array([-0.3, 0.0, 0.2])
    M = panda.link_placement(link, q)
    w = panda.link_twist(link, q, qd)[:3]
    dv = panda.point_velocity(link, p, q, qd) - panda.point_velocity(link, r, q, qd)
    np.testing.assert_allclose(dv, np.cross(w, M.act(p) - M.act(r)), atol=1e-13)


# ------------------------------------------------------------------ serial velocity
def test_serial_jacobian_matches_finite_differences(leg):
    """Column k of serial_jacobian equals log(M(q + h e_k) M(q − h e_k)⁻¹)/(2h) of the tip
    placement (h = 1e-6, relative 1e-7)."""
    h = 1e-6
    for q, _, _ in _states(leg, 3):
        J = leg.serial_jacobian(q)
        assert J.shape == (6, leg.nv)
        for k in range(leg.nv):
            e = np.zeros(leg.nv)
            e[k] = h
            D = leg.tip_placement(pin.integrate(leg.model, q, e)) * \
                leg.tip_placement(pin.integrate(leg.model, q, -e)).inverse()
            assert np.linalg.norm(J[:, k] - screws.log(D) / (2 * h)) < 1e-7 * (
                1 + np.linalg.norm(J[:, k]))


def test_serial_forward_velocity_is_tip_twist(leg):
    """serial_forward_velocity(q, qd) = J qd = the twist of the tip link (1e-13)."""
    for q, qd, _ in _states(leg, 3):
        V = leg.serial_forward_velocity(q, qd)
        np.testing.assert_allclose(V, leg.serial_jacobian(q) @ qd, atol=1e-13)
        np.testing.assert_allclose(V, leg.link_twist(leg.tip, q, qd), atol=1e-13)


@pytest.mark.parametrize("name", ["ur5", "manipulator", "chain_rp", "based_ur5"])
def test_serial_inverse_velocity_round_trip(request, name):
    """For a 6-joint chain, serial_inverse_velocity(q, J qd) returns qd (rel. 1e-8)."""
    leg = request.getfixturevalue(name)
    for q, qd, _ in _states(leg):
        if leg.serial_singularity_index(q) < 1e-6:
            continue
        x = leg.serial_inverse_velocity(q, leg.serial_forward_velocity(q, qd))
        assert np.linalg.norm(x - qd) < 1e-8 * np.linalg.norm(qd) / leg.serial_singularity_index(q)


def test_serial_inverse_velocity_redundant_is_minimum_norm(panda):
    """For the 7-joint Panda the rates reproduce the twist and have no component in the
    null space of J (least squares of least norm), to 1e-10."""
    for q, qd, _ in _states(panda):
        V = panda.serial_forward_velocity(q, qd)
        x = panda.serial_inverse_velocity(q, V)
        J = panda.serial_jacobian(q)
        assert np.linalg.norm(J @ x - V) < 1e-10 * np.linalg.norm(V)
        null = np.linalg.svd(J)[2][6:]
        assert np.linalg.norm(null @ x) < 1e-10 * np.linalg.norm(x)


def test_serial_inverse_velocity_deficient_chain():
    """A 5-joint UR5 chain (tip wrist_2_link) recovers reachable twists exactly and
    raises SingularityError for a twist outside the span of its joint twists."""
    leg5 = Leg.from_example_robot_data("ur5", tip="wrist_2_link")
    assert leg5.nv == 5
    q, qd, _ = next(_states(leg5, 1))
    V = leg5.serial_forward_velocity(q, qd)
    np.testing.assert_allclose(leg5.serial_inverse_velocity(q, V), qd, rtol=1e-9, atol=1e-12)
    normal = np.linalg.svd(leg5.serial_jacobian(q).T)[2][-1]  # orthogonal to all columns
    with pytest.raises(SingularityError, match="not reachable"):
        leg5.serial_inverse_velocity(q, V + normal)


def test_serial_inverse_velocity_raises_at_singularity(ur5):
    """At the UR5 elbow stretch the inverse velocity raises SingularityError carrying the
    index."""
    q = np.array([0.3, -0.7, 0.0, 0.5, 1.0, 0.2])
    with pytest.raises(SingularityError) as info:
        ur5.serial_inverse_velocity(q, np.ones(6))
    assert info.value.index < 1e-9 and info.value.kind == "serial inverse velocity"


def test_serial_inverse_velocity_bad_twist(ur5):
    """A twist that is not one finite 6-vector raises InputError."""
    q = np.array([0.3, -0.7, 1.0, 0.5, 1.0, 0.2])
    with pytest.raises(InputError):
        ur5.serial_inverse_velocity(q, np.ones(5))
    with pytest.raises(InputError):
        ur5.serial_inverse_velocity(q, np.ones((2, 6)))
    with pytest.raises(InputError):
        ur5.serial_inverse_velocity(q, [np.nan] * 6)


# ------------------------------------------------------------------- singularities
UR5_SINGULAR = {
    "wrist (wrist_2 = 0: wrist 1 and 3 axes aligned)": [0.3, -0.7, 1.1, 0.5, 0.0, 0.2],
    "wrist (wrist_2 = π)": [-1.0, -1.2, 0.8, 2.0, np.pi, 0.0],
    "elbow stretched (elbow = 0)": [0.3, -0.7, 0.0, 0.5, 1.0, 0.2],
    "elbow folded (elbow = π)": [0.0, -1.0, np.pi, 0.3, -1.1, 0.4],
}


@pytest.mark.parametrize("label", list(UR5_SINGULAR))
def test_ur5_known_singularities_have_zero_index(ur5, label):
    """The serial singularity index of the UR5 vanishes (< 1e-9) at its wrist and elbow
    singularities, and is_serial_singular says so."""
    q = np.array(UR5_SINGULAR[label])
    assert ur5.serial_singularity_index(q) < 1e-9
    assert ur5.is_serial_singular(q)
    assert abs(np.linalg.det(ur5.serial_jacobian(q))) < 1e-12


def test_ur5_random_configurations_are_regular(ur5):
    """At random UR5 configurations the index is mostly above 1e-4 and always in (0, 1]."""
    rng = np.random.default_rng(SEED)
    idx = np.array([ur5.serial_singularity_index(ur5.random_configuration(rng))
                    for _ in range(200)])
    assert np.all((idx > 0) & (idx <= 1.0))
    assert np.mean(idx > 1e-4) > 0.95
    assert not ur5.is_serial_singular(np.array([0.3, -0.7, 1.1, 0.5, 1.0, 0.2]))


def test_index_vanishes_with_det_jtj_for_deficient_chain():
    """For a 5-joint chain the index vanishes where det(JᵀJ) = 0 (eq. 48): the UR5 elbow
    stretch, and is regular elsewhere."""
    leg5 = Leg.from_example_robot_data("ur5", tip="wrist_2_link")
    q_sing = np.array([0.3, -0.7, 0.0, 0.5, 1.0])
    q_reg = np.array([0.3, -0.7, 1.0, 0.5, 1.0])
    J = leg5.serial_jacobian(q_sing)
    assert leg5.serial_singularity_index(q_sing) < 1e-9
    assert np.linalg.det(J.T @ J) < 1e-15
    assert leg5.serial_singularity_index(q_reg) > 1e-3


def _scaled_leg(leg: Leg, k: float) -> Leg:
    """The same chain with every length multiplied by ``k`` (e.g. metres → millimetres)."""
    m = pin.Model(leg.model)
    for j in range(1, m.njoints):
        M = m.jointPlacements[j]
        m.jointPlacements[j] = pin.SE3(M.rotation, k * M.translation)
    for f in m.frames:
        f.placement = pin.SE3(f.placement.rotation, k * f.placement.translation)
    lo, up = m.lowerPositionLimit.copy(), m.upperPositionLimit.copy()
    prismatic = _prismatic_q(leg)
    lo[prismatic] *= k
    up[prismatic] *= k
    m.lowerPositionLimit, m.upperPositionLimit = lo, up
    base = pin.SE3(leg.base.rotation, k * leg.base.translation)
    return Leg(model=m, tip=leg.tip, base=base, name=f"{leg.name}_x{k:g}")


def _prismatic_q(leg: Leg) -> np.ndarray:
    J = leg.serial_jacobian(leg.neutral())
    return np.flatnonzero(np.linalg.norm(J[:3], axis=0) == 0.0)


@pytest.mark.parametrize("name", ["ur5", "manipulator", "chain_rp", "panda"])
def test_singularity_index_is_unit_invariant(request, name):
    """The same chain in millimetres (prismatic coordinates in mm) has the same index
    (relative 1e-9) and the same inverse-velocity rates."""
    leg = request.getfixturevalue(name)
    mm = _scaled_leg(leg, 1000.0)
    assert mm.characteristic_length == pytest.approx(1000 * leg.characteristic_length)
    P = _prismatic_q(leg)
    for q, qd, _ in _states(leg):
        q_mm = q.copy()
        q_mm[P] *= 1000.0
        assert mm.serial_singularity_index(q_mm) == pytest.approx(
            leg.serial_singularity_index(q), rel=1e-9)
        if leg.serial_singularity_index(q) < 1e-6:
            continue
        V = leg.serial_forward_velocity(q, qd)
        qd_mm = qd.copy()
        qd_mm[P] *= 1000.0
        V_mm = np.r_[V[:3], 1000.0 * V[3:]]
        np.testing.assert_allclose(mm.serial_forward_velocity(q_mm, qd_mm), V_mm,
                                   rtol=1e-12, atol=1e-9)
        x = leg.serial_inverse_velocity(q, V)  # qd itself, or the least-norm rates (Panda)
        x[P] *= 1000.0
        np.testing.assert_allclose(mm.serial_inverse_velocity(q_mm, V_mm), x,
                                   rtol=1e-7, atol=1e-7)


def test_singularity_index_of_seed003_example_is_regular(chain_6r):
    """The seed 003 6R chain is regular at the paper's start and target (index > 1e-2),
    and singular when stretched (all angles zero)."""
    assert chain_6r.serial_singularity_index(serial_chains.SEED003_START) > 1e-2
    assert chain_6r.serial_singularity_index(serial_chains.SEED003_TARGET) > 1e-2
    assert chain_6r.serial_singularity_index(np.zeros(6)) < 1e-9
