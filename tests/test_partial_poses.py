"""Partial poses (issue 17.5): lower-mobility mechanisms driven by their own coordinates,
full poses projected onto the motion manifold, and assembly on the workspace boundary."""

from __future__ import annotations

import numpy as np
import pytest

from pkm_pin.builders import MECHANISMS
from pkm_pin.builders.spatial import agile_eye
from pkm_pin.cli import main
from pkm_pin.errors import AssemblyError, InputError
from pkm_pin.position import DependentCoordinates, OffMotionManifold
from pkm_pin.solve import POSE_COORDINATES, pose_coordinates
from pkm_pin.tolerances import POSE_PROJECTION_TOL, TYPE_I_CLOSURE_TOL


@pytest.fixture(scope="module")
def rps3():
    return MECHANISMS["rps3"]().build()


@pytest.fixture(scope="module")
def eye():
    return agile_eye().build()


def round_trip(mech, given: dict) -> tuple[float, float]:
    """FK(IK(partial)): the largest error of the given coordinates in the pose FK
    returns, and the largest difference between the actuated values of IK of that pose
    and the first IK's."""
    q = mech.inverse_kinematics(given).q_actuated
    back = mech.forward_kinematics(q)
    c = pose_coordinates(back.pose)
    coords = max(abs(c[POSE_COORDINATES.index(name)] - value) for name, value in given.items())
    again = mech.inverse_kinematics(back.pose, guess=back).q_actuated
    return float(coords), float(np.max(np.abs(again - q)))


@pytest.mark.parametrize("given", [dict(z=0.8, roll=0.1, pitch=0.0),
                                   dict(z=1.1, roll=-0.2, pitch=0.15)])
def test_rps3_round_trip_by_z_roll_pitch(rps3, given):
    """A 3-RPS (1T2R) driven by z, roll, pitch: FK(IK) returns them to 1e-10."""
    coords, actuated = round_trip(rps3, given)
    assert coords <= 1e-10 and actuated <= 1e-10


def test_rps3_completion_solves_the_parasitic_motions(rps3):
    """complete_pose returns a pose with the given coordinates exactly and parasitic x, y,
    yaw (nonzero x for a roll) on the motion: it assembles to the closure tolerance."""
    pose = rps3.complete_pose(z=0.8, roll=0.1, pitch=0.0)
    c = pose_coordinates(pose)
    assert c[2:5] == pytest.approx([0.8, 0.1, 0.0], abs=1e-12)
    assert abs(c[0]) > 1e-4  # the parasitic shift of the 3-RPS
    assert rps3.assemble(pose, project=False).residual <= 1e-12


@pytest.mark.parametrize("given", [dict(roll=0.2, pitch=-0.1, yaw=0.3),
                                   dict(roll=-0.4, pitch=0.3, yaw=-0.2)])
def test_agile_eye_round_trip_by_roll_pitch_yaw(eye, given):
    """The agile eye (3R) driven by roll, pitch, yaw: FK(IK) returns them to 1e-10."""
    coords, actuated = round_trip(eye, given)
    assert coords <= 1e-10 and actuated <= 1e-10


def test_delta_by_x_y_z():
    """The Delta (3T) is driven by x, y, z; its rotations stay zero."""
    delta = MECHANISMS["delta"]().build()
    pose = delta.complete_pose(x=0.05, y=-0.02, z=-0.8)
    assert pose_coordinates(pose) == pytest.approx([0.05, -0.02, -0.8, 0, 0, 0], abs=1e-12)
    coords, actuated = round_trip(delta, dict(x=0.05, y=-0.02, z=-0.8))
    assert coords <= 1e-10 and actuated <= 1e-10


def test_fewer_coordinates_than_dof_hold_the_others_at_the_guess(rps3):
    """Given z only, a 3-RPS holds roll and pitch at home (info['held'])."""
    asm = rps3.assemble({"z": 0.9})
    assert set(asm.info["held"]) == {"roll", "pitch"}
    assert pose_coordinates(asm.pose)[2:5] == pytest.approx([0.9, 0, 0], abs=1e-12)


