"""Linkage (issue 16): assembly, mobility, output analysis, velocity maps and position
problems of general closed-loop mechanisms, and its agreement with seed 000's per-leg
reading on every shipped mechanism.

Numbers asserted: the four-bar crank-rocker (0.2, 0.6, 0.5, 0.7 m) against its closed
form (angles, ω4/ω2 = a sin(θ3 − θ2) / (c sin(θ3 − θ4)), dead centres = class I, driven
from the rocker = class II); the five-bar (unit links, bases 1.5 m apart): dof 2, type II
with the distal links collinear at cos α = −1/4, type I with branch B stretched; the
RSSR rod: dof 2, one idle spin about the line through its two spherical centres.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from linkage_models import (
    CRANK,
    GROUND,
    ROCKER,
    five_bar,
    five_bar_q,
    four_bar,
    four_bar_angles,
    four_bar_dead_centre,
    four_bar_q,
    spherical_rod,
)

import pkm_pin
from pkm_pin import engine, screws
from pkm_pin.errors import AssemblyError, InputError, SingularityError, TreeFrameNotFound
from pkm_pin.linkage import Linkage, LoopClosureError
from pkm_pin.model.closure_model import configuration, from_mechanism

TOML = sorted(Path(__file__).resolve().parents[1].glob("models/mechanisms/*.toml"))
FAR = pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.5, 1.1), np.array([100.0, -40.0, 25.0]))


@functools.lru_cache(maxsize=None)
def shipped(path: Path):
    mech = pkm_pin.load_mechanism(path)
    return mech, Linkage(from_mechanism(mech)), configuration(mech, mech.home_assembly)


def fd_velocity(link: Linkage, a, h: float = 1e-6):
    """Central differences over forward kinematics: output twists (6 × n, world origin,
    from log6 of the output poses) and tree velocities (nv × n, pin.difference)."""
    T, V = [], []
    for k in range(len(link.actuated)):
        dq = np.zeros(len(link.actuated))
        dq[k] = h
        p = link.forward_kinematics(a.q_actuated + dq, a.q, starts=0)
        m = link.forward_kinematics(a.q_actuated - dq, a.q, starts=0)
        T.append(screws.log(p.output_pose * m.output_pose.inverse()) / (2 * h))
        V.append(pin.difference(link.model.tree, m.q, p.q) / (2 * h))
    return np.array(T).T, np.array(V).T


# ------------------------------------------------------------------ four-bar
def test_four_bar_assembles_from_an_open_reference():
    """The neutral reference leaves a 0.4 m gap; assembly closes it to 1e-12 and names
    the loop's residual."""
    link = Linkage(four_bar())
    assert np.linalg.norm(link.model.closure_residual(link.model.reference)) > 0.3
    a = link.assemble()
    assert a.residual <= 1e-12 and set(a.closure_residuals) == {"loop"}
    t2 = a.q_actuated[0]
    t3, t4, _ = four_bar_angles(t2)
    crossed = abs(np.sin(a.q[2] - t4)) > 1e-6
    if not crossed:
        np.testing.assert_allclose(np.sin(a.q[2] - t4), 0.0, atol=1e-9)


def test_four_bar_forward_kinematics_and_velocity_closed_form():
    """FK equals the closed-form angles; ω4/ω2 = a sin(θ3 − θ2) / (c sin(θ3 − θ4)); the
    velocity maps equal finite differences of FK."""
    link = Linkage(four_bar())
    a = link.forward_kinematics([0.7], four_bar_q(0.6))
    np.testing.assert_allclose(a.q, four_bar_q(0.7), atol=1e-10)
    an = link.analyze(a.q)
    assert (an.dof, an.output_dof, an.motion_type, an.redundant_constraints) == (1, 1, "1R", 1)
    assert an.mobility.grubler == 0 and an.singularity == "none"
    t3, t4, _ = four_bar_angles(0.7)
    ratio = CRANK * np.sin(t3 - 0.7) / (ROCKER * np.sin(t3 - t4))
    t = an.forward_velocity([1.0])
    np.testing.assert_allclose(t, [0, 0, ratio, 0, -GROUND * ratio, 0], atol=1e-10)
    T, V = fd_velocity(link, a)
    np.testing.assert_allclose(t, T[:, 0], atol=1e-7)
    np.testing.assert_allclose(an.joint_rates([1.0]), V[:, 0], atol=1e-7)
    np.testing.assert_allclose(an.inverse_velocity(t), [1.0], atol=1e-10)
    np.testing.assert_allclose(an.A @ screws.DELTA @ t, an.B @ [1.0], atol=1e-10)


