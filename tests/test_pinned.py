"""Legs meeting at a pin (our TOML ``closure = "spherical" | "revolute"``): the planar
five-bar and the point-platform Delta, checked against closed forms and finite
differences on the closure manifold."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from pkm_pin import InputError, MechanismFileError, load_mechanism
from pkm_pin.builders import PINNED, five_bar
from pkm_pin.linkage import Linkage
from pkm_pin.model.pinned import PIN, pinned_legs

ROOT = Path(__file__).resolve().parents[1]
FIVE_BAR = ROOT / "models" / "pinned" / "five_bar.toml"
DELTA_POINT = ROOT / "models" / "pinned" / "delta_point.toml"
A, L1, L2 = 0.1, 0.2, 0.25  # five_bar() defaults: half base, proximal, distal


def _point_velocity(twist: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Velocity of the point ``p`` of a body moving with the axis-first twist
    ``(ω; v_O)``: ``v_O + ω × p``."""
    return twist[3:] + np.cross(twist[:3], p)


def _five_bar_points(q: np.ndarray):
    """Bases, elbows and pin of the five-bar at ``q = (L1, L2, R1, R2)`` (closed form)."""
    bases = [np.array([-A, 0.0]), np.array([A, 0.0])]
    elbows, tips = [], []
    for b, (t1, t2) in zip(bases, (q[:2], q[2:])):
        e = b + L1 * np.array([math.cos(t1), math.sin(t1)])
        elbows.append(e)
        tips.append(e + L2 * np.array([math.cos(t1 + t2), math.sin(t1 + t2)]))
    return bases, elbows, tips


def _five_bar_velocity_equation(q: np.ndarray):
    """``A ṗ = B q̇_a`` of the five-bar: each distal link keeps its length,
    ``(p − e_i)·(ṗ − ė_i) = 0`` with ``ė_i = q̇_i ẑ × (e_i − b_i)``."""
    bases, elbows, tips = _five_bar_points(q)
    p = tips[0]
    Am = np.array([p - e for e in elbows])
    Bm = np.diag([(p - e) @ np.array([-(e - b)[1], (e - b)[0]]) for b, e in zip(bases, elbows)])
    return Am, Bm, p


@pytest.fixture(scope="module")
def five() -> Linkage:
    return load_mechanism(FIVE_BAR)


@pytest.fixture(scope="module")
def delta() -> Linkage:
    return load_mechanism(DELTA_POINT)


def test_committed_files_are_the_builders_output(tmp_path):
    for build in PINNED.values():
        for path in build().write(tmp_path):
            rel = path.relative_to(tmp_path)
            assert (ROOT / "models" / rel).read_text() == path.read_text(), rel


def test_five_bar_assembles_at_home_with_the_closed_form_pin(five):
    a = five.assemble()
    assert a.residual < 1e-12
    _, _, tips = _five_bar_points(a.q)
    np.testing.assert_allclose(tips[0], tips[1], atol=1e-12)  # the legs meet
    np.testing.assert_allclose(tips[0], [0.0, 0.3], atol=1e-12)  # home_xy of the builder


def test_five_bar_mobility_and_redundancy(five):
    m = five.mobility(five.assemble().q)
    # 4 joints; the revolute pin writes 5 rows of which 2 are independent in the plane
    assert (m.dof, m.redundant_constraints, m.idle_dof) == (2, 3, 0)
    assert five.grubler == -1  # Grübler's count misses the planar redundancy
    assert m.independent_actuators == ("L/R1", "R/R1")


def test_five_bar_output_is_the_pin_point_with_two_translations(five):
    an = five.analyze(five.assemble().q)
    # the pin is a point: 2T, not the "1T1R" of the first leg's distal link
    assert (an.motion_type, an.output_dof, an.translations) == ("2T", 2, 2)
    np.testing.assert_allclose(an.platform_twists[:, :3], 0.0, atol=1e-15)
    np.testing.assert_allclose(np.abs(an.platform_twists[:, 5]), 0.0, atol=1e-15)


def test_five_bar_actuation_wrenches_are_the_distal_links_through_the_pin(five):
    q = five.assemble().q
    an = five.analyze(q)
    _, elbows, tips = _five_bar_points(q)
    p = np.r_[tips[0], 0.0]
    for row, e in zip(an.A, elbows):
        f, m = row[:3], row[3:]
        d = np.r_[tips[0] - e, 0.0]
        assert np.linalg.norm(np.cross(f, d)) < 1e-12 * np.linalg.norm(d)  # along the link
        np.testing.assert_allclose(m, np.cross(p, f), atol=1e-12)  # a line through the pin


