"""Position problems (seed 003): continuation FK, IK, assembly modes, iterative IK.

Seed 003: Demidov 2025, see docs/references.md.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from helpers import random_platform_twist, shipped_mechanisms

from pkm_pin import Leg, screws
from pkm_pin.builders import MECHANISMS, rpr3_type2_pose
from pkm_pin.builders.spatial import stewart
from pkm_pin.errors import ForwardKinematicsError, InputError, SingularityError
from pkm_pin.formulas.stewart import SEED003_DL, SEED003_LINES, SEED003_TWIST, seed003_geometry
from pkm_pin.position import iterative_ik, screw_step

#: Shipped mechanism ``name``, built once for the module.
mech = shipped_mechanisms()


def pose_error(a: pin.SE3, b: pin.SE3, L: float) -> float:
    e = pin.log6(a.actInv(b)).vector
    return float(np.max(np.abs(np.r_[e[:3] / L, e[3:]])))


#: Motion types whose platform poses are not ``exp`` of a platform twist sized by
#: :func:`random_platform_twist` (rotation and translation parts sized apart): the
#: curved 1T2R motion (parasitic x, y, yaw) and rotations about a centre away from the
#: world origin (3R). Their poses come from forward kinematics of random actuations.
CURVED_MOTIONS = ("1T2R", "3R")


@pytest.mark.parametrize("name", sorted(MECHANISMS))
def test_fk_of_ik_is_identity(name):
    """FK(IK(pose)) returns the pose to 1e-10 from a guess 5 cm / 5° away."""
    m = mech(name)
    home = m.home_assembly
    L = m.characteristic_length
    scales = m.actuated_scales  # L for a prismatic actuator, 1 rad for a revolute one
    curved = m.home_analysis.motion_type in CURVED_MOTIONS
    rng = np.random.default_rng(3)
    for _ in range(3):
        if curved:
            qa = home.q_actuated + rng.uniform(-0.1, 0.1, m.n_actuated) * scales
            pose = m.forward_kinematics(qa).pose
        else:
            pose = screws.exp(random_platform_twist(m, home, rng, 0.15, 0.1 * L)) * home.pose
        target = m.assemble(pose)
        qa = m.inverse_kinematics(pose).q_actuated
        np.testing.assert_allclose(qa, target.q_actuated)
        if curved:
            guess = m.forward_kinematics(qa + 0.04 * scales * np.sign(rng.normal(size=3)))
        else:
            g = random_platform_twist(m, target, rng, np.radians(5), 0.05)
            guess = m.assemble(screws.exp(g) * pose, target)
        a = m.forward_kinematics(qa, guess)
        assert pose_error(a.pose, pose, L) < 1e-10
        assert a.residual <= 1e-12
        assert a.info["residual"] <= 1e-12 and a.info["steps"] >= 1
        assert a.info["inertia"] is False


@pytest.mark.parametrize("name", ["stewart", "rpr3", "delta", "rps3", "orthoglide_quasi"])
def test_compiled_and_euler_continuations_agree(name):
    """Both continuations reach the same assembly (pose and legs) from home; the
    compiled one reports its method, and in millimetres it gives the same pose × 1000."""
    m = mech(name)
    L = m.characteristic_length
    rng = np.random.default_rng(7)
    qa = m.home_assembly.q_actuated + rng.uniform(-0.03, 0.03, m.n_actuated) * L
    a = m.forward_kinematics(qa, method="compiled")
    b = m.forward_kinematics(qa, method="euler")
    assert a.info["method"] == "compiled" and b.info["method"] == "euler"
    assert pose_error(a.pose, b.pose, L) < 1e-10
    for qa_leg, qb_leg in zip(a.leg_q, b.leg_q):
        np.testing.assert_allclose(qa_leg, qb_leg, atol=1e-9)
    np.testing.assert_allclose(a.q_actuated, qa, atol=1e-12 * max(1.0, L))
    mm = MECHANISMS[name](scale=1000.0).build()
    scales = np.where([s > 1.0 for s in mm.kernel.scales], 1000.0, 1.0)  # prismatic: mm
    c = mm.forward_kinematics(qa * scales, method="compiled")
    np.testing.assert_allclose(c.pose.translation, 1000.0 * a.pose.translation, atol=1e-7)
    np.testing.assert_allclose(c.pose.rotation, a.pose.rotation, atol=1e-10)


def test_compiled_continuation_steps_guess_and_bad_method():
    """Explicit steps are taken as asked (no halving needed for a small move), a pose
    guess is accepted, and an unknown method is refused."""
    m = mech("stewart")
    home = m.home_assembly
    target = m.assemble(screws.exp(np.array([0.01, 0.0, 0.02, 0.01, -0.02, 0.0])) * home.pose)
    a = m.forward_kinematics(target.q_actuated, steps=3, method="compiled")
    assert a.info["steps"] == 3 and a.info["halvings"] == 0
    assert pose_error(a.pose, target.pose, m.characteristic_length) < 1e-10
    b = m.forward_kinematics(target.q_actuated, home.pose, method="compiled")
    assert pose_error(b.pose, target.pose, m.characteristic_length) < 1e-10
    with pytest.raises(InputError, match="method"):
        m.forward_kinematics(target.q_actuated, method="newton")


def test_continuation_near_rpr3_type2_pose():
    """The continuation follows the home mode up to 5 cm short of the type II pose
    (direct Newton from home does not converge there: the continuation takes steps)."""
    m = mech("rpr3")
    P2 = rpr3_type2_pose()
    pose = pin.SE3(P2.rotation, P2.translation + np.array([-0.05, 0.0, 0.0]))
    target = m.assemble(pose)
    index = m.analyze(target).indices["type_II"]
    assert 0.01 < index < 0.1  # near, not at, the singularity
    a = m.forward_kinematics(target.q_actuated)
    assert pose_error(a.pose, pose, m.characteristic_length) < 1e-10
    assert a.info["steps"] >= 5 and not a.info.get("direct_newton")


def test_motion_by_inertia_crosses_rpr3_type2_pose():
    """With a type II threshold of 0.09 seed 003's continuation (method "euler") moves
    by inertia across the 3-RPR singularity and reaches the pose 5 cm beyond it (the
    default FK does not cross it). The index is homogenised about the platform centre
    (frame-invariant): it is about 2.5 times the world-origin one of the seed's example,
    whose threshold was 0.035; along this path it falls to 0.058 in the home mode."""
    m = mech("rpr3")
    P2 = rpr3_type2_pose()
    pose = pin.SE3(P2.rotation, P2.translation + np.array([0.05, 0.0, 0.0]))
    qa = m.inverse_kinematics(pose).q_actuated
    L = m.characteristic_length
    plain = m.forward_kinematics(qa)
    assert plain.info["inertia"] is False
    assert pose_error(plain.pose, pose, L) > 1e-2  # the other assembly mode, also valid
    np.testing.assert_allclose(plain.q_actuated, qa, atol=1e-12)
    a = m.forward_kinematics(qa, inertia_tol=0.09, method="euler")  # seed 003's method
    assert a.info["inertia"] is True and a.info["inertia_steps"] >= 1
    assert pose_error(a.pose, pose, L) < 1e-10
    np.testing.assert_allclose(a.q_actuated, qa, atol=1e-12)


def test_fk_all_rpr3_beyond_type2_pose():
    """Past the type II pose the 3-RPR has ≥ 2 assembly modes; the one given is found."""
    m = mech("rpr3")
    P2 = rpr3_type2_pose()
    pose = pin.SE3(P2.rotation, P2.translation + np.array([0.05, 0.0, 0.0]))
    qa = m.inverse_kinematics(pose).q_actuated
    # 32 starts (the default): 8 found a single mode with numpy 2.4's SVD basis
    modes = m.forward_kinematics_all(qa)
    assert len(modes) >= 2
    L = m.characteristic_length
    for a in modes:
        np.testing.assert_allclose(a.q_actuated, qa, atol=1e-10)
        assert a.residual <= 1e-12
    assert min(pose_error(a.pose, pose, L) for a in modes) < 1e-10
    for i in range(len(modes)):
        for j in range(i):
            assert pose_error(modes[i].pose, modes[j].pose, L) > 1e-6


def test_fk_all_stewart_two_modes():
    """The 6-UPS has ≥ 2 distinct valid assembly modes at its home leg lengths."""
    m = mech("stewart")
    qa = m.home_assembly.q_actuated
    modes = m.forward_kinematics_all(qa, starts=16)
    assert len(modes) >= 2
    for a in modes:
        np.testing.assert_allclose(a.q_actuated, qa, atol=1e-10)
        assert a.residual <= 1e-12
        assert all(leg.within_limits(q) for leg, q in zip(m.legs, a.leg_q))
    assert pose_error(modes[0].pose, modes[1].pose, m.characteristic_length) > 1e-3


def test_ik_all_rrr3_elbows():
    """The 3-RRR has 2³ = 8 working modes (elbows) at home, the home one first."""
    m = mech("rrr3")
    modes = m.inverse_kinematics_all(m.home)
    assert len(modes) == 8
    np.testing.assert_allclose(modes[0].q_actuated, m.home_assembly.q_actuated, atol=1e-9)
    qas = np.array([a.q_actuated for a in modes])
    assert len({tuple(np.round(q, 6)) for q in qas}) == 8
    for a in modes:
        for leg, anchor, q in zip(m.legs, m.anchors, a.leg_q):
            assert pose_error(leg.tip_placement(q), m.home * anchor, 1.0) < 1e-10


def test_bad_inputs():
    """Wrong length, NaN, bad steps and an unreachable target give specific errors."""
    m = mech("stewart")
    qa = m.home_assembly.q_actuated
    with pytest.raises(InputError, match="6 values"):
        m.forward_kinematics(qa[:5])
    with pytest.raises(InputError, match="finite"):
        m.forward_kinematics(np.r_[qa[:5], np.nan])
    with pytest.raises(InputError, match="steps"):
        m.forward_kinematics(qa, steps=0)
    with pytest.raises(ForwardKinematicsError, match="outside its joint limits"):
        m.forward_kinematics(qa + 100.0)
    # inside the stroke but not assemblable: one leg far longer than the others
    far = qa.copy()
    far[0] = 0.95 * m.legs[0]._bounds[1][2]
    far[1] = 0.35 * m.legs[1]._bounds[1][2]
    with pytest.raises(ForwardKinematicsError) as err:
        m.forward_kinematics(far)
    assert err.value.reached is not None
    with pytest.raises(InputError):
        m.inverse_kinematics([0.0, 1.0])
    with pytest.raises(InputError):
        screw_step(SEED003_LINES[:5], SEED003_DL)
    with pytest.raises(SingularityError):
        screw_step(np.vstack([SEED003_LINES[:5], SEED003_LINES[0]]), SEED003_DL)


def test_screw_step_seed003_example():
    """Seed 003: dl1 = dl4 = 0.1 m gives the twist (0.05, 0.05, 0 | 0.1, 0, 0.05)."""
    t = screw_step(SEED003_LINES, SEED003_DL)
    np.testing.assert_allclose(t, [0.05, 0.05, 0.0, 0.1, 0.0, 0.05], atol=1e-15)
    np.testing.assert_allclose(t, SEED003_TWIST, atol=1e-15)
    assert np.linalg.norm(t[:3]) == pytest.approx(0.0707, abs=1e-4)


@pytest.fixture(scope="module")
def sps6():
    """Seed 003's ℓ-coordinate body built as a 6-SPS (6-UPS builder, unit legs)."""
    base, plat = seed003_geometry()
    design = stewart(base, plat, home=pin.SE3.Identity(), name="6-SPS seed 003",
                     slug="sps6_seed003", urdf_file="sps_leg_seed003.urdf")
    return design.build()


