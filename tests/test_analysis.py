"""Closed-loop analysis: mobility, A/B Jacobians, velocity maps, singularity classes."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from helpers import shipped_mechanisms

from pkm_pin import Assembly, AssemblyError, InputError, SingularityError, screws
from pkm_pin.builders.planar import rpr3_type2_pose, rrr3_stretched_pose
from pkm_pin.builders.spatial import upu3_constraint_singular_pose
from pkm_pin.crosscheck import crosscheck

# name -> (dof, motion type, Grübler count, redundant constraints)
EXPECTED = {
    "rpr3": (3, "2T1R", -3, 6),
    "rrr3": (3, "2T1R", -3, 6),
    "stewart": (6, "3T3R", 6, 0),
    "delta": (3, "3T", 0, 3),
    "upu3": (3, "3T", 3, 0),
    "rps3": (3, "1T2R", 3, 0),
}

#: Built mechanism, cached per (name, scale) for the whole module.
mechanism = shipped_mechanisms()


#: mechanisms whose platform motion is not a subgroup (exp of a platform twist leaves
#: the assembly manifold): their random poses need the forward position solution
CURVED = {"rps3"}


def nearby_pose(mech, rng, size=0.03):
    """A pose reached from home by a small random motion inside the platform twists
    (home itself for mechanisms in CURVED)."""
    if mech.name.startswith("3-RPS"):
        return mech.home
    an = mech.analyze()
    # rows of platform_twists are orthonormal once v is divided by the characteristic
    # length: this motion turns by about `size` rad and moves by about `size` lengths
    t = rng.normal(size=an.dof) * size @ an.platform_twists
    return screws.exp(t) * mech.home


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_mobility_of_shipped_models(name):
    """DOF, motion type, Grübler count and redundant constraints match the known values."""
    an = mechanism(name).analyze()
    dof, motion, grubler, redundant = EXPECTED[name]
    assert (an.dof, an.motion_type, an.grubler, an.redundant_constraints) == (
        dof, motion, grubler, redundant)
    assert an.dof == an.grubler + an.redundant_constraints
    assert an.singularity == "none"
    assert not an.constraint_singular


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_velocity_maps_match_finite_differences(name):
    """forward/inverse velocity agree with central differences of the assembly along exp6."""
    mech = mechanism(name)
    rng = np.random.default_rng(7)
    for _ in range(2):
        assembly = mech.assemble(nearby_pose(mech, rng), mech.home_assembly)
        an = mech.analyze(assembly)
        qd = rng.normal(size=mech.n_actuated)
        t = an.forward_velocity(qd)
        np.testing.assert_allclose(an.inverse_velocity(t), qd, rtol=1e-9, atol=1e-9)
        h = 1e-6  # exp(±h t) leaves a curved assembly manifold by O(h²): tol 1e-9
        plus = mech.assemble(screws.exp(h * t) * assembly.pose, assembly, tol=1e-9)
        minus = mech.assemble(screws.exp(-h * t) * assembly.pose, assembly, tol=1e-9)
        fd = (plus.q_actuated - minus.q_actuated) / (2 * h)
        np.testing.assert_allclose(fd, qd, rtol=1e-5, atol=1e-6 * np.abs(qd).max())


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_passive_rates_reproduce_the_platform_twist(name):
    """Every leg's joint rates from passive_rates map through its Jacobian to the twist."""
    mech = mechanism(name)
    an = mech.analyze()
    t = np.random.default_rng(3).normal(size=an.dof) @ an.platform_twists
    for leg_screws, qd in zip(an.legs, an.passive_rates(t)):
        np.testing.assert_allclose(leg_screws.jacobian @ qd, t, atol=1e-10)


@pytest.mark.parametrize("name", ["rpr3", "stewart"])
def test_pinocchio_path_equals_hand_written_formulas(name):
    """The Pinocchio path equals the hand-written formulas to 1e-9 at random poses."""
    mech = mechanism(name)
    rng = np.random.default_rng(11)
    for _ in range(5):
        an = mech.analyze(mech.assemble(nearby_pose(mech, rng, 0.1)))
        errors = crosscheck(an)
        assert errors is not None and max(errors.values()) < 1e-9, errors


