"""Tests of pkm_pin.leg: Pinocchio joint twists against hand-written screw formulas.

The leg URDFs are written inline as plain XML (no project builders), and the expected
twists from the formulas of seed 000 with plain numpy: the planar 3-RPR leg (eq. 50-52,
with the prismatic screws made unit), a Gough-Stewart U-P-S leg (lines through the joint
centres along the current joint axes), and a parallelogram written as a revolute plus a
mimicking revolute. Jacobians are also checked against finite differences of the tip
placement taken with ``pin.integrate`` and ``pin.log6``. Seeded random configurations.

Seed 000: Michalková & Guldan, see docs/references.md.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from helpers import fd_jacobian, spans_equal
from helpers import screw_rank as rank

from pkm_pin import InputError, Leg, LegSolution, screws

Y = np.array([0.0, 1.0, 0.0])


# ------------------------------------------------------------------ URDF helpers
def _joint(name, jtype, parent, child, xyz=(0, 0, 0), axis=(1, 0, 0),
           limits=(-np.pi, np.pi), mimic=None):
    """A <joint> element as text."""
    parts = [f'<joint name="{name}" type="{jtype}">', f'<parent link="{parent}"/>',
             f'<child link="{child}"/>', '<origin xyz="{} {} {}" rpy="0 0 0"/>'.format(*xyz)]
    if jtype != "fixed":
        parts.append('<axis xyz="{} {} {}"/>'.format(*axis))
        parts.append(f'<limit lower="{limits[0]!r}" upper="{limits[1]!r}" '
                     'effort="10" velocity="10"/>')
    if mimic is not None:
        parts.append(f'<mimic joint="{mimic[0]}" multiplier="{mimic[1]}" offset="0"/>')
    return "".join(parts) + "</joint>"


def _robot(name, joints):
    """A URDF robot from joint texts; the links are those the joints name."""
    links = []
    for j in joints:
        for tag in ("parent", "child"):
            link = j.split(f'<{tag} link="')[1].split('"')[0]
            if link not in links:
                links.append(link)
    body = "".join(f'<link name="{n}"/>' for n in links) + "".join(joints)
    return f'<?xml version="1.0"?>\n<robot name="{name}">{body}</robot>'


def rpr3_leg_xml(base_pivot) -> str:
    """3-RPR leg: revolute A0 about +y at the base pivot, prismatic A1 along the local x
    (value = distance to the platform pivot), revolute A2 about +y at the pivot."""
    return _robot("rpr", [
        _joint("A0", "revolute", "ground", "link0", xyz=base_pivot, axis=(0, 1, 0)),
        _joint("A1", "prismatic", "link0", "link1", axis=(1, 0, 0), limits=(0.2, 3.0)),
        _joint("A2", "revolute", "link1", "platform", axis=(0, 1, 0)),
    ])


def ups_leg_xml(base_point) -> str:
    """U-P-S leg: revolutes about x then y at the base point, prismatic along z,
    revolutes about x, y, z at the tip (zero offsets between the joint frames)."""
    return _robot("ups", [
        _joint("U1", "revolute", "ground", "cross", xyz=base_point, axis=(1, 0, 0)),
        _joint("U2", "revolute", "cross", "cylinder", axis=(0, 1, 0)),
        _joint("P", "prismatic", "cylinder", "piston", axis=(0, 0, 1), limits=(0.5, 2.5)),
        _joint("S1", "revolute", "piston", "ball1", axis=(1, 0, 0)),
        _joint("S2", "revolute", "ball1", "ball2", axis=(0, 1, 0)),
        _joint("S3", "revolute", "ball2", "platform", axis=(0, 0, 1)),
    ])


def parallelogram_xml() -> str:
    """Revolute R1 about y, rod of length 1 along x, revolute R2 about y mimicking R1
    with multiplier −1, tip 0.5 further along x."""
    return _robot("parallelogram", [
        _joint("R1", "revolute", "base", "rod", axis=(0, 1, 0), limits=(-1.5, 1.5)),
        _joint("R2", "revolute", "rod", "plate", xyz=(1, 0, 0), axis=(0, 1, 0),
               limits=(-1.5, 1.5), mimic=("R1", -1)),
        _joint("T", "fixed", "plate", "tip", xyz=(0.5, 0, 0)),
    ])


# ------------------------------------------------------------ hand-written maths
def rot_x(t):
    c, s = np.cos(t), np.sin(t)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(t):
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_z(t):
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def hand_line(point, direction):
    """(s; r × s) with s the unit direction."""
    s = np.asarray(direction, float) / np.linalg.norm(direction)
    return np.r_[s, np.cross(point, s)]


def hand_couple(direction):
    return np.r_[np.zeros(3), np.asarray(direction, float) / np.linalg.norm(direction)]


def rpr3_hand_twists(b, q):
    """Corrected eq. 50 for a leg at base pivot b: leg angle a = −q[A0], length q[A1]."""
    a, length = -q[0], q[1]
    d = np.array([np.cos(a), 0.0, np.sin(a)])
    p = b + length * d
    return np.array([np.r_[Y, np.cross(b, Y)], np.r_[np.zeros(3), d], np.r_[Y, np.cross(p, Y)]])


def ups_hand_twists_and_tip(base_point, q, base: pin.SE3):
    """U-P-S joint twists: lines through the joint centres along the current world axes
    (couple along the leg for the prismatic), and the world tip position/rotation."""
    R0, p0 = base.rotation, base.translation
    centre_u = p0 + R0 @ base_point
    R1 = R0 @ rot_x(q[0])
    R2 = R1 @ rot_y(q[1])
    centre_s = centre_u + q[2] * R2[:, 2]
    R3 = R2 @ rot_x(q[3])
    R4 = R3 @ rot_y(q[4])
    twists = np.array([
        hand_line(centre_u, R0[:, 0]),
        hand_line(centre_u, R1[:, 1]),
        hand_couple(R2[:, 2]),
        hand_line(centre_s, R2[:, 0]),
        hand_line(centre_s, R3[:, 1]),
        hand_line(centre_s, R4[:, 2]),
    ])
    return twists, centre_s, R4 @ rot_z(q[5])


def random_q(leg: Leg, rng: np.random.Generator) -> np.ndarray:
    """A configuration uniformly inside the (finite) joint limits."""
    if leg.nq != leg.nv:  # continuous joints (cos, sin): the leg's own sampler
        return leg.random_configuration(rng)
    return rng.uniform(leg.lower, leg.upper)


PLANAR_XZ = np.array([[0, 1, 0, 0, 0, 0], [0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 0, 1]], float)
BASE = pin.SE3(rot_z(0.7) @ rot_x(-0.4), np.array([0.3, -1.2, 0.8]))
UPS_POINT = np.array([0.6, -0.3, 0.1])


def rpr3_leg(b) -> Leg:
    return Leg.from_urdf(rpr3_leg_xml(b), "platform", ["A1"])


def ups_leg(base=None) -> Leg:
    return Leg.from_urdf(ups_leg_xml(UPS_POINT), "platform", ["P"], base=base)


def continuous_xml() -> str:
    """Continuous joint on a slanted axis with rpy, a continuous joint mimicking it
    (multiplier 2, offset 0.1), then a tip: nq = 2, nv = 1."""
    return _robot("cont", [
        '<joint name="J1" type="continuous"><parent link="a"/><child link="b"/>'
        '<origin xyz="0.1 0.2 0.3" rpy="0.3 0.2 0.1"/><axis xyz="1 1 0"/></joint>',
        '<joint name="J2" type="continuous"><parent link="b"/><child link="c"/>'
        '<origin xyz="0.5 0 0"/><axis xyz="0 0 1"/>'
        '<mimic joint="J1" multiplier="2" offset="0.1"/></joint>',
        _joint("T", "fixed", "c", "tip", xyz=(0.4, 0, 0)),
    ])


def parallelogram_leg() -> Leg:
    return Leg.from_urdf(parallelogram_xml(), "tip", ["R1"])


# ---------------------------------------------------------------- 3-RPR (seed 000)
@pytest.mark.parametrize("b_x", [0.0, 1.0, 2.0])
def test_rpr3_joint_twists_match_corrected_eq_50(b_x):
    """Pinocchio's 3-RPR leg twists equal the corrected eq. 50 (unit prismatic screw)."""
    b = np.array([b_x, 0.0, 0.0])
    leg = rpr3_leg(b)
    rng = np.random.default_rng(int(10 * b_x))
    for _ in range(20):
        q = random_q(leg, rng)
        np.testing.assert_allclose(leg.joint_twists(q), rpr3_hand_twists(b, q), atol=1e-12)


