"""Partial output poses of a linkage without legs (issue 25 leftovers): the tree solved
for some of its output frame's pose coordinates (:mod:`pkm_pin.output_driver`), the
others free; checked against the loops, the targets and forward kinematics."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkm_pin
from pkm_pin.cli import main
from pkm_pin.errors import InputError
from pkm_pin.linkage import LoopClosureError
from pkm_pin.output_driver import OutputDriver, partial_pose
from pkm_pin.solve import POSE_COORDINATES, pose_coordinates

MODELS = Path(__file__).resolve().parents[1] / "models"


@pytest.fixture(scope="module")
def five_bar():
    return pkm_pin.load_mechanism(MODELS / "loops" / "five_bar.urdf")


@pytest.fixture(scope="module")
def cassie():
    return pkm_pin.load_mechanism(MODELS / "loops" / "cassie_knee.urdf")


def _check(link, a, given: dict) -> np.ndarray:
    """The loops closed to 1e-9 and the given coordinates met to 1e-9; the coordinates."""
    assert np.abs(link.model.closure_residual(a.q)).max() < 1e-9
    c = pose_coordinates(a.output_pose)
    for name, value in given.items():
        assert c[POSE_COORDINATES.index(name)] == pytest.approx(value, abs=1e-9)
    return c


def test_partial_pose_of_the_five_bar(five_bar):
    """The 5-bar (a point output moving in x, y; no legs to read): x alone is met with y
    free (it moves off its home value 0.15), from the reference's branch; x and y
    together give the configuration of the full pose's inverse kinematics to 1e-9; the
    actuated values found give the same output back by forward kinematics."""
    assert five_bar.platform_structure[0] is None
    home = pose_coordinates(five_bar.home_assembly.output_pose)
    a = five_bar.inverse_kinematics({"x": home[0] + 0.01})
    c = _check(five_bar, a, {"x": home[0] + 0.01})
    assert abs(c[1] - home[1]) > 1e-5 and abs(c[1] - home[1]) < 0.01
    target = {"x": home[0] + 0.01, "y": home[1] + 0.01}
    b = five_bar.inverse_kinematics(target)
    _check(five_bar, b, target)
    full = five_bar.inverse_kinematics(pin.SE3(np.eye(3), np.array([*target.values(), 0.0])))
    assert np.allclose(b.q, full.q, atol=1e-9)
    fk = five_bar.forward_kinematics(a.q_actuated, guess=a.q)
    assert np.allclose(fk.output_pose.translation, a.output_pose.translation, atol=1e-9)


def test_partial_pose_of_the_cassie_knee(cassie):
    """The Cassie-like knee (two loops, a body output moving in x, z, pitch): z alone
    and pitch alone each met, the loops closed; z and pitch together fix the output,
    and forward kinematics from the actuated values found gives it back to 1e-9."""
    home = pose_coordinates(cassie.home_assembly.output_pose)
    for given in ({"z": home[2] + 0.01}, {"pitch": home[4] + 0.01},
                  {"z": home[2] + 0.01, "pitch": home[4] - 0.02}):
        a = cassie.inverse_kinematics(given)
        c = _check(cassie, a, given)
        assert np.allclose(c[[1, 3, 5]], home[[1, 3, 5]], atol=1e-9)  # y, roll, yaw held
    fk = cassie.forward_kinematics(a.q_actuated, guess=cassie.home_assembly.q)
    assert np.allclose(pose_coordinates(fk.output_pose), c, atol=1e-9)


def test_partial_pose_refusals(five_bar):
    """Coordinates the output cannot move along, an angle of a point output, an unknown
    name, a value that is not finite: one InputError sentence each; a coordinate out of
    reach: a LoopClosureError naming the partial output pose."""
    q0 = five_bar.home_assembly.q
    with pytest.raises(InputError, match="not independent"):
        partial_pose(five_bar.model, {"z": 0.0}, q0)
    with pytest.raises(InputError, match="is a point: give x, y, z only"):
        five_bar.inverse_kinematics({"pitch": 0.1})
    with pytest.raises(InputError, match="must be distinct names"):
        OutputDriver(five_bar.model, ("w",), q0)
    with pytest.raises(InputError, match="finite"):
        partial_pose(five_bar.model, {"x": float("nan")}, q0)
    with pytest.raises(LoopClosureError, match="partial output pose") as raised:
        five_bar.inverse_kinematics({"x": 10.0})  # far beyond the links' reach (0.15 m)
    assert raised.value.residual > 1.0
    q, r, steps = partial_pose(five_bar.model, {"x": 0.01}, q0)
    assert r < 1e-9 and 0 < steps < 100


def test_cli_ik_at_on_a_linkage(capsys):
    """pkm-pin ik FIVE_BAR --at x=0.01 [--json]: the pose reached has x = 0.01, the loops
    closed (residual printed), the given coordinates echoed."""
    path = str(MODELS / "loops" / "five_bar.urdf")
    assert main(["ik", path, "--at", "x=0.01", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["given"] == {"x": 0.01}
    assert data["pose"]["xyz"][0] == pytest.approx(0.01, abs=1e-9)
    assert data["residual"] < 1e-9
    assert main(["ik", path, "--at", "x=0.01"]) == 0
    assert capsys.readouterr().out.startswith("given      x=0.01 (the other coordinates free)")
    assert main(["ik", path, "--at", "x=0.01", "--pose", "0", "0", "0", "0", "0", "0"]) == 2


def test_cli_analyze_at_on_a_linkage(capsys, five_bar):
    """pkm-pin analyze FIVE_BAR --at x=0.01 --json: analysed at the configuration of
    Linkage.inverse_kinematics({"x": 0.01}) (the same q to 1e-12); --at with --q: exit 2."""
    path = str(MODELS / "loops" / "five_bar.urdf")
    assert main(["analyze", path, "--at", "x=0.01", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["pose"]["xyz"][0] == pytest.approx(0.01, abs=1e-9)
    assert np.allclose(data["q"], five_bar.inverse_kinematics({"x": 0.01}).q, atol=1e-12)
    assert main(["analyze", path, "--at", "x=0.01", "--q", "0", "0"]) == 2
    assert "not both" in capsys.readouterr().err
