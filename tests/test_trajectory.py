"""Motions given as actuated values over time and the efforts along them
(pkm_pin.trajectory, issue 26 items 2 and 3): the spline, the consistency of q(t), v(t),
a(t), the power balance Σ τ q̇_a = d(T + V)/dt along the default motion, the summary
numbers, and the massless-model rule.

Models with inertias: the Gepetto files (tests/data/gepetto, their own inertias; the
Cassie-like leg's rods spin freely about their axes: idle motions), the four-bar and
the RSSR (a rod spinning about its axis, centre of mass off it) with the seeded random
inertias of tests/test_dynamics.py.

Power balance (central differences, h = 1e-4 s, at t = 0.3, 0.9, 1.55 s of the default
motion, gravity (0.3, −1, −9.81), relative to Σ |τ q̇_a|), measured::

    four_bar 1.4e-08   cassie_knee 4.2e-09   5bar_linkage 1.6e-07
    cassie_like 1.6e-08 (payload 1.6e-08)   rssr (idle spin) 1.5e-07
"""

from __future__ import annotations

import dataclasses
import functools
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from linkage_models import four_bar, four_bar_q, spherical_rod
from test_dynamics import G, with_inertias

import pkm_pin
from pkm_pin import dynamics as dyn
from pkm_pin import trajectory as tr
from pkm_pin.builders import MECHANISMS
from pkm_pin.errors import InputError
from pkm_pin.linkage import Linkage

ROOT = Path(__file__).resolve().parents[1]
GEPETTO = ROOT / "tests" / "data" / "gepetto"


@functools.lru_cache(maxsize=None)
def model(name: str):
    """``(closure model with inertias, assembled q0)``."""
    if name == "four_bar":
        return with_inertias(four_bar()), four_bar_q(0.7)
    if name == "rssr":
        return with_inertias(spherical_rod()), Linkage(spherical_rod()).home_assembly.q
    if name == "cassie_knee":
        link = pkm_pin.load_mechanism(ROOT / "models/loops/cassie_knee.urdf")
        return with_inertias(link.model), link.home_assembly.q
    link = pkm_pin.load_mechanism(GEPETTO / name / "robot.urdf")
    return link.model, link.home_assembly.q


# ------------------------------------------------------------------- the spline
def test_spline_reproduces_the_samples_and_its_acceleration_is_continuous():
    """The clamped spline passes through every sample (1e-12), is at rest at both ends,
    and its acceleration from the left and the right of each knot agrees to 1e-6."""
    rng = np.random.default_rng(0)
    t = np.cumsum(rng.uniform(0.05, 0.3, 12))
    Q = rng.normal(size=(12, 3))
    m = tr.SplineMotion(t, Q, ("a", "b", "c"))
    q, qd, _ = m(t)
    assert np.allclose(q, Q, rtol=0, atol=1e-12)
    assert np.allclose(qd[[0, -1]], 0.0, atol=1e-12)
    eps = 1e-9
    left, right = m(t[1:-1] - eps)[2], m(t[1:-1] + eps)[2]
    assert np.allclose(left, right, rtol=0, atol=1e-6 * np.abs(left).max())
    # the third derivative jumps: the spline is C² and not more
    s = m.spline
    assert np.abs(s(t[1:-1] - eps, 3) - s(t[1:-1] + eps, 3)).max() > 1e-3


def test_natural_spline_has_zero_end_accelerations():
    """bc_type="natural": q̈_a = 0 at both ends; a wrong bc_type is an InputError."""
    t = np.linspace(0.0, 1.0, 6)
    m = tr.SplineMotion(t, np.sin(3 * t), bc_type="natural")
    assert np.allclose(m(t[[0, -1]])[2], 0.0, atol=1e-12)
    with pytest.raises(InputError, match="bc_type"):
        tr.SplineMotion(t, t, bc_type="quintic")


def test_csv_columns_in_any_order_and_errors(tmp_path):
    """A CSV whose actuated columns are in another order gives the same spline; a wrong
    header, a non-number and times that do not increase are InputErrors naming the
    file (and the line)."""
    t = np.linspace(0, 1, 5)
    Q = np.c_[np.sin(t), np.cos(t)]
    path = tmp_path / "m.csv"
    path.write_text("# comment\nt,b,a\n" + "\n".join(f"{x},{c},{s}" for x, s, c in
                                                     zip(t, Q[:, 0], Q[:, 1])) + "\n")
    m = tr.read_csv(path, ("a", "b"))
    assert np.allclose(m(t)[0], Q, atol=1e-12)
    path.write_text("t,a,c\n0,1,2\n1,2,3\n")
    with pytest.raises(InputError, match="header must be t,a,b"):
        tr.read_csv(path, ("a", "b"))
    path.write_text("t,a,b\n0,1,2\n1,x,3\n")
    with pytest.raises(InputError, match=r"m.csv:3: 'x' is not a number"):
        tr.read_csv(path, ("a", "b"))
    path.write_text("t,a,b\n0,1,2\n0,2,3\n")
    with pytest.raises(InputError, match="increase strictly"):
        tr.read_csv(path, ("a", "b"))


