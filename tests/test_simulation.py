"""Forward dynamics (pkm_pin.simulation, issue 26 item 4): round trip through the
inverse dynamics, drift stabilisation, energy balance, Pinocchio's constrained dynamics
against our own KKT rows, the PD controller, the facades' delegation, errors.

Models: the planar five-bar (point closure: Pinocchio; revolute 5D closure: our rows),
the TOML Stewart (six welds, spherical joints and a free-flyer platform), the TOML Delta
(mimic joints: our rows) with seeded random inertias (:func:`with_random_inertias`), and
Gepetto's 5-bar (tests/data/gepetto, its own inertias).

Measured (0.1 s, dt = 1 ms, RK4, random sine efforts of the size of the gravity torques
from a random consistent velocity; round trip over 5 samples):

    model          method     round trip  max drift  energy (efforts)  energy (free)
    five_bar       pinocchio  2.1e-12     2.2e-12    2.5e-11           2.1e-11
    five_bar rev.  kkt        1.6e-15     2.2e-12    2.5e-11           2.1e-11
    stewart        pinocchio  4.3e-15     9.3e-11    6.2e-11           1.7e-10
    delta          kkt        4.1e-15     1.4e-10    2.5e-11           7.0e-13
    gepetto 5bar   pinocchio  2.7e-14     3.6e-11    7.4e-10           1.8e-08
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from linkage_models import five_bar, five_bar_q, four_bar, four_bar_q

import pkm_pin
from pkm_pin import dynamics as dyn
from pkm_pin import simulation as sim
from pkm_pin.builders.loops import with_random_inertias
from pkm_pin.errors import InputError
from pkm_pin.linkage import Linkage
from pkm_pin.model import configuration

ROOT = Path(__file__).resolve().parents[1]
G = (0.3, -1.0, -9.81)


def _toml(name: str):
    mech = pkm_pin.load_mechanism(ROOT / "models" / "mechanisms" / f"{name}.toml")
    return with_random_inertias(mech.closure_model), configuration(mech, mech.home_assembly)


def _gepetto(name: str):
    link = pkm_pin.load_mechanism(ROOT / "tests" / "data" / "gepetto" / name / "robot.urdf")
    return link.model, link.home_assembly.q


MODELS = {
    "five_bar": lambda: (with_random_inertias(five_bar("point")), five_bar_q([0.7, 1.2])),
    "five_bar_revolute": lambda: (with_random_inertias(five_bar("revolute")),
                                  five_bar_q([0.7, 1.2])),
    "stewart": lambda: _toml("stewart"),
    "delta": lambda: _toml("delta"),
    "gepetto_5bar": lambda: _gepetto("5bar_linkage"),
}
METHOD = {"five_bar": "pinocchio", "five_bar_revolute": "kkt", "stewart": "pinocchio",
          "delta": "kkt", "gepetto_5bar": "pinocchio"}


@functools.lru_cache(maxsize=None)
def model(name: str):
    return MODELS[name]()


def random_start(cm, q, rng, scale=0.3):
    """A random consistent velocity (from random actuated rates)."""
    n = len(cm.actuated)
    v, _ = dyn.motion_from_actuated(cm, q, scale * rng.normal(size=n), np.zeros(n))
    return v


def sine_efforts(cm, q, rng):
    """Random sines of the size of the tree's gravity torques at ``q``."""
    tree = pin.Model(cm.tree)
    tree.gravity = pin.Motion(np.array(G), np.zeros(3))
    size = 1.0 + np.linalg.norm(pin.computeGeneralizedGravity(tree, tree.createData(), q))
    n = len(cm.actuated)
    A, w = size * rng.normal(size=n), rng.uniform(5.0, 30.0, size=n)
    return lambda t, q, v: A * np.cos(w * t)


@pytest.mark.parametrize("name", sorted(MODELS))
def test_round_trip_through_inverse_dynamics(name):
    """Random efforts → simulate → inverse_dynamics at the simulated (q, v, a) gives the
    efforts back to 1e-6 relative; the closures stay closed."""
    cm, q = model(name)
    rng = np.random.default_rng(1)
    r = sim.simulate(cm, q, random_start(cm, q, rng), 0.05, 1e-3,
                     efforts=sine_efforts(cm, q, rng), gravity=G)
    assert r.method == METHOD[name]
    assert r.q.shape == (51, cm.nq) and r.efforts.shape == (51, len(cm.actuated))
    for k in (0, 17, 33, 50):
        idr = dyn.inverse_dynamics(cm, r.q[k], r.v[k], r.a[k], gravity=G)
        assert np.linalg.norm(idr.efforts - r.efforts[k]) <= \
            1e-6 * np.linalg.norm(r.efforts[k]), (name, k)
    assert r.max_drift < 1e-9
    assert r.energy_error < 1e-7


