"""Sensitivity of any linkage to geometric errors (pkm_pin.tree_sensitivity).

Checked against the ground truth (the perturbed model re-assembled at the same actuated
values: central differences of the output pose), against the per-leg sensitivity of
seed 000's wrenches where a platform structure exists (the same parameter read by both
backends), under a rigid motion of the whole mechanism and a change of unit, and on the
errors an overconstrained linkage cannot absorb.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pkm_pin
from pkm_pin import screws
from pkm_pin.errors import InputError, SingularityError
from pkm_pin.linkage import Linkage, LoopClosureError
from pkm_pin.model import ClosureModel
from pkm_pin.tolerances import COMPATIBILITY_TOL
from pkm_pin.tree_sensitivity import parameter_names, perturb, sensitivity

ROOT = Path(__file__).resolve().parents[1]
LOOPS = ROOT / "models" / "loops"


def _load(name: str) -> Linkage:
    return pkm_pin.load_mechanism(LOOPS / name, backend="general")


def _output_twist(link: Linkage, errors: dict, assembly) -> pin.SE3:
    """The output placement of ``link``'s model with ``errors``, re-assembled at the
    actuated values of ``assembly`` (from its configuration)."""
    moved = Linkage(perturb(link.model, errors))
    return moved.forward_kinematics(assembly.q_actuated, guess=assembly.q).output_pose


def _central_difference(link: Linkage, name: str, assembly, h: float) -> np.ndarray:
    """d(output pose)/d(error) as a world twist (axis-first, about the origin)."""
    plus = _output_twist(link, {name: h}, assembly)
    minus = _output_twist(link, {name: -h}, assembly)
    d = pin.log6(plus * minus.inverse())  # left difference: a world twist, linear first
    return np.r_[d.angular, d.linear] / (2 * h)


@pytest.mark.parametrize("name", ["cassie_knee.urdf", "ankle.urdf", "five_bar.xml",
                                  "four_bar.urdf"])
def test_columns_are_the_reassembled_output_motion(name):
    """Every parameter the linkage absorbs: its column is the output's motion when the
    perturbed model is assembled again at the same actuated values (central differences,
    h = 1e-6 of the unit), for joint origins, joint axes and closure frames alike."""
    link = _load(name)
    a = link.home_assembly
    sens = link.tree_sensitivity(a)
    assert sens.parameters == parameter_names(link.model)
    kinds = {p.rpartition("/")[2].split(".")[0] for p in sens.parameters}
    assert {"origin", "axis", "a", "b"} <= kinds
    L = link.model.length
    checked = 0
    for k, p in enumerate(sens.parameters):
        if p in sens.incompatible:
            continue
        h = 1e-6 * (L if p.endswith((".x", ".y", ".z")) else 1.0)
        fd = _central_difference(link, p, a, h)
        scale = np.r_[np.full(3, L), np.ones(3)]  # ω·L and v: comparable sizes
        np.testing.assert_allclose(sens.matrix[:, k] * scale, fd * scale, atol=1e-6 * L,
                                   err_msg=p)
        checked += 1
    assert checked >= 15


def test_an_error_the_linkage_cannot_absorb_is_named_and_leaves_the_loop_open():
    """The planar four-bar (a point closure) cannot absorb its crank shifted along z:
    that parameter is incompatible, the perturbed model does not assemble, while an
    in-plane shift of the same joint is absorbed (compatibility at round-off)."""
    link = _load("four_bar.urdf")
    sens = link.tree_sensitivity()
    assert "crank_joint/origin.z" in sens.incompatible
    compat = dict(zip(sens.parameters, sens.compatibility))
    assert compat["crank_joint/origin.z"] > 0.1
    assert compat["crank_joint/origin.x"] < COMPATIBILITY_TOL
    assert "crank_joint/origin.x" not in sens.incompatible
    a = link.home_assembly
    with pytest.raises(LoopClosureError):
        _output_twist(link, {"crank_joint/origin.z": 1e-3}, a)
    _output_twist(link, {"crank_joint/origin.x": 1e-3}, a)  # assembles


@pytest.mark.parametrize("name, pairs", [
    ("four_bar.urdf", [("coupler_tip/base", "crank_joint")]),
    ("delta_loops.urdf", [("leg_1_tip/base", "hip_1"), ("leg_3_tip/base", "hip_3")]),
    ("five_bar.xml", [("tree/base", "mot1")]),
])
def test_both_backends_give_the_same_column_for_the_same_error(name, pairs):
    """Where a platform structure exists, a leg's base placement (the per-leg reading,
    seed 000's wrenches) and the placement of that leg's first joint (the tree's closure
    Jacobian) are the same geometric error: same column to 1e-11."""
    link = _load(name)
    legs, tree = link.sensitivity(), link.tree_sensitivity()
    compared = 0
    for base, joint in pairs:
        for c in ("x", "y", "z", "roll", "pitch", "yaw"):
            if f"{joint}/origin.{c}" in tree.incompatible:
                continue
            np.testing.assert_allclose(legs.column(f"{base}.{c}"),
                                       tree.column(f"{joint}/origin.{c}"), atol=1e-11)
            compared += 1
    assert compared >= 3


def _moved(model: ClosureModel, M: pin.SE3, scale: float = 1.0) -> ClosureModel:
    """``model`` carried rigidly by ``M`` (every root joint and universe frame) and its
    lengths multiplied by ``scale`` (``M``'s translation given in the model's unit)."""
    M = pin.SE3(M.rotation, M.translation * scale)
    tree = pin.Model(model.tree)
    for j in range(1, tree.njoints):
        P = tree.jointPlacements[j]
        P = pin.SE3(P.rotation, P.translation * scale)
        tree.jointPlacements[j] = M * P if tree.parents[j] == 0 else P
    for f in range(len(tree.frames)):
        frame = tree.frames[f]
        P = pin.SE3(frame.placement.rotation, frame.placement.translation * scale)
        frame.placement = M * P if frame.parentJoint == 0 else P
        tree.frames[f] = frame
    closures = tuple(c.__class__(c.kind, c.frame_a, c.frame_b,
                                 pin.SE3(c.placement_a.rotation, c.placement_a.translation * scale),
                                 pin.SE3(c.placement_b.rotation, c.placement_b.translation * scale),
                                 c.name, c.coef) for c in model.closures)
    return ClosureModel(tree, closures, model.actuated, model.output, model.name,
                        reference=model.reference)


def test_a_rigid_motion_and_a_unit_change_carry_the_columns():
    """The Cassie-like knee moved rigidly and written in millimetres: the columns of the
    parameters below the root joints are the same twists moved (``Ad(M)``) and scaled
    (rotations per length error ÷ 1000, translations per angle error × 1000), and the
    same parameters are incompatible."""
    link = _load("cassie_knee.urdf")
    M = pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.7, 1.1), np.array([0.4, -1.2, 2.0]))
    q = link.home_assembly.q
    ref = sensitivity(link.model, q)
    moved = sensitivity(_moved(link.model, M, 1000.0), q)
    assert moved.parameters == ref.parameters
    tree = link.model.tree
    roots = {tree.names[j] for j in range(1, tree.njoints) if tree.parents[j] == 0}

    def below_roots(names):  # a root joint's origin is written in the world's axes
        return [n for n in names if not (n.split("/")[0] in roots and "/origin." in n)]

    assert below_roots(moved.incompatible) == below_roots(ref.incompatible)
    assert len(below_roots(ref.incompatible)) > 5
    compared = 0
    M_mm = pin.SE3(M.rotation, M.translation * 1000.0)
    for k, p in enumerate(ref.parameters):
        if p not in below_roots([p]) or p in ref.incompatible:
            continue
        length = p.endswith((".x", ".y", ".z"))
        in_mm = ref.matrix[:, k] * (np.r_[np.full(3, 1e-3), np.ones(3)] if length
                                    else np.r_[np.ones(3), np.full(3, 1e3)])
        expected = screws.transform(in_mm, M_mm)
        scale = np.r_[np.full(3, 1.0), np.full(3, 1e-3)] if not length else np.r_[
            np.full(3, 1e3), np.ones(3)]
        np.testing.assert_allclose(moved.matrix[:, k] * scale, expected * scale, atol=1e-8,
                                   err_msg=p)
        compared += 1
    assert compared > 30


def test_a_general_linkage_answers_sensitivity_through_its_tree():
    """A linkage with no platform structure (the Cassie-like knee: a multi-loop leg) is no
    longer refused: its sensitivity is the tree's; a machine with legs keeps the per-leg
    reading, and both answer tree_sensitivity."""
    cassie = _load("cassie_knee.urdf")
    assert cassie.platform_structure[0] is None
    s = cassie.sensitivity()
    np.testing.assert_array_equal(s.matrix, cassie.tree_sensitivity().matrix)
    assert s.parameters == parameter_names(cassie.model)
    np.testing.assert_allclose(s.point_matrix()[3:], screws.about(s.matrix.T, s.assembly.pose
                                                                 .translation).T[3:])
    four = _load("four_bar.urdf")
    assert four.sensitivity().parameters[0] == "coupler_tip/base.x"
    assert four.tree_sensitivity().parameters[0] == "crank_joint/origin.x"


def test_an_output_the_closures_leave_free_is_a_singularity():
    """A passive joint between the actuator and the output with no closure to hold it:
    the output's error is undetermined, whatever the rounding (a structural null space)."""
    tree = pin.Model()
    j1 = tree.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "motor")
    j2 = tree.addJoint(j1, pin.JointModelRZ(), pin.SE3(np.eye(3), np.array([0.3, 0, 0])),
                       "elbow")
    tree.addFrame(pin.Frame("tip", j2, 0, pin.SE3(np.eye(3), np.array([0.2, 0, 0])),
                            pin.FrameType.OP_FRAME))
    model = ClosureModel(tree, (), ("motor",), "tip", "arm")
    with pytest.raises(SingularityError, match="undetermined"):
        sensitivity(model, np.zeros(2))
    held = ClosureModel(tree, (), ("motor", "elbow"), "tip", "arm")
    s = sensitivity(held, np.array([0.4, -0.3]))
    np.testing.assert_allclose(s.column("motor/origin.x"), [0, 0, 0, 1, 0, 0], atol=1e-15)


