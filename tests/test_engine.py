"""The analysis engine (pkm_pin.engine): its stages, its linear algebra, and its results
against the independent numpy oracle (``tests/oracle_batch.py``: the same definitions
written with stacked ``numpy.linalg.svd``), for one pose and along sweeps.

Single-pose analyses and sweeps run the same engine: they agree pose by pose.
"""

from __future__ import annotations

import numpy as np
import oracle_batch
import pinocchio as pin
import pytest
from test_analysis import mechanism  # built mechanisms, cached per (name, scale)

from pkm_pin import engine, screws
from pkm_pin.analysis import SINGULAR_TOL, layout_of
from pkm_pin.builders.planar import rpr3_type2_pose
from pkm_pin.builders.spatial import upu3_constraint_singular_pose
from pkm_pin.engine.linalg import (
    JACOBI_SKIP,
    JACOBI_TOL,
    certainly_invertible,
    descending,
    jacobi,
    lu,
    lu_column,
)
from pkm_pin.engine.stages import (
    SQUARE,
    actuation_wrench,
    leg_constraints,
    motion_twists,
    platform_system,
)
from pkm_pin.screws import RTOL, homogenise
from pkm_pin.sweep import _evaluate_chunk_pinocchio, evaluate_chunk, pose_array
from pkm_pin.twists import joint_twists, sweep_pass

ALL = ["rpr3", "rrr3", "stewart", "delta", "upu3", "orthoglide", "orthoglide_quasi"]


def path(mech, n=40, size=0.25):
    """Poses along a line of the platform twist system through home (both ways)."""
    an = mech.home_analysis
    L = mech.characteristic_length
    c = np.array([1.0, 0.5, -0.3, 0.2, 0.1, 0.4])[: an.dof] @ an.platform_twists
    c /= max(np.linalg.norm(c[:3]), np.linalg.norm(c[3:]) / L)
    return pose_array([screws.exp(s * size * c) * mech.home for s in np.linspace(-1, 1, n)])


def centres(assemblies) -> np.ndarray:
    """The platform centres of the assemblies (the engine homogenises about them)."""
    return np.array([a.pose.translation for a in assemblies])


def oracle(mech, assemblies, rtol=RTOL):
    """The numpy oracle on the legs' Jacobians and motion twists (Leg.screws), written
    about each assembly's platform centre as the engine does; its A rows are moved back
    about the world origin (the engine's A)."""
    Js, Ts = [], []
    moves = [pin.SE3(np.eye(3), -a.pose.translation) for a in assemblies]
    for k, leg in enumerate(mech.legs):
        pairs = [leg.screws(a.leg_q[k]) for a in assemblies]
        Js.append(np.stack([screws.adjoint(M) @ J for (J, _), M in zip(pairs, moves)]))
        Ts.append(np.stack([screws.transform(T, M) for (_, T), M in zip(pairs, moves)]))
    b = oracle_batch.analyse(Js, Ts, [leg.actuated_v for leg in mech.legs],
                             mech.characteristic_length, rtol)
    b.A[:] = [screws.transform(A, M.inverse()) for A, M in zip(b.A, moves)]
    return b


def same_span(A, B, atol=1e-9):
    """Rows of A and B (homogenised, orthonormal or not) span the same space."""
    if A.shape[0] != B.shape[0]:
        return False
    if not A.shape[0]:
        return True
    Qa, _ = np.linalg.qr(A.T)
    Qb, _ = np.linalg.qr(B.T)
    return np.allclose(Qa @ Qa.T, Qb @ Qb.T, atol=atol)


