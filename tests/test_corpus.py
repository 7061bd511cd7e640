"""The corpus of published closed-loop files (tests/data, issue 25): each loads, assembles
from its reference and has the mobility and the default output of the table in
docs/closed_loops.md ("Corpus of published files"); the default output is the body the
mechanism exists to move (pkm_pin.output_choice)."""

from __future__ import annotations

import json
import re
import shutil
import warnings
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkm_pin
from pkm_pin.cli import main
from pkm_pin.linkage import Linkage, LoopClosureError
from pkm_pin.model import read_extended_urdf
from pkm_pin.output_choice import choose_output, name_score, rank_outputs

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"
LOOPS = ROOT / "models" / "loops"

#: Why a file does not assemble (the files' own geometry: docs/closed_loops.md, "When a
#: file does not assemble"; the error's diagnosis is tested in tests/test_closure_gaps.py).
NO_ASSEMBLY = "does not assemble from its reference: {}"
#: Why a two-legged robot reads as type I with any one output frame.
TWO_LEGS = ("two legs of six motors: one output frame moves with one leg's six motors, "
            "not with the other's, so inverse = 0 (type I) by construction; it needs "
            "several outputs")
#: The same for kangaroo_like_2legs, whose linear actuators' short strokes move the foot
#: far: forward is small (3.7e-3) without any singularity (each leg alone: class none).
TWO_LEGS_PISTONS = TWO_LEGS + "; forward is small (short piston strokes), not zero"
#: pkm_pin's corrected closures file for kangaroo_like (tests/data/corrected/README.md).
KANGAROO_CORRECTED = DATA / "corrected" / "kangaroo_like.yaml"


@dataclass(frozen=True)
class Case:
    """One corpus file and what it must give (None: not known until it assembles)."""

    path: str
    dof: int | None
    idle: int | None
    redundant: int | None
    independent: int | None
    output: str
    ties: tuple = ()
    motion: str | None = None
    singularity: str = "none"
    no_assembly: str = ""  # the loop that does not close, when it does not assemble
    singular_why: str = ""  # why the default output is singular at home, when it is

    @property
    def id(self) -> str:
        return self.path.split("/", 1)[1].rsplit("/", 1)[0]


