"""Tests of pkm_pin.closure_gaps and of what a linkage that does not assemble reports and
draws (issue 25, item 2): the open loops with their gaps in mm and degrees, the joints
held at a limit, the hint; ``view`` draws the open tree with the gaps; ``analyze`` stays
an error of one line."""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from linkage_models import COUPLER, CRANK, GROUND, ROCKER, four_bar
from test_view import page_commands

import pkm_pin
from pkm_pin.cli import main
from pkm_pin.closure_gaps import ANGLE_CLOSED, closure_gaps, diagnose
from pkm_pin.errors import InputError
from pkm_pin.linkage import Linkage, LoopClosureError
from pkm_pin.view import node_name, view
from pkm_pin.view_linkage import GAP_COLOURS

DATA = Path(__file__).resolve().parents[1] / "tests" / "data"
KANGAROO = DATA / "gepetto" / "kangaroo_like" / "robot.urdf"
TALOS = DATA / "gepetto" / "true_talos_2_legs" / "talos_full_v2.urdf"
SHORT = (0.2, 0.1, 0.2, 1.0)  # crank + coupler + rocker = 0.5 < ground 1.0
ROCKER_RANGE = (np.pi - 0.05, np.pi)  # the rocker folded back towards the crank pivot


def _error(link: Linkage, **options) -> LoopClosureError:
    with pytest.raises(LoopClosureError) as e:
        link.assemble(**options)
    return e.value


@pytest.fixture(scope="module")
def short_error():
    return _error(Linkage(four_bar(lengths=SHORT)), starts=4)


def limited_rocker() -> Linkage:
    """The default four-bar with its rocker held in :data:`ROCKER_RANGE`: its tip then
    lies 0.2 m from the crank pivot, nearer than the folded crank and coupler reach
    (coupler − crank = 0.4 m), so the loop closes only with the rocker beyond its
    limits."""
    model = four_bar()
    tree = pin.Model(model.tree)
    i = tree.joints[tree.getJointId("rocker")].idx_q
    tree.lowerPositionLimit[i], tree.upperPositionLimit[i] = ROCKER_RANGE
    return Linkage(replace(model, tree=tree, reference=np.array([0.0, 0.0, np.pi - 0.02])))


@pytest.fixture(scope="module")
def limit_error():
    return _error(limited_rocker(), starts=4)


# ------------------------------------------------------------ small models
def test_a_loop_too_short_to_close_reports_its_gap_in_mm(short_error):
    """Crank 0.2 + coupler 0.1 + rocker 0.2 m against a 1 m ground: no configuration
    comes nearer than 0.5 m (all three stretched along the ground), and the best one
    found is within 5 mm of that; the message gives the gap in mm, no joint at a limit,
    and the generic hint."""
    e = short_error
    (gap,) = e.diagnosis.gaps
    assert gap.name == "loop" and gap.kind == "point"
    shortest = SHORT[3] - sum(SHORT[:3])
    assert shortest - 1e-12 <= gap.distance <= shortest + 5e-3
    assert np.linalg.norm(gap.b - gap.a) == pytest.approx(gap.distance)
    assert e.diagnosis.at_limits == () and not e.diagnosis.closes_without_limits
    assert re.search(r"open loops: 'loop' 50[0-5](\.\d+)? mm;", str(e))
    assert "hint: check the closure frames" in str(e)


def test_the_best_configuration_reached_is_kept(short_error):
    """``error.q`` is the best configuration; :meth:`Linkage.reached` gives it as an
    assembly whose residual is the loop's residual norm there."""
    link = Linkage(four_bar(lengths=SHORT))
    a = link.reached(short_error)
    np.testing.assert_array_equal(a.q, short_error.q)
    assert a.residual == pytest.approx(short_error.residual)
    assert a.closure_residuals["loop"] == pytest.approx(short_error.residual)
    with pytest.raises(InputError, match="carries the best configuration"):
        link.reached(LoopClosureError("loop", 1.0))


def test_a_joint_at_its_limit_is_named_with_the_value_the_loop_needs(limit_error):
    """The limited rocker: the best configuration holds it at its lower limit π − 0.05
    (its tip then farthest from the crank pivot), the gap is at least the folded
    crank–coupler's 0.4 m minus that distance (and the best found within 2 cm of it);
    lifting the limit closes the loop at a rocker angle
    outside the range, which the message gives with a hint about limits."""
    e = limit_error
    (hit,) = e.diagnosis.at_limits
    assert (hit.joint, hit.side) == ("rocker", "lower")
    assert hit.value == pytest.approx(ROCKER_RANGE[0]) and hit.limits == ROCKER_RANGE
    assert not ROCKER_RANGE[0] <= hit.needed <= ROCKER_RANGE[1]
    tip = np.array([GROUND, 0.0]) + ROCKER * np.array([np.cos(hit.value), np.sin(hit.value)])
    (gap,) = e.diagnosis.gaps
    nearest = COUPLER - CRANK - np.linalg.norm(tip)  # no configuration comes nearer
    assert nearest - 1e-12 <= gap.distance <= nearest + 0.02
    assert e.diagnosis.closes_without_limits
    assert "at a limit: rocker at its lower limit 3.092 (range [3.092, 3.142]; the loops " \
        "close at" in str(e)
    assert "hint: the loops close with those joints beyond their limits" in str(e)