def assert_equals_oracle(mech, assemblies, r):
    """Engine results ``r`` (full) equal the oracle's, pose by pose."""
    b = oracle(mech, assemblies)
    L = mech.characteristic_length
    np.testing.assert_array_equal(r.dof, b.dof)
    np.testing.assert_array_equal(r.translations, b.translations)
    np.testing.assert_array_equal(r.redundant, b.redundant)
    for key in ("type_I", "type_II"):
        np.testing.assert_allclose(getattr(r, key), getattr(b, key), rtol=1e-8, atol=1e-11,
                                   err_msg=key)
    np.testing.assert_allclose(1 / r.condition, 1 / b.condition, rtol=1e-8, atol=1e-14)
    np.testing.assert_allclose(r.A, b.A, atol=1e-9 * max(1.0, L))
    np.testing.assert_allclose(r.B, b.B, atol=1e-9 * max(1.0, L))
    for i in range(len(assemblies)):
        d = r.dof[i]
        assert same_span(r.platform[i, :d], b.platform[i][np.any(b.platform[i] != 0, 1)])
        assert same_span(r.constraints[i, :6 - d],
                         b.constraints[i][np.any(b.constraints[i] != 0, 1)])
        for k in range(len(mech.legs)):
            W = b.leg_constraints[k][i]
            assert same_span(r.leg_constraints[i, k, :r.leg_dims[i, k]], W[np.any(W != 0, 1)])


# ------------------------------------------------------------------- whole engine
@pytest.mark.parametrize("name", ALL)
def test_engine_equals_the_numpy_oracle_along_a_path(name):
    """DOF, motion type, redundancy, indices, A, B and every basis equal the oracle's."""
    mech = mechanism(name)
    X = path(mech, n=12)
    assemblies = [mech.assemble(x) for x in X]
    J = np.stack([joint_twists(mech, a.leg_q) for a in assemblies])
    r = engine.analyse(J, layout_of(mech), centres=centres(assemblies))
    assert_equals_oracle(mech, assemblies, r)


@pytest.mark.parametrize("name", ["rpr3", "stewart", "delta", "upu3"])
def test_single_pose_analysis_and_sweep_give_the_same_numbers(name):
    """Analysis (one pose, cold start) and sweep (warm starts) run the same engine."""
    mech = mechanism(name)
    X = path(mech, n=10)
    res = mech.sweep(X)
    for i, x in enumerate(X):
        an = mech.analyze(mech.assemble(x))
        assert res.dof[i] == an.dof
        assert res.singularity[i] == an.singularity
        for key in ("type_I", "type_II"):
            assert getattr(res, key)[i] == pytest.approx(an.indices[key], rel=1e-9, abs=1e-13)


def test_compiled_and_pinocchio_chunks_agree():
    """The compiled-leg chunk and the Leg.solve chunk give the same assemblies and the
    same engine results (the sweep's two ways of assembling)."""
    for name in ("rpr3", "stewart", "orthoglide_quasi"):
        mech = mechanism(name)
        X = path(mech, n=20)
        home = mech.home_analysis
        ref = homogenise(home._about_centre(home.platform_twists), mech.characteristic_length)
        fast = evaluate_chunk(mech, X, ref, RTOL, SINGULAR_TOL)
        slow = _evaluate_chunk_pinocchio(mech, X, layout_of(mech, RTOL, ref), None, 4)
        np.testing.assert_array_equal(fast["ok"], slow["ok"])
        ok = fast["ok"]
        assert ok.sum() >= 15
        np.testing.assert_array_equal(fast["dof"][ok], slow["dof"][ok])
        for key in ("type_I", "type_II", "det"):
            np.testing.assert_allclose(fast[key][ok], slow[key][ok], rtol=1e-8, atol=1e-11)
        np.testing.assert_allclose(fast["q_actuated"][ok], slow["q_actuated"][ok], atol=1e-9)


def test_millimetres_give_the_same_sweep(monkeypatch):
    """The Stewart platform in millimetres: same DOF, indices, det (unit-invariant), and
    the compiled legs converge as in metres (no pose falls back to Mechanism.assemble)."""
    import pkm_pin.sweep as sweep_module

    m, mm = mechanism("stewart"), mechanism("stewart", 1000.0)
    X = path(m, n=12)
    Xmm = X.copy()
    Xmm[:, :3] *= 1000.0
    redone = []
    monkeypatch.setattr(sweep_module, "_assemble_again", lambda *a, **k: redone.append(a))
    a, b = m.sweep(X), mm.sweep(Xmm)
    assert not redone
    np.testing.assert_array_equal(a.dof, b.dof)
    np.testing.assert_array_equal(a.singularity, b.singularity)
    for key in ("type_I", "type_II", "condition", "det"):
        np.testing.assert_allclose(getattr(a, key), getattr(b, key), rtol=1e-7, err_msg=key)


