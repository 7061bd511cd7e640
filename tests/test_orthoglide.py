"""Orthoglide of seed 001: the hand-written closed forms and the Pinocchio path agree.

Seed 001: Pashkevich & Gomolitsky 2007, see docs/references.md.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pinocchio as pin
import pytest
from helpers import MECHANISM_DIR, URDF_DIR

from pkm_pin import load_mechanism, screws
from pkm_pin.builders.orthoglide import QUASI, orthoglide, orthoglide_quasi
from pkm_pin.formulas import orthoglide as og
from pkm_pin.formulas.orthoglide import OrthoglideParameters

E = 0.1  # tool offset of the shipped designs


def _random_parameters(rng) -> dict:
    """Random quasi-orthogonal geometry (builder keyword arguments)."""
    return {"L": tuple(1.0 + rng.uniform(-0.05, 0.05, 3)),
            "phi": tuple(rng.uniform(-0.05, 0.05, 3)),
            "dd": tuple(rng.uniform(-0.03, 0.03, 3)), "e": float(rng.uniform(0.0, 0.15))}


def _formula_parameters(geometry: dict) -> OrthoglideParameters:
    return OrthoglideParameters(L=geometry["L"], phi=geometry["phi"], dd=geometry["dd"],
                                e=geometry["e"])


@pytest.fixture(scope="module")
def random_machines():
    """Three random quasi-orthogonal Orthoglides: (mechanism, formula parameters)."""
    rng = np.random.default_rng(2024)
    out = []
    for _ in range(3):
        g = _random_parameters(rng)
        out.append((orthoglide(**g).build(), _formula_parameters(g)))
    return out


@pytest.fixture(scope="module")
def quasi():
    return orthoglide_quasi().build(), OrthoglideParameters(**QUASI, e=E)


def _points(rng, n: int) -> np.ndarray:
    return rng.uniform(-0.2, 0.2, (n, 3))


# ================================================================ closed forms only
def test_inverse_kinematics_has_8_solutions_satisfying_2():
    """All 8 sign combinations of (3) satisfy (2) and carry their corrected index (4)."""
    params = OrthoglideParameters(**QUASI, e=E)
    rng = np.random.default_rng(1)
    for p in _points(rng, 5):
        sols = og.inverse_kinematics_all(p, params)
        assert len(sols) == 8
        for signs, rho in sols.items():
            assert np.max(np.abs(og.residuals(p, rho, params))) < 1e-12
            assert og.configuration_signs(p, rho, params) == signs


def test_printed_index_4_is_right_only_for_the_orthogonal_machine():
    """sign(rho_i - p_i) of (4) equals the configuration index for phi = dd = 0, not in general."""
    nominal = OrthoglideParameters()
    p = np.array([0.1, -0.05, 0.2])
    for signs, rho in og.inverse_kinematics_all(p, nominal).items():
        assert og.configuration_signs_printed(p, rho) == signs
    # tilted x axis, p on the z axis just beyond reach of the untilted leg: s_x = -1 gives
    # 0 = p_x < rho_x < c.u, so the printed sign(rho_x - p_x) says +1
    tilted = OrthoglideParameters(L=(1.0, 1.1, 1.1), phi=(0.3, 0.0, 0.0), dd=(0.0, 0.0, 0.0))
    p = np.array([0.0, 0.0, 1.02])
    rho = og.inverse_kinematics(p, tilted, (-1, 1, 1))
    assert np.max(np.abs(og.residuals(p, rho, tilted))) < 1e-12
    assert og.configuration_signs(p, rho, tilted)[0] == -1
    assert og.configuration_signs_printed(p, rho)[0] == 1


def test_forward_kinematics_both_solutions_and_branch_index():
    """Both roots of the quadratic satisfy (2), and m = sign(det A) at each one."""
    params = OrthoglideParameters(**QUASI, e=E)
    rng = np.random.default_rng(2)
    for p in _points(rng, 5):
        rho = og.inverse_kinematics(p, params)
        both = og.forward_kinematics_both(rho, params)
        assert np.linalg.norm(both[1] - both[-1]) > 0.1
        for m, q in both.items():
            assert np.max(np.abs(og.residuals(q, rho, params))) < 1e-11
            assert og.branch_index(q, rho, params) == m
        assert np.allclose(both[og.branch_index(p, rho, params)], p, atol=1e-12)


def test_printed_p0_of_14_is_not_the_particular_solution():
    """(13)'s p0 solves the two plane equations (10); the printed (14) does not."""
    params = OrthoglideParameters(**QUASI)
    rho = np.array([1.1, 0.95, 1.05])
    g = og.carriage_points(rho, params)
    n1, n2 = -2 * (g[0] - g[1]), -2 * (g[1] - g[2])
    L2, gg = np.array(params.L) ** 2, np.einsum("ij,ij->i", g, g)
    xi = np.array([(L2[0] - L2[1]) - (gg[0] - gg[1]), (L2[1] - L2[2]) - (gg[1] - gg[2])])
    _, p0 = og.forward_line(rho, params)
    assert np.allclose([n1 @ p0, n2 @ p0], xi, rtol=0, atol=1e-12)
    printed = og.p0_printed_14(rho, params)
    assert np.max(np.abs([n1 @ printed, n2 @ printed] - xi)) > 1e-3


