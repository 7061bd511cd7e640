"""A base–legs–platform structure detected in any closure model: the same machine gives
the same analysis whatever file and tree describe it (issue 24)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from linkage_models import five_bar, four_bar

import pkm_pin
from pkm_pin import Mechanism
from pkm_pin.builders.extended_urdf import write_extended_urdf
from pkm_pin.cli import main
from pkm_pin.errors import InputError, MechanismFileError
from pkm_pin.linkage import Linkage
from pkm_pin.model import Closure, ClosureModel, configuration
from pkm_pin.model.structure import detect_platform

MODELS = Path(__file__).resolve().parents[1] / "models"
STEWART = MODELS / "mechanisms" / "stewart.toml"


@pytest.fixture(scope="module")
def stewart(tmp_path_factory):
    """The shipped 6-UPS as TOML legs and as an Extended URDF (tree through leg 1 and
    its S joint, legs 2–6 cut after P and closed by point closures), with the URDF
    tree's configuration at the TOML's home."""
    toml = pkm_pin.load_mechanism(STEWART)
    path = write_extended_urdf(toml, tmp_path_factory.mktemp("stewart"))
    link = pkm_pin.load_mechanism(path, backend="general")
    tree, q = link.model.tree, np.array(link.model.reference)
    for i, (leg, q_leg) in enumerate(zip(toml.legs, toml.home_assembly.leg_q)):
        for name, value in zip(leg.joint_names, q_leg):
            if tree.existJointName(f"leg{i + 1}_{name}"):
                q[tree.joints[tree.getJointId(f"leg{i + 1}_{name}")].idx_q] = value
    return toml, link, q, path


def test_stewart_extended_urdf_is_detected_as_six_legs(stewart):
    """The URDF's tree leg and five point closures are six legs, in the actuated order."""
    _, link, _, _ = stewart
    structure, reason = detect_platform(link.model)
    assert reason == "" and not structure.free_flyer
    assert [(leg.name, leg.kind, len(leg.joints)) for leg in structure.legs] == \
        [("leg1", "tree", 6)] + [(f"leg{i}", "point", 3) for i in range(2, 7)]


def test_same_stewart_same_numbers_whatever_the_file(stewart):
    """TOML legs and the Extended URDF read through the legs backend: same home pose,
    A and B to 1e-12, indices to 1e-9, at home and at a second pose."""
    toml, link, q, _ = stewart
    mech = Mechanism.from_closure_model(link.model, q)
    assert mech.characteristic_length == pytest.approx(toml.characteristic_length, rel=1e-12)
    assert np.allclose(mech.home.homogeneous, toml.home.homogeneous, atol=1e-12)
    moved = toml.home * pin.SE3(pin.rpy.rpyToMatrix(0.05, -0.04, 0.1), np.array([0.03, -0.02,
                                                                                  0.05]))
    for pose in (toml.home, moved):
        a, b = toml.analyze(pose), mech.analyze(pose)
        assert (a.dof, a.motion_type, a.singularity) == (b.dof, b.motion_type, b.singularity)
        np.testing.assert_allclose(b.A, a.A, atol=1e-12)
        np.testing.assert_allclose(b.B, a.B, atol=1e-12)
        for key, value in a.indices.items():
            assert b.indices[key] == pytest.approx(value, rel=1e-9, abs=1e-12), key


def test_forward_kinematics_agree_and_map_back_to_the_file(stewart):
    """FK of the detected mechanism equals the TOML's; its assembly mapped back to the
    URDF tree closes every closure and puts the output frame at the pose."""
    toml, link, q, _ = stewart
    mech = Mechanism.from_closure_model(link.model, q)
    q_a = toml.home_assembly.q_actuated + np.array([0.02, -0.01, 0.03, 0.0, 0.01, -0.02])
    a, b = toml.forward_kinematics(q_a), mech.forward_kinematics(q_a)
    np.testing.assert_allclose(b.pose.homogeneous, a.pose.homogeneous, atol=1e-10)
    np.testing.assert_allclose(mech.source_configuration(mech.home_assembly), q, atol=1e-10)
    q_b = mech.source_configuration(b)
    assert np.abs(link.model.closure_residual(q_b)).max() < 1e-10
    data = link.model.tree.createData()
    pin.framesForwardKinematics(link.model.tree, data, q_b)
    placed = data.oMf[link.model.tree.getFrameId("platform")]
    np.testing.assert_allclose(placed.homogeneous, b.pose.homogeneous, atol=1e-10)