def test_near_constraint_singular_poses():
    """3-UPU lowered towards its constraint-singular pose (constraint singular values from
    0 to 3e-2 of the largest): every rank decision equals the oracle's (SVD), the sweep
    equals the per-pose Analysis, the exactly singular pose has 4 DOF."""
    mech = mechanism("upu3")
    L = mech.characteristic_length
    base = upu3_constraint_singular_pose()
    heights = np.array([0.0, 1e-12, 1e-9, 1e-7, 1e-5, 1e-3, 3e-2]) * L
    X = pose_array([pin.SE3(base.rotation, base.translation + [0, 0, h]) for h in heights])
    assemblies = [mech.assemble(x) for x in X]
    J = np.stack([joint_twists(mech, a.leg_q) for a in assemblies])
    r = engine.analyse(J, layout_of(mech), centres=centres(assemblies))
    b = oracle(mech, assemblies)
    np.testing.assert_array_equal(r.dof, b.dof)
    np.testing.assert_array_equal(r.redundant, b.redundant)
    res = mech.sweep(X)
    for i, x in enumerate(X):
        an = mech.analyze(mech.assemble(x))
        assert res.dof[i] == an.dof == r.dof[i]
        assert res.singularity[i] == an.singularity
        assert res.type_II[i] == pytest.approx(an.indices["type_II"], rel=1e-8, abs=1e-12)
    assert res.dof[0] == 4 and res.dof[-1] == 3


def test_type_II_pose_of_the_rpr3_in_a_sweep():
    """At the 3-RPR type II pose the type II index vanishes (to round-off) and the
    carried det changes sign across it."""
    mech = mechanism("rpr3")
    P2 = rpr3_type2_pose()
    X = pose_array([pin.SE3(P2.rotation, P2.translation + [dx, 0, 0])
                    for dx in (-0.02, -0.01, 0.0, 0.01, 0.02)])
    res = mech.sweep(X)
    assert res.ok.all()
    assert res.type_II[2] < 1e-9
    assert res.singularity[2] in ("II", "III")
    assert res.det[0] * res.det[-1] < 0
    assemblies = [mech.assemble(x) for x in X]
    b = oracle(mech, assemblies)
    np.testing.assert_allclose(res.type_II, b.type_II, rtol=1e-7, atol=1e-11)


def test_closures_pinocchio_does_not_confirm_are_solved_again(monkeypatch):
    """With the kernel allowed to stop after a step from a large residual (TRUST = 1e-2),
    Pinocchio's closure check rejects those poses and Mechanism.assemble solves them
    again: the sweep still equals the per-pose path."""
    import pkm_pin.sweep as sweep_module

    mech = mechanism("stewart")
    X = path(mech, n=8, size=0.6)  # big steps: large predictor residuals
    monkeypatch.setattr(sweep_module, "TRUST", 1e-2)
    redone = []
    original = sweep_module._assemble_again

    def spy(*args, **kwargs):
        redone.append(args[5])
        return original(*args, **kwargs)

    monkeypatch.setattr(sweep_module, "_assemble_again", spy)
    ref = homogenise(mech.home_analysis.platform_twists, mech.characteristic_length)
    fast = evaluate_chunk(mech, X, ref, RTOL, SINGULAR_TOL)
    assert len(redone) >= 1  # the safety net was used
    assert fast["ok"].all()
    for i, x in enumerate(X):
        an = mech.analyze(mech.assemble(x))
        assert fast["type_II"][i] == pytest.approx(an.indices["type_II"], rel=1e-8)


