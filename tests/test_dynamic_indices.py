"""Dynamic design indices (pkm_pin.dynamic_indices, issue 26 item 5): the actuator-space
inertia against a hand-computed five-bar with point masses and against Pinocchio's
kinetic energy, the apparent output inertia against the energy and the square case's
``J_x⁻ᵀ Λ J_x⁻¹``, invariance under a rigid motion of the whole mechanism and under a
change of length unit, the gravity efforts against virtual work (``Gᵀ g(q)``).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from linkage_models import five_bar, five_bar_q

import pkm_pin
from pkm_pin import dynamic_indices as di
from pkm_pin import dynamics as dyn
from pkm_pin.builders.loops import with_random_inertias
from pkm_pin.errors import InputError
from pkm_pin.linkage import Linkage
from pkm_pin.model import configuration

ROOT = Path(__file__).resolve().parents[1]
G = (0.3, -1.0, -9.81)
W = pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.7, 1.1), np.array([0.4, -1.0, 2.0]))


def point_mass_five_bar(m_a=1.3, m_b=0.7, m_p=2.1, kind="point"):
    """The unit five-bar with point masses only: ``m_a``, ``m_b`` at the elbows (ends of
    the proximal links A1, B1), ``m_p`` at the tip (end of A2)."""
    cm = five_bar(kind)
    tree = pin.Model(cm.tree)
    zero = np.zeros((3, 3))
    masses = {"A1": m_a, "B1": m_b, "A2": m_p, "B2": 0.0}
    for j in range(1, tree.njoints):
        tree.inertias[j] = pin.Inertia(masses[tree.names[j]], np.array([1.0, 0, 0]), zero)
    return dataclasses.replace(cm, tree=tree)


def five_bar_tip_jacobian(q):
    """Hand-derived: with E_A = (cos θ_A, sin θ_A), E_B = (1.5 + cos θ_B, sin θ_B) and
    |P − E_A| = |P − E_B| = 1, differentiating gives
    [(P − E_A)ᵀ; (P − E_B)ᵀ] Ṗ = [(P − E_A)·Ė_A; (P − E_B)·Ė_B]."""
    ta, tb = q[0], q[2]
    Ea = np.array([np.cos(ta), np.sin(ta)])
    Eb = np.array([1.5 + np.cos(tb), np.sin(tb)])
    P = Ea + np.array([np.cos(ta + q[1]), np.sin(ta + q[1])])
    dEa, dEb = np.array([-np.sin(ta), np.cos(ta)]), np.array([-np.sin(tb), np.cos(tb)])
    A = np.array([P - Ea, P - Eb])
    return np.linalg.solve(A, np.diag([(P - Ea) @ dEa, (P - Eb) @ dEb]))


@pytest.mark.parametrize("kind", ["point", "revolute"])
def test_five_bar_point_masses_closed_form(kind):
    """Λ = diag(m_a, m_b) + m_p J_Pᵀ J_P (unit links), to 1e-12."""
    cm, q = point_mass_five_bar(kind=kind), five_bar_q([0.6, 1.3])
    r = di.dynamic_indices(cm, q)
    Jp = five_bar_tip_jacobian(q)
    expected = np.diag([1.3, 0.7]) + 2.1 * Jp.T @ Jp
    assert np.allclose(r.inertia, expected, rtol=1e-12, atol=1e-12)
    ev = np.linalg.eigvalsh(expected)
    assert np.allclose(r.eigenvalues, ev, rtol=1e-12)
    assert r.condition == pytest.approx(ev[1] / ev[0], rel=1e-12)
    assert r.units == ("rad", "rad") and r.idle_motions == 0


def test_point_output_apparent_mass_closed_form():
    """The five-bar's tip as a point output (3 × 3, kg): in the plane
    Λ_x = m_p I + J_P⁻ᵀ diag(m_a, m_b) J_P⁻¹ (a lone tip mass: its own mass), zero out of
    the plane the tip cannot leave."""
    q = five_bar_q([0.6, 1.3])
    cm = dataclasses.replace(point_mass_five_bar(), output_point=True)
    r = di.dynamic_indices(cm, q)
    Jp = five_bar_tip_jacobian(q)
    Ji = np.linalg.inv(Jp)
    expected = np.zeros((3, 3))
    expected[:2, :2] = 2.1 * np.eye(2) + Ji.T @ np.diag([1.3, 0.7]) @ Ji
    assert r.output_inertia.shape == (3, 3)
    assert np.allclose(r.output_inertia, expected, rtol=1e-10, atol=1e-12)
    assert np.allclose(r.output_jacobian[:2], Jp, rtol=1e-12, atol=1e-12)
    alone = dataclasses.replace(point_mass_five_bar(0.0, 0.0, 2.1), output_point=True)
    assert np.allclose(di.dynamic_indices(alone, q).output_inertia[:2, :2], 2.1 * np.eye(2),
                       rtol=1e-10)


def _models():
    stewart = pkm_pin.load_mechanism(ROOT / "models" / "mechanisms" / "stewart.toml")
    delta = pkm_pin.load_mechanism(ROOT / "models" / "mechanisms" / "delta.toml")
    g5 = pkm_pin.load_mechanism(ROOT / "tests" / "data" / "gepetto" / "5bar_linkage" /
                                "robot.urdf")
    return {
        "five_bar": (with_random_inertias(five_bar("point")), five_bar_q([0.7, 1.2])),
        "stewart": (with_random_inertias(stewart.closure_model),
                    configuration(stewart, stewart.home_assembly)),
        "delta": (with_random_inertias(delta.closure_model),
                  configuration(delta, delta.home_assembly)),
        "gepetto_5bar": (g5.model, g5.home_assembly.q),
    }


MODELS = _models()


@pytest.mark.parametrize("name", sorted(MODELS))
def test_kinetic_energy(name):
    """½ q̇ᵀ Λ q̇ = ½ vᵀ M v along the consistent velocity of q̇ (Kelvin: ≤ when idle
    motions are left at their minimum-norm rates); Λ from Pinocchio's kinetic energy by
    polarisation, T(e_i + e_j) − T(e_i) − T(e_j) (no mimic joint)."""
    cm, q = MODELS[name]
    r = di.dynamic_indices(cm, q)
    n = len(cm.actuated)
    M = di.mass_matrix(cm, q)
    qd = np.random.default_rng(6).normal(size=n)
    v = r.G @ qd
    assert np.linalg.norm(cm.closure_jacobian(q) @ v) <= 1e-10 * np.linalg.norm(v)
    assert np.allclose(v[list(cm.actuated_v)], qd, rtol=1e-12, atol=1e-12)
    T = 0.5 * qd @ r.inertia @ qd
    assert T == pytest.approx(0.5 * v @ M @ v, rel=1e-12)
    vmn, _ = dyn.motion_from_actuated(cm, q, qd, np.zeros(n))
    assert T <= 0.5 * vmn @ M @ vmn * (1 + 1e-12)
    if r.idle_motions == 0:
        assert T == pytest.approx(0.5 * vmn @ M @ vmn, rel=1e-12)
    if not any(j.shortname() == "JointModelMimic" for j in cm.tree.joints):
        data = cm.tree.createData()

        def energy(x):
            return pin.computeKineticEnergy(cm.tree, data, q, r.G @ x)

        E = np.eye(n)
        pol = np.array([[energy(E[i] + E[j]) - energy(E[i]) - energy(E[j]) for j in range(n)]
                        for i in range(n)])
        assert np.allclose(pol, r.inertia, rtol=1e-9, atol=1e-12 * np.abs(r.inertia).max())


@pytest.mark.parametrize("name", sorted(MODELS))
def test_output_inertia_gives_the_kinetic_energy(name):
    """T = ½ tᵀ Λ_x t for the output twist t = J_x q̇ (about the output's origin)."""
    cm, q = MODELS[name]
    r = di.dynamic_indices(cm, q)
    rng = np.random.default_rng(7)
    for _ in range(3):
        qd = rng.normal(size=len(cm.actuated))
        t = r.output_jacobian @ qd
        assert 0.5 * t @ r.output_inertia @ t == pytest.approx(0.5 * qd @ r.inertia @ qd,
                                                               rel=1e-9)


def test_output_inertia_square_case():
    """Six actuators (the Stewart): Λ_x = J_x⁻ᵀ Λ J_x⁻¹, and J_x is the output twist about
    its origin (finite differences of the platform pose along v = G q̇)."""
    cm, q = MODELS["stewart"]
    r = di.dynamic_indices(cm, q)
    Ji = np.linalg.inv(r.output_jacobian)
    assert np.allclose(r.output_inertia, Ji.T @ r.inertia @ Ji, rtol=1e-9,
                       atol=1e-9 * np.abs(r.output_inertia).max())
    qd = np.random.default_rng(8).normal(size=6)
    h = 1e-6
    P = [cm.kinematics(pin.integrate(cm.tree, q, s * h * (r.G @ qd))).output_placement
         for s in (-1, 1)]
    dR = (P[1].rotation - P[0].rotation) / (2 * h)
    w = pin.unSkew(dR @ cm.kinematics(q).output_placement.rotation.T)
    dp = (P[1].translation - P[0].translation) / (2 * h)
    assert np.allclose(r.output_jacobian @ qd, np.r_[w, dp], rtol=1e-6, atol=1e-7)


def test_invariance_under_a_rigid_motion_and_a_unit_change():
    """The whole mechanism moved in the world: same Λ and eigenvalues, Λ_x turned
    (blockdiag(R, R) Λ_x blockdiag(R, R)ᵀ), the gravity efforts with gravity turned the
    same; in millimetres (inertias ×1e6 in kg mm²): Λ ×1e6, the condition unchanged."""
    q = five_bar_q([0.7, 1.2])
    ref = with_random_inertias(five_bar("revolute"))
    moved = with_random_inertias(five_bar("revolute", where=W))
    a, b = di.dynamic_indices(ref, q), di.dynamic_indices(moved, q)
    assert np.allclose(b.eigenvalues, a.eigenvalues, rtol=1e-10)
    assert np.allclose(b.inertia, a.inertia, rtol=1e-10)
    R = np.kron(np.eye(2), W.rotation)
    assert np.allclose(b.output_inertia, R @ a.output_inertia @ R.T, rtol=1e-9,
                       atol=1e-10 * np.abs(a.output_inertia).max())
    ga = di.gravity_efforts(ref, q[None], gravity=G)
    gb = di.gravity_efforts(moved, q[None], gravity=W.rotation @ np.array(G))
    assert np.allclose(gb.efforts, ga.efforts, rtol=1e-9)
    mm = with_random_inertias(five_bar("revolute", scale=1000.0))
    c = di.dynamic_indices(mm, q)
    assert np.allclose(c.inertia, 1e6 * a.inertia, rtol=1e-9)
    assert c.condition == pytest.approx(a.condition, rel=1e-9)


def test_scaled_inertia_mixes_units_through_the_length():
    """The Stewart's prismatic actuators: Λ in kg, Λ̃ = L² Λ in kg m², eigenvalues of Λ̃."""
    cm, q = MODELS["stewart"]
    r = di.dynamic_indices(cm, q)
    assert r.units == ("m",) * 6
    assert np.allclose(r.scaled_inertia, cm.length ** 2 * r.inertia, rtol=1e-14)
    assert np.allclose(r.eigenvalues, np.linalg.eigvalsh(r.scaled_inertia), rtol=1e-12)


@pytest.mark.parametrize("name", ["five_bar", "stewart", "gepetto_5bar"])
def test_gravity_efforts_are_virtual_work(name):
    """τ_g = Gᵀ g(q) (g(q) Pinocchio's generalized gravity: the virtual work of gravity
    along the motion of each actuator) equals inverse_dynamics at rest."""
    cm, q = MODELS[name]
    gm = di.gravity_efforts(cm, np.array([q, np.full(cm.nq, np.nan)]), gravity=G)
    assert gm.ok.tolist() == [True, False] and gm.reasons[0][0] == 1
    tree = pin.Model(cm.tree)
    tree.gravity = pin.Motion(np.array(G), np.zeros(3))
    gq = pin.computeGeneralizedGravity(tree, tree.createData(), q)
    G_ = di.dynamic_indices(cm, q).G
    assert np.allclose(gm.efforts[0], G_.T @ gq, rtol=1e-9,
                       atol=1e-10 * np.linalg.norm(gq))
    assert np.allclose(gm.peak, np.abs(gm.efforts[0]))


def test_gravity_map_over_a_linkage_sweep():
    """Linkage.gravity_map: the sweep's configurations, static efforts per row."""
    cm = with_random_inertias(five_bar("point"))
    link = Linkage(cm)
    q0 = five_bar_q([0.7, 1.2])
    Q = np.array([[q0[0] + d, q0[2] + d] for d in np.linspace(0, 0.2, 5)])
    gm = link.gravity_map(Q, q0, gravity=G, condition=True)
    assert gm.ok.all() and np.isfinite(gm.condition).all()
    for qa, q, tau in zip(Q, gm.q, gm.efforts):
        assert np.allclose(cm.actuated_values(q), qa, atol=1e-9)
        ref = dyn.inverse_dynamics(cm, q, np.zeros(cm.nv), np.zeros(cm.nv), gravity=G)
        assert np.allclose(tau, ref.efforts, rtol=1e-12)
    r = link.dynamic_indices(q0)
    assert r.inertia.shape == (2, 2)


def test_bad_input():
    cm, q = MODELS["five_bar"]
    with pytest.raises(InputError, match="shape"):
        di.gravity_efforts(cm, np.zeros((3, 2)))


def test_mechanism_gravity_map_over_poses():
    """Mechanism.gravity_map: each pose assembled (a pose out of reach: a nan row with its
    reason), the efforts those of inverse_dynamics at that configuration; the TOML legs
    have no mass, so a payload wrench stands for the load."""
    mech = pkm_pin.load_mechanism(ROOT / "models" / "mechanisms" / "stewart.toml")
    home = mech.home
    poses = [home, pin.SE3(home.rotation, home.translation + np.array([0.0, 0.01, 0.02])),
             pin.SE3(home.rotation, home.translation + np.array([0.0, 0.0, 50.0]))]
    w = np.array([1.0, -2.0, -30.0, 0.5, 0.2, -0.1])
    gm = mech.gravity_map(poses, wrench=w)
    assert gm.ok.tolist() == [True, True, False] and gm.reasons[0][0] == 2
    cm = mech.closure_model
    for pose, tau in zip(poses[:2], gm.efforts):
        q = configuration(mech, mech.assemble(pose, mech.home_assembly))
        ref = dyn.inverse_dynamics(cm, q, np.zeros(cm.nv), np.zeros(cm.nv), wrench=w)
        assert np.allclose(tau, ref.efforts, rtol=1e-7)
    assert np.abs(gm.efforts[0]).max() > 0


def test_cli_indices(capsys):
    """pkm-pin dynamics FILE --indices [--json]: the indices at home, as the API gives
    them; a model without mass: one line, exit 2."""
    import json

    from pkm_pin.cli import main

    path = ROOT / "tests" / "data" / "gepetto" / "5bar_linkage" / "robot.urdf"
    assert main(["dynamics", str(path), "--indices", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    link = pkm_pin.load_mechanism(path)
    r = link.dynamic_indices()
    assert np.allclose(out["inertia"], r.inertia, rtol=1e-12)
    assert out["condition"] == pytest.approx(r.condition, rel=1e-12)
    assert np.allclose(out["gravity_efforts"], dyn.inverse_dynamics(
        link.model, link.home_assembly.q, np.zeros(link.model.nv), np.zeros(link.model.nv)
    ).efforts, rtol=1e-12)
    assert main(["dynamics", str(path), "--indices"]) == 0
    text = capsys.readouterr().out
    assert "condition" in text and text.count("output     Λ_x about the output origin") == 1
    rows = text.split("(ω; v):\n", 1)[1].splitlines()[:6]
    printed = np.array([[float(x) for x in row.split()] for row in rows])
    X = r.output_inertia  # printed to 4 digits, round-off below 1e-12 of the largest as 0
    assert printed.shape == (6, 6)
    assert np.allclose(printed, np.where(np.abs(X) <= 1e-12 * np.abs(X).max(), 0, X),
                       rtol=1e-3, atol=1e-12)
    assert main(["dynamics", "--indices"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no body has a mass" in err[0]


def test_cli_indices_per_submechanism(capsys):
    """pkm-pin dynamics BIPED --indices: each leg's indices with its own six motors and
    foot (issue 25): its Λ the whole's diagonal block (the legs share no moving body, so
    the off-diagonal blocks are round-off), its gravity efforts the whole's, its Λ_x
    that of its own foot named as the whole's output; --sub K: leg K alone; --sub on a
    platform mechanism or without --indices: one line, exit 2."""
    import json

    from pkm_pin.cli import main

    path = ROOT / "tests" / "data" / "gepetto" / "digit_like_2legs" / "robot.urdf"
    assert main(["dynamics", str(path), "--indices", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    whole = pkm_pin.load_mechanism(path)
    r = whole.dynamic_indices()
    tau = di.gravity_efforts(whole.model, whole.home_assembly.q[None]).efforts[0]
    legs = out["submechanisms"]
    assert [len(s["actuated"]) for s in legs] == [6, 6]
    assert np.abs(r.inertia[:6, 6:]).max() < 1e-12 * np.abs(r.inertia).max()
    for k, (leg, block) in enumerate(zip(legs, (slice(0, 6), slice(6, 12)))):
        assert leg["index"] == k and leg["actuated"] == list(r.actuated[block])
        assert np.allclose(leg["inertia"], r.inertia[block, block], rtol=1e-9, atol=1e-14)
        assert np.allclose(leg["gravity_efforts"], tau[block], rtol=1e-9, atol=1e-12)
        ev = np.linalg.eigvalsh(r.inertia[block, block])
        assert np.allclose(leg["eigenvalues"], ev, rtol=1e-9)
        assert leg["condition"] == pytest.approx(ev[-1] / ev[0], rel=1e-9)
    left = pkm_pin.load_mechanism(path, output="foot_left").dynamic_indices()
    assert np.allclose(legs[0]["output_inertia"], r.output_inertia, rtol=1e-7, atol=1e-10)
    assert np.allclose(legs[1]["output_inertia"], left.output_inertia, rtol=1e-7,
                       atol=1e-10)
    assert main(["dynamics", str(path), "--indices", "--sub", "1", "--json"]) == 0
    one = json.loads(capsys.readouterr().out)
    assert one["actuated"] == legs[1]["actuated"]
    assert np.allclose(one["inertia"], legs[1]["inertia"], rtol=1e-12)
    assert main(["dynamics", str(path), "--indices"]) == 0
    text = capsys.readouterr().out
    assert "2 independent sub-mechanisms" in text and text.count("condition") == 2
    assert text.count("output     Λ_x") == 2
    for argv, words in ((["--indices", "--sub", "2"], "numbered 0 to 1"),
                        (["--sub", "0"], "--sub K goes with --indices")):
        assert main(["dynamics", str(path), *argv]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and words in err[0]