def test_default_motion_amplitudes():
    """The default motion: 0.1 rad per revolute actuator (or less near limits), 0.1 L per
    prismatic one; it starts at home and is periodic over the duration."""
    cm, q0 = model("cassie_knee")
    m = tr.default_motion(cm, q0, duration=1.5)
    assert np.all(m.amplitude <= 0.1) and np.all(m.amplitude > 0)
    start, end = m([0.0, 1.5])[0]
    assert np.allclose(start, end) and m.stop == 1.5
    mech = pkm_pin.load_mechanism(ROOT / "models/mechanisms/rpr3.toml")
    cm, q0 = tr.closure_model_of(mech)
    m = tr.default_motion(cm, q0)
    prismatic = [k for k, n in enumerate(cm.actuated)
                 if cm.velocity_units[cm.tree.joints[cm.tree.getJointId(n)].idx_v] != 1.0]
    assert prismatic and np.allclose(m.amplitude[prismatic], 0.1 * cm.length)


# ---------------------------------------------------------- q(t), v(t), a(t)
@pytest.mark.parametrize("name", ["four_bar", "rssr", "cassie_like", "5bar_linkage"])
def test_motion_is_consistent_with_the_closures(name):
    """Along the default motion: closures closed, J v and J a + J̇ v at 1e-8 of their
    terms, the actuated values, rates and accelerations those of the motion."""
    cm, q0 = model(name)
    motion = tr.default_motion(cm, q0)
    (q, v, a, Qa, Qd, Qdd), _ = tr.motion_states(cm, motion, np.linspace(0, 2, 41), q0,
                                                  gravity=G)
    U, rows = cm.velocity_units, dyn.row_units(cm)
    act = list(cm.actuated_v)
    for i in range(len(q)):
        assert np.linalg.norm(cm.closure_residual(q[i])) < 1e-8
        assert np.allclose(cm.actuated_values(q[i]), Qa[i], atol=1e-9)
        assert np.allclose(v[i, act], Qd[i], atol=1e-12) and np.allclose(a[i, act], Qdd[i],
                                                                          atol=1e-9)
        J, rdd, drift = dyn.closure_acceleration(cm, q[i], v[i], a[i])
        Jd = J / rows[:, None] * U
        norm = np.linalg.norm(Jd, 2)
        assert np.linalg.norm(Jd @ (v[i] / U)) <= 1e-8 * norm * np.linalg.norm(v[i] / U)
        assert np.linalg.norm(rdd / rows) <= 1e-8 * (norm * np.linalg.norm(a[i] / U)
                                                    + np.linalg.norm(drift / rows))


def test_idle_acceleration_balances_the_idle_joints():
    """RSSR rod (spins about its axis, centre of mass off it): the idle acceleration leaves
    no generalized force along the spin, Nᵀ rnea(q, v, a) = 0 to 1e-10."""
    cm, q0 = model("rssr")
    rng = np.random.default_rng(1)
    v, a = dyn.motion_from_actuated(cm, q0, rng.normal(size=1), rng.normal(size=1))
    a = dyn.idle_acceleration(cm, q0, v, a, gravity=G)
    J, _, _ = dyn.closure_acceleration(cm, q0, v, a)
    S = np.zeros((1, cm.nv))
    S[0, cm.actuated_v[0]] = 1.0
    N = np.linalg.svd(np.vstack([J, S]))[2][-1]  # the spin
    tree = pin.Model(cm.tree)
    tree.gravity = pin.Motion(np.array(G), np.zeros(3))
    tau = pin.rnea(tree, tree.createData(), q0, v, a)
    assert abs(N @ tau) <= 1e-10 * np.abs(tau).max()
    dyn.inverse_dynamics(cm, q0, v, a, gravity=G)  # balanced: no InconsistentMotion


# --------------------------------------------------------------- power balance
def _energy(cm, q, v, g) -> float:
    tree = pin.Model(cm.tree)
    tree.gravity = pin.Motion(np.array(g, float), np.zeros(3))
    data = tree.createData()
    return float(pin.computeKineticEnergy(tree, data, q, v)
                 + pin.computePotentialEnergy(tree, data, q))


