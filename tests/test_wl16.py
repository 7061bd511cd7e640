"""Gepetto's ``wl16_like`` (issue 24 item 5, issue 25 item 4): a 6-SPS leg whose twelve
spherical joints are each written as three revolutes, five 6d closures, six actuated
prismatic joints; and the sparse idle-motion basis of linkages.

Numbers asserted: 42 joints, 30 closure rows, Grübler 12; at a generic configuration
DOF 12 (rank J_c 30) and idle DOF 6 (the six legs' spins; rank with the actuated rows
36). The tree solver alone (from ``q = 0``) stops with ``hip_part_motor_part_5_rev1``
at exactly π/2 — ``rev0`` and ``rev2`` of that spherical joint on one line, a gimbal
lock — where idle DOF is 9; :meth:`Linkage.assemble` steps off it. Each of the six
sparse idle motions moves at most 4 joints (the orthonormal basis: 14 each) and spans
the same space (projectors equal to 1e-9).
"""

from __future__ import annotations

import json
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from linkage_models import four_bar, four_bar_q

import pkm_pin
from pkm_pin.cli import main
from pkm_pin.linkage import Linkage, describe_motion
from pkm_pin.model.closure_model import NullSpace, sparse_basis
from pkm_pin.screws import svd_rank
from pkm_pin.solve import solve_tree
from pkm_pin.tolerances import RANK_RTOL

ROOT = Path(__file__).resolve().parents[1]
WL16 = ROOT / "tests" / "data" / "gepetto" / "wl16_like" / "robot.urdf"
LOCKED = "hip_part_motor_part_5_rev1"


@pytest.fixture(scope="module")
def wl16():
    link = pkm_pin.load_mechanism(WL16)
    return link, link.assemble()


def _coordinate(link: Linkage, name: str) -> tuple[int, int]:
    joint = link.model.tree.joints[link.model.tree.getJointId(name)]
    return joint.idx_q, joint.idx_v


def _raw_idle(link: Linkage, q) -> tuple[np.ndarray, np.ndarray]:
    """The sparse idle basis and the orthonormal one it was made from (dimensionless)."""
    ns = NullSpace(link.model, link.model.kinematics(q), RANK_RTOL)
    rank_x, _, _, Vt = svd_rank(ns.X, RANK_RTOL)
    return ns.idle(RANK_RTOL), ns.N @ Vt[rank_x:].T


def _joints_moved(link: Linkage, v: np.ndarray) -> list[str]:
    tree = link.model.tree
    return [tree.names[j] for j in range(1, tree.njoints)
            if np.abs(v[tree.joints[j].idx_v:tree.joints[j].idx_v + tree.joints[j].nv]).max()
            > 1e-9 * np.abs(v).max()]


def _same_span(B: np.ndarray, K: np.ndarray) -> None:
    np.testing.assert_allclose(B @ np.linalg.pinv(B), K @ K.T, atol=1e-9)


# ------------------------------------------------------------------- wl16_like
def test_wl16_loads_with_42_joints_and_5_welds(wl16):
    """The unchanged published files load (no geometry read): 42 one-DOF joints, five
    6d closures, six actuated prismatic joints, Grübler 42 − 30 = 12."""
    link, _ = wl16
    model = link.model
    assert model.tree.njoints - 1 == 42 and model.nv == 42 and model.n_rows == 30
    assert [c.kind for c in model.closures] == ["weld"] * 5
    assert sorted(link.actuated) == [f"motor_{k}" for k in range(1, 7)]
    assert link.grubler == 12


def test_wl16_assembles_off_the_gimbal_lock_with_dof_12_and_idle_6(wl16):
    """The assembly has DOF 12 and idle DOF 6, equal to the generic values of nearby
    configurations (not singular), no representation singularity, the former gimbal
    joint off π/2 and every loop closed."""
    link, a = wl16
    mob = link.mobility(a)
    assert (mob.dof, mob.idle_dof, mob.rank) == (12, 6, 30)
    assert (mob.generic_dof, mob.generic_idle_dof, mob.singular) == (12, 6, False)
    assert mob.representation == () and mob.singular_words == ""
    iq, _ = _coordinate(link, LOCKED)
    assert abs(np.cos(a.q[iq])) > 1e-3
    assert a.residual < 1e-10
    an = link.analyze(a)
    assert (an.dof, an.idle_dof) == (12, 6) and not an.mobility.singular