def test_general_backend_of_the_toml_stewart(stewart):
    """load_mechanism(backend='general') reads TOML legs as a Mechanism whose answers
    are the general elimination's (a Linkage), with the same forward velocity map;
    backend='legs' of the URDF is a Mechanism read leg by leg."""
    toml, _, _, path = stewart
    general = pkm_pin.load_mechanism(STEWART, backend="general")
    assert isinstance(general, Mechanism) and general.backend == "general"
    assert isinstance(general.general, Linkage)
    legs = pkm_pin.load_mechanism(path, backend="legs")
    assert isinstance(legs, Mechanism) and legs.backend == "legs"
    q = configuration(toml, toml.home_assembly)
    la, ma = general.analyze(q), toml.home_analysis
    for k in range(6):
        rate = np.eye(6)[k]
        np.testing.assert_allclose(la.forward_velocity(rate), ma.forward_velocity(rate),
                                   atol=1e-9)


def _parity(link: Linkage) -> Mechanism:
    """Both backends at the linkage's assembly: same DOF, motion type, class and
    forward velocity map (1e-9)."""
    a = link.assemble()
    mech = Mechanism.from_closure_model(link.model, a.q)
    la, ma = link.analyze(a.q), mech.home_analysis
    assert (la.dof, la.motion_type, la.singularity) == (ma.dof, ma.motion_type, ma.singularity)
    n = len(link.actuated)
    for k in range(n):
        np.testing.assert_allclose(ma.forward_velocity(np.eye(n)[k]),
                                   la.forward_velocity(np.eye(n)[k]), atol=1e-9)
    return mech


@pytest.mark.parametrize("name,kinds", [
    ("loops/delta_loops.urdf", ["weld"] * 3),
    ("loops/four_bar.urdf", ["tree", "point"]),
    ("loops/four_bar.xml", ["tree", "point"]),
])
def test_backend_parity_on_shipped_models(name, kinds):
    """Every shipped model with a platform structure: the general elimination and the
    per-leg engine give the same mobility and velocity maps."""
    link = pkm_pin.load_mechanism(MODELS / name)
    structure, _ = detect_platform(link.model)
    assert sorted(leg.kind for leg in structure.legs) == sorted(kinds)
    assert structure.free_flyer == (name.endswith("delta_loops.urdf"))
    _parity(link)


def test_five_bar_as_a_body_same_indices_from_urdf_and_mjcf():
    """The shipped five-bar analysed as a body (MJCF) reads as a tree leg and a point
    leg; the four-bar's per-leg indices are the same from its URDF and its MJCF."""
    mech = _parity(pkm_pin.load_mechanism(MODELS / "loops/five_bar.xml"))
    assert mech.home_analysis.dof == 2
    a = pkm_pin.load_mechanism(MODELS / "loops/four_bar.urdf", backend="legs")
    b = pkm_pin.load_mechanism(MODELS / "loops/four_bar.xml", backend="legs")
    for key, value in a.home_analysis.indices.items():
        assert b.home_analysis.indices[key] == pytest.approx(value, rel=1e-9), key


@pytest.mark.parametrize("kind", ["revolute", "point"])
def test_five_bar_closures_become_joints(kind):
    """A revolute closure is one revolute about its z axis, a point closure a spherical
    joint: both five-bars are 2-DOF and match the general backend."""
    mech = _parity(Linkage(five_bar(kind)))
    assert [leg.nv for leg in mech.legs] == [2, 3 if kind == "revolute" else 5]