@pytest.mark.parametrize("name, payload", [("four_bar", None), ("cassie_knee", None),
                                           ("5bar_linkage", None), ("cassie_like", None),
                                           ("cassie_like", (3.0, -2.0, -40.0, 0, 0, 0)),
                                           ("rssr", None)])
def test_power_balance_along_the_default_motion(name, payload):
    """Σ τ q̇_a = d(T + V − f·p)/dt (kinetic, gravity's potential, a constant payload force
    f at the output origin p) by central differences (h = 1e-4 s) at three times of the
    default motion, to 1e-6 of Σ |τ q̇_a|."""
    cm, q0 = model(name)
    motion, h = tr.default_motion(cm, q0), 1e-4
    f = None if payload is None else np.array(payload)
    data = cm.tree.createData()

    def payload_potential(q) -> float:
        if f is None:
            return 0.0
        pin.framesForwardKinematics(cm.tree, data, q)
        return -float(f[:3] @ data.oMf[cm.tree.getFrameId(cm.output)].translation)

    for t in (0.3, 0.9, 1.55):
        st = tr.study(cm, motion, times=[t - h, t, t + h], gravity=G, payload=f, q0=q0)
        E = [_energy(cm, st.q[k], st.v[k], G) + payload_potential(st.q[k]) for k in (0, 2)]
        power = st.efforts[1] @ st.speeds[1]
        scale = np.abs(st.efforts[1] * st.speeds[1]).sum()
        assert abs(power - (E[1] - E[0]) / (2 * h)) <= 1e-6 * scale, (name, t)


# ----------------------------------------------------------------- the numbers
def test_summary_equals_hand_computations():
    """Peak and RMS effort, peak speed, peak power and both energies equal sums written
    out on the returned arrays; powers are efforts × speeds."""
    cm, q0 = model("cassie_like")
    st = tr.study(cm, samples=41, q0=q0)
    assert st.efforts.shape == (41, len(cm.actuated)) and st.actuated == cm.actuated
    summary = st.summary()
    t = st.t
    for k, name in enumerate(st.actuated):
        tau, qd = st.efforts[:, k], st.speeds[:, k]
        P = [tau[i] * qd[i] for i in range(len(t))]
        s = summary[name]
        assert s["peak_effort"] == max(abs(x) for x in tau)
        assert s["peak_speed"] == max(abs(x) for x in qd)
        assert s["peak_power"] == max(abs(x) for x in P)
        sq = sum((tau[i] ** 2 + tau[i + 1] ** 2) / 2 * (t[i + 1] - t[i]) for i in range(40))
        assert s["rms_effort"] == pytest.approx(np.sqrt(sq / (t[-1] - t[0])), rel=1e-12)
        e_abs = sum((abs(P[i]) + abs(P[i + 1])) / 2 * (t[i + 1] - t[i]) for i in range(40))
        e_net = sum((P[i] + P[i + 1]) / 2 * (t[i + 1] - t[i]) for i in range(40))
        assert s["energy"] == pytest.approx(e_abs, rel=1e-12)
        assert s["net_energy"] == pytest.approx(e_net, rel=1e-12, abs=1e-12 * e_abs)
        assert s["effort_unit"] == "N m" and s["speed_unit"] == "rad/s"
    assert np.array_equal(st.powers, st.efforts * st.speeds)


def test_efforts_are_the_inverse_dynamics_of_each_sample():
    """Each sample's efforts are inverse_dynamics of its (q, v, a) with the payload about
    the world origin (f; m + p × f); the payload part alone is the payload's."""
    cm, q0 = model("cassie_like")
    f = np.array([5.0, 1.0, -30.0, 0.2, -0.1, 0.3])
    st = tr.study(cm, samples=5, q0=q0, payload=f)
    data = cm.tree.createData()
    for i in range(5):
        pin.framesForwardKinematics(cm.tree, data, st.q[i])
        p = data.oMf[cm.tree.getFrameId(cm.output)].translation
        w = np.r_[f[:3], f[3:] + np.cross(p, f[:3])]
        r = dyn.inverse_dynamics(cm, st.q[i], st.v[i], st.a[i], wrench=w)
        assert np.allclose(st.efforts[i], r.efforts, rtol=1e-12, atol=1e-12)
        assert np.allclose(st.payload_efforts[i], r.payload_efforts, rtol=1e-12, atol=1e-12)