def test_the_plain_tree_solve_stops_at_the_gimbal_lock(wl16):
    """What assembly used to keep: the tree solver from q = 0 stops with rev1 at π/2
    (to 1e-12), reported singular against the generic DOF 12 / idle DOF 6."""
    link, _ = wl16
    model = link.model
    sol = solve_tree(model, model.reference)
    assert sol.converged
    iq, _ = _coordinate(link, LOCKED)
    assert sol.q[iq] == pytest.approx(np.pi / 2, abs=1e-12)
    mob = link.mobility(sol.q)
    assert mob.singular is True and (mob.generic_dof, mob.generic_idle_dof) == (12, 6)
    assert any(LOCKED in r for r in mob.representation)


def test_a_configuration_put_at_the_gimbal_lock_is_reported_singular(wl16):
    """rev1 held at π/2 and the loops closed again: the counter-rotation of rev0 and rev2
    moves nothing (closed form: J_c (e_rev0 − e_rev2) = 0 to 1e-12), and the mobility
    is singular with the generic ranks stated (closure Jacobian 30, 36 with the
    actuated rows: DOF 12, idle DOF 6 nearby)."""
    link, a = wl16
    model = link.model
    iq, iv = _coordinate(link, LOCKED)
    q0 = a.q.copy()
    q0[iq] = np.pi / 2
    free = np.ones(model.nv, bool)
    free[iv] = False
    sol = solve_tree(model, q0, free=free)
    assert sol.converged and sol.q[iq] == np.pi / 2
    e = np.zeros(model.nv)
    e[_coordinate(link, "hip_part_motor_part_5_rev0")[1]] = 1.0
    e[_coordinate(link, "hip_part_motor_part_5_rev2")[1]] = -1.0
    assert np.abs(model.closure_jacobian(sol.q) @ e).max() < 1e-12
    mob = link.mobility(sol.q)
    assert mob.singular is True
    assert (mob.generic_dof, mob.generic_idle_dof) == (12, 6)
    assert mob.representation == (
        f"{LOCKED} at a gimbal lock (the axes of hip_part_motor_part_5_rev0 and "
        "hip_part_motor_part_5_rev2 coincide)",)
    words = mob.singular_words
    assert words.startswith("singular configuration: ")
    assert "12 and 6 at nearby configurations" in words
    assert "closure Jacobian rank 30, generic 30" in words and "generic 36" in words


def test_forward_kinematics_keeps_the_actuated_values_off_the_lock(wl16):
    """Forward kinematics at the assembly's actuated values, warm-started at the gimbal
    lock, returns those values (to 1e-9) at a generic configuration: DOF 12, idle 6."""
    link, a = wl16
    sol = solve_tree(link.model, link.model.reference)
    fk = link.forward_kinematics(a.q_actuated, sol.q, starts=0)
    np.testing.assert_allclose(fk.q_actuated, a.q_actuated, atol=1e-9)
    mob = link.mobility(fk)
    assert (mob.dof, mob.idle_dof, mob.singular, mob.representation) == (12, 6, False, ())


# ----------------------------------------------- forward kinematics near home (issue 25)
#: Actuated values (motor_1, motor_2, motor_3, motor_5, motor_6, motor_4 [m]) of an
#: assembly away from the type II singularities the home sits next to (type II index
#: 0.025 where home's is 0.00126).
GENERIC = np.array([0.965, 0.963, 0.831, 0.43, 0.694, 0.996])


def _type_ii(link: Linkage, a) -> float:
    return link.analyze(a, nearby=0).indices["type_II"]


def _check_fk(link: Linkage, b, target: np.ndarray) -> None:
    """``b`` closes every loop, has the target actuated values (to 1e-9), and its
    output pose gives them back (inverse kinematics from ``b``, to 1e-7)."""
    norms = link.model.closure_norms(link.model.kinematics(b.q).residual)
    assert norms.max() < 1e-10 and b.residual < 1e-10
    np.testing.assert_allclose(b.q_actuated, target, atol=1e-9)
    back = link.inverse_kinematics(b.output_pose, guess=b)
    np.testing.assert_allclose(back.q_actuated, target, atol=1e-7)


@pytest.fixture(scope="module")
def wl16_generic(wl16):
    link, _ = wl16
    return link.assemble(q_actuated=GENERIC)


def test_fk_one_centimetre_on_each_motor_from_a_generic_assembly(wl16, wl16_generic):
    """From an assembly off the singularities (type II index 0.025), ±0.01 m on each
    of the six motors: forward kinematics closes the loops (1e-10), reproduces the
    motor values (1e-9) and the pose found gives them back."""
    link, _ = wl16
    a = wl16_generic
    assert _type_ii(link, a) > 0.02 and not link.mobility(a, nearby=0).singular
    for k in range(6):
        for step in (0.01, -0.01):
            target = a.q_actuated + step * np.eye(6)[k]
            _check_fk(link, link.forward_kinematics(target, a), target)