def test_four_bar_dead_centres_are_type_I_and_rocker_drive_type_II():
    """Near the extended dead centre (crank and coupler collinear) the rocker's rate
    ω4/ω2 = a sin(θ3 − θ2) / (c sin(θ3 − θ4)) vanishes linearly in the crank's distance δ
    from it, and so does the inverse index (crank driven) and the forward index (rocker
    driven); 1e-8 rad off it both read as class I / class II and the unbounded maps
    raise. Nothing is asserted at the exact dead centre, where rounding decides."""
    theta2, dead = four_bar_dead_centre()
    link = Linkage(four_bar())
    driven = Linkage(four_bar(actuated=("rocker",), output="crank_body"))
    assert np.abs(link.model.closure_residual(dead)).max() < 1e-12
    slopes = []
    for delta in (1e-3, -1e-3, 1e-4, -1e-4, 1e-8, -1e-8):
        crank = theta2 - delta
        a = link.forward_kinematics([crank], dead + [0, 0.01 * np.sign(delta), 0], starts=0)
        an, dn = link.analyze(a.q), driven.analyze(a.q)
        t3, t4 = a.q[0] + a.q[1], a.q[2]
        ratio = CRANK * np.sin(t3 - crank) / (ROCKER * np.sin(t3 - t4))
        assert abs(ratio) < abs(delta)  # the rocker stops at the dead centre
        np.testing.assert_allclose(an.forward_velocity([1.0])[2], ratio, rtol=1e-6)
        np.testing.assert_allclose(dn.indices["forward"], an.indices["inverse"], rtol=1e-6)
        slopes.append(an.indices["inverse"] / abs(delta))
        if abs(delta) < 1e-7:
            assert an.dof == dn.dof == 1
            assert an.singularity == "I" and dn.singularity == "II"
            with pytest.raises(SingularityError):
                an.inverse_velocity(an.platform_twists[0])
            with pytest.raises(SingularityError):
                dn.forward_velocity([1.0])
        else:
            assert an.singularity == dn.singularity == "none"
    np.testing.assert_allclose(slopes, slopes[2], rtol=1e-2)  # linear in δ
    assert Linkage(four_bar()).analyze(four_bar_q(1.5)).singularity == "none"


def test_transmission_angle_closed_form():
    """The general forward index follows the transmission angle: it is largest where μ
    is nearest 90° along a crank revolution (the sweep samples both)."""
    link = Linkage(four_bar())
    angles = np.linspace(0.1, 2 * np.pi + 0.1, 40)
    sw = link.sweep(angles[:, None], four_bar_q(0.1))
    assert sw.converged.all() and (sw.dof == 1).all()
    t4 = [four_bar_angles(t)[1] for t in angles]
    np.testing.assert_allclose(np.cos(sw.q[:, 2] - t4), 1.0, atol=1e-9)
    mu = np.array([four_bar_angles(t)[2] for t in angles])
    assert abs(mu[np.argmax(sw.forward)] - np.pi / 2) <= abs(mu[np.argmin(sw.forward)] - np.pi / 2)


def test_inverse_kinematics_of_a_one_dof_output():
    """IK to the rocker pose of crank 1.1 rad recovers crank 1.1 rad (one targeted row)."""
    link = Linkage(four_bar())
    goal = link.forward_kinematics([1.1], four_bar_q(1.0))
    a = link.inverse_kinematics(goal.output_pose, four_bar_q(1.0))
    np.testing.assert_allclose(a.q, four_bar_q(1.1), atol=1e-9)


def test_loop_that_cannot_close_is_named():
    """A four-bar whose coupler is too short raises LoopClosureError naming 'loop'."""
    link = Linkage(four_bar(lengths=(0.2, 0.1, 0.2, 1.0)))
    with pytest.raises(LoopClosureError, match="loop 'loop' does not close") as e:
        link.assemble(starts=4)
    assert isinstance(e.value, AssemblyError) and e.value.residual > 0.1


