"""Faults found by auditing (issue 17, items 6 and 7), each pinned by a test."""

from __future__ import annotations

import time

import pytest
from test_analysis import mechanism  # built mechanisms, cached per (name, scale)

from pkm_pin import Assembly, InputError, InvalidAssembly, Leg, UrdfError
from pkm_pin.urdf import MAX_LINKS

REVOLUTE = ('<joint name="{n}" type="revolute"><parent link="{p}"/><child link="{c}"/>'
            '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>')


def test_analysis_refuses_a_hand_made_assembly_whose_leg_does_not_close():
    mech = mechanism("stewart")
    a = mech.home_assembly
    assert mech.analyze(Assembly(mech, a.pose, a.leg_q)).dof == 6  # a true one is analysed
    q = [x.copy() for x in a.leg_q]
    q[2][1] += 1e-3
    with pytest.raises(InvalidAssembly, match=r"leg '3' does not close.*Mechanism.assemble"):
        mech.analyze(Assembly(mech, a.pose, q))


def test_analysis_refuses_a_hand_made_assembly_outside_the_joint_limits():
    mech = mechanism("stewart")
    a = mech.home_assembly
    q = [x.copy() for x in a.leg_q]
    q[0][0] = 3.0  # beyond the ±π/2 of the universal joint
    with pytest.raises(InvalidAssembly, match=r"leg '1': coordinate 0 \(3\) is outside"):
        mech.analyze(Assembly(mech, a.pose, q))


@pytest.mark.parametrize("kind", ["floating", "planar"])
def test_a_leg_with_a_floating_or_planar_joint_is_refused(kind):
    xml = ('<robot name="f"><link name="a"/><link name="b"/><link name="c"/>'
           f'<joint name="j" type="{kind}"><parent link="a"/><child link="b"/></joint>'
           + REVOLUTE.format(n="k", p="b", c="c") + "</robot>")
    with pytest.raises(InputError, match=r"joint 'j' is a .* joint \([36] DOF\).*one coordinate"):
        Leg.from_urdf(xml, "c")


def test_a_urdf_beyond_the_size_limit_is_refused_at_once():
    n = 2 * MAX_LINKS
    links = "".join(f'<link name="l{i}"/>' for i in range(n + 1))
    joints = "".join(REVOLUTE.format(n=f"j{i}", p=f"l{i}", c=f"l{i + 1}") for i in range(n))
    t = time.perf_counter()
    with pytest.raises(UrdfError, match=rf"{n + 1} links and {n} joints, more than the "
                                        rf"{MAX_LINKS}"):
        Leg.from_urdf(f'<robot name="big">{links}{joints}</robot>', f"l{n}")
    assert time.perf_counter() - t < 5.0  # a clean error, not minutes of parsing


@pytest.mark.parametrize("kwargs, message", [
    ({"tol": -1.0}, "tol must be a number between 0 and 1"),
    ({"tol": float("nan")}, "tol must be a number between 0 and 1"),
    ({"tol": 2.0}, "tol must be a number between 0 and 1"),
    ({"restarts": -1}, "restarts must be a non-negative integer"),
])
def test_assemble_checks_its_tolerances_before_running(kwargs, message):
    mech = mechanism("rpr3")
    with pytest.raises(InputError, match=message):
        mech.assemble(mech.home, **kwargs)


def test_serial_arm_at_a_wrist_singularity_is_type_I_only(ur5):
    """Every joint of a serial arm is actuated: locking them locks the tool, so a wrist
    singularity (q5 = 0: joints 4 and 6 aligned) is type I, never II/III, and no twist
    is uncontrolled (the actuation wrenches of the dependent joints are not defined
    there: the engine asks which platform twists remain with the actuators locked)."""
    import numpy as np

    from pkm_pin import Mechanism

    q = np.array([0.3, -1.2, 1.4, -0.6, 0.0, 0.7])
    arm = Mechanism([ur5], home=ur5.tip_placement(q), home_q=[q])
    an = arm.analyze()
    assert (an.dof, an.singularity) == (5, "I")
    assert an.indices["type_I"] < 1e-12 and an.indices["type_II"] > 0.5
    assert an.uncontrolled_twist is None and an.lost_actuated_rates is not None
    assert arm.sweep([arm.home]).singularity[0] == "I"
    regular = arm.analyze(arm.assemble(ur5.tip_placement(q + [0, 0, 0, 0, 0.8, 0]), [q]))
    assert regular.singularity == "none"