def test_five_bar_forward_and_inverse_velocity_match_the_closed_form(five):
    q = five.assemble().q
    an = five.analyze(q)
    Am, Bm, p = _five_bar_velocity_equation(q)
    for qd in (np.array([1.0, 0.0]), np.array([0.3, -0.7])):
        t = an.forward_velocity(qd)
        np.testing.assert_allclose(t[:3], 0.0, atol=1e-15)  # a point: no rotation
        v = _point_velocity(t, np.r_[p, 0.0])
        np.testing.assert_allclose(v[:2], np.linalg.solve(Am, Bm @ qd), atol=1e-12)
        assert abs(v[2]) < 1e-12
        np.testing.assert_allclose(an.inverse_velocity(t), qd, atol=1e-12)


def test_five_bar_velocity_against_finite_differences_of_forward_kinematics(five):
    a = five.assemble()
    an = five.analyze(a.q)
    h = 1e-6
    qa = a.q[[0, 2]]
    for k in range(2):
        dq = np.zeros(2)
        dq[k] = h
        plus = five.forward_kinematics(qa + dq, guess=a)
        minus = five.forward_kinematics(qa - dq, guess=a)
        p_plus, p_minus = _five_bar_points(plus.q)[2][0], _five_bar_points(minus.q)[2][0]
        fd = (p_plus - p_minus) / (2 * h)
        v = _point_velocity(an.forward_velocity(dq / h), np.r_[_five_bar_points(a.q)[2][0], 0])
        np.testing.assert_allclose(v[:2], fd, atol=1e-7)


def test_five_bar_type_II_where_the_distal_links_align(five):
    # symmetric elbows with |E_L E_R| = 2 L2: the distal links are collinear at the pin
    theta = math.acos((L2 - A) / L1)
    q = np.array([math.pi - theta, theta - math.pi, theta, math.pi - theta])
    Am, _, _ = _five_bar_velocity_equation(q)
    assert abs(np.linalg.det(Am)) < 1e-12  # the closed form is singular there
    kin = five.model.kinematics(q)
    assert np.linalg.norm(kin.residual) < 1e-12
    assert five.analyze(q).singularity in ("II", "III")


def test_five_bar_type_I_where_a_leg_is_stretched(five):
    # right leg stretched (R2 = 0): its tip at distance L1 + L2 from its base
    r = L1 + L2
    p = np.array([A + r * math.cos(1.9), r * math.sin(1.9)])
    from pkm_pin.builders.pinned import elbow_angles

    q_left = elbow_angles(np.array([-A, 0.0]), p, L1, L2, -1)
    q = np.r_[q_left, 1.9, 0.0]
    _, Bm, _ = _five_bar_velocity_equation(q)
    assert abs(Bm[1, 1]) < 1e-12
    assert np.linalg.norm(five.model.kinematics(q).residual) < 1e-12
    assert five.analyze(q).singularity in ("I", "III")


def test_delta_point_assembles_with_three_dof_and_no_idle_motion(delta):
    a = delta.assemble()
    assert a.residual < 1e-12
    m = delta.mobility(a.q)
    assert (m.dof, m.redundant_constraints, m.idle_dof, delta.grubler) == (3, 0, 0, 3)
    assert delta.analyze(a.q).motion_type == "3T"


def test_pinned_inverse_kinematics_reaches_the_point(five, delta):
    for link, shift in ((five, [0.01, 0.02, 0.0]), (delta, [0.02, -0.01, 0.03])):
        a = link.assemble()
        target = pin.SE3(pin.rpy.rpyToMatrix(0.3, 0.2, 0.1), a.output_pose.translation + shift)
        b = link.inverse_kinematics(target, guess=a)  # the point: the rotation is free
        np.testing.assert_allclose(b.output_pose.translation, target.translation, atol=1e-10)