def test_rpr3_tip_is_the_platform_pivot():
    """The 3-RPR leg tip sits at b + L (cos a, 0, sin a) with a = −q[A0], turned by
    q[A0] + q[A2] about y."""
    b = np.array([1.0, 0.0, 0.0])
    leg = rpr3_leg(b)
    rng = np.random.default_rng(7)
    for _ in range(10):
        q = random_q(leg, rng)
        a = -q[0]
        tip = leg.tip_placement(q)
        np.testing.assert_allclose(tip.translation, b + q[1] * np.array([np.cos(a), 0, np.sin(a)]),
                                   atol=1e-13)
        np.testing.assert_allclose(tip.rotation, rot_y(q[0] + q[2]), atol=1e-13)


def test_rpr3_leg_properties():
    """The 3-RPR leg has joints A0, A1, A2, nq = nv = 3, and a neutral inside the limits."""
    leg = rpr3_leg([0.0, 0.0, 0.0])
    assert leg.joint_names == ["A0", "A1", "A2"]
    assert leg.actuated == ("A1",)
    assert (leg.nq, leg.nv) == (3, 3)
    q0 = leg.neutral()
    np.testing.assert_allclose(q0, [0.0, 0.2, 0.0], atol=0)  # prismatic clipped to its limit
    assert leg.within_limits(q0)
    np.testing.assert_allclose(leg.lower, [-np.pi, 0.2, -np.pi], atol=1e-15)
    np.testing.assert_allclose(leg.upper, [np.pi, 3.0, np.pi], atol=1e-15)


