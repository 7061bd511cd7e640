"""Cross-check of the serial kinematics: Pinocchio path = hand-written reduction = finite
differences.

The Pinocchio path is :class:`pkm_pin.Leg` (:mod:`pkm_pin.serial`); the witness is the
recursive screw reduction of seed 002 written out in numpy
(:mod:`pkm_pin.formulas.serial_reduction`), fed with a chain description read off the
Pinocchio model by the adapter :func:`leg_chain` below (joint placements, joint axes
from the joint motion subspaces, the leg's base folded into the first offset). Robots:
UR5 and Panda (example-robot-data) and the seed 002 §6 manipulator (R R P + spherical
pair, ``models/urdf/manipulator_seed002.urdf``), at seeded random states.

Seed 002: anon., Polish, 1987, see docs/references.md.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from helpers import fd_point, random_states, serial_model_path

from pkm_pin import Leg, screws
from pkm_pin.formulas import serial_reduction as red

SEED = 7
N_STATES = 6
#: Relative tolerances (of 1 + the magnitude compared).
TOL_EXACT = 1e-11      # Pinocchio vs the reduction: both exact, round-off only
TOL_FD_V = 1e-7        # central first difference, h = 1e-6
TOL_FD_A = 1e-6        # central second difference, h = 1e-4


# -------------------------------------------------------------------------- adapter
def leg_chain(leg: Leg) -> list[red.ChainJoint]:
    """The leg's Pinocchio chain as the reduction's joint list.

    One :class:`~pkm_pin.formulas.serial_reduction.ChainJoint` per joint of the model
    (all 1-DOF, each the child of the previous): offset = the joint placement in its
    parent joint's frame (the leg's base placement pre-multiplied on the first), kind and
    unit axis from the joint's motion subspace (a revolute has a non-zero angular part, a
    prismatic a zero one), name = the link the joint carries.
    """
    m = leg.model
    chain = []
    q0 = pin.neutral(m)
    for j in range(1, m.njoints):
        jm = m.joints[j]
        if m.parents[j] != j - 1 or jm.nq != 1 or jm.nv != 1:
            raise ValueError(f"joint {m.names[j]!r}: the adapter takes plain 1-DOF chains")
        jd = jm.createData()
        jm.calc(jd, q0)
        s = screws.from_pinocchio(np.asarray(jd.S).reshape(6, -1))[:, 0]
        revolute = np.linalg.norm(s[:3]) > 0
        offset = m.jointPlacements[j].homogeneous
        if j == 1:
            offset = leg.base.homogeneous @ offset
        chain.append(red.ChainJoint("R" if revolute else "P", offset,
                                    s[:3] if revolute else s[3:], name=_link_of_joint(m, j)))
    return chain


def _link_of_joint(model: pin.Model, j: int) -> str:
    return next(f.name for f in model.frames
                if f.type == pin.FrameType.BODY and f.parentJoint == j)


def _body_frames(leg: Leg):
    return [(f.name, f) for f in leg.model.frames if f.type == pin.FrameType.BODY]


def _world_point(states, frame: pin.Frame, p_link: np.ndarray) -> np.ndarray:
    """World position, from the reduction's link pose, of a point given in a link frame."""
    p_joint = frame.placement.act(p_link)
    T = states[frame.parentJoint - 1].pose
    return T[:3, :3] @ p_joint + T[:3, 3]


# ------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module", params=["ur5", "panda", "manipulator_seed002", "ur5_on_base"])
def leg(request, tmp_path_factory) -> Leg:
    if request.param == "manipulator_seed002":
        return Leg.from_urdf(serial_model_path("manipulator_seed002", tmp_path_factory), "tip")
    if request.param == "ur5_on_base":
        base = pin.SE3(pin.rpy.rpyToMatrix(-0.2, 0.6, 2.0), np.array([1.0, 0.5, -0.3]))
        return Leg.from_example_robot_data("ur5", base=base)
    return Leg.from_example_robot_data(request.param)


def _states(leg: Leg, n: int = N_STATES):
    """Seeded random (q, qd, qdd): rates in [-1.5, 1.5], accelerations in [-2, 2]."""
    return random_states(leg, n, SEED, qd_max=1.5, qdd_max=2.0)


def _close(a, b, rtol) -> bool:
    return bool(np.linalg.norm(np.asarray(a) - b) <= rtol * (1.0 + np.linalg.norm(b)))


# --------------------------------------------------------------------------- tests
def test_adapter_reproduces_link_placements(leg):
    """The reduction's link poses T_0i equal the Pinocchio world placements of the
    joints (1e-12), so the adapter describes the same chain."""
    chain = leg_chain(leg)
    for q, qd, qdd in _states(leg, 3):
        states = red.chain_kinematics(chain, q, qd, qdd)
        pin.forwardKinematics(leg.model, leg.data, q)
        for j, st in enumerate(states, start=1):
            np.testing.assert_allclose(st.pose, (leg.base * leg.data.oMi[j]).homogeneous,
                                       atol=1e-12)


def test_link_twists_pinocchio_equal_reduction_motors(leg):
    """Every link twist (ω; v_O) of the Pinocchio path equals the reduction's motor moved
    to the world origin (relative 1e-11)."""
    chain = leg_chain(leg)
    for q, qd, qdd in _states(leg):
        states = red.chain_kinematics(chain, q, qd, qdd)
        twists = leg.link_twists(q, qd)
        for name, f in _body_frames(leg):
            expected = np.zeros(6) if f.parentJoint == 0 else states[f.parentJoint - 1].motor
            assert _close(twists[name], expected, TOL_EXACT), name