def test_delta_point_velocity_against_finite_differences(delta):
    a = delta.assemble()
    an = delta.analyze(a.q)
    model = delta.model
    fid = model.tree.getFrameId(PIN)

    def pin_point(q):
        data = model.tree.createData()
        pin.framesForwardKinematics(model.tree, data, q)
        return data.oMf[fid].translation.copy()

    p0 = pin_point(a.q)
    qa = a.q[[0, 3, 6]]
    h = 1e-6
    for k in range(3):
        dq = np.zeros(3)
        dq[k] = h
        fd = (pin_point(delta.forward_kinematics(qa + dq, guess=a).q)
              - pin_point(delta.forward_kinematics(qa - dq, guess=a).q)) / (2 * h)
        np.testing.assert_allclose(_point_velocity(an.forward_velocity(dq / h), p0), fd,
                                   atol=1e-7)


def test_pinned_model_in_millimetres_has_the_same_ranks():
    m, mm = five_bar().build(), five_bar(scale=1000.0).build()
    a, b = m.mobility(m.assemble().q), mm.mobility(mm.assemble().q)
    assert (a.dof, a.redundant_constraints) == (b.dof, b.redundant_constraints)


# ---------------------------------------------------------------- bad input
def _write(tmp_path, text: str) -> Path:
    (tmp_path / "pinned").mkdir(exist_ok=True)
    path = tmp_path / "pinned" / "m.toml"
    path.write_text(text)
    return path


def _five_bar_text(**replace) -> str:
    text = FIVE_BAR.read_text().replace("../urdf/", str(ROOT / "models" / "urdf") + "/")
    for old, new in replace.items():
        text = text.replace(old, new)
    return text


def test_unknown_closure_is_named(tmp_path):
    path = _write(tmp_path, _five_bar_text(**{'closure = "revolute"': 'closure = "glue"'}))
    with pytest.raises(MechanismFileError, match=r"closure.*'glue'.*'weld', 'spherical'"):
        load_mechanism(path)


def test_home_pose_of_a_pinned_mechanism_is_refused(tmp_path):
    path = _write(tmp_path, _five_bar_text() + "\n[home]\nxyz = [0, 0.3, 0]\n")
    with pytest.raises(MechanismFileError, match=r"home.*no platform pose.*home_q"):
        load_mechanism(path)


def test_pinned_legs_input_errors():
    legs = five_bar().legs_built()
    with pytest.raises(InputError, match="unknown pin 'weld'"):
        pinned_legs(legs, None, "weld")
    with pytest.raises(InputError, match="at least two legs"):
        pinned_legs(legs[:1], None, "spherical")
    with pytest.raises(InputError, match="1 anchors given for 2 legs"):
        pinned_legs(legs, [pin.SE3.Identity()], "spherical")


def test_five_bar_forward_kinematics_all_finds_both_circle_intersections(five):
    """At given motor angles the pin lies on both distal circles (radius L2 about each
    elbow): the two intersections are the two assembly modes."""
    a = five.assemble()
    qa = a.q_actuated + np.array([0.1, -0.05])
    modes = five.forward_kinematics_all(qa)
    assert len(modes) == 2 and modes.complete is False and modes.method == "multistart"
    e = [np.array([x, 0.0]) + L1 * np.array([math.cos(t), math.sin(t)])
         for x, t in ((-A, qa[0]), (A, qa[1]))]
    d = e[1] - e[0]
    dist = np.linalg.norm(d)
    mid = e[0] + 0.5 * d
    h = math.sqrt(L2 ** 2 - (dist / 2) ** 2)
    normal = np.array([-d[1], d[0]]) / dist
    expected = sorted([tuple(mid + h * normal), tuple(mid - h * normal)])
    got = sorted(tuple(m.output_pose.translation[:2]) for m in modes)
    np.testing.assert_allclose(got, expected, atol=1e-10)
    # the first mode is the reference's branch (nearest the reference configuration)
    assert modes[0].output_pose.translation[1] > modes[1].output_pose.translation[1]


def test_forward_kinematics_all_raises_out_of_reach(five):
    from pkm_pin import ForwardKinematicsError

    with pytest.raises(ForwardKinematicsError, match="no assembly.*not proven"):
        five.forward_kinematics_all([math.pi / 2 + 1.5, math.pi / 2 - 1.5], patience=1)