CORPUS = [
    Case("gepetto/5bar_linkage/robot.urdf", 3, 1, 3, 2, "effector", ("rod_2",), "1T1R"),
    Case("gepetto/5bar_linkage_iso3d/robot.urdf", 2, 0, 0, 2, "effector", (), "1T1R"),
    Case("gepetto/5bar_linkage_iso6d/robot.urdf", 2, 0, 0, 2, "effector", (), "1T1R"),
    Case("gepetto/robot_delta/robot.urdf", 5, 3, 9, 2, "effector",
         ("transmission_connecting_rod",), "2T"),
    Case("gepetto/cassie_like/robot.urdf", 7, 2, 0, 5, "foot", ("servo_gauche",), "2T3R"),
    Case("gepetto/digit_like/robot.urdf", 9, 3, 0, 6, "foot", (), "3T3R"),
    Case("gepetto/talos_like/robot.urdf", 7, 1, 0, 6, "foot", (), "3T3R"),
    Case("gepetto/disney_like/robot.urdf", 9, 3, 0, 6, "foot", (), "3T3R", "III",
         singular_why="one idle motion (free_universal4 and the ankle's three revolutes "
         "ankle_universal_2_rev0-2, free_hip_x at 1.5e-3) moves the foot (homogenised "
         "singular value 5.2e-4), so no body fits and the foot reads forward = inverse = 0: "
         "free_universal4's axis passes 0.295 mm beside the centre of the ball joint "
         "ankle_universal_2, whose fourth rotation it would otherwise only repeat"),
    Case("gepetto/battobot_6d/robot.urdf", 12, 0, 0, 12, "foot_right", ("foot_left",),
         "3T3R", "I", singular_why=TWO_LEGS),
    Case("gepetto/digit_like_2legs/robot.urdf", 12, 0, 0, 12, "foot", ("foot_left",),
         "3T3R", "I", singular_why=TWO_LEGS),
    Case("gepetto/digit_like_2legs_6D/robot.urdf", 12, 0, 0, 12, "foot", ("foot_left",),
         "3T3R", "I", singular_why=TWO_LEGS),
    Case("gepetto/digit_like_2legs_old/robot.urdf", 12, 0, 0, 12, "foot", ("foot_left",),
         "3T3R", "I", singular_why=TWO_LEGS),
    Case("gepetto/old/digit_like_2legs/robot.urdf", 18, 6, 0, 12, "foot", ("foot_left",),
         "3T3R", "I", singular_why=TWO_LEGS),
    Case("gepetto/kangaroo_like/robot.urdf", None, None, None, None, "hip_center",
         no_assembly="its welds' orientations close, eight loops' points stay apart, "
         "'closedloop7_BCclosedloop7_A' by 81 mm: every loop typed 6d (generateYAML's "
         "default), the pair closedloop1 dropped, 'sherical_4bar' a revolute; with the "
         "two-leg export's kinds it assembles (tests/data/corrected)"),
    Case("gepetto/kangaroo_like_2legs/robot.urdf", 40, 28, 0, 12, "foot", ("foot_2",),
         "3T3R", "I", singular_why=TWO_LEGS_PISTONS),
    Case("gepetto/true_talos_2_legs/talos_full_v2.urdf", None, None, None, None, "imu_link",
         no_assembly="both ankle loops close only with leg_*_shin_joint at -0.867 rad, "
         "outside the file's range [0, 2.618]"),
    Case("pinocchio/closed_chain.xml", 16, 16, 2, 0, "left-foot",
         ("right-foot", "left-foot-crank", "right-foot-crank"), "2T3R", "II",
         singular_why="no <actuator> in the file: every motion is idle"),
    Case("menagerie/robotiq_2f85/2f85.xml", 3, 2, 2, 1, "left_driver", (), "1R"),
    Case("menagerie/agility_cassie/cassie.xml", 16, 6, 2, 10, "left-foot",
         ("right-foot", "left-foot-crank", "right-foot-crank"), "2T3R", "III",
         singular_why="the knee and heel springs (stiffness, no motor: ClosureModel.springs, "
         "held when the output is chosen, so the foot is) are idle and move the foot: a "
         "rigid-body reading of a compliant leg"),
    Case("ankles/g1_ankle/g1_ankle.xml", 2, 0, 0, 2, "roll_link", (), "2R"),
    Case("ankles/tiangong_ankle/tg10_ankle.xml", 4, 2, 0, 2, "foot_link", (), "2R"),
]

GEPETTO = [c for c in CORPUS if c.path.startswith("gepetto/")]


def _marks(case: Case, regular: bool = False) -> list:
    if case.no_assembly:
        return [pytest.mark.xfail(strict=True, raises=LoopClosureError,
                                  reason=NO_ASSEMBLY.format(case.no_assembly))]
    if regular and case.singular_why:
        return [pytest.mark.xfail(strict=True, raises=AssertionError,
                                  reason=case.singular_why)]
    return []


@lru_cache(maxsize=None)
def _loaded(path: str):
    """``(linkage, home assembly or the error it raised)``, loaded once per session."""
    link = pkm_pin.load_mechanism(DATA / path)
    try:
        return link, link.home_assembly
    except LoopClosureError as e:
        return link, e


def _home(path: str):
    link, assembly = _loaded(path)
    if isinstance(assembly, Exception):
        raise assembly
    return link, assembly


@pytest.mark.parametrize("case", [pytest.param(c, id=c.id, marks=_marks(c)) for c in CORPUS])
def test_corpus_file_assembles_with_its_mobility_and_default_output(case):
    """The file loads, assembles from its reference, and has the table's dof, idle DOF,
    redundant closure rows, independent actuators, default output (and its ties) and
    output motion."""
    link, a = _home(case.path)
    assert case.dof is not None, "it assembles now: put its numbers in CORPUS and the doc"
    mob = link.mobility(a.q)
    assert (mob.dof, mob.idle_dof, mob.redundant_constraints,
            len(mob.independent_actuators)) == (case.dof, case.idle, case.redundant,
                                                case.independent)
    assert link.output == case.output
    assert choose_output(link.model, a.q).ties == case.ties
    assert link.analyze(a).motion_type == case.motion


@pytest.mark.parametrize("case", [c for c in CORPUS if c.no_assembly], ids=lambda c: c.id)
def test_a_file_that_does_not_assemble_keeps_the_readers_output(case):
    """Without an assembly the rule cannot be evaluated: the readers' default (the last
    link no closure uses) stays, and the load itself does not fail."""
    link, assembly = _loaded(case.path)
    assert isinstance(assembly, LoopClosureError)
    assert link.output == case.output == read_extended_urdf(DATA / case.path).output


