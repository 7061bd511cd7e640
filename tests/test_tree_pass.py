"""The single-pose Pinocchio pass (twists.TreePass) and the fixed-type compiled calls
(compiling.SameTypes) of the per-pose path."""

from __future__ import annotations

import pickle

import numpy as np
import pinocchio as pin
import pytest
from helpers import shipped_mechanisms
from numba import njit

from pkm_pin import twists
from pkm_pin.builders import MECHANISMS
from pkm_pin.compiling import PLAIN_CALLS, SameTypes
from pkm_pin.kernels import pose_error

mechanism = shipped_mechanisms()


def _reference(mech, leg_q, pose: np.ndarray):
    """Each leg's own Pinocchio pass: the joint twists and the closure errors."""
    errors = []
    for leg, q, anchor in zip(mech.legs, leg_q, mech.anchors):
        data = leg.model.createData()
        pin.framesForwardKinematics(leg.model, data, q)
        tip = (leg.base * data.oMf[leg.tip_id]).homogeneous
        errors.append(pose_error(tip, pose @ anchor.homogeneous, leg.characteristic_length,
                                 np.empty(6)))
    return twists.joint_twists(mech, leg_q), np.array(errors)


@pytest.mark.parametrize("name", sorted(MECHANISMS))
def test_tree_pass_equals_each_legs_pass(name):
    """Twists and closure errors of the one-call pass equal the per-leg pass, closed
    (errors at round-off) and off by a displacement of the pose (errors of 1e-2)."""
    mech = mechanism(name)
    if twists.has_mimic(mech):
        assert mech.tree_pass is None  # mimic joints: each leg on its own
        return
    asm = mech.home_assembly
    rng = np.random.default_rng(3)
    # a configuration off home too: every joint moved
    moved = [leg.clip(q + 0.05 * rng.standard_normal(q.shape)) if leg.nq == leg.nv else q
             for leg, q in zip(mech.legs, asm.leg_q)]
    for leg_q in (asm.leg_q, moved):
        off = pin.SE3(pin.rpy.rpyToMatrix(0.01, -0.02, 0.03), np.array([2e-3, -1e-3, 3e-3]))
        for offset in (pin.SE3.Identity(), off):
            M = (asm.pose * offset).homogeneous
            J, errors, worst = mech.tree_pass.run(np.concatenate(leg_q), M)
            J_ref, errors_ref = _reference(mech, leg_q, M)
            np.testing.assert_allclose(J, J_ref, rtol=0, atol=1e-12)
            np.testing.assert_allclose(errors, errors_ref, rtol=1e-9, atol=1e-14)
            assert worst == errors.max()


def test_tree_pass_reports_nan():
    """A configuration with a nan gives a nan error (the worst), not a small one."""
    mech = mechanism("stewart")
    Q = np.concatenate(mech.home_assembly.leg_q)
    Q[3] = np.nan
    _, errors, worst = mech.tree_pass.run(Q, mech.home.homogeneous)
    assert np.isnan(worst) and np.isnan(errors).any()


def test_mechanism_pickles_without_its_tree_pass():
    """The pass holds per-thread data: a pickled mechanism drops it and makes it again."""
    mech = MECHANISMS["stewart"]().build()
    asm = mech.assemble(mech.home)
    assert "tree_pass" in mech.__dict__
    copy = pickle.loads(pickle.dumps(mech))
    assert "tree_pass" not in copy.__dict__
    again = copy.assemble(mech.home)
    np.testing.assert_allclose(again.joint_twists, asm.joint_twists, atol=1e-14)
    # and the pass itself pickles (its data is made again on first use)
    tp = pickle.loads(pickle.dumps(mech.tree_pass))
    J, _, _ = tp.run(np.concatenate(asm.leg_q), asm.pose.homogeneous)
    np.testing.assert_allclose(J, asm.joint_twists, atol=1e-14)


@njit(cache=False)
def _weighted_sum(weights, x, out):
    s = 0.0
    for i in range(x.shape[0]):
        s += weights[i] * x[i]
    out[0] = s
    return s