def _rpr3_assembly(rng):
    """Three 3-RPR legs (base pivots A0, B0, C0 on the x-axis, L3 = L6 = 1) and joint
    values that put their tips on the pivots of one platform pose (x, z, θ)."""
    bases = [np.array([0.0, 0, 0]), np.array([1.0, 0, 0]), np.array([2.0, 0, 0])]
    offsets = [np.array([-0.3, 0, -0.2]), np.array([0.3, 0, -0.2]), np.array([0.0, 0, 0.3])]
    centre = np.array([1.0 + rng.uniform(-0.3, 0.3), 0.0, 1.0 + rng.uniform(-0.3, 0.3)])
    theta = rng.uniform(-0.5, 0.5)
    legs, qs, pivots = [], [], []
    for b, e in zip(bases, offsets):
        p = centre + rot_y(theta) @ e
        a = np.arctan2(p[2] - b[2], p[0] - b[0])
        legs.append(rpr3_leg(b))
        qs.append(np.array([-a, np.linalg.norm(p - b), theta + a]))
        pivots.append(p)
    return legs, qs, pivots, theta


@pytest.mark.parametrize("seed", range(5))
def test_rpr3_legs_twist_systems_intersect_in_eq_55(seed):
    """At an assembly, the three 3-RPR legs' twist systems intersect in (55) and the union
    of their constraint systems is (54); the platform has mobility 3."""
    legs, qs, pivots, theta = _rpr3_assembly(np.random.default_rng(seed))
    twists = []
    for leg, q, p in zip(legs, qs, pivots):
        tip = leg.tip_placement(q)
        np.testing.assert_allclose(tip.translation, p, atol=1e-13)
        np.testing.assert_allclose(tip.rotation, rot_y(theta), atol=1e-13)
        twists.append(leg.joint_twists(q))
    L = float(np.mean([leg.characteristic_length for leg in legs]))
    for T in twists:
        assert screws.rank(T, L) == 3
        assert spans_equal(screws.reciprocal(T, L), PLANAR_XZ, L)  # (54) per leg
    platform = screws.intersection(*twists, length=L)
    assert platform.shape == (3, 6)
    assert spans_equal(platform, PLANAR_XZ, L)  # (55)
    constraints = screws.union(*[screws.reciprocal(T, L) for T in twists], length=L)
    assert spans_equal(constraints, PLANAR_XZ, L)  # (54)
    assert screws.reciprocal(constraints, L).shape == (3, 6)  # mobility 3