def test_home_sits_next_to_folds_and_fk_beyond_one_says_so(wl16):
    """The file's home (its legs nearly coplanar with the hip plane) is near a type II
    singularity (index 0.00126, condition of A 1471). +0.01 m on motor_2 lies beyond a
    fold of home's branch: the continuation closes the loops up to 0.35 % of the way
    (3.5e-5 m), where the index has fallen tenfold and its square extrapolates to zero
    at the fold (t 0.0035; an independent fine continuation, 5e-7 m steps, stops at
    0.0035 too); the error says so with those numbers. -0.01 m on motor_2 and on
    motor_4, and -0.001 m on all six, move away from it and succeed."""
    link, home = wl16
    qa = home.q_actuated
    index = link.analyze(home, nearby=0).indices
    assert index["type_II"] == pytest.approx(0.00126, rel=0.01)
    assert index["condition_A"] == pytest.approx(1471, rel=0.01)
    target = qa + 0.01 * np.eye(6)[1]
    with pytest.raises(pkm_pin.linkage.LoopClosureError) as info:
        link.forward_kinematics(target, home)
    path = info.value.continuation
    assert path.fold and 0.0034 < path.t <= path.t_fold < 0.0036
    assert path.type_ii[0] == pytest.approx(index["type_II"])
    assert path.type_ii[1] < 0.15 * path.type_ii[0]
    np.testing.assert_allclose(path.q_actuated, qa + path.t * (target - qa), atol=1e-9)
    assert str(info.value).startswith("the actuated values lie beyond a fold of the "
                                      "guess's assembly branch (a type II singularity")
    assert "hint:" not in str(info.value)
    q = home.q
    for t in np.linspace(0.0, 0.0034, 69)[1:]:  # the branch exists up to there
        sol = solve_tree(link.model, q, targets=qa + t * (target - qa))
        assert sol.converged
        q = sol.q
    for k, step in ((1, -0.01), (5, -0.01)):
        target = qa + step * np.eye(6)[k]
        _check_fk(link, link.forward_kinematics(target, home), target)
    _check_fk(link, link.forward_kinematics(qa - 0.001, home), qa - 0.001)


def test_fk_continuation_does_not_jump_across_a_fold(wl16, wl16_generic):
    """From the generic assembly, -0.05 m on motor_5: the solve from the guess alone
    does not converge, and the guess's branch ends at a fold on the way (a sweep of 100
    steps closes up to some step, then none). The continuation of forward kinematics
    stops between those two steps, not past them on another branch (its corrections
    from the tangent prediction are bounded), and says it is a fold."""
    link, _ = wl16
    a = wl16_generic
    target = a.q_actuated - 0.05 * np.eye(6)[3]
    assert not solve_tree(link.model, a.q, targets=target).converged
    ts = np.linspace(0.0, 1.0, 101)[1:]
    swept = link.sweep(a.q_actuated + ts[:, None] * (target - a.q_actuated), a)
    last = int(np.flatnonzero(swept.converged).max())
    assert 0 < last < 99 and swept.converged[:last + 1].all()
    assert not swept.converged[last + 1:].any()
    path = link._continuation(a.q, target, 1e-12, 100)
    assert path.solution is None and ts[last] <= path.t < ts[last + 1]
    link._fold_words(path, target)
    assert path.fold and path.t <= path.t_fold < ts[last + 1]


def test_wl16_sparse_idle_basis(wl16):
    """The six idle motions each move at most 4 joints (a leg's spin: its hip rev2 and
    its foot-side joints; the orthonormal basis moves 14 joints per motion), span the
    orthonormal basis' space (projectors to 1e-9) and have six distinct sentences."""
    link, a = wl16
    B, K = _raw_idle(link, a.q)
    assert B.shape == K.shape == (42, 6)
    moved = [len(_joints_moved(link, B[:, k])) for k in range(6)]
    assert max(moved) <= 4
    assert min(len(_joints_moved(link, K[:, k])) for k in range(6)) > 4
    _same_span(B, K)
    words = link.mobility(a).idle_motions
    assert len(words) == len(set(words)) == 6
    assert sum("spin about the line through their joints at" in w for w in words) >= 5