@pytest.mark.parametrize("name", sorted(MODELS))
def test_energy_conserved_without_efforts_and_gravity(name):
    """Unactuated, gravity-free: T + V constant (relative to T) to 1e-7."""
    cm, q = model(name)
    v = random_start(cm, q, np.random.default_rng(2))
    r = sim.simulate(cm, q, v, 0.05, 1e-3, gravity=(0, 0, 0))
    assert np.all(r.work == 0.0)
    assert r.kinetic[0] > 0
    assert np.abs(r.energy - r.energy[0]).max() <= 1e-7 * r.kinetic[0]
    assert r.energy_error < 1e-7


def test_energy_balance_with_work_converges_at_fourth_order():
    """With gravity and efforts, |E − E0 − W| falls ~16× when dt halves (RK4) on the
    five-bar (vector-space joints); the semi-implicit integrator is first order."""
    cm, q = model("five_bar")
    rng = np.random.default_rng(3)
    v, eff = random_start(cm, q, rng), sine_efforts(cm, q, rng)
    errs = [sim.simulate(cm, q, v, 0.2, dt, efforts=eff, gravity=G, baumgarte=0).energy_error
            for dt in (4e-3, 2e-3)]
    assert errs[0] / errs[1] > 10, errs
    semi = [sim.simulate(cm, q, v, 0.2, dt, efforts=eff, gravity=G, baumgarte=0,
                         integrator="semi-implicit").energy_error for dt in (4e-3, 2e-3)]
    assert 1.5 < semi[0] / semi[1] < 3, semi
    assert semi[1] > 100 * errs[1]


@pytest.mark.parametrize("name", ["five_bar", "stewart", "gepetto_5bar"])
def test_pinocchio_and_our_rows_give_the_same_acceleration(name):
    """pin.constraintDynamics (RigidConstraintModel, Baumgarte corrector) and our KKT rows
    agree, with and without gains, and so do the closure forces (non-redundant models).
    The welds (Stewart, Gepetto 5-bar) off the closures (q moved by 1e-6, v by 1e-3, so
    the gains act: they change a by 0.2–0.4 %) to 1e-10; the five-bar's point closure at
    a consistent state only: off it, Pinocchio's CONTACT_3D constrains the relative
    classical acceleration in C_a axes without our −ω_a × U term of φ̈ (U the relative
    velocity: the velocity drift), 5e-4 relative with U ~ 1e-3."""
    cm, q = model(name)
    rng = np.random.default_rng(4)
    v = random_start(cm, q, rng)
    tau = sine_efforts(cm, q, rng)(0.0, q, v)
    if name != "five_bar":
        q = pin.integrate(cm.tree, q, 1e-6 * rng.normal(size=cm.nv))
        v = v + 1e-3 * rng.normal(size=cm.nv)
    g = np.array(G)
    a0, _ = sim._Dynamics(cm, g, (0.0, 0.0), "kkt").acceleration(q, v, tau)
    for gains in ((0.0, 0.0), (400.0, 40.0)):
        ap, lp = sim._Dynamics(cm, g, gains, "pinocchio").acceleration(q, v, tau)
        ak, lk = sim._Dynamics(cm, g, gains, "kkt").acceleration(q, v, tau)
        assert np.linalg.norm(ap - ak) <= 1e-10 * np.linalg.norm(ak), name
        if cm.redundant_constraints(q) == 0:  # off the closure C_a and C_b differ by
            # 1e-6: Pinocchio's λ in C_a's frame, ours in C_b's
            tol = 1e-8 if name == "five_bar" else 1e-5
            assert np.linalg.norm(lp - lk) <= tol * np.linalg.norm(lk), name
    if name != "five_bar":
        assert np.linalg.norm(ak - a0) > 1e-3 * np.linalg.norm(a0)