# ------------------------------------------------------------- Gough-Stewart U-P-S
@pytest.mark.parametrize("base", [None, BASE], ids=["identity-base", "moved-base"])
def test_ups_joint_twists_are_lines_through_joint_centres(base):
    """U-P-S twists: lines through the U and S centres along the current joint axes, the
    prismatic a couple along the leg; the tip at the S centre (base placement included)."""
    leg = ups_leg(base)
    rng = np.random.default_rng(11)
    for _ in range(20):
        q = random_q(leg, rng)
        expected, centre, rotation = ups_hand_twists_and_tip(
            UPS_POINT, q, base if base is not None else pin.SE3.Identity())
        np.testing.assert_allclose(leg.joint_twists(q), expected, atol=1e-12)
        tip = leg.tip_placement(q)
        np.testing.assert_allclose(tip.translation, centre, atol=1e-13)
        np.testing.assert_allclose(tip.rotation, rotation, atol=1e-13)


def test_ups_spherical_group_is_the_last_three_revolutes():
    """The spherical joint of a U-P-S leg is found as velocity indices (3, 4, 5)."""
    assert ups_leg(BASE).spherical_groups == [(3, 4, 5)]


def test_rpr3_and_ur5_have_no_spherical_group(ur5):
    """Chains without three concurrent revolutes in a row have no spherical group."""
    assert rpr3_leg([0.0, 0.0, 0.0]).spherical_groups == []
    assert ur5.spherical_groups == []
    assert parallelogram_leg().spherical_groups == []


@pytest.mark.parametrize("middle", [np.pi / 2, -np.pi / 2])
def test_ups_motion_twists_full_rank_at_gimbal_lock(middle):
    """At the gimbal lock (middle S angle ±π/2) joint_twists has rank 5 and motion_twists
    rank 6, its spherical rows being three orthogonal lines through the S centre."""
    leg = ups_leg(BASE)
    rng = np.random.default_rng(12)
    L = leg.characteristic_length
    for _ in range(5):
        q = random_q(leg, rng)
        q[4] = middle
        T = leg.joint_twists(q)
        M = leg.motion_twists(q)
        assert rank(T, L) == 5
        assert rank(M, L) == 6
        assert screws.rank(T, L) == 5
        assert screws.rank(M, L) == 6
        centre = leg.tip_placement(q).translation
        expected = np.array([hand_line(centre, e) for e in np.eye(3)])
        np.testing.assert_allclose(M[3:], expected, atol=1e-12)
        np.testing.assert_allclose(M[:3], T[:3], atol=0)


def test_ups_motion_twists_span_joint_twists_away_from_lock():
    """Away from the gimbal lock motion_twists and joint_twists span the same system."""
    leg = ups_leg(BASE)
    rng = np.random.default_rng(13)
    L = leg.characteristic_length
    for _ in range(10):
        q = random_q(leg, rng)
        q[4] = rng.uniform(-1.2, 1.2)
        T, M = leg.joint_twists(q), leg.motion_twists(q)
        assert spans_equal(T[3:], M[3:], L)
        assert rank(T, L) == 6