def test_bad_parameters_and_errors_are_refused_by_name():
    link = _load("four_bar.urdf")
    with pytest.raises(InputError, match="'hip/origin.x' names no geometric parameter.*"
                                         "crank_joint|'hip/origin.x' names no geometric"):
        link.tree_sensitivity(parameters=["hip/origin.x"])
    with pytest.raises(InputError, match="must be finite"):
        perturb(link.model, {"crank_joint/origin.x": float("nan")})
    assert link.tree_sensitivity(parameters="crank_joint").parameters == [
        n for n in parameter_names(link.model) if n.startswith("crank_joint/")]
    assert link.tree_sensitivity(parameters="*/origin.z").parameters == [
        n for n in parameter_names(link.model) if n.endswith("/origin.z")]


def test_calibration_of_a_multi_loop_leg_recovers_injected_errors():
    """The Cassie-like knee (no platform structure): errors injected in four of its tree's
    parameters, output poses 'measured' on the perturbed model at eight actuated values,
    calibration from the nominal model recovers them (1e-9) and its residual vanishes."""
    link = _load("cassie_knee.urdf")
    truth = {"knee_rod_joint/origin.x": 2e-3, "plantar_rod_joint/origin.z": -1.5e-3,
             "tarsus_joint/origin.x": 1e-3, "foot_joint/origin.z": 4e-3}
    real = Linkage(perturb(link.model, truth))
    home = link.home_assembly
    rng = np.random.default_rng(3)
    samples = []
    for _ in range(8):
        qa = home.q_actuated + rng.uniform(-0.15, 0.15, home.q_actuated.size)
        samples.append((qa, real.forward_kinematics(qa, guess=home.q).output_pose))
    result = link.calibrate(samples, list(truth))
    assert result.converged and not result.incompatible and not result.unidentifiable
    for name, error in truth.items():
        assert abs(result.errors[name] - error) < 1e-9, name
    assert result.residual_before > 1e-4 and result.residual_after < 1e-10
    assert isinstance(result.mechanism, Linkage)