@pytest.mark.parametrize("name", ["rpr3", "stewart", "delta", "orthoglide_quasi"])
def test_pinocchio_pass_gives_the_legs_twists_and_closure(name):
    """The sweep's Pinocchio pass returns each leg's axis-first world Jacobian (the
    twists ``Leg.jacobian`` gives, base placement included) as rows, and closure errors
    at round-off; a leg configuration moved off its solution is reported. Written into
    a caller's array (a sweep's blocks reuse one), the rows are the same, in its first
    rows."""
    from pkm_pin.sweep import pose_matrices

    mech = mechanism(name)
    X = path(mech, n=6)
    poses = pose_matrices(X)
    sols = [mech.assemble(pin.SE3(p)).leg_q for p in poses]
    Qs = [np.array([s[k] for s in sols]) for k in range(len(mech.legs))]
    targets = np.stack([poses @ a.homogeneous for a in mech.anchors])
    Qs[0][2] += 1e-3  # pose 2: leg 0 no longer closes
    J, bad = sweep_pass(mech, Qs, targets, np.arange(len(X)), 1e-12)
    np.testing.assert_array_equal(bad, np.arange(len(X)) == 2)
    coords = layout_of(mech).coords
    for k, leg in enumerate(mech.legs):
        for i in range(len(X)):
            np.testing.assert_allclose(J[i, coords[k]:coords[k + 1]], leg.jacobian(Qs[k][i]).T,
                                       rtol=0, atol=1e-14)
            np.testing.assert_allclose(joint_twists(mech, [Q[i] for Q in Qs]), J[i],
                                       rtol=0, atol=1e-14)
    some = np.array([1, 2, 5])  # a subset of the poses: their rows, in order
    Js, bads = sweep_pass(mech, Qs, targets, some, 1e-12)
    np.testing.assert_array_equal(Js, J[some])
    np.testing.assert_array_equal(bads, bad[some])
    out = np.full((len(X) + 2, *J.shape[1:]), np.nan)
    Jo, bado = sweep_pass(mech, Qs, targets, some, 1e-12, out)
    assert np.shares_memory(Jo, out) and len(Jo) == len(some)
    np.testing.assert_array_equal(out[:len(some)], J[some])
    np.testing.assert_array_equal(bado, bad[some])
    assert np.isnan(out[len(some):]).all()
    with pytest.raises(ValueError, match="out of shape"):
        sweep_pass(mech, Qs, targets, some, 1e-12, out[:2])


def test_scratch_buffer_is_reused_unless_still_read(monkeypatch):
    """The sweep's Pinocchio pass copies its arrays into a per-thread scratch buffer
    that the next block reuses (a fresh one per block could be new pages from the
    system each time); it grows for a larger block, and one still read when its block
    ends (an exception) is not reused; another thread has its own."""
    import threading

    from pkm_pin import twists
    from pkm_pin.twists import _scratch

    monkeypatch.setattr(twists, "_SCRATCH", threading.local())  # no buffer yet
    with _scratch(64) as a:
        a.write(b"x" * 64)
    with _scratch(32) as b:
        assert b is a and b.tell() == 0
    with _scratch(128) as c:
        assert c is not a
    try:
        with _scratch(16) as d:
            view = np.frombuffer(d.getbuffer(), dtype=np.uint8)
            raise KeyError("a failure while the buffer is read")
    except KeyError:
        pass
    assert d is c and view.size >= 128
    with _scratch(16) as e:
        assert e is not d
        e.write(b"y" * 16)  # usable
    del view
    other = []
    thread = threading.Thread(target=lambda: other.append(_scratch(16).__enter__()))
    thread.start()
    thread.join()
    with _scratch(16) as f:
        assert f is e and other[0] is not f


# ------------------------------------------------------------------------- stages
def _random_twists(rng, k, rank, L=1.0):
    """k unit homogenised twists (rows) of the given rank."""
    T = rng.normal(size=(k, rank)) @ rng.normal(size=(rank, 6))
    return T / np.linalg.norm(T, axis=1, keepdims=True)


def test_leg_stage_gives_the_reciprocal_system_and_its_rank():
    """leg_constraints: rank of the twists and an orthonormal basis of their reciprocal
    (every constraint row c has T Δ c = 0), for 1 to 7 twists of every rank; a leg of
    six independent twists is certified without SVD and gives the LU factors of
    X = T Δ."""
    rng = np.random.default_rng(0)
    for k in range(1, 8):
        for rank in range(1, min(k, 6) + 1):
            T = _random_twists(rng, k, rank)
            X, W, V, sv = np.empty((8, 6)), np.empty((48, 6)), np.eye(6), np.empty(6)
            C, LU, perm = np.empty((6, 6)), np.empty((6, 6)), np.empty(6, np.int64)
            r, m, mode = leg_constraints(T, 0, k, RTOL, X, W, V, sv, C, 0, LU, perm)
            assert r == rank and m == 6 - rank
            assert (mode == SQUARE) == (k == 6 and rank == 6)
            if mode == SQUARE:
                L, U = np.tril(LU, -1) + np.eye(6), np.triu(LU, 1) + np.diag(1 / np.diag(LU))
                np.testing.assert_allclose(L @ U, (T @ screws.DELTA)[perm], atol=1e-14)
            np.testing.assert_allclose(T @ screws.DELTA @ C[:m].T, 0.0, atol=1e-12)
            np.testing.assert_allclose(C[:m] @ C[:m].T, np.eye(m), atol=1e-12)