@pytest.mark.parametrize("k", [1e3, 1e-3])
def test_ups_ranks_and_twists_unit_invariant(k):
    """The U-P-S leg built in mm (or km) has the same ranks, line twists whose moments
    scale by k (the unit couple unchanged), and a characteristic length k times larger."""
    xml = ups_leg_xml(UPS_POINT * k).replace('lower="0.5" upper="2.5"',
                                             f'lower="{0.5 * k!r}" upper="{2.5 * k!r}"')
    base_k = pin.SE3(BASE.rotation, BASE.translation * k)
    leg_k = Leg.from_urdf(xml, "platform", ["P"], base=base_k)
    leg = ups_leg(BASE)
    assert abs(leg_k.characteristic_length - k * leg.characteristic_length) <= (
        1e-12 * k * leg.characteristic_length)
    rng = np.random.default_rng(14)
    for lock in (False, True):
        q = random_q(leg, rng)
        if lock:
            q[4] = np.pi / 2
        q_k = q.copy()
        q_k[2] *= k
        T, T_k = leg.joint_twists(q), leg_k.joint_twists(q_k)
        lines = [0, 1, 3, 4, 5]  # revolute lines: moments scale; the prismatic couple not
        np.testing.assert_allclose(T_k[:, :3], T[:, :3], atol=1e-12)
        np.testing.assert_allclose(T_k[lines, 3:], k * T[lines, 3:], atol=1e-12 * max(k, 1))
        np.testing.assert_allclose(T_k[2], T[2], atol=1e-12)
        assert screws.rank(T_k) == screws.rank(T) == (5 if lock else 6)
        assert screws.rank(leg_k.motion_twists(q_k)) == 6


def test_ups_joint_origins_are_the_joint_centres():
    """joint_origins gives the world joint-frame origins: U centre twice, then the S
    centre for the prismatic (its frame moves with it) and the three S revolutes."""
    leg = ups_leg(BASE)
    q = random_q(leg, np.random.default_rng(15))
    _, centre_s, _ = ups_hand_twists_and_tip(UPS_POINT, q, BASE)
    centre_u = BASE.act(UPS_POINT)
    np.testing.assert_allclose(leg.joint_origins(q), [centre_u, centre_u] + 4 * [centre_s],
                               atol=1e-13)


def test_screws_gives_jacobian_and_motion_twists_of_the_same_q():
    """screws(q) returns jacobian(q) and motion_twists(q), whatever was evaluated before."""
    leg = ups_leg(BASE)
    rng = np.random.default_rng(16)
    q, other = random_q(leg, rng), random_q(leg, rng)
    expected_J, expected_T = leg.jacobian(q), leg.motion_twists(q)
    leg.tip_placement(other)
    J, T = leg.screws(q)
    np.testing.assert_allclose(J, expected_J, atol=1e-14)
    np.testing.assert_allclose(T, expected_T, atol=1e-14)


# -------------------------------------------------------- parallelogram (mimic)
def test_parallelogram_is_one_coordinate():
    """A revolute plus a mimicking revolute (multiplier −1) is one joint coordinate."""
    leg = parallelogram_leg()
    assert leg.joint_names == ["R1"]
    assert (leg.nq, leg.nv) == (1, 1)
    assert leg.actuated == ("R1",)


def test_parallelogram_tip_translates_without_turning():
    """The parallelogram tip keeps its orientation and sits at (cos q + 0.5, 0, −sin q)."""
    leg = parallelogram_leg()
    for q in np.linspace(-1.5, 1.5, 13):
        tip = leg.tip_placement([q])
        np.testing.assert_allclose(tip.rotation, np.eye(3), atol=1e-14)
        np.testing.assert_allclose(tip.translation, [np.cos(q) + 0.5, 0, -np.sin(q)], atol=1e-14)


def test_parallelogram_twist_is_couple_perpendicular_to_rod():
    """The parallelogram's single joint twist is a pure translation perpendicular to the
    rod, of magnitude rod length × rate (1 m per rad)."""
    leg = parallelogram_leg()
    for q in np.linspace(-1.5, 1.5, 13):
        twist = leg.joint_twists([q])
        assert twist.shape == (1, 6)
        rod = np.array([np.cos(q), 0.0, -np.sin(q)])
        np.testing.assert_allclose(twist[0, :3], 0.0, atol=1e-14)
        assert abs(twist[0, 3:] @ rod) <= 1e-14
        np.testing.assert_allclose(twist[0, 3:], [-np.sin(q), 0, -np.cos(q)], atol=1e-14)
        assert screws.pitch(twist[0]) == np.inf