def test_linkage_transmission_of_the_five_bar_and_four_bar_closed_forms(five):
    """Linkage.transmission (issue 18 for general linkages): the five-bar's
    ITI_i = |sin γ_i| (proximal vs distal link of leg i) and OTI = |sin ψ| (between
    the distal links); the four-bar driven by its crank: ITI = |sin(θ3 − θ2)| (crank vs
    coupler) and OTI = |sin μ| = |sin(θ3 − θ4)| (the transmission angle)."""
    from pkm_pin.builders.loops import four_bar_home

    for shift in ([0.0, 0.0], [0.2, -0.1], [-0.3, 0.25]):
        a = five.forward_kinematics(five.assemble().q_actuated + shift, guess=five.assemble())
        _, elbows, tips = _five_bar_points(a.q)
        base = [np.array([-A, 0.0]), np.array([A, 0.0])]
        prox = [e - b for e, b in zip(elbows, base)]
        dist = [tips[0] - e for e in elbows]
        def cross2(u, v):
            return u[0] * v[1] - u[1] * v[0]

        sin = [abs(cross2(p, d)) / (np.linalg.norm(p) * np.linalg.norm(d))
               for p, d in zip(prox, dist)]
        psi = abs(cross2(*dist)) / (np.linalg.norm(dist[0]) * np.linalg.norm(dist[1]))
        tr = five.transmission(a)
        np.testing.assert_allclose(tr.iti, sin, atol=1e-10)
        np.testing.assert_allclose(tr.oti, [psi, psi], atol=1e-10)
        assert tr.lti == pytest.approx(min(*sin, psi), abs=1e-10) and tr.cti == 1.0
    bar = load_mechanism(ROOT / "models" / "loops" / "four_bar.urdf")
    home = bar.assemble()
    t2_home = four_bar_home()[0]
    for dq in (0.0, 0.7, 2.0, -1.2):
        a = bar.forward_kinematics([dq], guess=home)
        t2, t3, t4 = four_bar_home(crank_angle=t2_home + dq)
        tr = bar.transmission(a)
        assert tr.iti[0] == pytest.approx(abs(math.sin(t3 - t2)), abs=1e-9)
        assert tr.oti[0] == pytest.approx(abs(math.sin(t3 - t4)), abs=1e-9)


def test_linkage_report_gives_the_transmission_in_words(five):
    from pkm_pin.report import linkage_report_data, text

    a = five.assemble()
    data = linkage_report_data(five, a)
    tr = five.transmission(a)
    assert data["transmission"]["lti"] == pytest.approx(tr.lti, rel=1e-12)
    assert (f"transmission       LTI = {tr.lti:.3g}, CTI = {tr.cti:.3g}: {tr.worst}"
            in text(data))


def test_linkage_cti_of_planar_loops_is_one(five):
    """Planar loops: every side's constraints (forces normal to the plane through the pin
    for the five-bar's point output; out-of-plane wrenches for the four-bar's rocker) are
    imposed by the other side, or the output's own support, as well, so no output twist
    appears when one side's constraints are removed: CTI 1 per side (not nan), and the
    linkage report carries it."""
    from pkm_pin.report import linkage_report_data

    bar = load_mechanism(ROOT / "models" / "loops" / "four_bar.urdf")
    for link in (five, bar):
        a = link.assemble()
        for shift in (0.0, 0.3):
            b = link.forward_kinematics(a.q_actuated + shift, guess=a)
            tr = link.transmission(b)
            np.testing.assert_array_equal(tr.leg_cti, 1.0)
            assert tr.cti == 1.0 and len(tr.leg_names) == len(link.actuated)
    data = linkage_report_data(five, five.assemble())["transmission"]
    assert data["cti"] == 1.0 and data["leg_cti"] == [1.0, 1.0]


def test_linkage_sweep_gives_the_transmission_indices(five):
    """Linkage.sweep(..., transmission=True): lti/cti columns equal Linkage.transmission
    at each point (nan without the flag)."""
    a = five.assemble()
    Q = a.q_actuated + np.array([[0.0, 0.0], [0.1, -0.05], [0.2, -0.1]])
    res = five.sweep(Q, guess=a, transmission=True)
    assert res.converged.all()
    for q, lti, cti in zip(res.q, res.lti, res.cti):
        tr = five.transmission(q)
        assert lti == pytest.approx(tr.lti, abs=1e-12)
        assert cti == pytest.approx(tr.cti, abs=1e-12)
    assert np.isnan(five.sweep(Q, guess=a).lti).all()