def test_analyze_cli_on_wl16_reports_dof_12_idle_6_without_warnings(capsys):
    """``pkm-pin analyze`` of wl16_like: DOF 12, idle DOF 6, not singular, six distinct
    idle sentences, and no warning (numpy's divide-by-zero included) reaches the user;
    the analysis at the gimbal lock emits none either."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["analyze", str(WL16)]) == 0
        text = capsys.readouterr().out
        assert "DOF                12  (idle DOF 6;" in text
        assert "singular configuration" not in text
        assert main(["analyze", str(WL16), "--json"]) == 0
        link = pkm_pin.load_mechanism(WL16)
        sol = solve_tree(link.model, link.model.reference)
        an = link.analyze(sol.q)
    report = json.loads(capsys.readouterr().out)
    assert (report["dof"], report["idle_dof"], report["singular"]) == (12, 6, False)
    assert (report["generic_dof"], report["generic_idle_dof"]) == (12, 6)
    assert len(set(report["idle_motions"])) == 6
    assert an.mobility.singular and np.isfinite(an.A).all() and np.isfinite(an.B).all()


# ----------------------------------------------------------------- sparse basis
def test_sparse_basis_recovers_mixed_sparse_motions():
    """Four motions of 2, 2, 3 and 2 of 12 coordinates (two of them sharing coordinate
    4), mixed by a random rotation: the basis found gives back the two separate motions
    exactly, two motions of 2 and 3 coordinates among 3, 4, 6, 7 (the shared one may be
    traded: (3, 6, 7) is as sparse as (4, 6, 7)), and spans the same space (projectors
    to 1e-9)."""
    S = np.zeros((12, 4))
    S[[0, 1], 0] = [1.0, -2.0]
    S[[3, 4], 1] = [0.5, 1.0]
    S[[4, 6, 7], 2] = [1.0, 1.0, -1.0]
    S[[9, 11], 3] = [3.0, 1.0]
    R = np.linalg.qr(np.random.default_rng(7).normal(size=(4, 4)))[0]
    K = np.linalg.qr(S @ R)[0]
    B = sparse_basis(K)
    supports = sorted(tuple(np.flatnonzero(B[:, k])) for k in range(4))
    assert supports[0] == (0, 1) and supports[-1] == (9, 11)
    assert sorted(len(x) for x in supports[1:3]) == [2, 3]
    assert set(supports[1]) | set(supports[2]) == {3, 4, 6, 7}
    _same_span(B, K)
    np.testing.assert_allclose(np.linalg.norm(B, axis=0), 1.0, rtol=1e-12)


@pytest.mark.parametrize("path", [ROOT / "models" / "loops" / "delta_loops.urdf",
                                  ROOT / "models" / "pinned" / "delta_point.toml"],
                         ids=["delta_loops", "delta_point"])
def test_delta_has_no_idle_motion_to_sparsify(path):
    """The Deltas (parallelogram legs; rods joined by a spherical pin) have DOF 3 and no
    idle motion at their reference assembly, generic there: the basis is empty."""
    link = pkm_pin.load_mechanism(path)
    a = link.assemble()
    mob = link.mobility(a)
    assert (mob.dof, mob.idle_dof, mob.idle_motions, mob.singular) == (3, 0, (), False)
    B, K = _raw_idle(link, a.q)
    assert B.shape == K.shape == (link.model.nv, 0)


def test_ankle_rod_spins_each_move_few_joints():
    """The ankle's two S–S rods: two idle motions, one rod's spin each (its own
    spherical joints only), distinct sentences, same span as the orthonormal basis."""
    link = pkm_pin.load_mechanism(ROOT / "models" / "loops" / "ankle.urdf")
    a = link.assemble()
    B, K = _raw_idle(link, a.q)
    _same_span(B, K)
    moved = [_joints_moved(link, B[:, k]) for k in range(2)]
    assert all(len(m) <= 2 for m in moved) and not set(moved[0]) & set(moved[1])
    kin = link.model.kinematics(a.q)
    words = [describe_motion(link.model, kin, link.model.velocity_units * B[:, k])
             for k in range(2)]
    assert sorted(w.split()[0] for w in words) == ["rod_1", "rod_2"]
    assert all(" spins about the line through its joints at " in w for w in words)


def test_representation_singularity_at_a_joint_limit():
    """A four-bar whose rocker sits exactly at its lower limit: the representation list
    names the joint and its limit, and the mobility stays generic (DOF 1 here and at
    nearby configurations, which step into the range)."""
    model = four_bar()
    q = four_bar_q(0.7)
    tree = model.tree.copy()
    i = tree.joints[tree.getJointId("rocker")].idx_q
    tree.lowerPositionLimit[i], tree.upperPositionLimit[i] = q[i], q[i] + 1.0
    link = Linkage(replace(model, tree=tree))
    mob = link.mobility(q)
    assert mob.representation == (f"rocker at its lower limit {q[i]:.6g}",)
    assert (mob.dof, mob.generic_dof, mob.singular) == (1, 1, False)
