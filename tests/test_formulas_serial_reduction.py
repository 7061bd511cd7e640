"""Tests of the hand-written recursive screw reduction of a serial chain (seed 002).

Seed 002: anon., Polish, 1987, see docs/references.md.
"""

from __future__ import annotations

import numpy as np
import pytest

from pkm_pin.formulas import serial_reduction as sr


def _rotation(axis, angle):
    """Rodrigues rotation, written independently of the module."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _random_chain(rng: np.random.Generator, kinds: str):
    """Random chain: each offset a random rotation and a translation of ~0.3 m, random unit axes."""
    chain = []
    for k in kinds:
        T = np.eye(4)
        T[:3, :3] = _rotation(rng.normal(size=3), rng.uniform(0, np.pi))
        T[:3, 3] = rng.normal(0, 0.3, size=3)
        axis = rng.normal(size=3)
        chain.append(sr.ChainJoint(k, T, axis / np.linalg.norm(axis)))
    return chain


def _poses(chain, q):
    """Link poses by plain products of 4x4 transforms (no velocities)."""
    T, out = np.eye(4), []
    for j, qi in zip(chain, q):
        M = np.eye(4)
        if j.kind == "R":
            M[:3, :3] = _rotation(j.axis, qi)
        else:
            M[:3, 3] = qi * np.asarray(j.axis)
        T = T @ j.offset @ M
        out.append(T)
    return out


@pytest.mark.parametrize("kinds", ["RRPRRR", "PRPRPR", "RPP"])
def test_reduction_matches_central_differences_along_a_trajectory(kinds):
    """Poles, points, w, eps match central differences along q0 + qd t + qdd t^2/2."""
    rng = np.random.default_rng(len(kinds) + ord(kinds[0]))
    chain = _random_chain(rng, kinds)
    n = len(chain)
    q0, qd, qdd = rng.normal(size=n), rng.normal(size=n), rng.normal(size=n)
    local_points = rng.normal(0, 0.4, size=(n, 3))
    h = 1e-4

    def at(t):
        return _poses(chain, q0 + qd * t + 0.5 * qdd * t**2)

    Pm, P0, Pp = at(-h), at(0.0), at(h)
    states = sr.chain_kinematics(chain, q0, qd, qdd)
    wm = [s.w for s in sr.chain_kinematics(
        chain, q0 - qd * h + 0.5 * qdd * h**2, qd - qdd * h, qdd)]
    wp = [s.w for s in sr.chain_kinematics(
        chain, q0 + qd * h + 0.5 * qdd * h**2, qd + qdd * h, qdd)]
    for i, st in enumerate(states):
        np.testing.assert_allclose(st.pose, P0[i], atol=1e-14)
        np.testing.assert_allclose(st.pole, P0[i][:3, 3], atol=1e-14)
        v_fd = (Pp[i][:3, 3] - Pm[i][:3, 3]) / (2 * h)
        a_fd = (Pp[i][:3, 3] - 2 * P0[i][:3, 3] + Pm[i][:3, 3]) / h**2
        np.testing.assert_allclose(st.v_pole, v_fd, atol=1e-6)
        np.testing.assert_allclose(st.a_pole, a_fd, atol=1e-5)
        Rdot = (Pp[i][:3, :3] - Pm[i][:3, :3]) / (2 * h)
        W = Rdot @ P0[i][:3, :3].T
        np.testing.assert_allclose([W[2, 1], W[0, 2], W[1, 0]], st.w, atol=1e-6)
        np.testing.assert_allclose((wp[i] - wm[i]) / (2 * h), st.eps, atol=1e-6)
        # a point fixed in the link frame
        x = [T[:3, :3] @ local_points[i] + T[:3, 3] for T in (Pm[i], P0[i], Pp[i])]
        np.testing.assert_allclose(sr.point_velocity(st, x[1]), (x[2] - x[0]) / (2 * h), atol=1e-6)
        np.testing.assert_allclose(sr.point_acceleration(st, x[1]),
                                   (x[2] - 2 * x[1] + x[0]) / h**2, atol=1e-5)


def test_motor_is_the_velocity_of_the_body_point_at_the_origin():
    """motor[3:] = v_pole - w x pole is the FD velocity of the link point now at the origin."""
    rng = np.random.default_rng(11)
    chain = _random_chain(rng, "RPRR")
    q0, qd = rng.normal(size=4), rng.normal(size=4)
    h = 1e-6
    states = sr.chain_kinematics(chain, q0, qd, np.zeros(4))
    P0, Pp, Pm = _poses(chain, q0), _poses(chain, q0 + h * qd), _poses(chain, q0 - h * qd)
    for i, st in enumerate(states):
        local = np.linalg.solve(P0[i], [0, 0, 0, 1.0])  # link coordinates of the point at O
        v_fd = ((Pp[i] @ local)[:3] - (Pm[i] @ local)[:3]) / (2 * h)
        np.testing.assert_allclose(st.motor[3:], v_fd, atol=1e-8)
        np.testing.assert_allclose(st.motor[:3], st.w, atol=0)
        np.testing.assert_allclose(sr.point_velocity(st, np.zeros(3)), st.motor[3:], atol=1e-14)


def test_link_screw_axis_and_pitch():
    """Axis points move along the axis at speed pitch*|w|; the returned point is the foot from O."""
    rng = np.random.default_rng(12)
    chain = _random_chain(rng, "RRPR")
    states = sr.chain_kinematics(chain, rng.normal(size=4), rng.normal(size=4), np.zeros(4))
    for st in states:
        point, direction, pitch = sr.link_screw(st.motor)
        assert np.linalg.norm(direction) == pytest.approx(1.0, abs=1e-14)
        assert point @ direction == pytest.approx(0.0, abs=1e-12)
        for lam in (-1.0, 0.0, 2.0):
            v = sr.point_velocity(st, point + lam * direction)
            np.testing.assert_allclose(v, pitch * st.w, atol=1e-12)
        assert pitch == pytest.approx(st.w @ st.v_pole / (st.w @ st.w), rel=1e-12)


def test_link_screw_special_cases():
    """A pure rotation about a line has pitch 0, a translation pitch inf, rest gives None."""
    r, s = np.array([1.0, 2.0, 0.5]), np.array([0.0, 0.6, 0.8])
    point, direction, pitch = sr.link_screw(np.concatenate([2.0 * s, np.cross(r, 2.0 * s)]))
    assert pitch == pytest.approx(0.0, abs=1e-15)
    np.testing.assert_allclose(direction, s, atol=1e-15)
    np.testing.assert_allclose(np.cross(point - r, s), 0.0, atol=1e-15)  # on the line
    p_, d_, h_ = sr.link_screw([0, 0, 0, 0.0, 3.0, 4.0])
    assert h_ == float("inf")
    np.testing.assert_allclose(d_, [0, 0.6, 0.8])
    assert sr.link_screw(np.zeros(6)) is None


def test_first_revolute_link_screw_is_the_joint_axis():
    """With one revolute pair the link's screw is the joint axis line with pitch 0."""
    T = np.eye(4)
    T[:3, 3] = [0.2, -0.1, 0.3]
    chain = [sr.ChainJoint("R", T, np.array([0.0, 0.0, 1.0]))]
    st = sr.chain_kinematics(chain, [0.4], [2.0], [0.0])[0]
    point, direction, pitch = sr.link_screw(st.motor)
    np.testing.assert_allclose(direction, [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(point, [0.2, -0.1, 0.0], atol=1e-15)
    assert pitch == pytest.approx(0.0, abs=1e-15)


def test_prismatic_pair_adds_w_dot_vrel_over_w_squared_to_the_parameter():
    """Across a prismatic pair mu_(i+1) = mu_i + w.v_rel/|w|^2 (eq. (41) with |w|^2)."""
    rng = np.random.default_rng(41)
    chain = _random_chain(rng, "RRP")
    q, qd = rng.normal(size=3), rng.normal(size=3)
    st = sr.chain_kinematics(chain, q, qd, np.zeros(3))
    mu2 = sr.link_screw(st[1].motor)[2]
    mu3 = sr.link_screw(st[2].motor)[2]
    v_rel = qd[2] * st[2].axis
    w = st[1].w
    assert mu3 == pytest.approx(mu2 + w @ v_rel / (w @ w), rel=1e-12)
    assert abs(w @ v_rel / np.linalg.norm(w) - w @ v_rel / (w @ w)) > 1e-3  # |w| alone is wrong


def test_pole_matrix_is_seed002_16():
    """The matrix (16) of r times w is w x r, i.e. minus the usual cross-product matrix of r."""
    r, w = np.array([0.3, -0.2, 0.5]), np.array([1.0, 2.0, -1.5])
    B = sr.pole_matrix(r)
    np.testing.assert_allclose(B @ w, np.cross(w, r), atol=1e-15)
    np.testing.assert_allclose(B, -B.T)
    np.testing.assert_allclose(sr.collineation(np.block([[np.eye(3), r[:, None]],
                                                         [np.zeros((1, 3)), np.ones((1, 1))]])),
                               np.eye(4))


def test_constant_rate_end_point_velocity_like_the_paper_example():
    """For an R R P S(3R) chain at constant rates the end-point velocity matches FD."""
    rng = np.random.default_rng(7)
    chain = _random_chain(rng, "RRPRRR")
    q0, qd = rng.normal(size=6), rng.normal(size=6)
    e_local = np.array([0.1, 0.2, 0.3, 1.0])
    h = 1e-6
    st = sr.chain_kinematics(chain, q0, qd, np.zeros(6))[-1]
    e_now = (_poses(chain, q0)[-1] @ e_local)[:3]
    v_fd = ((_poses(chain, q0 + h * qd)[-1] @ e_local)[:3]
            - (_poses(chain, q0 - h * qd)[-1] @ e_local)[:3]) / (2 * h)
    np.testing.assert_allclose(sr.point_velocity(st, e_now), v_fd, atol=1e-8)


def test_reduction_graph_is_dot_text():
    """The graph is DOT text: w/v/S nodes per link, v_rel per prismatic pair, mu edges."""
    rng = np.random.default_rng(2)
    chain = _random_chain(rng, "RRPR")
    states = sr.chain_kinematics(chain, np.zeros(4), np.ones(4), np.zeros(4))
    dot = sr.reduction_graph(chain, states)
    assert dot.startswith("digraph screw_reduction {")
    assert dot.rstrip().endswith("}")
    assert dot.count("{") == dot.count("}") == 1
    for i in range(1, 5):
        assert f"  w{i} [" in dot and f"  v{i} [" in dot and f"  S{i} [" in dot
    assert dot.count("vrel3 [") == 1 and "vrel1" not in dot
    assert dot.count("style=dashed") == 8
    assert "mu_1 = " in dot
    assert sr.reduction_graph([("R", np.eye(4), [0, 0, 1])]).count("->") == 5


def test_bad_joint_kind_is_rejected():
    """A joint kind other than 'R' or 'P' raises ValueError."""
    with pytest.raises(ValueError):
        sr.chain_kinematics([("H", np.eye(4), [0, 0, 1])], [0.0], [0.0], [0.0])
