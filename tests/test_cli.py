"""The command-line interface: `pkm-pin analyze`."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from pkm_pin.cli import main


def test_analyze_default_prints_the_3rpr_report(capsys):
    """With no file, analyze reports the seed-000 3-RPR: 3 DOF 2T1R and a tiny cross-check error."""
    assert main(["analyze"]) == 0
    out = capsys.readouterr().out
    assert "3-RPR" in out
    assert "DOF                3  (2T1R)" in out
    assert "singularity        none" in out
    assert "cross-check" in out


def test_analyze_json_has_the_documented_keys(capsys):
    """--json prints one object with dof, motion_type, grubler, A, B, singularity, indices."""
    assert main(["analyze", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    for key in ("dof", "motion_type", "grubler", "A", "B", "singularity",
                "constraint_singular", "indices", "crosscheck_max_error"):
        assert key in report
    assert report["dof"] == 3 and report["motion_type"] == "2T1R" and report["grubler"] == -3
    assert len(report["A"]) == 3 and len(report["B"]) == 3
    assert report["crosscheck_max_error"] < 1e-9


def test_analyze_at_a_given_pose(capsys):
    """--pose moves the platform; the report shows that pose."""
    assert main(["analyze", "--json"]) == 0
    home = json.loads(capsys.readouterr().out)["pose"]
    x, y, z = home["xyz"]
    r, p, yaw = home["rpy"]
    assert main(["analyze", "--json", "--pose", str(x + 0.05), str(y), str(z), str(r),
                 str(p + 0.02), str(yaw)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["pose"]["xyz"][0] == pytest.approx(x + 0.05)
    assert report["dof"] == 3


def test_user_mistakes_give_one_line_and_status_2(tmp_path):
    """A missing file is one error line on stderr, exit status 2, no traceback."""
    proc = subprocess.run([sys.executable, "-m", "pkm_pin.cli", "analyze",
                           str(tmp_path / "missing.toml")], capture_output=True, text=True)
    assert proc.returncode == 2
    assert proc.stderr.startswith("pkm-pin: error:")
    assert "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