def test_structures_that_are_not_platforms_say_why():
    """Multi-loop, point outputs and a leg shared by two closures are left to the
    general backend, with the reason; a closure of the platform onto itself is refused."""
    cassie = pkm_pin.load_mechanism(MODELS / "loops/cassie_knee.urdf")
    assert "neither on the platform" in detect_platform(cassie.model)[1]
    point = pkm_pin.load_mechanism(MODELS / "loops/five_bar.urdf")
    assert detect_platform(point.model) == (None, "the output is a point, not a platform body")
    base = four_bar()
    with pytest.raises(InputError, match="two frames of one body"):
        ClosureModel(base.tree, (Closure("point", "rocker_end", "rocker_body", name="self"),),
                     ("rocker",), "rocker_body")
    twice = ClosureModel(base.tree, base.closures + (Closure("point", "coupler_body",
                                                             "rocker_body", name="again"),),
                         ("crank",), "rocker_body")
    assert "shares joint 'crank'" in detect_platform(twice)[1]
    with pytest.raises(InputError, match="not a base–legs–platform machine"):
        Mechanism.from_closure_model(cassie.model)
    with pytest.raises(MechanismFileError, match="neither on the platform"):
        pkm_pin.load_mechanism(MODELS / "loops/cassie_knee.urdf", backend="legs")
    with pytest.raises(InputError, match="backend='fast'"):
        pkm_pin.load_mechanism(STEWART, backend="fast")


def test_from_closure_model_refuses_an_open_configuration():
    """A configuration that does not close the loops is refused with its residual."""
    model = four_bar()
    with pytest.raises(InputError, match="does not close the loops"):
        Mechanism.from_closure_model(model, model.reference)


