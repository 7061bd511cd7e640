"""Batched sweeps over many poses, serial and on executors (threads, Dask)."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pinocchio as pin
import pytest
from helpers import shipped_mechanisms

from pkm_pin import InputError, screws
from pkm_pin.builders.planar import rpr3_type2_pose
from pkm_pin.sweep import pose_array, pose_matrices, serpentine_order, smooth_steps, visiting_order

#: Built mechanism, cached for the module.
mechanism = shipped_mechanisms()


def grid_around_home(mech, n=4, size=0.04):
    """(n², 6) poses: home moved in x and in the rotation about the platform's free axis."""
    an = mech.analyze()
    out = []
    for a in np.linspace(-size, size, n):
        for b in np.linspace(-size, size, n):
            t = a * an.platform_twists[0] + b * an.platform_twists[-1]
            out.append(pose_array([screws.exp(t) * mech.home])[0])
    return np.array(out)


@pytest.mark.parametrize("name", ["rpr3", "rrr3", "stewart", "delta", "upu3"])
def test_sweep_equals_per_pose_analysis(name):
    """Every array of the sweep equals what analyze() gives pose by pose."""
    mech = mechanism(name)
    X = grid_around_home(mech)
    res = mech.sweep(X)
    assert res.ok.all() and not res.failures
    for i, x in enumerate(X):
        an = mech.analyze(mech.assemble(x))
        assert res.dof[i] == an.dof
        assert res.singularity[i] == an.singularity
        assert res.type_I[i] == pytest.approx(an.indices["type_I"], rel=1e-9, abs=1e-12)
        assert res.type_II[i] == pytest.approx(an.indices["type_II"], rel=1e-9, abs=1e-12)
        np.testing.assert_allclose(res.q_actuated[i], an.assembly.q_actuated, atol=1e-9)


def test_unreachable_poses_are_recorded_not_raised():
    """Poses out of reach are listed in failures with the leg named; their arrays are empty."""
    mech = mechanism("rpr3")
    X = np.array([pose_array([mech.home])[0], [0.8, 0, 40.0, 0, 0.6, 0], [-30, 0, 0.6, 0, 0.6, 0]])
    res = mech.sweep(X)
    assert res.ok.tolist() == [True, False, False]
    assert [i for i, _ in res.failures] == [1, 2]
    assert all("cannot reach" in reason for _, reason in res.failures)
    assert np.isnan(res.type_II[1:]).all() and np.isnan(res.q_actuated[1:]).all()
    assert res.dof[1:].tolist() == [-1, -1] and res.singularity[1:].tolist() == ["", ""]


@pytest.mark.parametrize("name", ["stewart", "delta"])
def test_blocks_of_a_chunk_give_the_same_results(name, monkeypatch):
    """The Pinocchio pass and the engine run by blocks of a chunk's poses (sweep.BLOCK):
    blocks of 3 poses, with unreachable poses among them, give the results of one
    block."""
    from pkm_pin import sweep as sweep_module

    mech = mechanism(name)
    X = grid_around_home(mech, n=4)
    X[[2, 7]] += [100.0, 0, 0, 0, 0, 0]  # out of reach
    whole = mech.sweep(X)
    monkeypatch.setattr(sweep_module, "BLOCK", 3)
    blocks = mech.sweep(X)
    assert whole.ok.tolist() == blocks.ok.tolist() and whole.ok.sum() == len(X) - 2
    assert [i for i, _ in whole.failures] == [i for i, _ in blocks.failures] == [2, 7]
    for key in ("dof", "singularity"):
        assert getattr(whole, key).tolist() == getattr(blocks, key).tolist()
    for key in ("type_I", "type_II", "condition", "det", "q_actuated"):
        np.testing.assert_allclose(getattr(blocks, key), getattr(whole, key), rtol=1e-12,
                                   atol=1e-14)


def test_order_of_the_poses_does_not_matter():
    """Shuffling the poses shuffles the results and nothing else."""
    mech = mechanism("rrr3")
    X = grid_around_home(mech, n=5)
    perm = np.random.default_rng(0).permutation(len(X))
    a, b = mech.sweep(X), mech.sweep(X[perm])
    np.testing.assert_allclose(b.type_II, a.type_II[perm], rtol=1e-10)
    np.testing.assert_allclose(b.q_actuated, a.q_actuated[perm], atol=1e-10)