def test_differential_relations_16_by_finite_differences():
    """A dp = B dq for rho, L, phi, dd: the derived B's match central differences of the FK."""
    params = OrthoglideParameters(**QUASI, e=E)
    rng = np.random.default_rng(3)
    h = 1e-6
    for p in _points(rng, 3):
        rho = og.inverse_kinematics(p, params)
        m = og.branch_index(p, rho, params)
        S = og.sensitivities(p, rho, params)
        for i in range(3):
            d = np.zeros(3)
            d[i] = h
            fd = (og.forward_kinematics(rho + d, params, m)
                  - og.forward_kinematics(rho - d, params, m)) / (2 * h)
            assert np.max(np.abs(fd - S["rho"][:, i])) < 1e-7
            for key, field in (("L", "L"), ("phi", "phi"), ("dd", "dd")):
                plus, minus = list(getattr(params, field)), list(getattr(params, field))
                plus[i] += h
                minus[i] -= h
                hi = dataclasses.replace(params, **{field: tuple(plus)})
                lo = dataclasses.replace(params, **{field: tuple(minus)})
                fd = og.forward_kinematics(rho, hi, m) - og.forward_kinematics(rho, lo, m)
                fd /= 2 * h
                assert np.max(np.abs(fd - S[key][:, i])) < 1e-7, (key, i)


def test_printed_b_rho_and_b_phi_carry_slips():
    """Printed B_rho misses cos(phi_i) (equal for phi = 0); printed B_phi has the wrong sign."""
    params = OrthoglideParameters(**QUASI)  # e = 0: the paper's model
    p = np.array([0.05, -0.1, 0.08])
    rho = og.inverse_kinematics(p, params)
    derived, printed = og.b_rho(p, rho, params), og.b_rho_printed(p, rho, params)
    own = p[[0, 1, 2]]  # the missing factor: printed - derived = p_i (1 - cos phi_i)
    assert np.allclose(np.diag(printed - derived), own * (1 - np.cos(QUASI["phi"])), atol=1e-15)
    assert np.max(np.abs(printed - derived)) > 1e-6
    assert np.allclose(og.b_phi_printed(p, rho, params), -og.b_phi(p, rho, params), atol=1e-15)
    nominal = OrthoglideParameters(L=QUASI["L"])
    rho = og.inverse_kinematics(p, nominal)
    assert np.allclose(og.b_rho_printed(p, rho, nominal), og.b_rho(p, rho, nominal), atol=1e-15)


# ======================================================================= the machine
@pytest.mark.parametrize("build", [orthoglide, orthoglide_quasi], ids=["nominal", "quasi"])
def test_mobility_is_3t_with_3_redundant_constraints(build):
    """At home: 3 DOF, 3T, Grübler 0, 3 redundant constraints, not singular."""
    an = build().build().analyze()
    assert (an.dof, an.motion_type, an.grubler, an.redundant_constraints) == (3, "3T", 0, 3)
    assert an.singularity == "none"
    for leg_wrenches in an.leg_constraint_wrenches:  # each leg: two couples
        assert leg_wrenches.shape[0] == 2
        assert np.allclose(leg_wrenches[:, :3], 0.0, atol=1e-12)


def test_nominal_home_is_isotropic():
    """The nominal machine at p = 0: rho_i = L + e, A = identity up to row scaling."""
    mech = orthoglide().build()
    assert np.allclose(mech.home_assembly.q_actuated, 1.0 + E, atol=1e-12)
    assert math.isclose(mech.analyze().indices["condition_A"], 1.0, rel_tol=1e-9)


def test_pinocchio_inverse_kinematics_equals_3(random_machines):
    """The legs' IK at random points equals (3) with s = (+1, +1, +1), to 1e-10."""
    rng = np.random.default_rng(4)
    for mech, params in random_machines:
        for p in _points(rng, 4):
            qa = mech.inverse_kinematics(pin.SE3(np.eye(3), p)).q_actuated
            assert np.max(np.abs(qa - og.inverse_kinematics(p, params))) < 1e-10


def test_pinocchio_inverse_kinematics_all_finds_the_8_solutions():
    """With wide limits the Pinocchio path finds exactly the 8 solutions of (3)."""
    mech = orthoglide(**QUASI, stroke=(-3.0, 3.0), angle_limit=math.pi).build()
    params = OrthoglideParameters(**QUASI, e=E)
    p = np.array([0.05, -0.03, 0.02])
    ours = np.array([a.q_actuated for a in mech.inverse_kinematics_all(pin.SE3(np.eye(3), p))])
    assert ours.shape == (8, 3)
    for rho in og.inverse_kinematics_all(p, params).values():
        assert np.min(np.max(np.abs(ours - rho), axis=1)) < 1e-9