def test_dependent_coordinates_say_which_and_the_dof(rps3):
    """x is a parasitic motion of the 3-RPS, and four coordinates are too many: the error
    names the DOF, the motion type and a valid set."""
    with pytest.raises(DependentCoordinates, match=r"x does not change.*3 DOF \(1T2R\)"
                       r".*z, roll, pitch"):
        rps3.complete_pose(x=0.1, z=0.8)
    with pytest.raises(DependentCoordinates, match="4 coordinates for 3 DOF"):
        rps3.complete_pose(z=1.0, roll=0.0, pitch=0.0, yaw=0.0)


def test_unknown_names_and_bad_values_are_refused(rps3):
    """An unknown coordinate name, or a value that is not a finite number, is an
    InputError naming it."""
    with pytest.raises(InputError, match="'height'"):
        rps3.complete_pose(height=0.8)
    with pytest.raises(InputError, match="finite"):
        rps3.complete_pose(z=float("nan"))


def test_unreachable_partial_pose_raises(rps3):
    """A partial pose outside the workspace raises with the reason."""
    from pkm_pin.errors import ForwardKinematicsError

    with pytest.raises(ForwardKinematicsError, match="cannot be completed"):
        rps3.complete_pose(z=5.0, roll=0.0, pitch=0.0)


def test_a_completion_stopped_against_a_limit_is_not_continued(rps3, monkeypatch):
    """Newton stopped with a joint on its limit (a leg's stroke exhausted) is not
    continued: one solve instead of 1 + 4 + 16 steps, and the same error; a workspace over
    partial poses (5³) gets the same masks with and without the stop."""
    from pkm_pin import position
    from pkm_pin.errors import ForwardKinematicsError

    calls = []
    solve = position.solve_coordinates

    def counted(*args, **kwargs):
        calls.append(1)
        return solve(*args, **kwargs)

    monkeypatch.setattr(position, "solve_coordinates", counted)
    z = rps3.home.translation[2]
    beyond = dict(z=z + 3 * rps3.characteristic_length, roll=0.0, pitch=0.0)
    with pytest.raises(ForwardKinematicsError, match="cannot be completed") as stopped:
        rps3.complete_pose(**beyond)
    assert len(calls) == 1
    with_stop = rps3.workspace(n=5)
    monkeypatch.setattr(position, "_against_a_limit", lambda mech, leg_q: False)
    calls.clear()
    with pytest.raises(ForwardKinematicsError, match="cannot be completed") as continued:
        rps3.complete_pose(**beyond)
    assert len(calls) > 5
    assert str(stopped.value).split(":")[0] == str(continued.value).split(":")[0]
    without = rps3.workspace(n=5)
    assert with_stop.counts == without.counts
    for kind, mask in without.masks.items():
        assert np.array_equal(with_stop.masks[kind], mask), kind


def test_printed_precision_pose_is_projected(rps3):
    """A full pose printed at 6 significant digits is projected onto the manifold (the
    difference is reported, below the tolerance); one 1e-3 off is refused."""
    exact = pose_coordinates(rps3.complete_pose(z=0.8, roll=0.1, pitch=0.05))
    printed = np.array([float(f"{v:.6g}") for v in exact])
    asm = rps3.assemble(printed)
    assert 0 < asm.info["projection"] <= POSE_PROJECTION_TOL
    assert pose_coordinates(asm.pose) == pytest.approx(exact, abs=1e-6)
    assert asm.residual <= 1e-12
    assert rps3.inverse_kinematics(printed).q_actuated == pytest.approx(
        rps3.inverse_kinematics(exact).q_actuated, abs=1e-6)
    off = exact + np.r_[1e-3, 0, 0, 0, 0, 0]
    with pytest.raises(OffMotionManifold, match="nearest pose"):
        rps3.assemble(off)
    with pytest.raises(AssemblyError):
        rps3.assemble(off, project=False)