def test_kangaroo_like_notes_what_its_closures_file_misses():
    """The reader's notes on kangaroo_like (the message of its failed assembly ends with
    them): the pair closedloop1 the YAML leaves out, the revolute 'sherical_4bar'."""
    link, error = _loaded("gepetto/kangaroo_like/robot.urdf")
    notes = link.model.notes
    assert len(notes) == 2 and "'sherical_4bar'" in notes[0]
    assert "(closedloop1_A/closedloop1_B)" in notes[1]
    assert str(error).endswith("reader notes: " + "; ".join(notes))


def test_kangaroo_like_with_the_two_leg_exports_closure_kinds_is_one_of_its_legs():
    """kangaroo_like with pkm_pin's corrected closures file (the kinds its authors gave
    the same loops in kangaroo_like_2legs, the dropped pair closedloop1, 'sherical_4bar'
    spherical) assembles: 65 velocity coordinates (sherical_4bar's 3), 45 closure rows
    (nine points, three welds), all independent: isostatic (Grübler 20), 6 independent
    motors, 14 idle spins (rods and piston halves with a ball joint at each end); its
    foot fits, 3T3R, regular. Each leg of kangaroo_like_2legs, a separate export of the
    same design, gives the same numbers (tests/test_submechanisms.py), so the geometry is
    consistent and the published file's kinds are what keeps it open."""
    link = pkm_pin.load_mechanism(DATA / "gepetto/kangaroo_like/robot.urdf",
                                  closures=KANGAROO_CORRECTED)
    a = link.home_assembly
    mob = link.mobility(a.q)
    assert (mob.dof, mob.idle_dof, mob.redundant_constraints, mob.grubler,
            len(mob.independent_actuators)) == (20, 14, 0, 20, 6)
    assert link.output == "foot" and link.model.notes == ()
    an = link.analyze(a)
    assert an.motion_type == "3T3R" and an.singularity == "none"


@pytest.mark.parametrize("case", [pytest.param(c, id=c.id, marks=_marks(c, regular=True))
                                  for c in GEPETTO])
def test_default_output_of_a_gepetto_model_is_regular_at_home(case):
    """With the default output no Gepetto model reports a type I, II or III singularity
    at its home assembly (those that still do are listed with the reason)."""
    link, a = _home(case.path)
    assert link.analyze(a).singularity == "none"


@pytest.mark.parametrize("case", [c for c in GEPETTO if c.singular_why],
                         ids=lambda c: c.id)
def test_the_singular_defaults_read_as_the_table_says(case):
    """The Gepetto models still singular at home with their default output give the
    table's class (a two-legged robot: type I through its other leg)."""
    link, a = _home(case.path)
    an = link.analyze(a)
    assert an.singularity == case.singularity
    if case.singular_why == TWO_LEGS:
        assert an.indices["inverse"] == 0.0 and an.indices["forward"] > 0.3
    if case.singular_why == TWO_LEGS_PISTONS:
        assert an.indices["inverse"] == 0.0 and 1e-3 < an.indices["forward"] < 1e-2


def test_disney_likes_class_iii_is_free_universal4_beside_the_ball_joint():
    """disney_like's second leg half (free_hip_x, motors 2 and 4) holds the ankle through
    the ball joint ankle_universal_2 (three revolutes meeting at one point) followed by
    the revolute free_universal4, whose axis the file places 0.295 mm from the ball's
    centre (its origin (0.295, 0, -0.295) mm in universal_2's frame): concurrent, that
    revolute would only repeat a rotation of the ball (an idle spin of the cross); 0.3 mm
    aside it gives the ankle a lever that moves the foot with every motor locked, class
    III. The same model with that origin on the axis through the centre (a 0.3 mm change)
    keeps DOF 9, idle 3, and its foot fits and reads class none (forward 0.077, inverse
    0.042): the singularity is the file's offset, not a misreading (the 6d weld joins the
    two halves shin_mirror1 and shin_mirror2 of one shin; no gimbal lock at home)."""
    link, a = _home("gepetto/disney_like/robot.urdf")
    tree = link.model.tree
    data = tree.createData()
    pin.forwardKinematics(tree, data, a.q)
    centre = data.oMi[tree.getJointId("ankle_universal_2_rev0")].translation
    for k in (1, 2):
        assert np.allclose(data.oMi[tree.getJointId(f"ankle_universal_2_rev{k}")].translation,
                           centre, atol=1e-12)
    j = tree.getJointId("free_universal4")
    r = centre - data.oMi[j].translation
    axis = data.oMi[j].rotation[:, 2]
    assert np.linalg.norm(r - (r @ axis) * axis) == pytest.approx(2.9538e-4, rel=1e-3)
    moved = pin.Model(tree)
    placement = moved.jointPlacements[j].copy()
    placement.translation = np.zeros(3)
    moved.jointPlacements[j] = placement
    fixed = Linkage(replace(link.model, tree=moved, output="foot"))
    b = fixed.assemble()
    mob, an = fixed.mobility(b.q), fixed.analyze(b)
    assert (mob.dof, mob.idle_dof, mob.redundant_constraints) == (9, 3, 0)
    assert an.singularity == "none" and choose_output(fixed.model, b.q).fits
    assert an.indices["forward"] > 0.05 and an.indices["inverse"] > 0.03