def test_rpr3_type2_pose_is_type_II_with_a_real_uncontrolled_twist():
    """At concurrent leg lines the 3-RPR is type II and its uncontrolled twist moves no actuator."""
    mech = mechanism("rpr3")
    an = mech.analyze(rpr3_type2_pose())
    assert an.singularity == "II"
    assert an.indices["type_II"] < 1e-9
    t = an.uncontrolled_twist
    assert np.linalg.norm(an.A @ screws.DELTA @ t) < 1e-9 * np.linalg.norm(t)
    assert screws.contains(an.platform_twists, t)
    with pytest.raises(SingularityError, match="type II"):
        an.forward_velocity([0.1, 0.0, 0.0])
    w = an.unresisted_wrench
    assert abs(screws.reciprocal_product(w, t)) > 1e-3 * np.linalg.norm(w) * np.linalg.norm(t)


def test_rrr3_stretched_leg_is_type_I():
    """A fully stretched 3-RRR leg gives a type I singularity and refuses inverse velocity."""
    mech = mechanism("rrr3")
    an = mech.analyze(rrr3_stretched_pose())
    assert an.singularity == "I"
    assert an.indices["type_I"] < 1e-9
    assert an.lost_actuated_rates is not None
    t = an.platform_twists[0]
    with pytest.raises(SingularityError, match="type I"):
        an.inverse_velocity(t)


def test_rrr3_type_III_pose():
    """A stretched 3-RRR leg whose distal lines are also concurrent is type III."""
    from scipy.optimize import brentq

    mech = mechanism("rrr3")
    home = mech.home_assembly
    stretched = mech.assemble(rrr3_stretched_pose(), home)
    leg1 = mech.legs[0]
    base1 = leg1.joint_origins(stretched.leg_q[0])[0]
    reach = np.linalg.norm(leg1.tip_placement(stretched.leg_q[0]).translation - base1)
    anchor_xy = mech.anchors[0].translation
    theta = pin.rpy.matrixToRpy(stretched.pose.rotation)[2]
    R = pin.rpy.rpyToMatrix(0, 0, theta)

    def pose_at(phi):
        """Platform pose with leg 1 stretched towards direction phi (orientation fixed)."""
        pivot = base1 + reach * np.array([np.cos(phi), np.sin(phi), 0.0])
        return pin.SE3(R, pivot - R @ anchor_xy)

    d = stretched.pose.translation + R @ anchor_xy - base1
    phi0 = np.arctan2(d[1], d[0])

    def assembly_at(phi):
        """Leg 1 set exactly stretched (solving it would stop ~1e-5 rad short of it)."""
        q1 = stretched.leg_q[0] + (phi - phi0) * np.array([1.0, 0.0, -1.0])
        pose = pose_at(phi)
        assert leg1.tip_placement(q1).isApprox(pose * mech.anchors[0], 1e-12)
        others = mech.assemble(pose, stretched, tol=1e-10).leg_q[1:]
        return Assembly(mech, pose, [q1, *others])

    def concurrency(phi):
        asm = assembly_at(phi)
        pts = [leg.joint_origins(q) for leg, q in zip(mech.legs, asm.leg_q)]
        lines = np.array([screws.line(p[1], p[2] - p[1]) for p in pts])
        return np.linalg.det(lines[:, [0, 1, 5]])  # (d_x, d_y, m_z) of planar lines

    grid = phi0 + np.linspace(-0.6, 0.6, 49)
    values = []
    for phi in grid:
        try:
            values.append(concurrency(phi))
        except AssemblyError:
            values.append(np.nan)
    values = np.array(values)
    k = next(i for i in range(len(grid) - 1)
             if np.isfinite(values[i]) and np.isfinite(values[i + 1])
             and values[i] * values[i + 1] < 0)
    phi = brentq(concurrency, grid[k], grid[k + 1], xtol=1e-15)
    an = mech.analyze(assembly_at(phi))
    assert an.singularity == "III"
    assert an.indices["type_I"] < 1e-9 and an.indices["type_II"] < 1e-9