def test_actuation_stage_is_reciprocal_to_the_other_joints_and_does_work():
    """actuation_wrench: reciprocal to the leg's other twists, orthogonal to its
    constraints, work on the actuated twist; for independent twists (SVD or square
    path) and for a leg whose *other* twists are dependent; B = 0 when the actuated
    twist depends on the others."""
    rng = np.random.default_rng(1)
    cases = [(_random_twists(rng, 3, 3), True), (_random_twists(rng, 5, 5), True),
             (_random_twists(rng, 6, 6), True)]
    T = _random_twists(rng, 4, 4)
    cases.append((np.vstack([T[:2], T[1:2], T[2:]]), True))  # joints 1 and 2 equal
    dep = _random_twists(rng, 3, 3)
    cases.append((np.vstack([dep, dep[0] + dep[1]]), False))  # joint 3 depends on 0, 1
    for T, independent in cases:
        k = len(T)
        T = T / np.linalg.norm(T, axis=1, keepdims=True)
        ka = k - 1
        X, W, V, sv = np.empty((8, 6)), np.empty((48, 6)), np.eye(6), np.empty(6)
        C, LU, perm = np.empty((6, 6)), np.empty((6, 6)), np.empty(6, np.int64)
        r, m, mode = leg_constraints(T, 0, k, RTOL, X, W, V, sv, C, 0, LU, perm)
        w = np.empty(6)
        ok = actuation_wrench(T, 0, k, ka, r, mode, LU, perm, RTOL, X, W, V, sv, C, 0, m,
                              np.empty((8, 6)), np.eye(6), np.empty(6), w)
        assert ok == independent
        products = T @ screws.DELTA @ w
        if independent:
            others = [c for c in range(k) if not np.allclose(T[c], T[ka])]
            np.testing.assert_allclose(products[others], 0.0, atol=1e-10 * np.abs(w).max())
            assert abs(products[ka]) > 1e-3 * np.linalg.norm(w)
            np.testing.assert_allclose(C[:m] @ w, 0.0, atol=1e-10 * np.linalg.norm(w))
        else:
            np.testing.assert_allclose(products, 0.0, atol=1e-10)


def test_platform_stage_spans_the_reciprocal_of_the_union():
    """platform_system: rank of the union, orthonormal bases of it and of its reciprocal
    (Δ-reciprocal), and the rotations among the platform twists."""
    rng = np.random.default_rng(2)
    for m_c, rank in ((0, 0), (3, 3), (9, 3), (6, 5), (12, 6)):
        C = (rng.normal(size=(m_c, rank)) @ rng.normal(size=(rank, 6))) if rank else \
            np.zeros((m_c, 6))
        C = np.ascontiguousarray(C)
        W, V, sv, order = np.empty((max(m_c, 1), 6)), np.eye(6), np.empty(6), \
            np.empty(6, np.int64)
        cons, P, Pw = np.empty((6, 6)), np.zeros((6, 6)), np.empty((6, 3))
        rc, rot = platform_system(C.copy(), m_c, RTOL, 1e-7, W, V, sv, order, cons, P, Pw,
                                  np.empty((6, 3)), np.eye(3), np.empty(3))
        d = 6 - rc
        assert rc == rank
        np.testing.assert_allclose(P[:d] @ P[:d].T, np.eye(d), atol=1e-12)
        if m_c:
            np.testing.assert_allclose(C @ screws.DELTA @ P[:d].T, 0.0, atol=1e-10)
        assert rot == np.linalg.matrix_rank(P[:d, :3], tol=1e-7) if d else rot == 0