def test_sps6_seed003_body(sps6):
    """The 6-SPS of seed 003: its actuation wrenches are the printed leg lines and its
    forward map gives the printed twist."""
    assert sps6.name.startswith("6-SPS")
    an = sps6.analyze()
    np.testing.assert_allclose(an.A, SEED003_LINES, atol=1e-12)
    np.testing.assert_allclose(np.diag(an.B), 1.0, atol=1e-12)
    np.testing.assert_allclose(sps6.home_assembly.q_actuated, 1.0, atol=1e-12)
    np.testing.assert_allclose(an.forward_velocity(SEED003_DL), SEED003_TWIST, atol=1e-12)


def test_sps6_seed003_residual_falls_with_steps(sps6):
    """One Euler step (seed 003 as printed) leaves a leg-length error of a few % of the
    step; it falls ~1/N."""
    target = sps6.home_assembly.q_actuated + SEED003_DL
    L = sps6.characteristic_length
    errors = []
    for n in (1, 2, 4, 8):
        a = sps6.forward_kinematics(target, steps=n, method="euler")
        assert a.info["steps"] == n
        np.testing.assert_allclose(a.q_actuated, target, atol=1e-12)
        errors.append(a.info["continuation_error"] * L)
    assert 0.03 * 0.1 < errors[0] < 0.08 * 0.1  # 6.8 mm for a 0.1 m step (paper: ~5 mm)
    for e1, e2 in zip(errors, errors[1:]):
        assert 0.4 < e2 / e1 < 0.6