@pytest.mark.parametrize("path,rod,cls", [
    ("gepetto/cassie_like/robot.urdf", "half_hachil_rode_2", "III"),
    ("gepetto/digit_like/robot.urdf", "toe_a_1/2", "III"),
    ("gepetto/talos_like/robot.urdf", "rod_1", "III"),
    ("gepetto/disney_like/robot.urdf", "tigh_mirror1", "III"),
])
def test_a_rod_chosen_explicitly_still_reports_its_singularity(path, rod, cls):
    """output= wins over the rule: the rod the readers used to pick (its idle spin moves
    it) reads as class III at the same assembly where the foot reads regular."""
    link = pkm_pin.load_mechanism(DATA / path, output=rod)
    assert link.output == rod
    an = link.analyze(_home(path)[1])
    assert an.singularity == cls and an.indices["forward"] == 0.0
    ranked = {c.frame: c for c in rank_outputs(link.model, _home(path)[1].q)}
    assert ranked[rod].idle_dim >= 1 and not ranked[rod].fits


def test_the_rule_on_the_cassie_like_leg():
    """Cassie-like: the foot fits (5 controlled dimensions = 5 independent motors, no
    idle motion moves it, 6 joints from the base), the rods spin (idle) and the
    exporter's massless intermediate links come after the massive bodies."""
    link, a = _home("gepetto/cassie_like/robot.urdf")
    choice = choose_output(link.model, a.q)
    assert choice.frame == "foot" and choice.fits and choice.independent_actuators == 5
    c = {x.frame: x for x in choice.candidates}
    foot = c["foot"]
    assert (foot.motion_dim, foot.idle_dim, foot.depth, foot.rod, foot.named) == (5, 0, 6,
                                                                                 False, 3)
    assert c["half_planta_rode_2"].rod and c["half_planta_rode_2"].idle_dim == 1
    assert c["foot_2_int2_2"].massless and c["foot_2_int2_2"].fits
    assert [x.frame for x in choice.candidates[:2]] == ["foot", "foot_2"]
    assert "5 independent actuators" in choice.describe()


def _without_output_key(tmp_path: Path, name: str) -> Path:
    shutil.copy(LOOPS / f"{name}.urdf", tmp_path)
    text = (LOOPS / f"{name}.yaml").read_text()
    (tmp_path / f"{name}.yaml").write_text(re.sub(r"(?m)^output.*\n", "", text))
    return tmp_path / f"{name}.urdf"


@pytest.mark.parametrize("name,output,motion", [
    ("ankle", "foot", "2R"), ("cassie_knee", "foot", "1T1R"),
    ("delta_loops", "platform", "3T"), ("five_bar", "effector", "1T1R"),
    ("four_bar", "coupler", "1R")])
def test_shipped_models_without_their_output_key(tmp_path, name, output, motion):
    """Our models with the output key removed: the rule finds the foot, the Delta's free
    platform (reached through its three welds) and the five-bar's effector; the
    four-bar's coupler (one motion dimension, two joints from the base) beats the
    rocker the file names; each is regular at home."""
    link = pkm_pin.load_mechanism(_without_output_key(tmp_path, name))
    assert link.output == output
    an = link.analyze(link.home_assembly)
    assert an.motion_type == motion and an.singularity == "none"