def test_spherical_groups_become_three_lines_through_their_centre():
    """motion_twists: three concurrent revolutes at gimbal lock (two parallel axes) are
    replaced by the three lines through their centre; rows homogenised with unit norm."""
    c = np.array([0.3, -0.2, 0.5])
    z, x = np.array([0, 0, 1.0]), np.array([1.0, 0, 0])
    J = np.array([np.r_[z, np.cross(c, z)], np.r_[x, np.cross(c, x)], np.r_[z, np.cross(c, z)],
                  np.r_[0, 0, 0, 1.0, 0, 0]])
    T = np.empty((4, 6))
    L = 2.0
    motion_twists(J, np.array([[0, 1, 2]], np.int64), L, np.zeros(3), T, np.empty((3, 3)),
                  np.empty(3), np.empty(3))
    for t in range(3):
        e = np.eye(3)[t]
        expected = np.r_[e, np.cross(c, e) / L]
        np.testing.assert_allclose(T[t], expected / np.linalg.norm(expected), atol=1e-14)
    np.testing.assert_allclose(T[3], [0, 0, 0, 1, 0, 0], atol=1e-15)


# ----------------------------------------------------------------- linear algebra
def test_jacobi_singular_values_and_right_basis():
    """One-sided Jacobi (cold or warm started) matches numpy: singular values to
    round-off relative to the largest, X = W Vᵀ, V orthogonal; rank-deficient matrices
    converge in few sweeps (round-off columns are not chased)."""
    rng = np.random.default_rng(2)
    for m, n in ((6, 6), (6, 3), (3, 3), (5, 2), (3, 6), (12, 6), (1, 6)):
        A = rng.normal(size=(m, n))
        W, V, sv = np.empty((m, n)), np.eye(n), np.empty(n)
        jacobi(A, m, n, W, V, sv)
        order = np.empty(n, np.int64)
        descending(sv, n, order)
        ref = np.linalg.svd(A, compute_uv=False)
        np.testing.assert_allclose(sv[order][:len(ref)], ref, rtol=0, atol=1e-13 * ref[0])
        np.testing.assert_allclose(W @ V.T, A, atol=1e-13)
        np.testing.assert_allclose(V.T @ V, np.eye(n), atol=1e-13)
    A = rng.normal(size=(6, 6))  # warm start from a previous basis
    W, V, sv = np.empty((6, 6)), np.eye(6), np.empty(6)
    jacobi(A, 6, 6, W, V, sv)
    B = A + 1e-3 * rng.normal(size=(6, 6))
    jacobi(B, 6, 6, W, V, sv)
    np.testing.assert_allclose(np.sort(sv)[::-1], np.linalg.svd(B, compute_uv=False),
                               rtol=1e-13)
    U, _ = np.linalg.qr(rng.normal(size=(6, 6)))  # clustered and tiny singular values
    Vr, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    chosen = np.array([1.0, 1.0 + 2e-9, 1.0 + 1e-9, 0.5 + 1e-12, 0.5, 1e-6])
    W, V, sv = np.empty((6, 6)), np.eye(6), np.empty(6)
    jacobi(U @ np.diag(chosen) @ Vr.T, 6, 6, W, V, sv)
    np.testing.assert_allclose(np.sort(sv)[::-1], np.sort(chosen)[::-1], rtol=0, atol=1e-14)
    # a warm start a small rotation away from the singular basis: every rotation is in
    # the small-angle regime (tan θ and cos θ from their series), to round-off; with
    # skip = JACOBI_TOL (singular values only) the same values
    spread = np.array([3.0, 2.0, 1.5, 1.0, 0.3, 1e-4])
    A = U @ np.diag(spread) @ Vr.T
    for angle in (1e-7, 1e-9):
        S = angle * rng.normal(size=(6, 6))
        start = Vr @ (np.eye(6) + S - S.T)
        start, _ = np.linalg.qr(start)
        start *= np.sign(np.diag(start.T @ Vr))  # the columns of Vr, a little turned
        for skip in (JACOBI_SKIP, JACOBI_TOL):
            V = start.copy()
            jacobi(A, 6, 6, W, V, sv, skip)
            np.testing.assert_allclose(np.sort(sv)[::-1], spread, rtol=0, atol=1e-15 * spread[0])
            np.testing.assert_allclose(V.T @ V, np.eye(6), atol=1e-14)
            np.testing.assert_allclose(W @ V.T, A, atol=1e-14)
            if skip == JACOBI_SKIP:  # the columns orthogonal to round-off (cosines, or
                # inner products at the floor relative to ‖A‖_F², for the tiny column)
                off = np.abs(W.T @ W - np.diag(sv ** 2))
                bound = np.maximum(2e-15 * np.outer(sv, sv), 1e-15 * (A ** 2).sum())
                assert (off <= bound).all()