def test_iterative_ik_6r_seed003():
    """Seed 003's 6R example: 2°/0.02 m steps, then a Newton correction to 1e-10."""
    leg = Leg.from_urdf("models/urdf/chain_6r_seed003.urdf", "tip")
    q0 = np.radians([0, 30, 30, 30, 0, 0])
    q1 = np.radians([10, 40, 40, 40, 10, 10])
    target = leg.tip_placement(q1)
    r = iterative_ik(leg, target, q0, max_angle_step=np.radians(2), max_translation_step=0.02)
    assert r.steps == 10  # 18.5° rotation / 2° (the paper counts 9)
    assert np.degrees(r.angle) == pytest.approx(18.49, abs=0.01)
    assert np.linalg.norm(r.axis) == pytest.approx(1.0)
    assert np.linalg.norm(r.translation) == pytest.approx(0.1734, abs=1e-4)
    pos, ang = r.error_after_steps
    assert 1e-4 < pos < 1e-2 and 0.05 < np.degrees(ang) < 0.3
    assert r.converged
    assert r.error_after_correction[0] < 1e-10 and r.error_after_correction[1] < 1e-10
    np.testing.assert_allclose(r.q, q1, atol=1e-8)
    reaimed = iterative_ik(leg, target, q0, max_angle_step=np.radians(2),
                           max_translation_step=0.02, reaim=True)
    assert reaimed.error_after_steps[0] < 0.2 * pos