# ------------------------------------------------------------ Jacobian, base
LEG_FACTORIES = {
    "rpr3": lambda: rpr3_leg([1.0, 0.0, 0.0]),
    "ups-moved-base": lambda: ups_leg(BASE),
    "parallelogram": parallelogram_leg,
    "continuous-mimic": lambda: Leg.from_urdf(continuous_xml(), "tip"),
    "ur5": lambda: Leg.from_example_robot_data("ur5"),
    "ur5-moved-base": lambda: Leg.from_example_robot_data("ur5", base=BASE),
    "panda": lambda: Leg.from_example_robot_data("panda"),
}


@pytest.mark.parametrize("name", list(LEG_FACTORIES))
def test_jacobian_matches_finite_differences(name):
    """jacobian(q) equals central differences of tip_placement (pin.integrate, pin.log6)."""
    leg = LEG_FACTORIES[name]()
    rng = np.random.default_rng(21)
    for _ in range(5):
        q = random_q(leg, rng)
        J = leg.jacobian(q)
        assert J.shape == (6, leg.nv)
        np.testing.assert_allclose(J, fd_jacobian(leg, q), atol=1e-7 * (1 + np.abs(J).max()))


@pytest.mark.parametrize("name", ["rpr3", "ups-moved-base", "ur5"])
def test_joint_twists_are_jacobian_columns(name):
    """joint_twists(q) is jacobian(q) transposed (nv × 6)."""
    leg = LEG_FACTORIES[name]()
    q = random_q(leg, np.random.default_rng(22))
    T = leg.joint_twists(q)
    assert T.shape == (leg.nv, 6)
    np.testing.assert_array_equal(T, leg.jacobian(q).T)


def test_jacobian_is_axis_first():
    """A revolute about z at the origin has column (0,0,1 | 0,0,0); a prismatic along x
    has (0,0,0 | 1,0,0)."""
    xml = _robot("rp", [
        _joint("R", "revolute", "a", "b", axis=(0, 0, 1)),
        _joint("P", "prismatic", "b", "c", xyz=(0, 0, 0.5), axis=(1, 0, 0)),
    ])
    leg = Leg.from_urdf(xml, "c")
    J = leg.jacobian([0.0, 0.3])
    np.testing.assert_allclose(J[:, 0], [0, 0, 1, 0, 0, 0], atol=1e-15)
    np.testing.assert_allclose(J[:, 1], [0, 0, 0, 1, 0, 0], atol=1e-15)


@pytest.mark.parametrize("xml_factory, tip", [
    (lambda: ups_leg_xml(UPS_POINT), "platform"),
    (lambda: rpr3_leg_xml([1.0, 0.0, 0.0]), "platform"),
    (parallelogram_xml, "tip"),
])
def test_base_placement_moves_twists_and_tip(xml_factory, tip):
    """With a base placement, twists = transform(twists without base, base) and the tip
    placement = base * tip without base."""
    plain = Leg.from_urdf(xml_factory(), tip)
    moved = Leg.from_urdf(xml_factory(), tip, base=BASE)
    rng = np.random.default_rng(23)
    for _ in range(5):
        q = random_q(plain, rng)
        np.testing.assert_allclose(moved.joint_twists(q),
                                   screws.transform(plain.joint_twists(q), BASE), atol=1e-12)
        assert moved.tip_placement(q).isApprox(BASE * plain.tip_placement(q), 1e-12)


# ---------------------------------------------------------- example-robot-data
def test_ur5_leg_properties(ur5):
    """The UR5 leg has its six joints, all actuated, nq = nv = 6, neutral inside limits."""
    names = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
             "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]
    assert ur5.joint_names == names
    assert ur5.actuated == tuple(names)
    assert (ur5.nq, ur5.nv) == (6, 6)
    q0 = ur5.neutral()
    np.testing.assert_array_equal(q0, np.zeros(6))
    assert ur5.within_limits(q0)
    assert ur5.tip == "tool0"