def test_point_velocities_pinocchio_reduction_finite_differences(leg):
    """Velocity of a random point of every moving link: Pinocchio = reduction (1e-11) =
    central difference of its position along q(t) (1e-7)."""
    chain = leg_chain(leg)
    rng = np.random.default_rng(SEED + 1)
    h = 1e-6
    for q, qd, qdd in _states(leg):
        states = red.chain_kinematics(chain, q, qd, qdd)
        for name, f in _body_frames(leg):
            if f.parentJoint == 0:
                continue
            p = rng.uniform(-0.4, 0.4, 3)
            v_pin = leg.point_velocity(name, p, q, qd)
            P = _world_point(states, f, p)
            np.testing.assert_allclose(P, leg.point_position(name, p, q), atol=1e-12)
            v_red = red.point_velocity(states[f.parentJoint - 1], P)
            v_fd, _ = fd_point(leg, name, p, q, qd, qdd, h)
            assert _close(v_pin, v_red, TOL_EXACT), name
            assert _close(v_pin, v_fd, TOL_FD_V), name


def test_point_accelerations_pinocchio_reduction_finite_differences(leg):
    """Classical acceleration of a random point of every moving link: Pinocchio =
    reduction (1e-11) = central second difference of its position along q(t) (1e-6)."""
    chain = leg_chain(leg)
    rng = np.random.default_rng(SEED + 2)
    h = 1e-4
    for q, qd, qdd in _states(leg):
        states = red.chain_kinematics(chain, q, qd, qdd)
        for name, f in _body_frames(leg):
            if f.parentJoint == 0:
                continue
            p = rng.uniform(-0.4, 0.4, 3)
            a_pin = leg.point_acceleration(name, p, q, qd, qdd)
            a_red = red.point_acceleration(states[f.parentJoint - 1], _world_point(states, f, p))
            _, a_fd = fd_point(leg, name, p, q, qd, qdd, h)
            assert _close(a_pin, a_red, TOL_EXACT), name
            assert _close(a_pin, a_fd, TOL_FD_A), name


def test_link_screws_pinocchio_equal_reduction(leg):
    """Axis point, direction and pitch of every moving link: Pinocchio's link_screws =
    the reduction's link_screw of its motor = screws.axis/pitch (1e-10)."""
    chain = leg_chain(leg)
    L = leg.characteristic_length
    for q, qd, qdd in _states(leg):
        states = red.chain_kinematics(chain, q, qd, qdd)
        ours = leg.link_screws(q, qd)
        for name, f in _body_frames(leg):
            if f.parentJoint == 0:
                assert ours[name].at_rest
                continue
            motor = states[f.parentJoint - 1].motor
            point, direction, pitch = red.link_screw(motor)
            s = ours[name]
            assert s.pitch == pytest.approx(pitch, rel=1e-10, abs=1e-12)
            assert s.pitch == pytest.approx(screws.pitch(motor, length=L), rel=1e-10, abs=1e-12)
            np.testing.assert_allclose(s.point, point, atol=1e-10)
            np.testing.assert_allclose(s.direction, direction, atol=1e-12)
            np.testing.assert_allclose(screws.axis(motor, length=L)[1], direction, atol=1e-12)


def test_tip_jacobian_columns_equal_reduction_unit_rates(leg):
    """Column k of serial_jacobian is the tip motor of the reduction with unit rate on
    joint k alone (1e-11)."""
    chain = leg_chain(leg)
    tip_joint = leg.model.frames[leg.tip_id].parentJoint
    for q, _, _ in _states(leg, 2):
        J = leg.serial_jacobian(q)
        for k in range(leg.nv):
            e = np.zeros(leg.nv)
            e[k] = 1.0
            motor = red.chain_kinematics(chain, q, e, np.zeros(leg.nv))[tip_joint - 1].motor
            assert _close(J[:, k], motor, TOL_EXACT)


def test_seed002_constant_rates_end_point(tmp_path_factory):
    """Seed 002 §6: constant joint rates (qdd = 0); the end point E's velocity and
    acceleration agree between Pinocchio and the reduction (1e-11) at 20 states."""
    leg = Leg.from_urdf(serial_model_path("manipulator_seed002", tmp_path_factory), "tip")
    chain = leg_chain(leg)
    assert [j.kind for j in chain] == ["R", "R", "P", "R", "R", "R"]
    rng = np.random.default_rng(SEED)
    for _ in range(20):
        q, qd = leg.random_configuration(rng), rng.uniform(-1.0, 1.0, 6)
        states = red.chain_kinematics(chain, q, qd, np.zeros(6))
        E = states[-1]
        P = _world_point(states, leg.model.frames[leg.tip_id], np.zeros(3))
        assert _close(leg.point_velocity("tip", np.zeros(3), q, qd),
                      red.point_velocity(E, P), TOL_EXACT)
        assert _close(leg.point_acceleration("tip", np.zeros(3), q, qd, np.zeros(6)),
                      red.point_acceleration(E, P), TOL_EXACT)


def test_reduction_graph_mentions_every_link(leg):
    """The DOT text of the reduction graph names every moving link of the chain and has
    one screw node S_i per link, with numbers when states are given."""
    chain = leg_chain(leg)
    q, qd, qdd = next(_states(leg, 1))
    dot = red.reduction_graph(chain, red.chain_kinematics(chain, q, qd, qdd))
    assert dot.startswith("digraph") and dot.rstrip().endswith("}")
    for i, joint in enumerate(chain, start=1):
        assert joint.name in dot
        assert f"S{i} [" in dot
    assert dot.count("style=dashed, label=\"mu_") == leg.nv