def test_the_files_output_and_output_argument_win(tmp_path):
    """output= and the file's output key are kept (no rule); an MJCF names its output in
    <custom><text name="pkm_pin:output">, the shipped four-bar its rocker."""
    assert pkm_pin.load_mechanism(LOOPS / "four_bar.urdf").output == "rocker"
    assert pkm_pin.load_mechanism(DATA / "gepetto/cassie_like/robot.urdf",
                                  output="tarsus").output == "tarsus"
    assert pkm_pin.load_mechanism(LOOPS / "four_bar.xml").output == "rocker"
    text = (LOOPS / "four_bar.xml").read_text()
    bare = re.sub(r"(?s)\s*<custom>.*</custom>", "", text)
    assert "pkm_pin:output" not in bare
    (tmp_path / "four_bar.xml").write_text(bare)
    assert pkm_pin.load_mechanism(tmp_path / "four_bar.xml").output == "coupler"
    folder = tmp_path / "cassie"
    shutil.copytree(DATA / "gepetto/cassie_like", folder)
    with open(folder / "robot.yaml", "a") as f:
        f.write("output: tigh\n")
    assert pkm_pin.load_mechanism(folder / "robot.urdf").output == "tigh"


def test_the_text_report_names_the_likely_outputs_first(capsys):
    """The --output hint of a report on a rod starts with the foot and the motor crank
    that fits as well."""
    assert main(["analyze", str(DATA / "gepetto/cassie_like/robot.urdf"), "--output",
                 "half_hachil_rode_2"]) == 0
    (line,) = [x for x in capsys.readouterr().out.splitlines() if x.startswith("output   ")]
    assert "(likely: foot, servo_gauche; other frames: foot_2, " in line


@pytest.mark.parametrize("name,score", [("foot", 3), ("Effector", 3), ("left-foot", 2),
                                        ("foot_2", 2), ("foot_part", 1), ("tigh", 0)])
def test_end_body_names(name, score):
    """An end body's name scores 3, with a side prefix or suffix 2, inside a name 1."""
    assert name_score(name) == score


def test_every_corpus_file_is_credited():
    """Each corpus file is named in its folder's README with its source, and a licence
    lies beside it."""
    for case in CORPUS:
        folder = DATA / case.path.split("/")[0]
        readme = (folder / "README.md").read_text()
        assert case.path.split("/", 1)[1] in readme, case.path
        assert (folder / "LICENSE").is_file()
        assert (DATA / case.path).is_file()


G1_ANKLE = "ankles/g1_ankle/g1_ankle.xml"


def test_the_rule_on_a_parallel_ankle():
    """G1-like ankle: the foot (roll_link, 2 motion dimensions = 2 motors, none idle)
    is chosen over the crosses of the rods' universal joints (right_u_link: as deep as
    a rod, zero length, its only child the rod), which fit as well; it reads 2R, class
    none. The motor crank the readers used to pick reads 1R and type I."""
    link, a = _home(G1_ANKLE)
    choice = choose_output(link.model, a.q)
    assert choice.frame == "roll_link" and choice.fits and choice.ties == ()
    c = {x.frame: x for x in choice.candidates}
    u = c["right_u_link"]
    assert (u.fits, u.rod, u.depth, u.crank) == (True, True, 3, False)
    assert not c["roll_link"].rod and c["roll_link"].depth == 2
    assert not c["right_motor_link"].fits and c["right_motor_link"].crank
    an = link.analyze(a)
    assert (an.motion_type, an.singularity) == ("2R", "none")
    assert an.indices["inverse"] > 0.4 and an.indices["forward"] > 0.7
    motor = pkm_pin.load_mechanism(DATA / G1_ANKLE, output="right_motor_link")
    an = motor.analyze(a)
    assert (an.motion_type, an.singularity) == ("1R", "I")
    assert an.indices["inverse"] < 1e-12  # 0 up to rounding (2.8e-17 on one processor)


def test_springs_are_read_and_held_when_the_output_is_chosen():
    """Menagerie's Cassie: the shin and heel joints carry a stiffness and no motor; they
    are the model's springs (a note says so), and with them held every body below the
    knee counts 5 motor-set dimensions, so the foot (deepest, named like an end body) is
    the default output instead of the knee; with no springs the knee wins, as before."""
    import dataclasses

    link = pkm_pin.load_mechanism(DATA / "menagerie/agility_cassie/cassie.xml")
    assert link.model.springs == ("left-shin", "left-heel-spring", "right-shin",
                                  "right-heel-spring")
    assert any("a spring (stiffness)" in n for n in link.model.notes)
    q = link.home_assembly.q
    held = choose_output(link.model, q)
    assert held.frame == "left-foot" and held.candidates[0].controlled_dim == 5
    free = choose_output(dataclasses.replace(link.model, springs=()), q)
    assert free.frame == "left-knee"
    foot = next(c for c in free.candidates if c.frame == "left-foot")
    assert (foot.motion_dim, foot.idle_dim) == (5, 2)
    with pytest.raises(pkm_pin.InputError, match="springs: joint 'left-knee' must have"):
        dataclasses.replace(link.model, springs=("left-knee",))