def test_serpentine_order_visits_grid_neighbours():
    """On a grid, consecutive poses of the serpentine order are one grid step apart."""
    xs, ys = np.meshgrid(np.arange(7.0), np.arange(5.0), indexing="ij")
    X = np.zeros((xs.size, 6))
    X[:, 0], X[:, 1] = xs.ravel(), ys.ravel()
    order = serpentine_order(X)
    assert sorted(order) == list(range(len(X)))
    steps = np.abs(np.diff(X[order, :2], axis=0)).sum(axis=1)
    assert np.all(steps == 1.0)


def test_pose_matrices_are_pinocchio_rpy_placements():
    """The compiled placements equal pin.SE3(rpyToMatrix(roll, pitch, yaw), x) to 1e-15."""
    X = np.random.default_rng(3).uniform(-3.0, 3.0, size=(50, 6))
    H = pose_matrices(X)
    for x, h in zip(X, H):
        np.testing.assert_allclose(h, pin.SE3(pin.rpy.rpyToMatrix(x[3:]), x[:3]).homogeneous,
                                   rtol=0, atol=1e-15)


def test_smooth_steps_and_visiting_order():
    """Steps are compared with translations divided by the length: a straight line is
    smooth after its first two poses, a corner is not; a shuffled grid is visited in the
    serpentine order, a path in its own order."""
    line = np.zeros((6, 6))
    line[:, 0] = np.linspace(0.0, 5e-3, 6)  # 1 mm steps
    line[3:, 3] = 0.2 * np.arange(3)  # a 0.2 rad turn starts at pose 4
    np.testing.assert_array_equal(smooth_steps(line, 1e-3),
                                  [False, False, True, True, False, True])
    mm = line * np.r_[1e3, 1e3, 1e3, 1, 1, 1]
    np.testing.assert_array_equal(smooth_steps(mm, 1.0), smooth_steps(line, 1e-3))
    # a translation going back and forth by 1 mm while rolling 0.1 rad per step: a
    # corner for a 1 mm length, smooth for a 1 m length (the rotation dominates)
    zigzag = np.zeros((4, 6))
    zigzag[:, 0] = [0.0, 1e-3, 0.0, 1e-3]
    zigzag[:, 3] = 0.1 * np.arange(4)
    assert not smooth_steps(zigzag, 1e-3)[2:].any()
    assert smooth_steps(zigzag, 1.0)[2:].all()
    xs, ys = np.meshgrid(np.arange(7.0), np.arange(5.0), indexing="ij")
    X = np.zeros((xs.size, 6))
    X[:, 0], X[:, 1] = xs.ravel(), ys.ravel()
    shuffled = X[np.random.default_rng(0).permutation(len(X))]
    order = visiting_order(shuffled, 1.0)
    np.testing.assert_array_equal(order, serpentine_order(shuffled))
    np.testing.assert_array_equal(visiting_order(line, 1e-3), np.arange(6))


def test_anchor_targets_and_is_path():
    """Tip targets are pose · anchor (Pinocchio's SE3 product); a line and a serpentine
    scan are paths, a raster scan (jumps back at each row end) and a shuffled grid are
    not, and millimetres change nothing."""
    from pkm_pin.kernels import anchor_targets, is_path

    poses = [pin.SE3.Random() for _ in range(5)]
    anchors = [pin.SE3.Random() for _ in range(3)]
    out = np.empty((3, 5, 4, 4))
    anchor_targets(np.array([P.homogeneous for P in poses]),
                   np.array([A.homogeneous for A in anchors]), out)
    for k, A in enumerate(anchors):
        for i, P in enumerate(poses):
            np.testing.assert_allclose(out[k, i], (P * A).homogeneous, atol=1e-14)
    line = np.zeros((50, 6))
    line[:, 0] = np.linspace(0.0, 0.1, 50)
    line[:, 5] = np.linspace(0.0, 0.3, 50)
    assert is_path(line, 1.0, 16)
    xs, ys = np.meshgrid(np.arange(9.0), np.arange(8.0), indexing="ij")
    raster = np.zeros((xs.size, 6))
    raster[:, 0], raster[:, 1] = 1e-2 * xs.ravel(), 1e-2 * ys.ravel()
    assert not is_path(raster, 1.0, 16)
    snake = raster[serpentine_order(raster)]
    assert is_path(snake, 1.0, 16)
    shuffled = snake[np.random.default_rng(1).permutation(len(snake))]
    assert not is_path(shuffled, 1.0, 16)
    mm = np.r_[1e3, 1e3, 1e3, 1, 1, 1]
    for X in (line, raster, snake, shuffled):
        assert is_path(X * mm, 1e3, 16) == is_path(X, 1.0, 16)
    assert is_path(line[:2], 1.0, 16)


