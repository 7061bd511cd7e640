"""The benchmark scripts run (small sizes) and produce positive timings.

Marked ``benchmark``: ``python -m pytest -m "not benchmark"`` leaves them out of a quick
local run; CI runs them (nothing deselects them by default).
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import bench_analysis  # noqa: E402
import bench_dynamics  # noqa: E402
import bench_fk  # noqa: E402
import bench_general_fk  # noqa: E402
import bench_linkage  # noqa: E402
import bench_one_core  # noqa: E402
import bench_reach  # noqa: E402
import equivalence_table  # noqa: E402

pytestmark = pytest.mark.benchmark


def test_bench_analysis_runs_and_reports_every_figure(capsys):
    """bench_analysis.main times the five figures for both mechanisms."""
    rows = bench_analysis.main(n=20, n_loop=5)
    assert set(rows) == {"stewart", "rpr3"}
    for figures in rows.values():
        assert len(figures) == 5 and all(t > 0 for t in figures)
    out = capsys.readouterr().out
    assert "Pinocchio-call floor" in out and "hand-written" in out and "one call per pose" in out


def test_bench_fk_solves_to_the_same_poses(capsys):
    """bench_fk.main times both solvers; both reach the targets (printed errors)."""
    ours, ref, err_ours, err_ref = bench_fk.main(n=3)
    assert ours > 0 and ref > 0
    assert err_ours < 1e-9 and err_ref < 1e-9
    assert "ratio pkm_pin / scipy" in capsys.readouterr().out


def test_bench_linkage_times_the_three_figures(capsys):
    """bench_linkage.main times assembly, FK and analysis of the Cassie leg for pkm_pin
    and the hand-written loop (same solutions, checked inside), and the analysis on its
    numpy path."""
    rows = bench_linkage.main(n=10, repeat=1)
    assert set(rows) == {"assemble", "fk", "analyze", "analyze_numpy"}
    assert all(ours > 0 and hand > 0 for ours, hand in rows.values())
    assert "ratio pkm_pin / hand-written" in capsys.readouterr().out


def test_bench_general_fk_times_the_five_bar_and_the_cassie_leg(capsys):
    """bench_general_fk.main (PlaCo left out) times the 5-bar's FK through both drivers
    (solutions checked inside) and the Cassie-like leg against the hand-written loop."""
    rows = bench_general_fk.main(["--no-placo", "--repeat", "1", "--poses", "5"])
    assert rows["five_bar"]["ours"] > 0 and rows["five_bar"]["pinocchio"] > 0
    assert set(rows["cassie"]) == {"assemble", "fk"}
    assert all(t > 0 for figures in rows["cassie"].values() for t in figures)
    out = capsys.readouterr().out
    assert "Pinocchio driver" in out and "hand-written" in out


def test_equivalence_table_numbers_are_below_1e_9(capsys):
    """Every shipped TOML mechanism read as tree + closures equals pkm_pin.Analysis at
    home: same DOF, motion type and class; A, B and indices within 1e-9."""
    rows = equivalence_table.main()
    assert len(rows) == len(equivalence_table.MECHANISMS) >= 8
    for r in rows:
        assert r["same"] and max(r["dA"], r["dB"], r["dindex"]) <= 1e-9, r
    assert "| stewart |" in capsys.readouterr().out


def test_bench_workspace_runs_serial_and_on_dask(capsys):
    """bench_workspace.main times a small Delta workspace here and on a LocalCluster with
    1 and 2 worker processes (same masks, checked inside) and prints the scaling."""
    import bench_workspace

    rows = bench_workspace.main(n=6, chunk=64)
    assert set(rows) == {"serial", "dask 1", "dask 2"}
    assert all(t > 0 and rate > 0 for t, rate in rows.values())
    assert "efficiency" in capsys.readouterr().out


def test_bench_one_core_same_stewart_same_indices(capsys):
    """bench_one_core: the Stewart's Extended URDF through the legs backend, and through
    the general elimination of the URDF's own tree (with the legs' characteristic
    length, structure.legs_length), gives the TOML's indices to 1e-9 at every pose
    (before the shared length the URDF's tree read up to 1.4 apart)."""
    rows = bench_one_core.main(n=3, repeat=1)
    assert rows["diff_legs"] <= 1e-9 and rows["diff_general"] <= 1e-9
    assert rows["diff_urdf"] <= 1e-9
    assert set(rows["per_pose"]) == {"toml", "urdf/legs", "urdf/general"}
    assert "urdf/legs" in capsys.readouterr().out


def test_bench_dynamics_reports_both_ratios(capsys):
    """bench_dynamics.main times single calls, the hand-written solve, the Python path
    and the batch; the efforts agree (hand-written 1e-9, batch 1e-12) and both ratios
    are printed; so are trajectory.study's motion step before / now and a whole study
    per sample."""
    r = bench_dynamics.main(n=40, single=10, repeat=1)
    assert all(r[k] > 0 for k in ("single", "hand", "python", "batch"))
    assert r["diff"] < 1e-9 and r["diff_batch"] < 1e-12
    assert all(r[f"motion {k}"] > 0 for k in ("before", "now", "study", "study motion"))
    out = capsys.readouterr().out
    assert "inverse_dynamics / hand-written" in out and "single calls / batch" in out
    assert "velocity / acceleration step: before" in out and "a whole study" in out


def test_bench_reach_times_both_and_keeps_the_reachable_mask(capsys):
    """bench_reach.main times the 6-UPS workspace with and without the sweep's reach
    test (a 5³ grid, one round): both positive, the same reachable mask, some poses
    refused without a solve, the ratio printed."""
    figures = bench_reach.main(n=5, rounds=1)
    assert figures["with"] > 0 and figures["without"] > 0
    assert figures["same"] and figures["refused"] > 0
    assert "ratio x" in capsys.readouterr().out


def test_bench_reach_times_partial_poses_with_and_without_the_limit_stop(capsys):
    """bench_reach.partial times the 3-PRS workspace over partial poses (a 4³ grid) with
    and without the completion's limit stop: both positive, the same masks."""
    figures = bench_reach.partial(n=4, names=("prs3",))["prs3"]
    assert figures["with"] > 0 and figures["without"] > 0 and figures["same"]
    assert "same masks: True" in capsys.readouterr().out


def test_bench_reach_times_the_completion_compiled_and_in_python(capsys):
    """bench_reach.compiled_completion times the 3-RPS workspace over partial poses (a
    4³ grid) with the compiled completion and with its Python driver: both positive,
    the same masks."""
    figures = bench_reach.compiled_completion(n=4, names=("rps3",))["rps3"]
    assert figures["with"] > 0 and figures["without"] > 0 and figures["same"]
    assert "same masks: True" in capsys.readouterr().out


def test_bench_reach_times_the_tree_pose_rows_compiled_and_on_pinocchio(capsys):
    """bench_reach.tree_pose_rows times the pinned Delta's workspace over its point (a 4³
    grid) with the tree solver's pose rows compiled and on the Pinocchio driver: both
    positive, the same masks."""
    figures = bench_reach.tree_pose_rows(n=4)
    assert figures["with"] > 0 and figures["without"] > 0 and figures["same"]
    assert "same masks: True" in capsys.readouterr().out
