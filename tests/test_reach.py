"""A leg's reach (the triangle inequality over its offsets and strokes) and the sweep's
reach test: poses no leg can reach are refused without a solve, and nothing else
changes (issue 24: the workspace's unreachable poses cost the solver's budget)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from pkm_pin import load_mechanism, sweep

MECHANISMS = Path(__file__).resolve().parents[1] / "models" / "mechanisms"


@pytest.mark.parametrize("name", ["stewart", "rpr3", "rrr3", "upu3", "rps3", "delta", "agile_eye"])
def test_reach_bounds_every_configuration(name):
    """At 400 random configurations within the limits, every leg's tip stays within
    its reach from its root; the 6-UPS leg (no offsets, one stroke) reaches exactly its
    stroke [0.353, 2.353]; the agile eye's legs (every axis through one point) reach
    that point alone; a leg with mimic joints claims no bound."""
    mech = load_mechanism(MECHANISMS / f"{name}.toml")
    rng = np.random.default_rng(3)
    for leg in mech.legs:
        r_min, r_max = leg.reach
        assert 0.0 <= r_min <= r_max
        if name == "delta":
            assert (r_min, r_max) == (0.0, np.inf)
            continue
        data = leg.model.createData()
        for _ in range(400):
            q = leg.random_configuration(rng)
            pin.framesForwardKinematics(leg.model, data, q)
            d = np.linalg.norm(data.oMf[leg.tip_id].translation)
            assert r_min - 1e-12 <= d <= r_max + 1e-12
    if name == "agile_eye":
        assert all(leg.reach == (0.0, 0.0) for leg in mech.legs)
    if name == "stewart":
        lo, up = mech.legs[0].lower, mech.legs[0].upper
        prismatic = mech.legs[0].model.joints[mech.legs[0]._prismatic_joints[0]].idx_q
        assert mech.legs[0].reach == pytest.approx((lo[prismatic], up[prismatic]), abs=1e-12)


@pytest.mark.parametrize("name", ["rrr3", "stewart"])
def test_reach_test_keeps_the_workspace_on_homes_working_mode(name, monkeypatch):
    """A workspace with the sweep's reach test against the same without it (every pose
    solved): the same reachable poses; the poses refused name the leg and its reach.
    Where the singularity-free masks differ (the 3-RRR on an 8-point grid: without the
    test a leg tracked through the unreachable poses comes back on another working
    mode), the new mask is the one of each pose assembled from home alone (class none
    and home's sign of the carried determinant): after refused poses each leg starts
    again from home, as a miss is solved again."""
    mech = load_mechanism(MECHANISMS / f"{name}.toml")
    with_test = mech.workspace(n=8)
    refused, original = [], sweep.out_of_reach

    def solve_them_all(legs, Ts, length):
        refused.extend(original(legs, Ts, length)[1])  # what the test would have refused
        return np.ones(Ts.shape[1], bool), []

    monkeypatch.setattr(sweep, "out_of_reach", solve_them_all)
    without = mech.workspace(n=8)
    monkeypatch.setattr(sweep, "out_of_reach", original)
    np.testing.assert_array_equal(with_test.masks["reachable"], without.masks["reachable"])
    assert refused and all("cannot reach the pose" in why and "outside its reach" in why
                           for _, why in refused)
    home_det = np.sign(mech.sweep([mech.home]).det[0])
    differ = np.flatnonzero((with_test.masks["singularity-free"]
                             != without.masks["singularity-free"]).ravel())
    assert (name == "rrr3") == (len(differ) > 0)
    for i in differ:
        p = dict(zip(with_test.coords, with_test.points[i]))
        pose = np.r_[mech.home.translation, pin.rpy.matrixToRpy(mech.home.rotation)]
        for k, c in enumerate(("x", "y", "z", "roll", "pitch", "yaw")):
            pose[k] = p.get(c, pose[k])
        alone = mech.sweep(pose[None])
        free = alone.ok[0] and alone.singularity[0] == "none" \
            and np.sign(alone.det[0]) == home_det
        assert free == with_test.masks["singularity-free"].ravel()[i]