@pytest.mark.parametrize("method", ["pinocchio", "kkt"])
def test_drift_is_stabilised(method):
    """A start off the closures by 3e-9 (relative): Baumgarte's corrector brings the
    residual down 100×; without it, it stays."""
    cm, q = model("five_bar")
    q = q + np.array([5e-9, 0, 0, 0])
    r0 = sim.simulate(cm, q, None, 0.3, 2e-3, method=method, baumgarte=0)
    r1 = sim.simulate(cm, q, None, 0.3, 2e-3, method=method)
    assert r0.drift[0] > 1e-9
    assert r0.drift[-1] > 0.9 * r0.drift[0]
    assert r1.drift[-1] < 1e-2 * r1.drift[0]
    assert r1.baumgarte == pytest.approx(((1 / 0.04) ** 2, 2 / 0.04))


def test_stewart_long_motion_stays_closed():
    """0.3 s of the Stewart under gravity and efforts (free flyer and spherical joints:
    the Munthe-Kaas stages): drift < 1e-9, energy balance 1e-7."""
    cm, q = model("stewart")
    rng = np.random.default_rng(5)
    r = sim.simulate(cm, q, random_start(cm, q, rng), 0.3, 1e-3,
                     efforts=sine_efforts(cm, q, rng), gravity=G)
    assert r.max_drift < 1e-9
    assert r.energy_error < 1e-7


def test_pd_controller_tracks_a_target():
    """A PD on the four-bar's crank reaches a constant target; its efforts are
    kp (q* − q) − kd q̇ at every sample."""
    cm, q = with_random_inertias(four_bar()), four_bar_q(0.7)
    pd = sim.PD(kp=200.0, kd=30.0, target=[0.9])
    r = sim.simulate(cm, q, None, 1.5, 2e-3, controller=pd, gravity=G)
    qa = np.array([cm.actuated_values(x)[0] for x in r.q])
    assert abs(qa[-1] - 0.9) < 0.02  # gravity leaves a small static error
    expected = 200.0 * (0.9 - qa) - 30.0 * r.v[:, cm.actuated_v[0]]
    assert np.allclose(r.efforts[:, 0], expected, rtol=1e-12, atol=1e-12)
    moving = sim.PD(kp=50.0, kd=5.0, target=lambda t: [0.7 + 0.1 * np.sin(t)])
    assert np.allclose(moving(0.0, np.array([0.7]), np.array([0.0])), [5.0 * 0.1],
                       rtol=1e-6)


def test_facades_delegate(monkeypatch):
    """Linkage.simulate and Mechanism.simulate are simulate on their models, from home."""
    cm, q = with_random_inertias(four_bar()), four_bar_q(0.7)
    link = Linkage(cm)
    a = link.simulate(q, None, 0.02, 1e-3, gravity=G)
    b = sim.simulate(cm, q, None, 0.02, 1e-3, gravity=G)
    assert np.array_equal(a.q, b.q)
    home = link.simulate(None, None, 0.01, 1e-3, gravity=G)
    assert np.allclose(home.q[0], link.home_assembly.q)
    mech = pkm_pin.load_mechanism(ROOT / "models" / "mechanisms" / "stewart.toml")
    with pytest.raises(InputError, match="no mass"):  # the TOML legs carry no inertias
        mech.simulate(None, None, 0.005, 1e-3)
    seen = {}

    def spy(model, q0, v0, duration, dt, **options):
        seen.update(model=model, q0=q0, v0=v0, duration=duration, dt=dt, **options)

    monkeypatch.setattr(sim, "simulate", spy)
    mech.simulate(None, None, 0.5, 1e-3, gravity=G)
    assert seen["model"] is mech.closure_model and seen["gravity"] == G
    assert np.array_equal(seen["q0"], configuration(mech, mech.home_assembly))