def test_cli_backend_legs_prints_the_toml_indices(stewart, capsys):
    """pkm-pin analyze --backend legs of the Stewart's Extended URDF, at the TOML's home
    pose, prints the TOML's type I/II indices."""
    _, _, _, path = stewart
    assert main(["analyze", str(path), "--backend", "legs", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    mech = pkm_pin.load_mechanism(path, backend="legs")
    assert data["dof"] == 6
    for key, value in mech.home_analysis.indices.items():
        assert data["indices"][key] == pytest.approx(value, rel=1e-9)


def test_sensitivity_of_the_detected_legs_equals_the_toml(stewart):
    """Sensitivity to the parameters both descriptions share (base, U, P joints and
    anchors of every leg) is the same from the Extended URDF as from the TOML legs."""
    toml, link, q, _ = stewart
    mech = Mechanism.from_closure_model(link.model, q)
    ours, ref = mech.sensitivity(), toml.sensitivity()
    assert len(ours.parameters) == len(ref.parameters)
    shared = 0
    for name in ours.parameters:
        leg, _, rest = name.partition("/")
        theirs = f"{leg.removeprefix('leg')}/{rest.removeprefix(leg + '_')}"
        if theirs in ref.parameters:
            np.testing.assert_allclose(ours.column(name), ref.column(theirs), atol=1e-9,
                                       err_msg=name)
            shared += 1
    assert shared >= 6 * (6 + 3 * 8) + 6 * 6  # bases, U1, U2, P (origin + axis), anchors


def test_study_homotopy_and_partial_poses_on_the_detected_stewart(stewart):
    """Capabilities of platform machines reach the Extended URDF: every assembly mode by
    the Study homotopy (complete, the TOML's poses) and a partial pose."""
    toml, link, q, _ = stewart
    mech = Mechanism.from_closure_model(link.model, q)
    q_a = toml.home_assembly.q_actuated
    ours, ref = mech.forward_kinematics_all(q_a), toml.forward_kinematics_all(q_a)
    assert ours.method == ref.method == "homotopy" and ours.complete
    assert len(ours) == len(ref) >= 2
    for a, b in zip(ours, ref):
        np.testing.assert_allclose(a.pose.homogeneous, b.pose.homogeneous, atol=1e-9)
    z = float(toml.home.translation[2]) + 0.02
    partial = mech.assemble({"z": z, "roll": 0.0, "pitch": 0.0})
    assert partial.pose.translation[2] == pytest.approx(z, abs=1e-12)
    assert partial.residual < 1e-10


def test_linkage_report_names_the_structure_and_the_backend(capsys):
    """pkm-pin analyze of a general-backend file says whether a platform machine was
    found (and that --backend legs reads it per leg) or why not; JSON carries it."""
    assert main(["analyze", str(MODELS / "loops/delta_loops.urdf"), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["structure"]["platform"] and [leg["kind"] for leg in
                                              data["structure"]["legs"]] == ["weld"] * 3
    assert main(["analyze", str(MODELS / "loops/cassie_knee.urdf")]) == 0
    text = capsys.readouterr().out
    assert "structure          general linkage (not base–legs–platform: closure" in text
    assert main(["analyze", str(MODELS / "loops/delta_loops.urdf")]) == 0
    assert "analysed per leg (seed 000's indices" in capsys.readouterr().out
    assert main(["analyze", str(MODELS / "loops/delta_loops.urdf"), "--backend", "general"]) == 0
    assert "--backend legs analyses it per leg" in capsys.readouterr().out


def test_linkage_home_assembly_is_the_assembly_from_the_reference():
    """Linkage.home_assembly / home_analysis: assemble() from the reference, cached."""
    link = pkm_pin.load_mechanism(MODELS / "loops/four_bar.urdf")
    assert link.home_assembly is link.home_assembly
    np.testing.assert_allclose(link.home_assembly.q, link.assemble().q, atol=1e-12)
    assert link.home_analysis.dof == 1


def test_general_backend_hands_leg_by_leg_capabilities_to_the_legs(stewart):
    """The Stewart's Extended URDF read by the general backend: sensitivity, every working
    mode and the Study homotopy go through its legs (the TOML's numbers); a multi-loop
    leg refuses them with a sentence saying why."""
    toml, link, q, _ = stewart
    a = link.assemble(q)
    sens = link.sensitivity(a)
    ref = toml.sensitivity()
    np.testing.assert_allclose(sens.column("leg2/leg2_U1/origin.x"), ref.column("2/U1/origin.x"),
                               atol=1e-9)
    modes = link.forward_kinematics_all(a.q_actuated)
    assert modes.method == "homotopy" and modes.complete
    assert len(modes) == len(toml.forward_kinematics_all(toml.home_assembly.q_actuated))
    assert all(np.abs(link.model.closure_residual(m.q)).max() < 1e-9 for m in modes)
    assert link.forward_kinematics_all(a.q_actuated, method="multistart", patience=1).method \
        == "multistart"
    works = link.inverse_kinematics_all(toml.home)
    assert any(np.allclose(w.q_actuated, a.q_actuated, atol=1e-9) for w in works)
    cassie = pkm_pin.load_mechanism(MODELS / "loops/cassie_knee.urdf")
    # sensitivity is no longer refused: a multi-loop leg answers it through its tree
    # (tests/test_tree_sensitivity.py checks the numbers by re-assembly)
    assert cassie.sensitivity().parameters[0] == "achilles/origin.x"
    with pytest.raises(InputError, match="the Study homotopy reads a machine leg by leg"):
        cassie.forward_kinematics_all(cassie.home_assembly.q_actuated, method="homotopy")


def test_partial_pose_through_the_general_backend(stewart):
    """A partial pose given to the general backend of a platform machine is solved leg by
    leg: the coordinates asked for hold, the loops close; a multi-loop leg (no legs to
    read) answers it on its whole tree (tests/test_output_driver.py)."""
    toml, link, _, _ = stewart
    z = float(toml.home.translation[2]) + 0.03
    a = link.inverse_kinematics({"z": z, "roll": 0.02, "pitch": 0.0})
    assert a.output_pose.translation[2] == pytest.approx(z, abs=1e-10)
    assert pin.rpy.matrixToRpy(a.output_pose.rotation)[0] == pytest.approx(0.02, abs=1e-10)
    assert np.abs(link.model.closure_residual(a.q)).max() < 1e-9
    cassie = pkm_pin.load_mechanism(MODELS / "loops/cassie_knee.urdf")
    b = cassie.inverse_kinematics({"z": -0.79})
    assert b.output_pose.translation[2] == pytest.approx(-0.79, abs=1e-10)
    assert np.abs(cassie.model.closure_residual(b.q)).max() < 1e-9


def test_chain_urdf_round_trip_keeps_joints_axes_and_ranges():
    """A leg chain written as URDF and read back has the same joints, placements, axes
    (aligned or not) and ranges, an unlimited joint staying unlimited."""
    from pkm_pin import urdf
    from pkm_pin.model.chain_urdf import chain_urdf

    m = pin.Model()
    j1 = m.addJoint(0, pin.JointModelRZ(), pin.SE3(np.eye(3), np.array([0.1, 0, 0])), "a",
                    np.array([1.0]), np.array([1.0]), np.array([-1.0]), np.array([2.0]))
    axis = np.array([0.6, 0.0, 0.8])
    j2 = m.addJoint(j1, pin.JointModelPrismaticUnaligned(axis),
                    pin.SE3(pin.rpy.rpyToMatrix(0.1, 0.2, 0.3), np.array([0, 0.2, 0])), "b")
    m.lowerPositionLimit[1], m.upperPositionLimit[1] = -np.inf, np.inf
    m.addBodyFrame("tip", j2, pin.SE3(np.eye(3), np.array([0, 0, 0.3])), 0)
    back = urdf.build_model(urdf.read(chain_urdf(m, "tip", "chain")))
    assert list(back.names) == ["universe", "a", "b"]
    for j in (1, 2):
        np.testing.assert_allclose(back.jointPlacements[j].homogeneous,
                                   m.jointPlacements[j].homogeneous, atol=1e-12)
    np.testing.assert_allclose(back.joints[2].extract().axis, axis, atol=1e-12)
    assert (back.lowerPositionLimit[0], back.upperPositionLimit[0]) == (-1.0, 2.0)
    assert not np.isfinite(back.lowerPositionLimit[1]) and not np.isfinite(
        back.upperPositionLimit[1])
    data, ref = back.createData(), m.createData()
    q = np.array([0.3, 0.05])
    pin.framesForwardKinematics(back, data, q)
    pin.framesForwardKinematics(m, ref, q)
    np.testing.assert_allclose(data.oMf[back.getFrameId("tip")].homogeneous,
                               ref.oMf[m.getFrameId("tip")].homogeneous, atol=1e-12)


def test_default_backend_gives_the_machines_indices(stewart):
    """The Extended URDF read by default is read per leg (a structure is detected and
    its legs take the actuated values in the file's order): at the file's tree
    configuration of the TOML's home, the TOML's indices to 1e-9, the actuated joints
    named as the file names them. Read by the general backend, the characteristic
    length is the legs' (legs_length, without building them), so the seed 000 indices
    are the TOML's to 1e-9 too — the indices of the machine, not of the tree the file
    wrote (issue 24's 0.993/0.958, 0.166/0.400 came from two lengths)."""
    toml, link, q, path = stewart
    default = pkm_pin.load_mechanism(path)
    assert default.backend == "legs" and default.actuated == link.actuated
    d = default.analyze(q)
    np.testing.assert_allclose(d.assembly.q, q, atol=1e-9)
    for key in ("type_I", "type_II", "condition_A"):
        assert d.indices[key] == pytest.approx(toml.home_analysis.indices[key], rel=1e-9), key
    assert isinstance(link, Mechanism) and link.backend == "general"
    assert isinstance(link.general, Linkage)
    assert link.model.length == pytest.approx(toml.characteristic_length, rel=1e-12)
    a, b = link.analyze(q), toml.home_analysis
    assert (a.dof, a.singularity) == (b.dof, b.singularity)
    for key in ("type_I", "type_II", "condition_A"):
        assert a.indices[key] == pytest.approx(b.indices[key], rel=1e-9), key
    for g, l in ((a.velocity_ellipsoid(), b.velocity_ellipsoid()),
                 (a.force_ellipsoid(), b.force_ellipsoid())):
        np.testing.assert_allclose(g.semi_axes, l.semi_axes, rtol=1e-9)
    w = np.array([1.0, -2.0, 30.0, 0.5, 0.2, -0.1])
    np.testing.assert_allclose(a.actuator_efforts(w), b.actuator_efforts(w), rtol=1e-9)


@pytest.mark.parametrize("name", ["loops/delta_loops.urdf", "loops/four_bar.urdf",
                                  "loops/four_bar.xml", "loops/five_bar.xml"])
def test_legs_length_is_the_built_legs_length(name):
    """legs_length reads from the tree the characteristic length of the legs that
    Mechanism.from_closure_model builds; the general backend analyses with it."""
    from pkm_pin.model.structure import legs_length

    link = pkm_pin.load_mechanism(MODELS / name, backend="general")
    legs = pkm_pin.load_mechanism(MODELS / name, backend="legs")
    structure, _ = detect_platform(link.model)
    assert legs_length(link.model, structure) == pytest.approx(legs.characteristic_length,
                                                               rel=1e-12)
    assert link.model.length == pytest.approx(legs.characteristic_length, rel=1e-12)


def test_calibration_through_the_general_backend(stewart):
    """Errors injected into two legs of the Stewart read from its Extended URDF come back
    to 1e-9 from exact poses, through Linkage.calibrate (leg by leg); a multi-loop leg
    refuses the legs' parameter names, naming its own."""
    from pkm_pin.sensitivity import perturb

    _, link, _, _ = stewart
    legs = link.legs_mechanism
    names = ["leg2/leg2_U1/origin.x", "leg5/leg5_U1/origin.z"]
    assert set(names) <= set(link.sensitivity().parameters)
    true = {names[0]: 2e-3, names[1]: -1.5e-3}
    truth = perturb(legs, true)
    rng = np.random.default_rng(5)
    home = legs.home_assembly.q_actuated
    qs = [home + rng.uniform(-0.02, 0.02, home.size) for _ in range(10)]
    res = link.calibrate([(q, truth.forward_kinematics(q).pose) for q in qs], names)
    assert res.converged and res.parameters == names
    for n in names:
        assert res.errors[n] == pytest.approx(true[n], abs=1e-9), n
    assert res.residual_before > 1e-4 and res.residual_after < 1e-10
    # a multi-loop leg calibrates its tree's parameters (tests/test_tree_sensitivity.py):
    # the legs' names are not among them, and are refused naming those that are
    cassie = pkm_pin.load_mechanism(MODELS / "loops/cassie_knee.urdf")
    with pytest.raises(InputError, match="'leg2/leg2_U1/origin.x' names no geometric "
                                         "parameter of cassie_knee .* achilles/origin.x"):
        cassie.calibrate([], names)


def test_both_facades_answer_the_same_names(stewart):
    """The TOML Mechanism, its Extended URDF read by the general backend and through the
    legs backend answer the same names with the same values: the closure model, the
    actuated joints (six, in one order), the output frame, the characteristic length."""
    toml, link, _, path = stewart
    legs = pkm_pin.load_mechanism(path, backend="legs")
    for m in (toml, link, legs):
        assert isinstance(m.model, ClosureModel)
        assert m.n_actuated == len(m.actuated) == len(m.actuated_names) == 6
        assert m.characteristic_length == pytest.approx(toml.characteristic_length, rel=1e-12)
        assert m.output == m.model.output
    assert toml.model is toml.closure_model and link.model is link.closure_model
    assert legs.model is legs.source_model and legs.actuated == tuple(legs.actuated_names)
    assert [a.split("_")[-1] for a in link.actuated] == ["P"] * 6