# ----------------------------------------------------------------- five-bar
@pytest.mark.parametrize("kind, redundant", [("point", 1), ("revolute", 3)])
def test_five_bar_mobility_and_velocity(kind, redundant):
    """Point or revolute closure: dof 2, both actuators independent; the velocity maps
    equal finite differences of FK."""
    link = Linkage(five_bar(kind))
    q0 = five_bar_q([0.75, 1.2])
    a = link.forward_kinematics(q0[[0, 2]], q0)
    an = link.analyze(a.q)
    assert (an.dof, an.idle_dof, an.redundant_constraints) == (2, 0, redundant)
    assert an.mobility.independent_actuators == ("A1", "B1") and an.singularity == "none"
    T, V = fd_velocity(link, a)
    for k, qd in enumerate(np.eye(2)):
        np.testing.assert_allclose(an.forward_velocity(qd), T[:, k], atol=1e-7)
        np.testing.assert_allclose(an.joint_rates(qd), V[:, k], atol=1e-7)
        np.testing.assert_allclose(an.inverse_velocity(T[:, k]), qd, atol=1e-6)


def test_five_bar_singularities_closed_form():
    """Distal links collinear (cos α = −1/4): class II; branch B stretched: class I."""
    link = Linkage(five_bar())
    al = np.arccos(-0.25)
    q2 = np.array([al, -al, np.pi - al, al])
    assert np.abs(link.model.closure_residual(q2)).max() < 1e-12
    an = link.analyze(q2)
    assert an.singularity == "II" and an.indices["forward"] < 1e-9
    P = np.array([1.5, 0.0]) + 2 * np.array([np.cos(2 * np.pi / 3), np.sin(2 * np.pi / 3)])
    q1 = five_bar_q(P)
    assert np.abs(link.model.closure_residual(q1)).max() < 1e-12
    an = link.analyze(q1)
    assert an.singularity == "I" and an.indices["inverse"] < 1e-7  # √round-off: 3e-8


# --------------------------------------------------------------- idle motion
def test_rod_idle_spin_is_described():
    """The RSSR rod spins about the line through its two spherical centres: dof 2, one
    idle motion, one independent actuator, Grübler 2."""
    link = Linkage(spherical_rod())
    a = link.assemble()
    m = link.mobility(a.q)
    assert (m.dof, m.idle_dof, m.grubler, m.independent_actuators) == (2, 1, 2, ("crank",))
    kin = link.model.kinematics(a.q)
    centre = kin.joint_placements[link.model.tree.getJointId("ball")].translation
    end = kin.frame_placements[link.model.tree.getFrameId("rod_end")].translation
    text = m.idle_motions[0]
    assert text.startswith("rod spins about the line through its joints at")
    for p in (centre, end):
        assert "(" + ", ".join(f"{x:.6g}" for x in np.where(abs(p) < 1e-12, 0, p)) + ")" in text
    an = link.analyze(a.q)
    assert an.output_dof == 1 and an.singularity == "none"
    T, V = fd_velocity(link, a)
    np.testing.assert_allclose(an.forward_velocity([1.0]), T[:, 0], atol=1e-7)


# --------------------------------------------------------------- invariance
@pytest.mark.parametrize("build, q", [(four_bar, four_bar_q(0.7)),
                                      (five_bar, five_bar_q([0.75, 1.2]))])
def test_unit_and_frame_invariance(build, q):
    """Millimetres and a copy 100 m away, turned, give the same ranks, classes and
    indices (homogenised about the output frame)."""
    ref = Linkage(build()).analyze(q)
    for model in (build(scale=1000.0), build(where=FAR)):
        an = Linkage(model).analyze(q)
        assert (an.dof, an.output_dof, an.motion_type, an.singularity) == \
            (ref.dof, ref.output_dof, ref.motion_type, ref.singularity)
        for k, v in ref.indices.items():
            assert an.indices[k] == pytest.approx(v, rel=1e-7, abs=1e-9)