def test_det_changes_sign_across_the_type_II_pose():
    """Along x through the 3-RPR type II pose the carried det(A Δ) changes sign once."""
    mech = mechanism("rpr3")
    x2 = rpr3_type2_pose().translation[0]
    X0 = pose_array([mech.home])[0]
    X = np.repeat(X0[None], 21, axis=0)
    X[:, 0] = np.linspace(x2 - 0.1, x2 + 0.1, 21)
    res = mech.sweep(X)
    assert res.ok.all()
    assert np.sum(np.diff(np.sign(res.det)) != 0) == 1
    k = int(np.argmin(res.type_II))
    assert abs(X[k, 0] - x2) <= 0.01 + 1e-12


def test_thread_executor_gives_the_serial_results():
    """A ThreadPoolExecutor with small chunks reproduces the serial sweep."""
    mech = mechanism("stewart")
    X = grid_around_home(mech, n=4)
    serial = mech.sweep(X)
    with ThreadPoolExecutor(2) as ex:
        threaded = mech.sweep(X, executor=ex, chunk_size=5)
    np.testing.assert_allclose(threaded.type_II, serial.type_II, rtol=1e-9)
    np.testing.assert_allclose(threaded.q_actuated, serial.q_actuated, atol=1e-9)


def test_executor_tasks_unpickle_the_mechanism_once_per_process():
    """A task gets the mechanism as bytes and its digest; each process unpickles it once
    and its threads share that copy (never the caller's object; Pinocchio Data is per
    thread); the results are those of evaluate_chunk; corrupted bytes are refused."""
    import hashlib
    import pickle

    from pkm_pin import sweep
    from pkm_pin.screws import RTOL, homogenise

    mech = mechanism("rpr3")
    X = grid_around_home(mech, n=3)
    ref = homogenise(mech.home_analysis.platform_twists, mech.characteristic_length)
    blob = pickle.dumps(mech)
    digest = hashlib.sha256(blob).hexdigest()
    sweep._SHARED.clear()
    first = sweep._evaluate_shared(blob, digest, X, ref, RTOL, sweep.SINGULAR_TOL)
    again = sweep._evaluate_shared(blob, digest, X, ref, RTOL, sweep.SINGULAR_TOL)
    assert len(sweep._SHARED) == 1
    (here,) = sweep._SHARED.values()
    assert here is not mech
    with ThreadPoolExecutor(2) as ex:
        threaded = [f.result() for f in [ex.submit(sweep._evaluate_shared, blob, digest, X, ref,
                                                   RTOL, sweep.SINGULAR_TOL) for _ in range(4)]]
    assert len(sweep._SHARED) == 1 and next(iter(sweep._SHARED.values())) is here
    direct = sweep.evaluate_chunk(mech, X, ref, RTOL, sweep.SINGULAR_TOL)
    for part in (first, again, *threaded):
        np.testing.assert_array_equal(part["ok"], direct["ok"])
        np.testing.assert_allclose(part["type_II"], direct["type_II"], rtol=1e-12)
    with pytest.raises(RuntimeError, match="digest"):
        sweep._evaluate_shared(blob[:-1] + b"x", hashlib.sha256(b"other").hexdigest(), X,
                               ref, RTOL, sweep.SINGULAR_TOL)
    sweep._SHARED.clear()


def test_dask_local_cluster_gives_the_serial_results():
    """A Dask LocalCluster (2 worker processes) through its executor reproduces the sweep."""
    import distributed  # part of the test extra: dask[distributed]

    mech = mechanism("rpr3")
    X = grid_around_home(mech, n=6)
    serial = mech.sweep(X)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        result = mech.sweep(X, executor=client.get_executor(), chunk_size=12)
    np.testing.assert_allclose(result.type_II, serial.type_II, rtol=1e-9)
    np.testing.assert_allclose(result.q_actuated, serial.q_actuated, atol=1e-9)
    assert (result.singularity == serial.singularity).all()


def test_bad_sweep_input_is_refused():
    """Wrong shapes, NaN and a zero chunk size give specific InputErrors."""
    mech = mechanism("rpr3")
    with pytest.raises(InputError, match=r"\(N, 6\)"):
        mech.sweep(np.zeros((3, 5)))
    with pytest.raises(InputError, match="finite"):
        mech.sweep(np.full((2, 6), np.nan))
    with pytest.raises(InputError, match="chunk_size"):
        mech.sweep([mech.home], chunk_size=0)
    res = mech.sweep([mech.home, pin.SE3(mech.home)])
    assert res.ok.all()