def test_sweep_of_partial_poses_30x30(rps3):
    """A 30 × 30 z-roll grid of the 3-RPS (pitch 0) assembles entirely, given as one
    mapping of coordinate arrays; dependent ones are failures with the reason."""
    z, roll = np.meshgrid(np.linspace(0.7, 1.3, 30), np.linspace(-0.4, 0.4, 30))
    result = rps3.sweep({"z": z.ravel(), "roll": roll.ravel(), "pitch": 0.0})
    assert result.ok.sum() == 900
    assert np.all(result.poses[:, 4] == 0.0) and np.all(result.poses[:, 2] == z.ravel())
    bad = rps3.sweep([{"z": 0.9, "roll": 0.0, "pitch": 0.0}, {"x": 0.1, "z": 0.8}])
    assert bad.ok.tolist() == [True, False]
    assert bad.failures[0][0] == 1 and "not completed" in bad.failures[0][1]
    none = rps3.sweep([{"x": 0.1, "z": 0.8}, {"y": 0.2, "z": 0.8}])  # none completes
    assert not none.ok.any() and [i for i, _ in none.failures] == [0, 1]
    assert (none.dof == -1).all() and np.isnan(none.condition).all()
    assert none.singularity.tolist() == ["", ""] and none.q_actuated.shape == (2, 3)
    assert none.poses[0, 0] == 0.1 and none.poses[1, 1] == 0.2


def test_type_I_boundary_pose_assembles_and_is_analysed():
    """A 3-RRR pose with leg 1 stretched (type I): assembly by pose succeeds at the exact
    boundary and at printed precision just outside it (the residual reported, below
    TYPE_I_CLOSURE_TOL), and the analysis says type I; clearly outside is refused."""
    rrr = MECHANISMS["rrr3"]().build()
    # leg 1 (base (0, 1), anchor (0, 0.25), links 0.6 + 0.6) is straight at y = -0.45
    outside = -0.45 - 4e-7  # printed-precision error beyond the boundary
    for y in (-0.45, outside):
        asm = rrr.assemble([0, y, 0, 0, 0, 0])
        assert asm.residual <= TYPE_I_CLOSURE_TOL
        assert rrr.analyze(asm).singularity == "I"
    assert rrr.assemble([0, outside, 0, 0, 0, 0]).info["boundary"] == ["1"]
    with pytest.raises(AssemblyError):
        rrr.assemble([0, -0.4501, 0, 0, 0, 0])


def test_cli_at_on_ik_and_analyze(capsys):
    """ik and analyze take --at (a partial pose) and show the completed pose."""
    assert main(["ik", "rps3", "--at", "z=0.8", "roll=0.1", "pitch=0"]) == 0
    out = capsys.readouterr().out
    assert "given      z=0.8, roll=0.1, pitch=0" in out and "xyz [0.00124896, 0, 0.8]" in out
    assert main(["analyze", "rps3", "--at", "z=0.8", "roll=0.1", "pitch=0", "--json"]) == 0
    import json

    report = json.loads(capsys.readouterr().out)
    assert report["pose"]["xyz"][2] == pytest.approx(0.8) and report["dof"] == 3
    assert main(["ik", "rps3", "--at", "x=0.1", "z=0.8"]) == 2
    assert "not independent" in capsys.readouterr().err
    assert main(["ik", "rps3", "--at", "z=0.8", "--pose", "0", "0", "1", "0", "0", "0"]) == 2


def test_cli_map_over_z_roll_and_dependent_axes(tmp_path, capsys):
    """map --axes z roll --at pitch=0 of the 3-RPS assembles every pose and says how
    many; an xz map says why it cannot be made instead of writing an empty one."""
    prefix = tmp_path / "m"
    assert main(["map", "rps3", "--axes", "z", "roll", "--range", "0.7", "1.3", "-0.4",
                 "0.4", "--n", "30", "--at", "pitch=0", "--out", str(prefix), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "assembled  900 of 900" in out and "solved for x, y, yaw" in out
    data = np.load(tmp_path / "m.npz")
    assert data["ok"].shape == (30, 30) and data["ok"].all()
    assert data["poses"][3, 7, 2] == pytest.approx(data["u"][7])
    assert data["poses"][3, 7, 3] == pytest.approx(data["v"][3])
    assert main(["map", "rps3", "--plane", "xz", "--n", "30", "--out", str(prefix),
                 "--quiet"]) == 2
    assert "x does not change to first order" in capsys.readouterr().err