def test_closed_loops_and_rounding_are_not_listed():
    """At an assembled configuration no loop is open; :func:`diagnose` is empty."""
    link = Linkage(four_bar())
    q = link.assemble().q
    assert closure_gaps(link.model, q) == ()
    d = diagnose(link.model, q)
    assert d.gaps == () and d.at_limits == () and d.words().startswith("hint")


# ------------------------------------------------------------ published files
@pytest.fixture(scope="module")
def kangaroo_error():
    return _error(pkm_pin.load_mechanism(KANGAROO))


def test_kangaroo_like_reports_its_open_welds(kangaroo_error):
    """kangaroo_like's eleven welds (Gepetto's 6d contacts, read as Gepetto's loader
    reads them): the best configuration closes every orientation to below 1° but leaves
    the points of eight loops apart, closedloop7 (the knee four-bar) worst at about
    80 mm; no limit holds it (the file gives none), so the hint names lengths, frames
    or a closure stricter than its joint."""
    d = kangaroo_error.diagnosis
    assert d.gaps[0].name == "closedloop7_BCclosedloop7_A"
    assert 0.06 < d.gaps[0].distance < 0.1
    assert len(d.gaps) >= 6 and all(g.angle < ANGLE_CLOSED for g in d.gaps)
    assert d.at_limits == ()
    assert "orientations (nearly) close but their points stay apart" in d.hint


def test_true_talos_closes_only_beyond_its_shin_limits():
    """true_talos_2_legs: both ankle loops (3d) stay 0.2 m open with each
    leg_*_shin_joint at its lower limit 0; without that limit they close with the shin
    at a negative angle (the crank points up for positive angles)."""
    e = _error(pkm_pin.load_mechanism(TALOS))
    d = e.diagnosis
    assert {g.name for g in d.gaps} == {"closedloop1_ACclosedloop1_B",
                                        "closedloop2_ACclosedloop2_B"}
    assert sorted(h.joint for h in d.at_limits) == ["leg_left_shin_joint",
                                                    "leg_right_shin_joint"]
    assert all(h.side == "lower" and h.value == 0.0 and h.needed < 0 for h in d.at_limits)
    assert d.closes_without_limits


# ------------------------------------------------------------ view and CLI
def test_view_draws_the_open_tree_with_one_coloured_gap_per_open_loop(tmp_path):
    """``view`` of the too-short four-bar: the tree at the best configuration, a bar
    and a line for the gap between the two frames in the first gap colour with its
    legend entry, a title saying that it does not assemble; no idle axis nor wrench."""
    link = Linkage(four_bar(lengths=SHORT))
    path = tmp_path / "open.html"
    scene = view(link, html=path)
    assert isinstance(scene.error, LoopClosureError) and scene.analysis is None
    assert "does not assemble: 1 loop open" in scene.title_lines[1]
    root = f"/meshcat/pkm/{node_name(link.name)}"
    commands = page_commands(path.read_text(encoding="utf-8"))
    objects = {c["path"]: c for c in commands if c["type"] == "set_object"}
    assert {f"{root}/gaps/loop/bar", f"{root}/gaps/loop/line"} <= set(objects)
    assert not any(p.startswith((f"{root}/idle", f"{root}/wrenches")) for p in objects)
    line = objects[f"{root}/gaps/loop/line"]["object"]
    packed = line["geometries"][0]["data"]["attributes"]["position"]["array"]
    points = np.frombuffer(packed.data, dtype=np.float32)  # meshcat's Float32Array
    (gap,) = scene.gaps
    np.testing.assert_allclose(points.reshape(-1, 3), [gap.a, gap.b], atol=1e-6)
    entry = scene.legend[-1]
    assert entry.kind == "gap:loop" and entry.colours == (GAP_COLOURS[0],)
    assert re.search(r"\b50[0-5](\.\d+)? mm", entry.note)