def test_bad_input_is_refused():
    cm, q = model("five_bar_revolute")
    with pytest.raises(InputError, match="revolute"):
        sim.simulate(cm, q, None, 0.01, 1e-3, method="pinocchio")
    with pytest.raises(InputError, match="not both"):
        sim.simulate(cm, q, None, 0.01, 1e-3, efforts=[0, 0], controller=sim.PD(1, 1, [0, 0]))
    with pytest.raises(InputError, match="close the loops"):
        sim.simulate(cm, q + 0.01, None, 0.01, 1e-3)
    with pytest.raises(InputError, match="v0 is not consistent"):
        sim.simulate(cm, q, np.ones(cm.nv), 0.01, 1e-3)
    with pytest.raises(InputError, match="2 finite numbers"):
        sim.simulate(cm, q, None, 0.01, 1e-3, efforts=lambda t, q, v: [1.0])
    with pytest.raises(InputError, match="positive"):
        sim.simulate(cm, q, None, -1.0, 1e-3)
    with pytest.raises(InputError, match="integrator"):
        sim.simulate(cm, q, None, 0.01, 1e-3, integrator="euler")
    with pytest.raises(InputError, match="baumgarte"):
        sim.simulate(cm, q, None, 0.01, 1e-3, baumgarte=(1.0, -2.0))


def test_wrench_on_the_output():
    """A wrench on the output (Stewart: a constant world wrench about the origin): the
    simulated (q, v, a) give the efforts back through inverse_dynamics(wrench=w); the
    energy balance counts its power (J_o v)ᵀ Δ w."""
    cm, q = model("stewart")
    rng = np.random.default_rng(11)
    w = np.r_[rng.normal(size=3) * 50.0, rng.normal(size=3) * 10.0]
    r = sim.simulate(cm, q, random_start(cm, q, rng), 0.05, 1e-3,
                     efforts=sine_efforts(cm, q, rng), gravity=G, wrench=w)
    for k in (0, 25, 50):
        idr = dyn.inverse_dynamics(cm, r.q[k], r.v[k], r.a[k], gravity=G, wrench=w)
        assert np.linalg.norm(idr.efforts - r.efforts[k]) <= 1e-6 * np.linalg.norm(r.efforts[k])
    assert r.energy_error < 1e-7
    no_power = sim.simulate(cm, q, random_start(cm, q, rng), 0.05, 1e-3, gravity=G,
                            wrench=lambda t, q, v: w)
    assert no_power.energy_error < 1e-7 and np.abs(no_power.work).max() > 0
    with pytest.raises(InputError, match="6 finite numbers"):
        sim.simulate(cm, q, None, 0.01, 1e-3, wrench=lambda t, q, v: [1.0])


def test_replay_of_a_trajectory_study_tracks_it():
    """The study's efforts (Gepetto's 5-bar, default motion, first 0.6 s) as feedforward,
    no feedback: the simulation follows the study's actuated values to 2e-5 rad (the
    feedforward is linear between 10 ms samples); with the PD, closer."""
    from pkm_pin import trajectory as tr

    link = pkm_pin.load_mechanism(ROOT / "tests" / "data" / "gepetto" / "5bar_linkage" /
                                  "robot.urdf")
    st = tr.study(link)
    cm, _ = tr.closure_model_of(link)
    part = slice(0, 61)
    args = (cm, st.t[part], st.q[0], st.v[0], st.q_actuated[part], st.speeds[part],
            st.efforts[part])
    open_loop = sim.replay(*args, bandwidth=0.0)
    assert np.all(open_loop.kp == 0)
    assert open_loop.tracking_error.max() < 2e-5
    closed = sim.replay(*args, bandwidth=5.0)
    assert closed.tracking_error.max() < 0.5 * open_loop.tracking_error.max()
    assert closed.simulation.max_drift < 1e-10


def test_cli_simulate(capsys):
    """pkm-pin dynamics FILE --simulate [--json]: the replay's tracking error, drift and
    energy balance (Gepetto's 5-bar, 0.5 s of the default motion)."""
    import json

    from pkm_pin.cli import main

    path = ROOT / "tests" / "data" / "gepetto" / "5bar_linkage" / "robot.urdf"
    assert main(["dynamics", str(path), "--duration", "0.5", "--samples", "51",
                 "--simulate", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)["simulation"]
    assert out["method"] == "pinocchio" and len(out["tracking_error"]) == 2
    assert max(out["tracking_error"]) < 3e-4  # 0.2 rad sines over 0.5 s, 10 ms samples
    assert out["max_drift"] < 1e-9 and out["energy_error"] < 1e-7
    assert main(["dynamics", str(path), "--duration", "0.5", "--samples", "51",
                 "--simulate"]) == 0
    assert "tracking error" in capsys.readouterr().out