def test_upu3_constraint_singularity():
    """At its constraint singular pose the 3-UPU gains a rotation: 4 DOF, constraint singular."""
    mech = mechanism("upu3")
    an = mech.analyze(upu3_constraint_singular_pose())
    assert an.constraint_singular
    assert an.dof == 4
    assert an.motion_type == "3T1R"


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_millimetres_give_the_same_answers(name):
    """Scaled to millimetres: same DOF, motion type, classes; velocities scale by 1000."""
    m, mm = mechanism(name), mechanism(name, 1000.0)
    a, b = m.analyze(), mm.analyze()
    assert (a.dof, a.motion_type, a.singularity, a.redundant_constraints) == (
        b.dof, b.motion_type, b.singularity, b.redundant_constraints)
    for key in ("type_I", "type_II"):
        assert a.indices[key] == pytest.approx(b.indices[key], rel=1e-6)
    # actuated rates: prismatic in m/s become mm/s
    prismatic = np.array([leg.model.joints[leg.model.getJointId(j)].shortname().startswith(
        "JointModelP") for leg in m.legs for j in leg.actuated])
    qd = np.random.default_rng(1).normal(size=m.n_actuated)
    t = a.forward_velocity(qd)
    t_mm = b.forward_velocity(np.where(prismatic, 1000.0 * qd, qd))
    np.testing.assert_allclose(t_mm, np.r_[t[:3], 1000.0 * t[3:]], rtol=1e-7,
                               atol=1e-9 * np.abs(t_mm).max())


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_rotated_mechanism_gives_transformed_answers(name):
    """Rotating the whole mechanism rotates its twists and keeps DOF and classes."""
    from pkm_pin import Mechanism

    m = mechanism(name)
    R = pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.7, 1.1), np.array([0.2, -0.1, 0.4]))
    legs = []
    for leg in m.legs:
        clone = type(leg).from_urdf(leg.xml, leg.tip, leg.actuated, R * leg.base, leg.name)
        legs.append(clone)
    rotated = Mechanism(legs, m.anchors, m.name, R * m.home, m.home_assembly.leg_q)
    a, b = m.analyze(), rotated.analyze()
    assert (a.dof, a.motion_type, a.singularity) == (b.dof, b.motion_type, b.singularity)
    qd = np.random.default_rng(2).normal(size=m.n_actuated)
    np.testing.assert_allclose(b.forward_velocity(qd), screws.transform(a.forward_velocity(qd), R),
                               atol=1e-9)


def test_inverse_velocity_refuses_a_twist_outside_the_platform_system():
    """A rotation about x is no motion of the planar 3-RPR: a specific InputError."""
    an = mechanism("rpr3").analyze()
    with pytest.raises(InputError, match="not a motion of the platform"):
        an.inverse_velocity([1.0, 0, 0, 0, 0, 0])
    with pytest.raises(InputError, match="shape"):
        an.inverse_velocity([1.0, 0, 0])
    with pytest.raises(InputError, match="3 values"):
        an.forward_velocity([1.0, 0.0])
    with pytest.raises(InputError, match="finite"):
        an.forward_velocity([np.nan, 0.0, 0.0])


def test_full_jacobian_stacks_actuation_and_constraints():
    """For the 3-RPR the full Jacobian is 6×6, invertible, and annihilates nothing else."""
    an = mechanism("rpr3").analyze()
    J = an.full_jacobian
    assert J.shape == (6, 6)
    assert screws.rank(J) == 6
    t = an.forward_velocity([0.2, -0.1, 0.3])
    np.testing.assert_allclose((J @ screws.DELTA @ t)[3:], 0.0, atol=1e-12)
