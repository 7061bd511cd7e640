"""One mechanism used from several threads at once: Pinocchio data is per thread."""

from __future__ import annotations

import sys
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from helpers import random_platform_twist

from pkm_pin import screws
from pkm_pin.builders import MECHANISMS

THREADS = 4
POSES_PER_THREAD = 4


@pytest.fixture(scope="module", params=["rpr3", "stewart"])
def mech(request):
    """A shipped mechanism with its home assembly and analysis already computed."""
    m = MECHANISMS[request.param]().build()
    _ = m.home_analysis, m.kernel  # the caches every thread reads
    return m


@pytest.fixture
def fast_switching():
    """Threads switch every microsecond (instead of 5 ms) while the test runs."""
    before = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    yield
    sys.setswitchinterval(before)


def _poses(mech, n: int, seed: int = 0) -> list:
    """``n`` poses near home, moved along the platform twist system (they assemble)."""
    rng = np.random.default_rng(seed)
    home, L = mech.home_assembly, mech.characteristic_length
    return [screws.exp(random_platform_twist(mech, home, rng, 0.03, 0.03 * L)) * home.pose
            for _ in range(n)]


def _work(mech, pose) -> list[np.ndarray]:
    """Assemble, analyse, solve the forward kinematics back and take the sensitivity
    to the first leg's parameters at one pose: every array the results hold."""
    asm = mech.assemble(pose)
    an = mech.analyze(asm)
    fk = mech.forward_kinematics(asm.q_actuated)
    euler = mech.forward_kinematics(asm.q_actuated, method="euler")
    sens = mech.sensitivity(asm, mech.legs[0].name)
    leg, q = mech.legs[-1], asm.leg_q[-1]
    qd = np.linspace(0.1, 0.3, leg.nv)
    return [np.asarray(x, dtype=float) for x in (
        *asm.leg_q, an.A, an.B, list(an.indices.values()), an.platform_twists,
        fk.pose.homogeneous, *fk.leg_q, euler.pose.homogeneous, sens.matrix,
        leg.tip_placement(q).homogeneous, *leg.screws(q), leg.joint_origins(q),
        *leg.link_twists(q, qd).values(), leg.serial_jacobian(q),
    )]


def test_threads_give_the_single_threaded_results_exactly(mech, fast_switching):
    """Four threads assembling, analysing and solving the FK of different poses of one
    mechanism at once get exactly the results of one thread."""
    poses = _poses(mech, THREADS * POSES_PER_THREAD)
    expected = [_work(mech, p) for p in poses]
    barrier = threading.Barrier(THREADS)

    def run(k: int) -> list:
        barrier.wait()
        mine = range(k, len(poses), THREADS)  # each thread its own poses
        return [(i, _work(mech, poses[i])) for _ in range(2) for i in mine]

    with ThreadPoolExecutor(THREADS) as ex:
        results = [r for rs in ex.map(run, range(THREADS)) for r in rs]
    assert len(results) == 2 * len(poses)
    for i, got in results:
        assert len(got) == len(expected[i])
        for a, b in zip(got, expected[i]):
            np.testing.assert_array_equal(a, b)


def test_leg_data_is_private_to_each_thread(mech):
    """``leg.data`` is one object within a thread and a different one in each thread."""
    leg = mech.legs[0]
    here = leg.data
    assert leg.data is here

    def data_of_a_thread(_):
        first = leg.data
        return first, leg.data is first

    with ThreadPoolExecutor(THREADS) as ex:
        pooled = list(ex.map(data_of_a_thread, range(THREADS)))
    others = []
    for _ in range(THREADS):  # fresh threads: each one makes its own data
        box: list = []
        th = threading.Thread(target=lambda box=box: box.append(data_of_a_thread(None)))
        th.start()
        th.join()
        others.append(box[0])
    assert all(same for _, same in pooled + others)
    datas = [d for d, _ in others] + [here]
    assert len({id(d) for d in datas}) == len(datas)
    assert leg.data is here


def test_pickled_leg_has_no_data_and_makes_its_own(mech):
    """A pickled leg carries no Pinocchio data; the copy makes its own and computes the
    same kinematics."""
    import pickle

    leg = mech.legs[0]
    state = leg.__getstate__()
    assert not any(type(v).__name__ == "Data" or k in ("_local", "data") for k, v in state.items())
    copy = pickle.loads(pickle.dumps(leg))
    q = mech.home_assembly.leg_q[0]
    assert copy.data is not leg.data
    T0, J0 = leg.kinematics(q)
    T1, J1 = copy.kinematics(q)
    np.testing.assert_array_equal(T0.homogeneous, T1.homogeneous)
    np.testing.assert_array_equal(J0, J1)