def test_ur5_zero_pose_matches_dh_constants(ur5):
    """UR5 tool0 at q = 0 is at (a2 + a3, d4 + d6, d1 − d5) of the UR5 DH table."""
    a2, a3, d1, d4, d5, d6 = 0.425, 0.39225, 0.089159, 0.10915, 0.09465, 0.0823
    tip = ur5.tip_placement(np.zeros(6))
    np.testing.assert_allclose(tip.translation, [a2 + a3, d4 + d6, d1 - d5], atol=1e-9)


def test_panda_leg_properties(panda):
    """The Panda leg to panda_link8 has the seven arm joints (no finger)."""
    assert panda.joint_names == [f"panda_joint{i}" for i in range(1, 8)]
    assert (panda.nq, panda.nv) == (7, 7)
    assert panda.within_limits(panda.neutral())
    assert panda.jacobian(panda.neutral()).shape == (6, 7)


def test_panda_finger_branch_includes_finger_joint():
    """The chain to panda_leftfinger is the arm plus panda_finger_joint1 (prismatic)."""
    leg = Leg.from_example_robot_data("panda", "panda_leftfinger")
    assert leg.joint_names == [f"panda_joint{i}" for i in range(1, 8)] + ["panda_finger_joint1"]
    q = leg.neutral()
    np.testing.assert_allclose(leg.joint_twists(q)[-1, :3], 0.0, atol=1e-15)
    np.testing.assert_allclose(leg.jacobian(q), fd_jacobian(leg, q), atol=1e-7)


def test_panda_mimic_finger_branch_keeps_its_primary_joint():
    """The chain to panda_rightfinger (joint mimicking panda_finger_joint1, which lies on
    another branch) builds, keeping the primary joint as the finger coordinate."""
    leg = Leg.from_example_robot_data("panda", "panda_rightfinger")
    assert leg.nv == 8
    assert "panda_finger_joint1" in leg.joint_names
    q = leg.neutral()
    np.testing.assert_allclose(leg.jacobian(q), fd_jacobian(leg, q), atol=1e-7)
    left = Leg.from_example_robot_data("panda", "panda_leftfinger")
    np.testing.assert_allclose(leg.joint_twists(q)[-1], -left.joint_twists(q)[-1], atol=1e-12)


# ----------------------------------------------------------------------- solve
def _closure_residual(tip: pin.SE3, target: pin.SE3, length: float) -> float:
    """The closure residual by hand: world rotation vector of ``R_target R_tipᵀ`` and tip
    displacement / length (pkm_pin.solve.closure_error)."""
    w = pin.log3(target.rotation @ tip.rotation.T)
    d = (target.translation - tip.translation) / length
    return float(np.sqrt(w @ w + d @ d))


def test_solve_reaches_random_ur5_targets(ur5):
    """Leg.solve reaches reachable UR5 targets: converged, residual < 1e-10, in limits."""
    rng = np.random.default_rng(31)
    for _ in range(5):
        target = ur5.tip_placement(random_q(ur5, rng))
        sol = ur5.solve(target)
        assert isinstance(sol, LegSolution)
        assert sol.converged
        assert sol.residual < 1e-10
        assert ur5.within_limits(sol.q, tol=0.0)
        assert ur5.tip_placement(sol.q).isApprox(target, 1e-9)


def test_solve_with_base_placement_reaches_world_targets():
    """Leg.solve takes world targets for a leg whose base is moved."""
    leg = Leg.from_example_robot_data("ur5", base=BASE)
    rng = np.random.default_rng(32)
    for _ in range(3):
        target = leg.tip_placement(random_q(leg, rng))
        sol = leg.solve(target)
        assert sol.converged and sol.residual < 1e-10
        assert leg.tip_placement(sol.q).isApprox(target, 1e-9)


def test_solve_warm_start_near_solution_converges_quickly(ur5):
    """A warm start next to the solution converges within a few iterations."""
    rng = np.random.default_rng(33)
    q_true = random_q(ur5, rng) * 0.5
    sol = ur5.solve(ur5.tip_placement(q_true), q0=q_true + 1e-3)
    assert sol.converged
    assert sol.iterations <= 10
    np.testing.assert_allclose(sol.q, q_true, atol=1e-8)