def test_massless_model_is_refused_or_sized_for_the_payload_alone():
    """A model with no mass anywhere: refused, naming its bodies; with a payload, the
    efforts are the payload's alone and a note says so. Bodies without mass in a model
    with some are listed."""
    link = pkm_pin.load_mechanism(ROOT / "models/loops/four_bar.urdf")
    with pytest.raises(InputError, match=r"no mass on any body \(crank, coupler, rocker\)"):
        tr.study(link)
    st = tr.study(link, samples=5, payload=(0, 0, 0, 0, 0, 2.0))
    assert np.allclose(st.efforts, st.payload_efforts) and "payload's alone" in st.notes[0]
    assert np.abs(st.efforts).max() > 0
    cm, q0 = model("cassie_like")
    assert "foot_2_int1_2" in tr.massless_bodies(cm)
    tree = pin.Model(cm.tree)
    tree.inertias[1] = pin.Inertia.Zero()
    bare = dataclasses.replace(cm, tree=tree)
    assert tr.body_names(cm)[0] in tr.massless_bodies(bare)


def test_time_is_named_when_the_motion_leaves_the_workspace():
    """The Cassie-like knee's actuators driven 1 rad beyond home in 1 s: the forward
    kinematics stops closing at t = 0.575 s, and the error says when and where."""
    cm, q0 = model("cassie_knee")
    qa0 = cm.actuated_values(q0)
    m = tr.SplineMotion([0.0, 1.0], [qa0, qa0 + 1.0])
    with pytest.raises(pkm_pin.errors.ForwardKinematicsError,
                       match=r"at t = 0.575 s .* \(actuated 0.611656, 0.611656"):
        tr.study(cm, m, samples=41, q0=q0)


# ------------------------------------------------- motions of the output (item 2)
def _output_case(name: str):
    """``(closure model, q0, OutputMotion, held coordinates)``: the Gepetto 5-bar by its
    y, z; the Stewart by z and yaw (x, y, roll, pitch held at home); the 3-RPS by z,
    roll, pitch (x, y, yaw parasitic, none held)."""
    t = np.linspace(0.0, 2.0, 21)
    s = np.sin(np.pi * t)
    if name == "5bar_linkage":
        cm, q0 = model(name)
        c0 = tr._OutputCoordinates(cm).values(q0)
        return cm, q0, tr.OutputMotion(t, np.c_[c0[1] + 0.005 * s, c0[2] + 0.005 * s],
                                       ("y", "z")), ()
    cm, q0 = tr.closure_model_of(MECHANISMS[name]().build())
    c0 = tr._OutputCoordinates(cm).values(q0)
    if name == "stewart":
        return cm, q0, tr.OutputMotion(t, np.c_[0.2 * s + c0[5], c0[2] + 0.05 * s],
                                       ("yaw", "z")), ("x", "y", "roll", "pitch")
    return cm, q0, tr.OutputMotion(t, np.c_[c0[2] + 0.05 * s, 0.1 * s, 0.1 * np.cos(np.pi * t)
                                            - 0.1], ("z", "roll", "pitch")), ()


@pytest.mark.parametrize("name", ["5bar_linkage", "stewart", "rps3"])
def test_output_motion_is_followed_and_v_a_are_the_derivatives_of_q(name):
    """A motion given by some output coordinates: at each sample the loops close
    (1e-10), the given coordinates are the spline's (1e-10), the held ones keep their
    home values (1e-10); v and a equal central differences of q(t) and v(t) (h = 1e-4 s,
    between knots) to 1e-6 of their size, and J v, J a + J̇ v vanish (1e-8)."""
    cm, q0, motion, held = _output_case(name)
    oc = tr._OutputCoordinates(cm)
    home = oc.values(q0)
    t = np.linspace(0.0, 2.0, 9)
    (q, v, a, Qa, Qd, Qdd), _ = tr.motion_states(cm, motion, t, q0)
    given = [tr.POSE_COORDINATES.index(c) for c in motion.coordinates]
    kept = [tr.POSE_COORDINATES.index(c) for c in held]
    act = list(cm.actuated_v)
    for i in range(len(t)):
        c = oc.values(q[i])
        assert np.linalg.norm(cm.closure_residual(q[i])) < 1e-10
        assert np.allclose(c[given], motion(t[i])[0][0], rtol=0, atol=1e-10)
        assert np.allclose(c[kept], home[kept], rtol=0, atol=1e-10)
        assert np.allclose(Qd[i], v[i, act]) and np.allclose(Qdd[i], a[i, act])
        J, rdd, drift = dyn.closure_acceleration(cm, q[i], v[i], a[i])
        assert np.linalg.norm(J @ v[i]) <= 1e-8 * np.linalg.norm(J) * np.linalg.norm(v[i])
        assert np.linalg.norm(rdd) <= 1e-8 * (np.linalg.norm(J) * np.linalg.norm(a[i])
                                              + np.linalg.norm(drift))
    h = 1e-4
    for tc in (0.513, 1.234):
        (qq, vv, aa, *_), _ = tr.motion_states(cm, motion, [tc - h, tc, tc + h], q0)
        vd = pin.difference(cm.tree, qq[0], qq[2]) / (2 * h)
        ad = (vv[2] - vv[0]) / (2 * h)
        assert np.abs(vd - vv[1]).max() <= 1e-6 * np.abs(vv[1]).max(), (name, tc)
        assert np.abs(ad - aa[1]).max() <= 1e-6 * np.abs(aa[1]).max(), (name, tc)