def test_idle_motion_invariance():
    """The rod's idle spin survives millimetres and a far, turned placement."""
    base = Linkage(spherical_rod())
    q = base.assemble().q
    for model in (spherical_rod(scale=1000.0), spherical_rod(where=FAR)):
        m = Linkage(model).mobility(q)
        assert (m.dof, m.idle_dof) == (2, 1) and m.idle_motions[0].startswith("rod spins")


# ------------------------------------------------------ per-leg equivalence
@pytest.mark.parametrize("path", TOML, ids=[p.stem for p in TOML])
def test_equals_seed_000_reading(path):
    """On every shipped mechanism the linkage reading equals pkm_pin.Analysis: dof,
    motion type, class, forward and inverse velocity maps, indices (both homogenise
    about the platform's origin), A and B, and the constraint wrench span; about the
    world origin too (the engine analysing screws about the world origin)."""
    mech, link, q = shipped(path)
    ref = mech.home_analysis
    an = link.analyze(q)
    assert (an.dof, an.output_dof, an.idle_dof) == (ref.dof, ref.dof, 0)
    assert an.motion_type == ref.motion_type and an.singularity == ref.singularity
    for k in ("type_I", "type_II", "condition_A"):
        assert an.indices[k] == pytest.approx(ref.indices[k], abs=1e-9, rel=1e-9)
    np.testing.assert_allclose(an.A, ref.A, atol=1e-9)
    np.testing.assert_allclose(an.B, ref.B, atol=1e-9)
    qd = np.random.default_rng(1).normal(size=mech.n_actuated)
    t = ref.forward_velocity(qd)
    for a in (an, link.analyze(q)):
        np.testing.assert_allclose(a.forward_velocity(qd), t, atol=1e-9)
        np.testing.assert_allclose(a.inverse_velocity(t), ref.inverse_velocity(t), atol=1e-9)
        assert a.singularity == ref.singularity
    L = mech.characteristic_length
    proj = [screws.homogenise(C, L) for C in (an.constraint_wrenches, ref.constraint_wrenches)]
    proj = [np.linalg.pinv(C) @ C if len(C) else np.zeros((6, 6)) for C in proj]
    np.testing.assert_allclose(proj[0], proj[1], atol=1e-9)
    # about the world origin: the engine on the same twists with the centre at the origin
    world = link.analyze(q, about="world")
    r = engine.analyse(ref.joint_twists[None], mech.engine_layout)
    for k, key in (("type_I", "type_I"), ("type_II", "type_II"), ("condition_A", "condition")):
        assert world.indices[k] == pytest.approx(float(getattr(r, key)[0]), abs=1e-9,
                                                 rel=1e-9)
    np.testing.assert_allclose(world.A, r.A[0], atol=1e-9)


@pytest.mark.parametrize("path", TOML[-3:], ids=[p.stem for p in TOML[-3:]])
def test_shipped_inverse_kinematics(path):
    """IK to the output pose of a nearby FK solution recovers its actuated values."""
    mech, link, q = shipped(path)
    a0 = link.assemble(q, starts=0)
    goal = link.forward_kinematics(a0.q_actuated + 0.01 * mech.actuated_scales, q, starts=0)
    a = link.inverse_kinematics(goal.output_pose, q, starts=0)
    np.testing.assert_allclose(a.q_actuated, goal.q_actuated, atol=1e-8)


# ------------------------------------------------------------------ bad input
def test_bad_input():
    """Wrong sizes, non-finite values and unknown frames raise one-line InputErrors."""
    link = Linkage(four_bar())
    with pytest.raises(InputError, match="must have 3"):
        link.analyze(np.zeros(4))
    with pytest.raises(InputError, match="q_actuated must have 1"):
        link.forward_kinematics([0.1, 0.2])
    with pytest.raises(InputError, match="finite"):
        link.forward_kinematics([np.nan])
    with pytest.raises(TreeFrameNotFound, match="nowhere"):
        Linkage(four_bar(), output="nowhere")
    with pytest.raises(InputError, match="about"):
        link.analyze(four_bar_q(0.5), about="moon")
    with pytest.raises(InputError, match="pose"):
        link.inverse_kinematics(np.eye(4))
    with pytest.raises(InputError, match="not a motion"):
        link.analyze(four_bar_q(0.5)).inverse_velocity([1, 0, 0, 0, 0, 0])