def _strict(text: str) -> dict:
    def refuse(c):
        raise ValueError(f"non-strict JSON constant {c}")
    return json.loads(text, parse_constant=refuse)


@pytest.mark.parametrize("case", [c for c in CORPUS if not c.no_assembly], ids=lambda c: c.id)
def test_every_command_answers_on_the_file_without_a_numpy_warning(case, capsys, tmp_path):
    """Issue 25, "What it must show": analyze --json (strict JSON, no failed section,
    the table's DOF), analyze as text (the summary, DOF to class, before the tables; no
    nan/inf), check (exit 0 or 1, no nan), fk of the reference actuated values (its
    values kept to 1e-9, every loop closed to 1e-9, the output where analyze put it, 1e-9
    m) and view --html (the page written, titled with the file's name), every warning an
    error (no numpy warning reaches the terminal)."""
    link, _ = _home(case.path)
    path = str(DATA / case.path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["analyze", path, "--json"]) == 0
        data = _strict(capsys.readouterr().out)
        assert data["dof"] == case.dof and data["failed_sections"] == {}
        assert main(["analyze", path]) == 0
        lines = capsys.readouterr().out.splitlines()
        heads = [next(i for i, x in enumerate(lines) if x.startswith(h))
                 for h in ("DOF ", "idle motions ", "joints (q):", "A (actuation")]
        assert heads == sorted(heads) and heads[0] < 12
        assert not re.search(r"\b(nan|inf|NaN|Infinity)\b", "\n".join(lines))
        assert main(["check", path]) in (0, 1)
        assert not re.search(r"\b(nan|inf)\b", capsys.readouterr().out)
        assert main(["fk", path, *map(repr, data["q_actuated"]), "--json"]) == 0
        fk = _strict(capsys.readouterr().out)
        q = np.array(fk["q"])
        assert np.allclose(link.model.actuated_values(q), data["q_actuated"], atol=1e-9)
        assert np.abs(link.model.closure_residual(q)).max() < 1e-9
        assert np.allclose(fk["pose"]["xyz"], data["pose"]["xyz"], atol=1e-9)
        page = tmp_path / "page.html"
        assert main(["view", path, "--html", str(page)]) == 0
        capsys.readouterr()
    text = page.read_text()
    assert f"<title>pkm_pin: {link.name}" in text and len(text) > 10_000


def test_check_says_the_base_and_how_the_output_was_chosen(capsys):
    """check of Menagerie's Cassie: the free pelvis held as the base is said, and that the
    left foot was chosen by the default rule, naming the frames that fit as well (its
    ties in CORPUS) and --output; a file that names its output gets no such line."""
    case = next(c for c in CORPUS if c.path.endswith("cassie.xml"))
    assert main(["check", str(DATA / case.path)]) == 1
    out = capsys.readouterr().out
    assert "info  cassie-pelvis has a free joint in the file: it is held as the base" in out
    assert (f"info  output 'left-foot': not named in the file, chosen by the default rule "
            f"(the body the mechanism exists to move); as likely: {', '.join(case.ties)} "
            "(--output FRAME)") in out
    assert main(["check", str(LOOPS / "four_bar.urdf")]) == 0
    assert "chosen by the default rule" not in capsys.readouterr().out


@pytest.mark.parametrize("case", [c for c in CORPUS if not c.no_assembly and c.ties],
                         ids=lambda c: c.id)
def test_analyze_json_says_how_the_output_was_chosen_and_what_fits_as_well(case, capsys):
    """analyze --json of a file that names no output: output_named false and
    output_likely the default output then its ties (CORPUS), as the text hint lists
    them; --output names it: output_named true."""
    path = str(DATA / case.path)
    assert main(["analyze", path, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["output_named"] is False
    assert data["output_likely"] == [case.output, *case.ties]
    assert main(["analyze", path, "--json", "--output", case.ties[0]]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["output_named"] is True and data["output"] == case.ties[0]