def test_output_motion_power_balance():
    """Σ τ q̇_a = d(T + V)/dt along a motion of the Gepetto 5-bar's y, z (its own
    inertias; central differences h = 1e-4 s) to 1e-6 of Σ |τ q̇_a|."""
    cm, q0, motion, _ = _output_case("5bar_linkage")
    h = 1e-4
    for t in (0.37, 1.41):
        st = tr.study(cm, motion, times=[t - h, t, t + h], gravity=G, q0=q0)
        E = [_energy(cm, st.q[k], st.v[k], G) for k in (0, 2)]
        scale = np.abs(st.efforts[1] * st.speeds[1]).sum()
        assert abs(st.efforts[1] @ st.speeds[1] - (E[1] - E[0]) / (2 * h)) <= 1e-6 * scale


def test_pose_motion_and_coordinate_csv(tmp_path):
    """Poses as SE3s, as (N, 4, 4) and as (N, 6) give the same OutputMotion; a CSV with
    the header t,z,yaw reads as an OutputMotion (coordinates in the POSE_COORDINATES
    order); a header that is neither actuated names nor coordinates names both;
    dependent coordinates (the 5-bar moves in 2 dimensions of y, z, roll; x is fixed) are an
    InputError."""
    t = np.linspace(0, 1, 6)
    C = np.c_[0.1 * t, 0 * t, 1 + t, 0.1 * t, -0.2 * t, 3.0 + 0.5 * t]  # yaw through π
    poses = [pin.SE3(pin.rpy.rpyToMatrix(c[3:]), c[:3]) for c in C]
    a = tr.pose_motion(t, poses, ("z", "yaw"))
    b = tr.pose_motion(t, np.array([p.homogeneous for p in poses]), ("z", "yaw"))
    c = tr.pose_motion(t, C, ("yaw", "z"))
    for m in (a, b, c):
        assert m.coordinates == ("z", "yaw")
        assert np.allclose(m(t)[0], C[:, [2, 5]], atol=1e-12)  # unwrapped yaw
    path = tmp_path / "m.csv"
    path.write_text("t,yaw,z\n" + "\n".join(f"{x},{y},{z}" for x, z, y in
                                            zip(t, C[:, 2], C[:, 5])) + "\n")
    m = tr.read_csv(path, ("a", "b"))
    assert isinstance(m, tr.OutputMotion) and np.allclose(m(t)[0], C[:, [2, 5]])
    path.write_text("t,z,q\n0,1,2\n1,2,3\n")
    with pytest.raises(InputError, match="t,a,b .* or t and some of x,y,z,roll,pitch,yaw"):
        tr.read_csv(path, ("a", "b"))
    cm, q0 = model("5bar_linkage")
    with pytest.raises(InputError, match=r"x, z are not independent .* moves in 2 dimensions"):
        tr.motion_states(cm, tr.OutputMotion(t, np.c_[t, t], ("x", "z")), t, q0)


def test_idle_motions_that_run_away_are_refused_with_their_joints(capsys):
    """Robotiq's 2F-85 (Menagerie; its spring links' stiffness not modelled): the fingers'
    idle motions, followed by their own dynamics under gravity, run away (1e31 rad/s,
    then nan and numpy's overflow warnings, before the check). `pkm-pin dynamics` now
    stops at the first sample that moves them by more than IDLE_STEP_MAX, in one line
    naming those joints; no numpy warning reaches the user (warnings are errors here)."""
    import warnings

    from pkm_pin.cli import main
    from pkm_pin.trajectory import IDLE_STEP_MAX

    path = Path(__file__).parent / "data" / "menagerie" / "robotiq_2f85" / "2f85.xml"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["dynamics", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "the idle motions (right_coupler_joint, right_spring_link_joint" in err
    assert f"at most {IDLE_STEP_MAX:g}" in err and "actuate or lock those joints" in err
