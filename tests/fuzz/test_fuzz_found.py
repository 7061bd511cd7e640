"""Inputs the fuzz suite (``test_fuzz_readers.py``) found failing, kept as plain tests with
the exact input; each states what the CLI must now do."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from pkm_pin.cli import main

DATA = Path(__file__).resolve().parents[1] / "data"


def one_error_line(capsys) -> str:
    """The single ``pkm-pin: error:`` line of the last command (numba's compile notice of
    a first run on a fresh machine aside: these tests may be the first to compile)."""
    lines = [line for line in capsys.readouterr().err.strip().splitlines()
             if not line.startswith(("pkm_pin: compiling ", "pkm_pin: compiled in "))]
    assert len(lines) == 1 and lines[0].startswith("pkm-pin: error: "), lines
    return lines[0]


def test_an_analysis_error_names_the_file(tmp_path, capsys):
    """Gepetto's kangaroo_like folder (unchanged) whose loop does not close within the
    joint limits: the error line names the URDF, not only the loop (found on the corpus
    file itself: 'pkm-pin: error: loop ... does not close' said nothing of which file)."""
    folder = tmp_path / "kangaroo"
    shutil.copytree(DATA / "gepetto" / "kangaroo_like", folder)
    assert main(["analyze", str(folder / "robot.urdf"), "--json"]) == 2
    line = one_error_line(capsys)
    assert line.startswith(f"pkm-pin: error: {folder / 'robot.urdf'}: loop ")
    assert "does not close" in line


def test_a_reader_error_is_not_named_twice(tmp_path, capsys):
    """A reader error already naming the file keeps its own wording (no second prefix)."""
    path = tmp_path / "m.toml"
    path.write_text("name = 1\n")
    assert main(["analyze", str(path), "--json"]) == 2
    line = one_error_line(capsys)
    assert line.count("m.toml") == 1


def test_a_line_separator_in_a_file_name_stays_on_one_line(tmp_path, capsys):
    """A file whose name holds U+2028 (a line break for ``splitlines``, as for a terminal
    log reader) is named in an error line that stays one line."""
    path = tmp_path / "m\u2028x.toml"
    path.write_text("name = 1\n")
    assert main(["analyze", str(path), "--json"]) == 2
    assert "x.toml" in one_error_line(capsys)


FOUND = Path(__file__).resolve().parent / "found"


def _strict_json(text: str):
    """``text`` parsed as strict JSON: NaN and Infinity refused."""
    def refuse(name):
        raise ValueError(f"non-strict JSON constant {name}")

    return json.loads(text, parse_constant=refuse)


def test_mjcf_empty_pos_is_refused_not_an_svd_traceback(tmp_path, capsys):
    """models/loops/four_bar.xml with ``<compiler>`` dropped and the rocker's ``pos=""``
    (found by the fuzz suite): Pinocchio 4.1 read the empty position as uninitialised
    memory and the report's SVD raised LinAlgError. Now the MJCF reader refuses it,
    naming the body and the attribute."""
    path = tmp_path / "model.xml"
    path.write_bytes((FOUND / "mjcf_empty_pos_svd.xml").read_bytes())
    assert main(["analyze", str(path), "--json"]) == 2
    line = one_error_line(capsys)
    assert f"{path}, body[3] 'rocker' pos: must be 3 finite numbers, got ''" in line


def test_mjcf_empty_pos_gives_no_overflow_warning(tmp_path, capsys):
    """models/loops/five_bar.xml with proximal1's ``pos=""`` (found by the fuzz suite):
    a numpy overflow warning, then "length must be a positive number [m], got inf" — two
    lines, and an error that did not say which value was wrong. Now one line naming it."""
    path = tmp_path / "model.xml"
    path.write_bytes((FOUND / "mjcf_empty_pos_length_inf.xml").read_bytes())
    assert main(["analyze", str(path), "--json"]) == 2
    line = one_error_line(capsys)
    assert "body[1] 'proximal1' pos: must be 3 finite numbers, got ''" in line


@pytest.mark.parametrize("attribute,value,count", [
    ("pos", "0.1 0", 3), ("axisangle", "0 0 1", 4), ("quat", "1 0 0 0 0", 4),
    ("euler", " ", 3), ("axis", "", 3)])
def test_mjcf_number_counts_are_checked(tmp_path, capsys, attribute, value, count):
    """Every MJCF number attribute holds MuJoCo's count of numbers (a short or empty list
    is what Pinocchio reads as uninitialised memory)."""
    text = (FOUND / "mjcf_empty_pos_svd.xml").read_text().replace('pos=""', 'pos="0.1 0 0"')
    (tmp_path / "ok.xml").write_text(text)
    assert main(["analyze", str(tmp_path / "ok.xml"), "--json"]) == 0
    capsys.readouterr()
    first = {"pos": 'pos="0.03 0 0"', "axisangle": 'axisangle="0 0 1 1.0471975511966"',
             "axis": 'axis="0 0 1"', "quat": '<body name="base"', "euler": '<body name="base"'}
    new = f'{attribute}="{value}"' if attribute in ("pos", "axisangle", "axis") \
        else f'<body name="base" {attribute}="{value}"'
    bad = text.replace(first[attribute], new, 1)
    assert bad != text
    (tmp_path / "bad.xml").write_text(bad)
    assert main(["analyze", str(tmp_path / "bad.xml"), "--json"]) == 2
    assert f"{attribute}: must be {count} finite numbers, got {value!r}" in one_error_line(capsys)


def test_urdf_axis_without_xyz_is_refused_not_a_singular_matrix(tmp_path, capsys):
    """models/loops/delta_loops.urdf with joint wrist_3_2's ``<axis/>`` left without
    ``xyz`` (and a duplicated ``<limit>`` elsewhere; found by the fuzz suite): urdfdom
    reads such an axis as zero, the joint's rotations were not rotations, the weld
    residual NaN: a numpy warning on success, or ``LinAlgError: Singular matrix`` from
    the mobility search. The URDF reader now refuses it, naming the joint."""
    shutil.copy(FOUND / "delta_axis_without_xyz.urdf", tmp_path / "delta.urdf")
    shutil.copy(FOUND / "delta_axis_without_xyz.yaml", tmp_path / "delta.yaml")
    assert main(["analyze", str(tmp_path / "delta.urdf"), "--json"]) == 2
    line = one_error_line(capsys)
    assert "URDF: joint 'wrist_3_2' has an <axis> without xyz" in line
    assert str(tmp_path / "delta.urdf") in line


def _found_toml(tmp_path, name: str) -> Path:
    """A kept mechanism file, its leg URDF paths (the fuzz run's copy of models/urdf)
    pointed at this checkout's models/urdf."""
    text = (FOUND / name).read_text().replace("/tmp/fuzzrun/tree/models/urdf/",
                                               f"{DATA.parents[1] / 'models' / 'urdf'}/")
    path = tmp_path / "m.toml"
    path.write_text(text)
    return path


def test_huge_home_q_is_refused_not_an_overflow_warning(tmp_path, capsys):
    """The shipped agile eye with leg 1's home_q[2] = 3.68e287 (found by the fuzz suite):
    finite, so it was taken, and ``analyze`` printed numpy overflow warnings before its
    JSON. Now the numbers of a mechanism file are held within ±1e6 (m or rad), as the
    URDF's are, and the error names the leg, the key and the value."""
    assert main(["analyze", str(_found_toml(tmp_path, "toml_home_q_3e287.toml")), "--json"]) == 2
    line = one_error_line(capsys)
    assert "m.toml, leg '1' (legs[0]).home_q: has 3.68087e+287, beyond ±1e+06" in line


def test_huge_base_position_is_refused_not_two_lines(tmp_path, capsys):
    """The shipped agile eye with leg 1's base x = 1.34e154 (found by the fuzz suite):
    a numpy warning, then "relative pose error of inf" — two lines, and not naming the
    value. Now one line naming it."""
    assert main(["analyze", str(_found_toml(tmp_path, "toml_base_xyz_1e154.toml")), "--json"]) \
        == 2
    assert "(legs[0]).base.xyz: has 1.34078e+154, beyond ±1e+06" in one_error_line(capsys)


def test_mjcf_with_one_joint_left_analyses(tmp_path, capsys):
    """models/loops/four_bar.xml with the crank's and the rocker's joints and the
    actuator dropped (found by the fuzz suite): a tree of one 1-DOF joint, whose
    Jacobian Pinocchio's binding returns as a (6,) vector, raised IndexError in
    velocity_units. Now it analyses: exit 0 and strict, finite JSON."""
    path = tmp_path / "model.xml"
    path.write_bytes((FOUND / "mjcf_one_joint_tree.xml").read_bytes())
    assert main(["analyze", str(path), "--json"]) == 0
    captured = capsys.readouterr()
    data = _strict_json(captured.out)
    assert isinstance(data, dict) and data and not captured.err


def test_mjcf_with_one_actuated_joint_samples_its_nearby_configurations(tmp_path, capsys):
    """models/loops/four_bar.xml with the coupler's body renamed to an unknown tag and the
    rocker's joint dropped (found on the final code by the long run): one 1-DOF joint
    and an actuator, so the mobility samples nearby configurations through the Pinocchio
    path, where the binding's (6,) Jacobian broke the null space's matmul (ValueError).
    Every Jacobian read from Pinocchio is now (6, nv): exit 0, strict JSON, DOF 1."""
    path = tmp_path / "model.xml"
    path.write_bytes((FOUND / "mjcf_one_joint_nearby_samples.xml").read_bytes())
    assert main(["analyze", str(path), "--json"]) == 0
    captured = capsys.readouterr()
    data = _strict_json(captured.out)
    assert data["dof"] == 1 and data["actuated"] == ["crank_joint"]