def test_lu_certificate_and_determinant():
    """LU factors, determinant and columns of the inverse against numpy; a singular
    matrix has determinant 0 and no certificate; a 6×6 is certified of full rank at
    σ_min/σ_max = 1e-3 and left to the SVD at 1e-8 and 1e-12 (the bound |det| / ‖X‖_F⁶
    times the margin)."""
    rng = np.random.default_rng(3)
    LU, perm, x = np.empty((6, 6)), np.empty(6, np.int64), np.empty(6)
    for n in (1, 3, 6):
        X = rng.normal(size=(6, 6))
        assert lu(X, n, LU, perm) == pytest.approx(np.linalg.det(X[:n, :n]), rel=1e-12)
        inv = np.linalg.inv(X[:n, :n])
        for col in range(n):
            lu_column(LU, perm, n, col, x)
            np.testing.assert_allclose(x[:n], inv[:, col], rtol=1e-12, atol=1e-12)
    S = rng.normal(size=(6, 6))
    S[4] = 0.0
    assert lu(S, 6, LU, perm) == 0.0
    assert not certainly_invertible(S, 6, LU, perm, RTOL)
    assert lu(np.zeros((3, 3)), 3, LU, perm) == 0.0
    U, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    V, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    for small, certified in ((1e-3, True), (1e-8, False), (1e-12, False)):
        X = U @ np.diag([1.0, 0.9, 0.8, 0.5, 0.3, small]) @ V.T
        assert bool(certainly_invertible(X, 6, LU, perm, RTOL)) is certified
        if certified:
            for col in range(6):
                lu_column(LU, perm, 6, col, x)
                np.testing.assert_allclose(X @ x, np.eye(6)[col], atol=1e-10)


# ------------------------------------------------------------- compiled or not
@pytest.mark.parametrize("name", ["rpr3", "stewart", "delta"])
def test_plain_python_engine_gives_the_compiled_numbers_bit_for_bit(name):
    """A first single pose runs the engine's source as plain Python (no compilation
    wait): every array equals the compiled engine's exactly."""
    from pkm_pin.engine import core

    mech = mechanism(name)
    X = path(mech, n=3)
    J = np.stack([joint_twists(mech, mech.assemble(x).leg_q) for x in X])
    layout = layout_of(mech)
    for i in range(len(X)):
        a, b = core.allocate(1, layout), core.allocate(1, layout)
        p = np.array([X[i, :3]])
        core.analyse_into.py_func(J[i:i + 1], p, layout, a, True)
        core.analyse_into(J[i:i + 1], p, layout, b, True)
        for field, x, y in zip(core.Results._fields, a, b):
            np.testing.assert_array_equal(x, y, err_msg=field)


def test_a_long_compilation_says_what_it_is_doing(monkeypatch):
    """The compile notice names the function of pkm_pin being compiled and that it
    happens once, then the time it took; other packages' compilations are not
    reported."""
    import io

    from numba import njit
    from numba.core import event

    from pkm_pin import compiling

    monkeypatch.setattr(compiling, "NOTICE_AFTER", 0.0)
    stream = io.StringIO()
    listener = compiling._Notice(stream)
    event.register("numba:compile", listener)
    try:
        def ours(x):
            return x + 1.0

        def theirs(x):
            return x + 2.0

        ours.__module__ = "pkm_pin.example"
        theirs.__module__ = "someone_else"
        f, g = njit(ours), njit(theirs)
        g(1.0)
        f(1.0)
    finally:
        event.unregister("numba:compile", listener)
    text = stream.getvalue()
    assert "compiling example" in text and "ours" in text and "once" in text
    assert "compiled in" in text
    assert "theirs" not in text
