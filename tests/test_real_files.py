"""Robot files as people write them (issue 25): names shared between MJCF bodies, joints
and sites, formats pkm_pin does not read, strict JSON."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pkm_pin

LOOPS = Path(__file__).resolve().parents[1] / "models" / "loops"


def _clashing_four_bar(tmp_path: Path, sites: bool) -> Path:
    """The shipped MJCF four-bar with every joint named like its body (Cassie's habit)
    and, with ``sites``, the loop closed between two sites also named like bodies."""
    text = (LOOPS / "four_bar.xml").read_text()
    for body in ("crank", "coupler", "rocker"):
        text = text.replace(f'"{body}_joint"', f'"{body}"')
    if sites:
        text = text.replace('<joint name="coupler" type="hinge" axis="0 0 1"/>',
                            '<joint name="coupler" type="hinge" axis="0 0 1"/>'
                            '<site name="coupler" pos="0.09 0 0"/>')
        text = text.replace('<joint name="rocker" type="hinge" axis="0 0 1"/>',
                            '<joint name="rocker" type="hinge" axis="0 0 1"/>'
                            '<site name="rocker" pos="0.07 0 0"/>')
        text = text.replace('body1="coupler" body2="rocker" anchor="0.09 0 0"',
                            'site1="coupler" site2="rocker"')
    path = tmp_path / "four_bar_clash.xml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("sites", [False, True])
def test_mjcf_names_shared_by_bodies_joints_and_sites(tmp_path, sites):
    """Bodies keep their names, joint and site frames get a suffix; the linkage is the
    shipped four-bar (same joints, closure residual and analysis at home)."""
    link = pkm_pin.load_mechanism(_clashing_four_bar(tmp_path, sites))
    ref = pkm_pin.load_mechanism(LOOPS / "four_bar.xml")
    names = [f.name for f in link.model.tree.frames]
    assert len(names) == len(set(names)) and "crank_joint" in names
    assert link.actuated == ("crank",)
    c = link.model.closures[0]
    assert (c.frame_a, c.frame_b) == (("coupler_site", "rocker_site") if sites
                                      else ("coupler", "rocker"))
    a, b = link.assemble(), ref.assemble()
    np.testing.assert_allclose(a.q, b.q, atol=1e-10)
    assert link.analyze(a).dof == ref.analyze(b).dof == 1
    np.testing.assert_allclose(link.analyze(a).forward_velocity([1.0]),
                               ref.analyze(b).forward_velocity([1.0]), atol=1e-10)
    # the per-leg reading too (its legs' chains used to clash: "Several frames match")
    legs = pkm_pin.load_mechanism(_clashing_four_bar(tmp_path, sites), backend="legs")
    ref_legs = pkm_pin.load_mechanism(LOOPS / "four_bar.xml", backend="legs")
    np.testing.assert_allclose(legs.home_analysis.forward_velocity([1.0]),
                               ref_legs.home_analysis.forward_velocity([1.0]), atol=1e-10)
    np.testing.assert_allclose(legs.home_analysis.A, ref_legs.home_analysis.A, atol=1e-10)


@pytest.mark.parametrize("name,words", [
    ("robot.sdf", "SDF is not read"),
    ("robot.yaml", "is a closures file: give the .urdf it belongs to"),
    ("robot", "unknown suffix '(none)': pkm_pin reads a .toml mechanism file"),
])
def test_formats_not_read_are_named_with_what_is_read(tmp_path, capsys, name, words):
    """A file of a format pkm_pin does not read gets one line saying so and listing the
    formats it reads (an .sdf used to be reported as 'not valid TOML')."""
    from pkm_pin.cli import main

    path = tmp_path / name
    path.write_text('<sdf version="1.6"><model name="m"><link name="a"/></model></sdf>\n')
    assert main(["analyze", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and words in err and "TOML:" not in err
    assert "MJCF file (.xml, .mjcf)" in err or "closures file" in err


def test_strict_json_turns_non_finite_numbers_into_null_with_a_reason():
    """strict_json: nan and ±inf become null, listed under non_finite with where they
    stood; numpy numbers and arrays become plain JSON; a strict parser reads it."""
    import json

    from pkm_pin.report import strict_json

    text = strict_json({"A": np.array([[1.0, np.nan], [np.inf, 2.0]]), "dof": np.int64(3),
                        "ok": np.bool_(True), "indices": {"type_I": -np.inf}})
    data = json.loads(text, parse_constant=lambda c: pytest.fail(f"non-strict {c}"))
    assert data["A"] == [[1.0, None], [None, 2.0]] and data["dof"] == 3 and data["ok"] is True
    assert data["non_finite"] == {"A[0][1]": "nan", "A[1][0]": "inf",
                                  "indices.type_I": "-inf"}
    assert "non_finite" not in json.loads(strict_json({"x": 1.0}))


@pytest.mark.parametrize("spec", ["stewart", str(LOOPS / "five_bar.urdf")])
def test_a_failing_optional_section_leaves_the_rest_of_the_report(monkeypatch, capsys,
                                                                  spec):
    """An optional section that fails (battobot's transmission ended in IndexError) is
    reported as not computed with its error; the analysis is still printed, exit 0,
    and the JSON names the failed section (one report for both backends: a platform
    machine and a linkage)."""
    import json

    from pkm_pin import report
    from pkm_pin.cli import main

    def broken(*args):
        raise IndexError("index 0 is out of bounds for axis 0 with size 0")

    monkeypatch.setattr(report, "_transmission_of", broken)
    assert main(["analyze", spec]) == 0
    text = capsys.readouterr().out
    assert "transmission       not computed (IndexError: index 0 is out of bounds" in text
    assert "DOF" in text and "singularity" in text
    assert main(["analyze", spec, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["transmission"] is None and "IndexError" in data["failed_sections"]["transmission"]
    assert data["dof"] >= 2


def test_closure_of_a_body_onto_itself_is_refused_and_duplicates_are_named(capsys):
    """A closure between two frames of one body is an error naming it; a closure that
    repeats another (either way round) is named in the report, its rows redundant."""
    from linkage_models import four_bar

    from pkm_pin.errors import InputError
    from pkm_pin.linkage import Linkage
    from pkm_pin.model import Closure, ClosureModel
    from pkm_pin.model.closure_model import duplicate_closures
    from pkm_pin.report import linkage_report_data
    from pkm_pin.report import text as linkage_text

    base = four_bar()
    with pytest.raises(InputError, match="closure 'x' of the tree joins frame 'crank_body' to "
                                         "itself"):
        ClosureModel(base.tree, (Closure("point", "crank_body", "crank_body", name="x"),),
                     ("crank",), "rocker_body")
    c = base.closures[0]
    again = Closure(c.kind, c.frame_b, c.frame_a, c.placement_b, c.placement_a, name="again")
    model = ClosureModel(base.tree, base.closures + (again,), ("crank",), "rocker_body")
    assert duplicate_closures(model.closures) == [("again", c.name)]
    q = Linkage(base).assemble().q
    single, double = Linkage(base).analyze(q), Linkage(model).analyze(q)
    assert double.dof == single.dof == 1
    assert double.redundant_constraints == single.redundant_constraints + 3
    r = linkage_report_data(Linkage(model), Linkage(model).assemble(q))
    assert r["duplicate_closures"] == [["again", c.name]]
    assert f"duplicate closure  'again' repeats {c.name!r}" in linkage_text(r)


def test_five_bar_with_a_body_output_transmits_well_as_its_legs_do():
    """The shipped five-bar analysed as a body (its tree runs through motor 1's chain to
    the output): the actuator on the output's own chain has that chain as its leg, so
    the healthy five-bar reads healthy (ITI near 1, LTI 0.90, the legs backend's LTI),
    where it used to read 'LTI = 0: leg mot1 transmits poorly: ITI 0.00'."""
    link = pkm_pin.load_mechanism(LOOPS / "five_bar.xml")
    a = link.home_assembly
    tr = link.transmission(a)
    legs = link.legs_mechanism.analyze(link.legs_assembly(a)).transmission
    assert np.all(tr.iti > 0.99) and np.all(legs.iti > 0.99)
    assert tr.lti == pytest.approx(legs.lti, abs=1e-9) and tr.lti > 0.9
    np.testing.assert_allclose(tr.oti[1], legs.oti[1], atol=1e-9)
    assert "ITI 0.00" not in tr.worst


def test_joints_written_without_a_range_move(tmp_path):
    """A URDF whose <limit> elements give no lower/upper (Onshape exports, Gepetto's
    kangaroo_like) has unlimited joints, not URDF's default range [0, 0] that pinned
    every joint at 0: forward kinematics of the four-bar so written matches the shipped
    file's."""
    import re
    import shutil

    text = (LOOPS / "four_bar.urdf").read_text()
    bare = re.sub(r'\s(lower|upper)="[^"]*"', "", text)
    assert "lower=" not in bare
    (tmp_path / "four_bar.urdf").write_text(bare)
    shutil.copy(LOOPS / "four_bar.yaml", tmp_path / "four_bar.yaml")
    link = pkm_pin.load_mechanism(tmp_path / "four_bar.urdf")
    assert not np.isfinite(link.model.tree.lowerPositionLimit).any()
    ref = pkm_pin.load_mechanism(LOOPS / "four_bar.urdf")
    q_a = ref.home_assembly.q_actuated + 0.3
    np.testing.assert_allclose(link.forward_kinematics(q_a, link.home_assembly).q,
                               ref.forward_kinematics(q_a, ref.home_assembly).q, atol=1e-9)


def test_report_lists_which_joints_each_actuator_identifier_picked(tmp_path, capsys):
    """An actuator identifier that is not a joint's own name (Gepetto's substring rule)
    is shown with the joints it picked, in the text and in --json."""
    import json
    import shutil

    from pkm_pin.cli import main

    shutil.copy(LOOPS / "five_bar.urdf", tmp_path / "five_bar.urdf")
    text = (LOOPS / "five_bar.yaml").read_text().replace("['mot1', 'mot2']", "['mot']")
    (tmp_path / "five_bar.yaml").write_text(text)
    assert main(["analyze", str(tmp_path / "five_bar.urdf")]) == 0
    assert "(identifiers: 'mot' picked mot1, mot2)" in capsys.readouterr().out
    assert main(["analyze", str(tmp_path / "five_bar.urdf"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["actuator_matches"] == {"mot": ["mot1", "mot2"]}


def test_a_free_joint_at_the_root_is_the_base(tmp_path, capsys):
    """An MJCF whose root body floats (a <freejoint/>, as humanoids and Menagerie robots
    are written) is analysed relative to that body, held as the base: the four-bar so
    written has the shipped one's joints, configuration and DOF, and the report says
    so."""
    from pkm_pin.cli import main

    text = (LOOPS / "four_bar.xml").read_text().replace(
        '<body name="base">', '<body name="base" pos="0.3 -0.2 1.0"><freejoint/>', 1)
    path = tmp_path / "floating_four_bar.xml"
    path.write_text(text)
    link, ref = pkm_pin.load_mechanism(path), pkm_pin.load_mechanism(LOOPS / "four_bar.xml")
    assert list(link.model.tree.names) == list(ref.model.tree.names)
    assert link.model.notes == ("base has a free joint in the file: it is held as the base, "
                                "the mechanism analysed relative to it",)
    a, b = link.home_assembly, ref.home_assembly
    np.testing.assert_allclose(a.q, b.q, atol=1e-10)
    assert link.analyze(a).dof == ref.analyze(b).dof == 1
    assert main(["analyze", str(path)]) == 0
    assert "note               base has a free joint in the file" in capsys.readouterr().out


def test_a_keyframe_of_a_floating_robot_loses_its_free_joints_coordinates(tmp_path):
    """A <key> written for the floating robot (7 free-joint coordinates first, as
    Menagerie's Cassie ``home``) loads once the free joint is held: its joint part is
    kept as Pinocchio's reference configuration of that name, in the file's order."""
    text = (LOOPS / "four_bar.xml").read_text().replace(
        '<body name="base">', '<body name="base" pos="0.3 -0.2 1.0"><freejoint/>', 1)
    key = ('<keyframe><key name="home" qpos="0.3 -0.2 1 1 0 0 0 0.1 0.2 0.3" '
           'qvel="0 0 0 0 0 0 1 2 3"/></keyframe></mujoco>')
    path = tmp_path / "floating_four_bar.xml"
    path.write_text(text.replace("</mujoco>", key, 1))
    link = pkm_pin.load_mechanism(path)
    home = link.model.tree.referenceConfigurations["home"]
    np.testing.assert_array_equal(home, [0.1, 0.2, 0.3])
    assert link.model.tree.nq == 3


def test_check_names_a_duplicate_closure_and_refuses_a_self_closure(tmp_path, capsys):
    """Through the files: a closures file that closes the four-bar's loop twice (the
    second the other way round) checks with a warning naming both closures (exit 1),
    the DOF still 1 and 3 more redundant rows than the single loop's; a closure of a
    frame onto itself, in a closures file or an MJCF <connect>, is one error line
    (exit 2)."""
    import shutil

    from pkm_pin.cli import main

    shutil.copy(LOOPS / "four_bar.urdf", tmp_path / "four_bar.urdf")
    yaml = tmp_path / "four_bar.yaml"
    yaml.write_text("closed_loop: [['coupler_tip', 'rocker_tip'], ['rocker_tip', "
                    "'coupler_tip']]\ntype: ['3d', '3d']\nname_mot: ['crank_joint']\n")
    assert main(["check", str(tmp_path / "four_bar.urdf")]) == 1
    out = capsys.readouterr().out
    assert ("warn  closure 'rocker_tipCcoupler_tip' repeats 'coupler_tipCrocker_tip': its "
            "rows are redundant") in out
    assert "DOF 1, idle DOF 0" in out and "redundant closure equations 4" in out
    assert main(["check", str(LOOPS / "four_bar.urdf"), "--backend", "general"]) == 0
    assert "redundant closure equations 1" in capsys.readouterr().out
    assert main(["check", str(LOOPS / "four_bar.urdf")]) == 0  # read per leg: its legs'
    assert "redundant constraints 1" in capsys.readouterr().out
    yaml.write_text("closed_loop: [['coupler_tip', 'coupler_tip']]\ntype: ['3d']\n"
                    "name_mot: ['crank_joint']\n")
    assert main(["check", str(tmp_path / "four_bar.urdf")]) == 2
    err = capsys.readouterr().err
    assert "joins frame 'coupler_tip' to itself" in err and len(err.splitlines()) == 1
    xml = tmp_path / "self.xml"
    xml.write_text((LOOPS / "four_bar.xml").read_text().replace('body2="rocker"',
                                                                 'body2="coupler"'))
    assert main(["analyze", str(xml)]) == 2
    err = capsys.readouterr().err
    assert "closure 'coupler_rocker'" in err and "to itself" in err


def test_platform_text_report_gives_its_summary_before_the_tables():
    """The platform report (a 3-RPR at a type II pose): DOF, Grübler count, class II,
    the uncontrolled twist and the indices (type_II below 1e-12) come before the twist,
    wrench and A/B tables; a non-finite index reads 'undefined', never nan or inf."""
    import math

    from pkm_pin import report
    from pkm_pin.builders import MECHANISMS, rpr3_type2_pose

    an = MECHANISMS["rpr3"]().build().analyze(rpr3_type2_pose())
    data = report.report_data(an)
    lines = report.text(data).splitlines()
    order = [next(i for i, x in enumerate(lines) if x.startswith(h)) for h in (
        "DOF ", "Grübler count ", "singularity        II", "uncontrolled twist rotation",
        "indices ", "platform twists", "A (actuation", "B:")]
    # the summary first: nothing but what the mechanism is, its output and pose, its
    # DOF and idle motions before the counts and indices, every table after them
    assert order == sorted(order) and order[4] < lines.index("joints (q):")
    assert lines[order[0] - 1].startswith("pose ") and order[0] <= 5
    assert data["indices"]["type_II"] < 1e-12
    data["indices"] = {"type_I": math.inf, "type_II": math.nan, "condition_A": None}
    (line,) = [x for x in report.text(data).splitlines() if x.startswith("indices")]
    assert line.split(None, 1)[1] == ("type_I = undefined, type_II = undefined, "
                                      "condition_A = undefined")


@pytest.mark.parametrize("path,undefined,words", [
    ("gepetto/battobot_6d/robot.urdf", {"type_II", "condition_A"},
     "6 actuators (hipz_right, hipx_right, hipy_right, motor_ankle1_right, "
     "motor_ankle2_right, motor_knee_right) exert no wrench on the output: zero rows of A"),
    ("pinocchio/closed_chain.xml", {"type_I", "condition_A"}, "no actuator: A has no row"),
    ("gepetto/5bar_linkage_iso3d/robot.urdf", set(), ""),
])
def test_every_null_index_of_the_json_says_why(capsys, path, undefined, words):
    """analyze --json: each index that is null has its reason under indices_undefined
    (the other leg's motors of a biped read with one foot; no motor at all), and only
    those; a regular five-bar has none; the text prints each reason under the indices."""
    import json

    from pkm_pin.cli import main

    spec = str(Path(__file__).resolve().parent / "data" / path)
    assert main(["analyze", spec, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    nulls = {k for k, v in data["indices"].items() if v is None}
    assert nulls == set(data["indices_undefined"]) == undefined
    assert all(words in why for why in data["indices_undefined"].values())
    assert main(["analyze", spec]) == 0
    text = capsys.readouterr().out
    assert all(f"    {k} undefined (" in text for k in undefined)


@pytest.mark.parametrize("path", ["gepetto/cassie_like/robot.urdf",
                                  "gepetto/digit_like/robot.urdf",
                                  "gepetto/talos_like/robot.urdf",
                                  "gepetto/wl16_like/robot.urdf"])
def test_iti_of_a_regular_leg_is_zero_only_where_its_actuator_moves_nothing(path):
    """Legs whose knee and ankle pitch joints are held by rods (their foot's support
    chain has four parallel revolutes): at the regular home assembly (every B_ii > 0)
    every ITI and every OTI is positive, the analysis' own actuation wrench standing in
    where the chain reading gives none. Cassie-like's thigh and knee read 0.795 and
    0.954 and the leg transmits well (LTI 0.78 ≥ 0.7); before, cassie_like and
    digit_like read 'LTI = 0' (ITI 0 at a regular pose)."""
    from pkm_pin.transmission import GOOD_LTI

    link = pkm_pin.load_mechanism(Path(__file__).resolve().parent / "data" / path)
    a = link.home_assembly
    an = link.analyze(a)
    assert an.singularity == "none"
    tr = link.transmission(a, analysis=an)
    assert np.all(tr.iti > 1e-3) and np.all(tr.oti > 1e-3)
    assert np.all(np.abs(np.diag(an.B)) > 1e-3)
    if path.startswith("gepetto/cassie_like"):
        assert tr.iti[2:4] == pytest.approx([0.795, 0.954], abs=1e-3)
        assert tr.lti == pytest.approx(0.783, abs=1e-3) and tr.lti >= GOOD_LTI


def test_disney_like_workspace_reports_a_dead_actuator_without_a_numpy_warning():
    """Gepetto's ``disney_like`` assembles at home with two actuators whose wrenches on
    the foot vanish (class III): its workspace's carried determinant there is 0 (``A``
    singular), not nan, and no numpy warning reaches the user."""
    import warnings

    from pkm_pin import load_mechanism

    mech = load_mechanism(Path(__file__).resolve().parent / "data" / "gepetto" / "disney_like"
                          / "robot.urdf")
    norms = np.linalg.norm(mech.home_analysis.A, axis=1)
    assert mech.home_analysis.singularity == "III" and np.sum(norms == 0.0) == 2
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ws = mech.workspace(n=3)
    ok = np.asarray(ws.values["ok"], bool)
    assert ok.any()
    assert np.all(np.asarray(ws.values["det"])[ok] == 0.0)


def test_ik_all_of_a_continuum_says_so_without_nan():
    """An error with no measured residual (inverse_kinematics_all where the assemblies
    form a continuum) gives the reason alone: no "relative pose error of nan"."""
    from pkm_pin.errors import AssemblyError

    e = AssemblyError("output pose", float("nan"), "the assemblies do not settle")
    assert str(e) == "the output cannot reach the pose: the assemblies do not settle"
    assert "nan" not in str(AssemblyError("3", float("inf")))
    assert "relative pose error of 0.5" in str(AssemblyError("3", 0.5))


def test_a_forward_kinematics_error_never_prints_nan(capsys):
    """disney_like driven towards actuated values its home branch does not reach: the
    continuation's sentence gives the type II closeness index at the stop and at the
    guess, where an actuator exerts no wrench on the output (class III at home): it says
    'undefined' and why, never 'nan'."""
    import re

    from pkm_pin.cli import main

    path = Path(__file__).parent / "data" / "gepetto" / "disney_like" / "robot.urdf"
    assert main(["analyze", str(path), "--q", "2.0", "-1.25", "0.4", "1.6", "0.45",
                 "-0.1"]) == 2
    err = capsys.readouterr().err
    assert "undefined at the guess; undefined: an actuator exerts no wrench" in err
    assert not re.search(r"\bnan\b", err)