def test_json_platform_twists_are_the_text_reports_basis():
    """The JSON's platform twists are the readable basis the text prints (unit
    directions), not the analysis basis scaled by the characteristic length: the same
    Delta in metres and millimetres gives the same translations."""
    import numpy as np

    from pkm_pin.report import report_data

    m, mm = mechanism("delta"), mechanism("delta", scale=1000.0)
    a, b = report_data(m.home_analysis), report_data(mm.home_analysis)
    assert a["platform_twists"] == [x["screw"] for x in a["motion_basis"]]
    np.testing.assert_allclose(a["platform_twists"], b["platform_twists"], atol=1e-12)
    assert b["length"] == pytest.approx(1000.0 * a["length"])
    assert (a["idle_dof"], a["idle_motions"], a["redundant_constraints"]) == (0, [], 3)


def test_reports_label_lengths_in_the_models_unit(tmp_path):
    """A model written in millimetres says so (length_unit = "mm"): the report's pose
    header is not "[m]"; the default is the URDF's metre."""
    from pathlib import Path

    from pkm_pin import load_mechanism
    from pkm_pin.report import markdown

    toml = Path(__file__).resolve().parents[1] / "models" / "mechanisms" / "rpr3.toml"
    text = toml.read_text().replace("../urdf/", str(toml.parents[1] / "urdf") + "/")
    assert "| x [m] |" in markdown(load_mechanism(toml).home_analysis)
    path = tmp_path / "rpr3_mm.toml"
    path.write_text('length_unit = "mm"\n' + text)
    report = markdown(load_mechanism(path).home_analysis)
    assert "| x [mm] | y [mm] | z [mm] |" in report and "[m]" not in report


def test_view_html_into_a_folder_writes_a_page_there(tmp_path, capsys):
    """`pkm-pin view rpr3 --html DIR` writes DIR/rpr3.html (it ended in a traceback)."""
    from pkm_pin.cli import main

    assert main(["view", "rpr3", "--html", str(tmp_path)]) == 0
    assert (tmp_path / "rpr3.html").stat().st_size > 1000
    assert f"wrote      {tmp_path / 'rpr3.html'}" in capsys.readouterr().out


@pytest.mark.parametrize("kwargs, message", [
    ({"rtol": float("nan")}, "rtol must be a number between 0 and 1"),
    ({"rtol": -1.0}, "rtol must be a number between 0 and 1"),
    ({"singular_tol": 2.0}, "singular_tol must be a number between 0 and 1"),
])
def test_sweep_checks_its_tolerances(kwargs, message):
    mech = mechanism("rpr3")
    with pytest.raises(InputError, match=message):
        mech.sweep([mech.home], **kwargs)


def test_interrupted_executor_sweep_cancels_the_chunks_not_started():
    """Ctrl-C (or a failed chunk) while waiting on an executor: the chunks not started
    are cancelled at once instead of running to the end."""
    from concurrent.futures import Future

    class Interrupting:
        """An executor whose first result raises KeyboardInterrupt."""

        def __init__(self):
            self.futures = []

        def submit(self, fn, *args):
            f = Future()
            if not self.futures:
                f.set_exception(KeyboardInterrupt())
            self.futures.append(f)
            return f

    mech = mechanism("rpr3")
    ex = Interrupting()
    with pytest.raises(KeyboardInterrupt):
        mech.sweep([mech.home] * 10, executor=ex, chunk_size=2)
    assert len(ex.futures) == 5 and all(f.cancelled() for f in ex.futures[1:])


def test_a_pickled_delta_sweeps_in_worker_processes():
    """Legs with mimic joints (the Delta's parallelograms) travel as URDF text: Pinocchio
    4.1 unpickles JointModelMimic into a model that segfaults the first kinematics pass,
    which killed every process-pool or Dask sweep of a Delta."""
    import pickle
    from concurrent.futures import ProcessPoolExecutor

    import numpy as np

    mech = mechanism("delta")
    mech.closure_model  # a cached tree with mimic joints must not travel either
    copy = pickle.loads(pickle.dumps(mech))
    assert copy.sweep([copy.home]).ok.all()
    with ProcessPoolExecutor(2) as ex:
        res = mech.sweep([mech.home] * 4, executor=ex, chunk_size=2)
    assert res.ok.all()
    np.testing.assert_allclose(res.type_II, mech.sweep([mech.home] * 4).type_II, rtol=1e-12)