def test_solve_unreachable_target_reports_failure():
    """A 1-DOF leg asked for an impossible pose returns converged False, residual > 1e-3,
    q within limits, without raising; the residual is that of the q returned."""
    xml = _robot("one", [
        _joint("R", "revolute", "a", "b", axis=(0, 0, 1), limits=(-1.0, 1.0)),
        _joint("T", "fixed", "b", "tip", xyz=(1, 0, 0)),
    ])
    leg = Leg.from_urdf(xml, "tip", ["R"])
    target = pin.SE3(rot_x(0.3), np.array([0.0, 2.0, 0.5]))
    sol = leg.solve(target)
    assert not sol.converged
    assert sol.residual > 1e-3
    assert leg.within_limits(sol.q, tol=0.0)
    actual = _closure_residual(leg.tip_placement(sol.q), target, leg.characteristic_length)
    assert abs(actual - sol.residual) <= 1e-9 * sol.residual


@pytest.mark.parametrize("max_iter", [1, 2, 3, 5])
def test_solve_residual_is_that_of_the_returned_q(ur5, max_iter):
    """When Newton stops at max_iter, LegSolution.residual is the pose error of the q it
    returns (not of the iterate before the last step)."""
    rng = np.random.default_rng(31)
    target = ur5.tip_placement(random_q(ur5, rng))
    sol = ur5.solve(target, max_iter=max_iter, restarts=0)
    actual = _closure_residual(ur5.tip_placement(sol.q), target, ur5.characteristic_length)
    assert abs(actual - sol.residual) <= 1e-9 * max(actual, 1e-12)
    assert sol.converged == (actual <= 1e-12)


# ---------------------------------------------------------------------- inputs
@pytest.mark.parametrize("bad", [np.zeros(5), np.zeros(7), np.zeros((6, 1)),
                                 np.r_[np.zeros(5), np.nan], np.r_[np.inf, np.zeros(5)]],
                         ids=["short", "long", "column", "nan", "inf"])
@pytest.mark.parametrize("method", ["tip_placement", "jacobian", "joint_twists",
                                    "motion_twists", "kinematics"])
def test_bad_configuration_raises_input_error(ur5, method, bad):
    """q of the wrong length or with NaN/inf raises InputError naming the leg."""
    with pytest.raises(InputError, match="ur5"):
        getattr(ur5, method)(bad)


def test_configuration_may_be_a_list(ur5):
    """A plain list is accepted as a configuration."""
    q = [0.1, -0.2, 0.3, 0.4, -0.5, 0.6]
    assert ur5.tip_placement(q).isApprox(ur5.tip_placement(np.array(q)), 0.0)


def test_solve_takes_the_same_steps_in_millimetres():
    """Leg.solve's unknowns are dimensionless (prismatic increments / L): a U-P-S leg in
    millimetres converges in the same number of iterations to the same configuration
    (lengths × 1000) as in metres (before: ~40× more iterations in mm)."""
    from pkm_pin.builders import MECHANISMS

    m, mm = MECHANISMS["stewart"]().build(), MECHANISMS["stewart"](scale=1000.0).build()
    leg, leg_mm = m.legs[0], mm.legs[0]
    units = np.where(leg._velocity_units > 1.0, 1000.0, 1.0)
    rng = np.random.default_rng(5)
    for _ in range(5):
        t = np.r_[rng.normal(size=3) * 0.1, rng.normal(size=3) * 0.05]
        target = screws.exp(t) * m.home * m.anchors[0]
        target_mm = pin.SE3(target.rotation, 1000.0 * target.translation)
        a = leg.solve(target, m.home_assembly.leg_q[0])
        b = leg_mm.solve(target_mm, mm.home_assembly.leg_q[0])
        assert a.converged and b.converged
        assert a.iterations == b.iterations
        np.testing.assert_allclose(b.q, a.q * units, rtol=1e-9, atol=1e-9)