def test_same_types_calls_the_machine_code_and_checks_the_key():
    """After a first call through the dispatcher, calls with the same key object give the
    dispatcher's results; another key object goes through the dispatcher again."""
    call = SameTypes(_weighted_sum, key=0)
    w1, w2 = np.arange(4.0), np.ones(4)
    x, out = np.linspace(0, 1, 4), np.empty(1)
    assert call(w1, x, out) == pytest.approx(w1 @ x)
    assert call._known[0] is w1
    for k in range(3):  # the machine code, on new values of the other arguments
        y = x + k
        assert call(w1, y, out) == pytest.approx(w1 @ y) and out[0] == pytest.approx(w1 @ y)
    assert call(w2, x, out) == pytest.approx(x.sum())  # a new key: typed again
    assert call._known[0] is w2


def test_same_types_runs_plain_python_before_compiling():
    """With ``plain``, a function not compiled yet runs as plain Python (no compilation)
    for a one-off call."""

    @njit(cache=False)
    def fresh(weights, x, out):
        return _weighted_sum(weights, x, out) + 1.0

    call = SameTypes(fresh, key=0, plain=True)
    w, x, out = np.arange(3.0), np.ones(3), np.empty(1)
    assert call(w, x, out) == pytest.approx(4.0)
    assert not fresh.overloads  # nothing compiled


def test_tree_outputs_source_equals_compiled():
    """The closure check's source, run as plain Python on a fresh installation, gives the
    compiled numbers (twists and errors to the last bit)."""
    mech = mechanism("stewart")
    tp, asm = mech.tree_pass, mech.home_assembly
    q = np.concatenate([*asm.leg_q, tp.rest_q])
    Jt = pin.computeJointJacobians(tp.tree, tp.tree.createData(), q)
    pose = (asm.pose * pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.01, 0.0), np.zeros(3))).homogeneous
    f = tp.frames
    out = []
    for fn in (twists.tree_outputs, twists.tree_outputs.py_func):
        J, errors = np.empty((tp.nv, 6)), np.empty(len(mech.legs))
        worst = fn(tp.probes, Jt, f.anchors, f.lengths, pose, J, errors)
        out.append((J, errors, worst))
    np.testing.assert_array_equal(out[0][0], out[1][0])
    np.testing.assert_array_equal(out[0][1], out[1][1])
    assert out[0][2] == out[1][2] > 1e-3


def test_per_pose_calls_skip_numba_typing():
    """After an assembly and an analysis, the per-pose compiled calls (closure solver,
    closure check, engine) hold the machine code of their signature for this
    mechanism's arrays: later poses are not typed again; so does a sweep's engine call
    for its layout (once per block), with the numbers of numba's own dispatch."""
    from pkm_pin.engine import core
    from pkm_pin.engine.core import _analyse_into, _analyse_many
    from pkm_pin.solve import _solve_system
    from pkm_pin.twists import _tree_outputs

    mech = mechanism("stewart")
    # the first calls of a process may run plain Python (compiling.PLAIN_CALLS)
    for _ in range(PLAIN_CALLS + 2):
        asm = mech.assemble(mech.home, mech.home_assembly)
        mech.analyze(asm)
    assert _solve_system._known[0] is mech.kernel.chains
    assert _tree_outputs._known[0] is mech.tree_pass.probes
    assert _analyse_into._known[0] is mech.engine_layout
    assert all(f._known[1] is not None for f in (_solve_system, _tree_outputs, _analyse_into))
    X = np.array([[0.0, 0.0, 0.0, 0.0, 0.0, 0.0], [0.01, 0.0, 0.0, 0.0, 0.02, 0.0]])
    X[:, :3] += mech.home.translation
    first = mech.sweep(X)
    assert _analyse_many._known[0] is mech.sweep_layout and _analyse_many._known[1] is not None
    again = mech.sweep(X)
    np.testing.assert_array_equal(first.condition, again.condition)
    poses = [pin.SE3(pin.rpy.rpyToMatrix(*x[3:]), x[:3]) for x in X]
    Js = np.stack([twists.joint_twists(mech, mech.assemble(pose).leg_q) for pose in poses])
    layout, p = mech.sweep_layout, np.ascontiguousarray(X[:, :3])
    a, b = core.allocate(2, layout, False), core.allocate(2, layout, False)
    core.analyse_into(Js, p, layout, a, False)
    _analyse_many(Js, p, layout, b, False)
    np.testing.assert_array_equal(a.scalars, b.scalars)
    np.testing.assert_array_equal(a.counts, b.counts)