def test_cli_view_draws_a_file_that_does_not_assemble_and_analyze_refuses_it(
        tmp_path, capsys):
    """``pkm-pin view kangaroo_like`` writes the page and prints the message (exit 0);
    ``analyze`` stays an error of one line naming the open loops (exit 2)."""
    page = tmp_path / "k.html"
    assert main(["view", str(KANGAROO), "--html", str(page)]) == 0
    out = capsys.readouterr().out
    assert page.is_file()
    assert "open       drawn at the best configuration reached: loop " \
        "'closedloop7_BCclosedloop7_A' does not close" in out
    assert main(["analyze", str(KANGAROO)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("pkm-pin: error: ")
    assert "open loops: 'closedloop7_BCclosedloop7_A'" in err and "hint: " in err


def test_errors_survive_pickling():
    """A LoopClosureError (four-bar driven to an unreachable crank angle: targets not
    met, a loop open by tens of mm, the crank at a limit) comes back from pickle with
    its class, message, loop, residual, best q and diagnosis; so do AssemblyError and
    an InputError (an error raised in a worker process reaches the parent pickled)."""
    import pickle

    from pkm_pin.errors import AssemblyError, InputError
    from pkm_pin.linkage import LoopClosureError

    link = pkm_pin.load_mechanism(Path(__file__).resolve().parents[1] / "models" / "loops"
                                  / "four_bar.urdf", backend="general")
    with pytest.raises(LoopClosureError) as raised:
        link.forward_kinematics([5.0] * len(link.actuated))
    err = raised.value
    back = pickle.loads(pickle.dumps(err))
    assert type(back) is LoopClosureError and str(back) == str(err)
    assert back.leg == err.leg and back.residual == err.residual > 0.5
    assert np.array_equal(back.q, err.q) and back.diagnosis.words() == err.diagnosis.words()
    assert "mm" in back.diagnosis.words()
    for e in (AssemblyError("leg 2", 0.25, "8 starts"), InputError("bad --q")):
        b = pickle.loads(pickle.dumps(e))
        assert type(b) is type(e) and str(b) == str(e) and b.args == e.args
    assert pickle.loads(pickle.dumps(AssemblyError("leg 2", 0.25))).residual == 0.25


PAIR = """<mujoco model="parallelogram_pair">
  <worldbody>
    <body name="crank1">
      <joint name="q1" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0 0 0.1" size="0.005"/>
      <body name="coupler" pos="0 0 0.1">
        <joint name="q2" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.005"/>
        <site name="s1" pos="0.1 0 0"/>
        <site name="s1z" pos="0.1 0.01 0"/>
      </body>
    </body>
    <body name="crank2" pos="0.1 0 0">
      <joint name="q3" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0 0 0.1" size="0.005"/>
      <site name="s2" pos="0 0 0.1"/>
      <site name="s2z" pos="0 {dy} 0.1"/>
    </body>
  </worldbody>
  <equality><connect site1="s1" site2="s2"/><connect site1="s1z" site2="s2z"/></equality>
  <actuator><position joint="q1"/></actuator>
</mujoco>
"""


@pytest.mark.parametrize("gap", [0.0, 5e-10, 1e-6])
def test_redundant_closures_off_by_rounding_are_reconciled(tmp_path, gap):
    """A parallelogram whose coupler–crank joint is written as two site-form connects
    (two points on the hinge's axis, as Menagerie's ToddlerBot neck): the second pair of
    sites `gap` apart along the axis, which no joint closes. Exact: loaded as is. 5e-10 m
    (printed digits, relative 5e-9 ≤ ASSEMBLY_CHECK_RTOL): the second closure's point is
    moved onto the first by that gap, with a note, and the mechanism assembles (DOF 1).
    1e-6 m (a wrong file): left open, and its assembly is refused naming the loop."""
    from pkm_pin.closure_gaps import reconcile
    from pkm_pin.linkage import LoopClosureError
    from pkm_pin.model import read_mjcf

    path = tmp_path / "pair.xml"
    path.write_text(PAIR.format(dy=repr(0.01 + gap)))
    model = read_mjcf(path)
    fixed = reconcile(model)
    if gap == 0.0:
        assert fixed is model
    elif gap < 1e-8:
        assert fixed.closures[0] == model.closures[0]
        moved = (fixed.closures[1].placement_b.translation
                 - model.closures[1].placement_b.translation)
        np.testing.assert_allclose(moved, [0.0, -gap, 0.0], atol=1e-15)
        assert float(np.linalg.norm(fixed.closure_residual(fixed.reference))) <= 1e-12
        assert "closure connect1: its second frame moved onto the first by at most 5e-10 m" \
            in fixed.notes[-1]
        mech = pkm_pin.load_mechanism(path)
        assert mech.mobility().dof == 1 and mech.model.notes[-1] == fixed.notes[-1]
    else:
        assert fixed is model
        with pytest.raises(LoopClosureError, match="loop 'connect1' does not close"):
            pkm_pin.load_mechanism(path).home_assembly