def test_pinocchio_forward_kinematics_equals_closed_form(random_machines):
    """Continuation FK at random actuated coordinates equals the closed-form branch m = -1."""
    rng = np.random.default_rng(5)
    for mech, params in random_machines:
        for p in _points(rng, 3):
            rho = og.inverse_kinematics(p, params)
            a = mech.forward_kinematics(rho)
            closed = og.forward_kinematics(rho, params, -1)
            assert np.max(np.abs(a.pose.translation - closed)) < 1e-10
            assert np.allclose(a.pose.rotation, np.eye(3), atol=1e-10)


def test_second_forward_solution_assembles_with_the_same_actuated_coordinates(quasi):
    """The branch m = +1 of the closed form assembles in Pinocchio at the same rho, det A flips."""
    mech, params = quasi
    rho = og.inverse_kinematics(np.array([0.05, -0.03, 0.02]), params)
    p2 = og.forward_kinematics(rho, params, +1)
    a2 = mech.assemble(pin.SE3(np.eye(3), p2))
    assert np.max(np.abs(a2.q_actuated - rho)) < 1e-10
    assert og.branch_index(p2, rho, params) == 1
    # continuation started on that branch stays on it
    step = np.array([0.01, -0.02, 0.015])
    b = mech.forward_kinematics(rho + step, a2)
    closed = og.forward_kinematics(rho + step, params, +1)
    assert np.max(np.abs(b.pose.translation - closed)) < 1e-10


def test_velocity_map_a_and_b_rho_agree_up_to_row_scaling(random_machines):
    """Pinocchio's A (translational part) and B are the derived A and B_rho divided by L_i."""
    rng = np.random.default_rng(6)
    for mech, params in random_machines:
        for p in _points(rng, 3):
            a = mech.assemble(pin.SE3(np.eye(3), p))
            rho = a.q_actuated
            an = mech.analyze(a)
            A, B = og.jacobian_a(p, rho, params), og.b_rho(p, rho, params)
            # actuation wrenches are forces (f; p_C x f) along the bars: A Δ (0; v) = f . v
            for i in range(3):
                k = np.linalg.norm(A[i]) / np.linalg.norm(an.A[i, :3])
                sign = np.sign(an.A[i, :3] @ A[i])
                assert np.allclose(sign * k * an.A[i, :3], A[i], atol=1e-10)
                assert math.isclose(sign * k * an.B[i, i], B[i, i], rel_tol=1e-10)
            rho_dot = rng.normal(size=3)
            t = an.forward_velocity(rho_dot)
            assert np.allclose(t[:3], 0.0, atol=1e-12)
            assert np.allclose(t[3:], og.forward_velocity(p, rho, rho_dot, params), atol=1e-10)


def test_generic_sensitivity_equals_b_l_b_phi_b_d(random_machines):
    """Sensitivity columns of Pa2/origin.x, P/axis.ry, P/origin.z are A⁻¹B_L, −A⁻¹B_φ, A⁻¹B_d."""
    from pkm_pin.sensitivity import sensitivity

    rng = np.random.default_rng(7)
    for mech, params in random_machines:
        p = _points(rng, 1)[0]
        a = mech.assemble(pin.SE3(np.eye(3), p))
        S = og.sensitivities(p, a.q_actuated, params)
        sens = sensitivity(mech, a, ["*/Pa2/origin.x", "*/P/axis.ry", "*/P/origin.z"])
        assert sens.incompatible == []
        for i, leg in enumerate(("legx", "legy", "legz")):
            for name, key, sign in (("Pa2/origin.x", "L", 1), ("P/axis.ry", "phi", -1),
                                    ("P/origin.z", "dd", 1)):
                col = sens.column(f"{leg}/{name}")
                assert np.allclose(col[:3], 0.0, atol=1e-12)
                assert np.allclose(col[3:], sign * S[key][:, i], atol=1e-10), (leg, name)


def test_shipped_models_load_and_match_the_builders():
    """The shipped orthoglide*.toml load and assemble at home with the builders' joint values."""
    for build in (orthoglide, orthoglide_quasi):
        d = build()
        mech = load_mechanism(MECHANISM_DIR / f"{d.slug}.toml")
        for q, q_design in zip(mech.home_assembly.leg_q, d.home_q):
            assert np.allclose(q, q_design, atol=1e-9)
        for leg in d.legs:
            assert (URDF_DIR / leg.urdf_file).read_text() == leg.urdf


def test_scale_1000_gives_the_same_angles_and_lengths_times_1000():
    """In millimetres the joint angles are unchanged and rho is multiplied by 1000."""
    d, mm = orthoglide_quasi(), orthoglide_quasi(scale=1000.0)
    for q, q_mm in zip(d.home_q, mm.home_q):
        assert math.isclose(q_mm[0], 1000 * q[0], rel_tol=1e-12)
        assert np.allclose(q_mm[1:], q[1:], atol=1e-12)
    an = mm.build().analyze()
    assert (an.dof, an.motion_type, an.redundant_constraints) == (3, "3T", 3)
    assert screws.rank(an.constraint_wrenches, an.length) == 3
