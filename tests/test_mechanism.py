"""Mechanism files (TOML), construction in Python, and assembly."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from helpers import MECHANISM_DIR

from pkm_pin import (
    AssemblyError,
    InputError,
    Mechanism,
    MechanismFileError,
    load_mechanism,
    screws,
)
from pkm_pin.builders import MECHANISMS


@pytest.fixture(scope="module")
def rpr3_file(tmp_path_factory) -> Path:
    """The 3-RPR written to a temporary models folder."""
    root = tmp_path_factory.mktemp("models")
    MECHANISMS["rpr3"]().write(root)
    return next((root / "mechanisms").glob("*.toml"))


def _edited(path: Path, tmp_path: Path, old: str, new: str, count: int = 1) -> Path:
    text = path.read_text()
    assert old in text, f"{old!r} not in the file"
    out = path.parent / f"edited_{tmp_path.name}.toml"
    out.write_text(text.replace(old, new, count))
    return out


@pytest.mark.parametrize("toml", sorted(MECHANISM_DIR.glob("*.toml")), ids=lambda p: p.stem)
def test_every_shipped_mechanism_file_loads_and_assembles_at_home(toml):
    """Each committed mechanism file loads, and assembles at home with a tiny residual."""
    mech = load_mechanism(toml)
    asm = mech.home_assembly
    assert asm.residual < 1e-10
    for leg, anchor, q in zip(mech.legs, mech.anchors, asm.leg_q):
        assert leg.within_limits(q)
        err = pin.log6(leg.tip_placement(q).actInv(mech.home * anchor)).vector
        assert np.linalg.norm(err) < 1e-9 * max(1.0, mech.characteristic_length)


def test_file_and_python_construction_agree(rpr3_file):
    """The file and the builder give the same actuated coordinates at home."""
    a = load_mechanism(rpr3_file).home_assembly
    b = MECHANISMS["rpr3"]().build().home_assembly
    np.testing.assert_allclose(a.q_actuated, b.q_actuated, atol=1e-12)
    assert load_mechanism(rpr3_file).actuated_names == ["A/A1", "B/B0", "C/C1"]


@pytest.mark.parametrize(
    "old, new, where, what",
    [
        ('tip = "tip"', 'tip = "nowhere"', "legs[0].tip", "nowhere"),
        ('actuated = ["A1"]', 'actuated = ["Z9"]', "legs[0].actuated", "Z9"),
        ('actuated = ["A1"]', 'actuated = "A1"', "legs[0].actuated", "list of joint names"),
        ('tip = "tip"', 'tip = "tip"\ncolour = "red"', "legs[0]", "unknown key"),
        ("name = ", "nmae = ", "top level", "unknown key"),
        ("rpr_leg_a.urdf", "missing_leg.urdf", "legs[0].urdf", "no such file"),
        ("[home]\nxyz = [", "[home]\nxyz = [1.0, ", "home.xyz", "3 numbers"),
        ('tip = "tip"', "tip = 3", "legs[0].tip", "must be a str"),
    ],
)
def test_mistakes_in_a_mechanism_file_name_file_leg_and_key(rpr3_file, tmp_path, old, new,
                                                            where, what):
    """Each mistake gets a MechanismFileError naming the file, the leg/key and the problem."""
    path = _edited(rpr3_file, tmp_path, old, new)
    with pytest.raises(MechanismFileError) as info:
        load_mechanism(path)
    message = str(info.value)
    assert str(path) in message
    assert where.replace("legs[0]", "(legs[0])") in message or where in message
    assert what in message


def test_missing_file_and_bad_toml(tmp_path):
    """A missing file and a syntax error each give a MechanismFileError."""
    with pytest.raises(MechanismFileError, match="no such file"):
        load_mechanism(tmp_path / "nope.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("name = [unclosed\n")
    with pytest.raises(MechanismFileError, match="not valid TOML"):
        load_mechanism(bad)
    empty = tmp_path / "empty.toml"
    empty.write_text('name = "x"\n')
    with pytest.raises(MechanismFileError, match=r"\[\[legs\]\]"):
        load_mechanism(empty)


def test_python_construction_errors():
    """Wrong anchors, duplicate leg names and non-legs are refused with InputError."""
    legs = MECHANISMS["rpr3"]().legs_built()
    with pytest.raises(InputError, match="anchors"):
        Mechanism(legs, anchors=[pin.SE3.Identity()])
    with pytest.raises(InputError, match="distinct"):
        Mechanism([legs[0], legs[0]])
    with pytest.raises(InputError, match="not a pkm_pin.Leg"):
        Mechanism([legs[0], "leg"])


def test_assembly_respects_prismatic_limits_and_reports_unreachable_leg():
    """A pose beyond a leg's stroke raises AssemblyError naming that leg, never a negative
    length."""
    mech = MECHANISMS["rpr3"]().build()
    far = pin.SE3(mech.home.rotation, mech.home.translation + np.array([0.0, 0.0, 50.0]))
    with pytest.raises(AssemblyError, match="leg 'A'") as info:
        mech.assemble(far)
    assert info.value.residual > 1e-3
    for leg, q in zip(mech.legs, mech.home_assembly.leg_q):
        assert leg.within_limits(q)
    with pytest.raises(InputError, match="pose"):
        mech.assemble([0.0, 1.0])
    with pytest.raises(InputError, match="finite"):
        mech.assemble([0.0, 0.0, np.nan, 0.0, 0.0, 0.0])


def test_assembly_restarts_from_a_bad_guess():
    """From a guess far off (and at the limits) the restarts still find the assembly."""
    mech = MECHANISMS["stewart"]().build()
    bad = [leg.clip(np.full(leg.nq, 10.0)) for leg in mech.legs]
    asm = mech.assemble(mech.home, guess=bad)
    assert asm.residual < 1e-10
    for leg, q in zip(mech.legs, asm.leg_q):
        assert leg.within_limits(q)


def test_warm_start_keeps_the_working_mode():
    """Assembling near home from the home assembly keeps every 3-RRR elbow on its side."""
    mech = MECHANISMS["rrr3"]().build()
    home = mech.home_assembly
    pose = screws.exp(np.array([0, 0, 0.05, 0.02, -0.01, 0])) * mech.home
    asm = mech.assemble(pose, home)
    for q0, q1 in zip(home.leg_q, asm.leg_q):
        assert np.sign(q0[1]) == np.sign(q1[1])


def test_spherical_joint_at_gimbal_lock_is_no_false_singularity():
    """A Stewart leg whose spherical group is at gimbal lock keeps the platform at 6 DOF."""
    mech = MECHANISMS["stewart"]().build()
    leg = mech.legs[0]
    (i, j, k), = leg.spherical_groups
    q = mech.home_assembly.leg_q[0].copy()
    q[j] = np.pi / 2
    assert screws.rank(leg.joint_twists(q)) == 5
    assert screws.rank(leg.motion_twists(q)) == 6
    # rebuild the mechanism with an anchor that puts leg 0 at that configuration at home
    anchors = list(mech.anchors)
    anchors[0] = mech.home.inverse() * leg.tip_placement(q)
    guess = list(mech.home_assembly.leg_q)
    guess[0] = q
    locked = Mechanism(mech.legs, anchors, mech.name, mech.home, guess)
    an = locked.analyze()
    assert an.dof == 6 and an.singularity == "none"
    assert re.fullmatch(r"3T3R", an.motion_type)