def test_fk_starts_at_any_index_and_small_steps():
    """A start whose type II index is below the threshold no longer blocks FK: with
    inertia_tol = 0.99 (above the index of any pose) the quasi-orthogonal Orthoglide
    still solves a 1e-6, a 1e-3 and a 5 % step from home, by direct Newton; the Euler
    continuation too (no twist yet: plain Euler steps)."""
    m = mech("orthoglide_quasi")
    home = m.home_assembly
    L = m.characteristic_length
    for d in (1e-6, 1e-3, 0.05):
        qa = home.q_actuated + d * L * np.array([1.0, -0.5, 0.3])
        a = m.forward_kinematics(qa, inertia_tol=0.99)
        assert a.info["direct_newton"] is True
        np.testing.assert_allclose(a.q_actuated, qa, atol=1e-12 * L)
        b = m.forward_kinematics(qa, inertia_tol=0.99, method="euler")
        assert pose_error(a.pose, b.pose, L) < 1e-10


def test_fk_error_says_how_far_it_got():
    """An out-of-reach target: the error carries λ (the fraction of the way reached,
    between 0 and 1) and says it in its message."""
    m = mech("stewart")
    far = m.home_assembly.q_actuated.copy()
    far[0] = 0.95 * m.legs[0]._bounds[1][2]
    far[1] = 0.35 * m.legs[1]._bounds[1][2]
    with pytest.raises(ForwardKinematicsError, match="λ = ") as err:
        m.forward_kinematics(far, method="euler")
    assert 0.0 < err.value.lam < 1.0
    assert f"{err.value.lam:.4g}" in str(err.value)
    with pytest.raises(ForwardKinematicsError, match="λ = "):
        m.forward_kinematics(far, method="compiled")