def test_cli_sensitivity_of_any_file(capsys):
    """``pkm-pin sensitivity``: strict JSON with every parameter, largest effect first,
    each twist the API's at the output origin; the text names what cannot be absorbed;
    a TOML machine and ``--q`` go through the same command; bad options are one line."""
    import json

    from pkm_pin.cli import main

    path = str(LOOPS / "cassie_knee.urdf")
    assert main(["sensitivity", path, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    sens = _load("cassie_knee.urdf").sensitivity()
    assert len(data["parameters"]) == len(sens.parameters)
    M = sens.point_matrix()
    L = data["length"]
    effects = [r["position_gain"] + L * r["rotation_gain"] for r in data["parameters"]]
    assert effects == sorted(effects, reverse=True)
    for row in data["parameters"][:10]:
        np.testing.assert_allclose(row["twist"], M[:, sens.parameters.index(row["name"])],
                                   atol=1e-12)
    assert {r["name"] for r in data["parameters"] if not r["compatible"]} == \
        set(sens.incompatible)
    assert main(["sensitivity", path, "--top", "3"]) == 0
    text = capsys.readouterr().out
    assert "knee/origin.z" in text and f"cannot absorb {len(sens.incompatible)}" in text
    assert main(["sensitivity", "stewart", "--q", *["1.0"] * 5]) == 2
    assert "--q" in capsys.readouterr().err
    toml = pkm_pin.load_mechanism(ROOT / "models" / "mechanisms" / "stewart.toml")
    qa = toml.home_assembly.q_actuated + 0.01
    assert main(["sensitivity", "stewart", "--json", "--q", *map(str, qa)]) == 0
    moved = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(moved["point"], toml.forward_kinematics(qa).pose.translation,
                               atol=1e-9)
    assert main(["sensitivity", "stewart", "--top", "2", "--parameters", "1/U1"]) == 0
    assert "1/U1/origin" in capsys.readouterr().out
    assert main(["sensitivity", path, "--parameters", "nope"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "'nope' names no geometric parameter" in err[0]
    assert main(["sensitivity", path, "--top", "0"]) == 2
    assert "--top must be at least 1" in capsys.readouterr().err


def test_closures_sharing_a_name_get_distinct_parameters():
    """Two closures of one name (files do that): the second's parameters carry its index,
    and perturbing it moves that closure only."""
    from dataclasses import replace

    link = _load("five_bar.xml")
    model = link.model
    twin = replace(model, closures=model.closures + (replace(model.closures[0]),))
    names = parameter_names(twin)
    first = model.closures[0].name or "closure 0"
    k = len(model.closures)
    assert f"{first}/a.x" in names and f"{first}#{k}/a.x" in names
    moved = perturb(twin, {f"{first}#{k}/a.x": 1e-3})
    assert moved.closures[0].placement_a == twin.closures[0].placement_a
    assert not moved.closures[k].placement_a.isApprox(twin.closures[k].placement_a)
