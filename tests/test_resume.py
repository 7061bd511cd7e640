"""Nothing computed is lost: checkpointed studies survive an interrupt, a killed Dask worker
and an unwritable folder (issue 28, item 4)."""

from __future__ import annotations

import os
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from helpers import shipped_mechanisms

from pkm_pin import cli
from pkm_pin.checkpoint import Checkpoint, Interrupted
from pkm_pin.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
mechanism = shipped_mechanisms()
#: A small study: a 6 × 6 × 6 constant-orientation workspace of the Stewart platform in
#: chunks of 30 cells (8 chunks, then the boundary cells' sub-points).
STUDY = dict(n=6, chunk_size=30)


def _stop_at(stage: str, chunk: int):
    """An ``on_chunk`` hook raising KeyboardInterrupt once ``chunk`` chunks of ``stage``
    are recorded."""
    def hook(name, recorded):
        if name == stage and recorded == chunk:
            raise KeyboardInterrupt
    return hook


def _same(a, b) -> bool:
    """Equal arrays, bit for bit (nan where nan)."""
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype.kind == "f":
        return a.shape == b.shape and a.tobytes() == b.tobytes()
    return np.array_equal(a, b)


def _assert_same_workspace(ws, ref) -> None:
    for k in ref.values:
        assert _same(ws.values[k], ref.values[k]), k
    for k in ref.masks:
        assert _same(ws.masks[k], ref.masks[k]), k
    assert {k: v.as_dict() for k, v in ws.volumes.items()} == \
        {k: v.as_dict() for k, v in ref.volumes.items()}
    assert ws.counts == ref.counts


@pytest.fixture(scope="module")
def stewart():
    """The Stewart platform and its uninterrupted small workspace."""
    mech = mechanism("stewart")
    return mech, mech.workspace(("x", "y", "z"), **STUDY)


@pytest.mark.parametrize("stage,chunk", [("cells", 3), ("refine", 1)])
def test_interrupted_at_a_chunk_then_resumed_gives_identical_arrays(stewart, tmp_path, stage,
                                                                     chunk):
    """A KeyboardInterrupt after a chosen chunk keeps the chunks done; the resume ends
    with the uninterrupted run's arrays, bit for bit, and removes the partial file."""
    mech, ref = stewart
    prefix = tmp_path / "ws"
    with pytest.raises(Interrupted) as info:
        mech.workspace(("x", "y", "z"), **STUDY,
                       checkpoint=Checkpoint(prefix, on_chunk=_stop_at(stage, chunk)))
    assert info.value.exit_status == 130
    partial = tmp_path / "ws.partial.npz"
    with np.load(partial) as z:
        done = z[f"{stage}.done"]
        assert done.sum() == chunk * STUDY["chunk_size"]
        if stage == "refine":  # the cells are all kept
            assert z["cells.done"].all()
            assert _same(z["cells.det"].reshape(ref.shape), ref.values["det"])
    assert "done" in str(info.value)
    ws = mech.workspace(("x", "y", "z"), **STUDY, checkpoint=prefix, resume=True)
    _assert_same_workspace(ws, ref)
    assert not partial.exists()


def test_a_sweep_interrupted_and_resumed_gives_the_same_result(tmp_path):
    """sweep(checkpoint=…) interrupted after two chunks and resumed equals the plain sweep,
    failures included."""
    mech = mechanism("rpr3")
    L = mech.characteristic_length
    X = np.tile(mech.home_assembly.pose.translation.tolist() + [0, 0, 0], (40, 1))
    X[:, 0] += np.linspace(-1.5 * L, 1.5 * L, 40)  # some poses do not assemble
    plain = mech.sweep(X, chunk_size=8)
    with pytest.raises(Interrupted):
        mech.sweep(X, chunk_size=8,
                   checkpoint=Checkpoint(tmp_path / "s", on_chunk=_stop_at("sweep", 2)))
    again = mech.sweep(X, chunk_size=8, checkpoint=Checkpoint(tmp_path / "s", resume=True,
                                                              keep=True))
    for k, a in plain.arrays().items():
        assert _same(getattr(again, k), a), k
    assert again.failures == plain.failures
    assert (tmp_path / "s.partial.npz").exists()  # keep=True


def test_resuming_another_study_is_refused(stewart, tmp_path):
    """A resume with other arguments names what differs; a new run does not overwrite
    an unfinished study, and a resume needs a partial file."""
    mech, _ = stewart
    prefix = tmp_path / "ws"
    with pytest.raises(Interrupted):
        mech.workspace(("x", "y", "z"), **STUDY,
                       checkpoint=Checkpoint(prefix, on_chunk=_stop_at("cells", 1)))
    with pytest.raises(InputError, match=r"another study \(n: \[6, 6, 6\] there, "
                                         r"\[7, 7, 7\] here\)"):
        mech.workspace(("x", "y", "z"), n=7, chunk_size=30, checkpoint=prefix, resume=True)
    with pytest.raises(InputError, match="another study.*chunk_size"):
        mech.workspace(("x", "y", "z"), n=6, chunk_size=40, checkpoint=prefix, resume=True)
    with pytest.raises(InputError, match="unfinished study.*--resume"):
        mech.workspace(("x", "y", "z"), **STUDY, checkpoint=prefix)
    with pytest.raises(InputError, match="no .*other.partial.npz"):
        mech.workspace(("x", "y", "z"), **STUDY, checkpoint=tmp_path / "other", resume=True)


def test_an_unwritable_or_wrong_folder_is_refused_before_the_work(tmp_path, monkeypatch,
                                                                  capsys):
    """An unwritable folder, a file where the folder should be and a folder under the
    partial file's name are one-line errors (status 2) before any pose is evaluated."""
    import pkm_pin.checkpoint as checkpoint
    from pkm_pin import sweep

    def no_work(*args, **kwargs):
        raise AssertionError("the study started")

    monkeypatch.setattr(sweep, "evaluate_chunk", no_work)
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    if os.geteuid() == 0:  # root writes anywhere: the folder refuses through mkstemp
        mkstemp = checkpoint.tempfile.mkstemp

        def refused(*args, dir=None, **kwargs):
            if Path(dir) == locked:
                raise PermissionError(13, "Permission denied")
            return mkstemp(*args, dir=dir, **kwargs)

        monkeypatch.setattr(checkpoint.tempfile, "mkstemp", refused)
    (tmp_path / "afile").write_text("")
    (tmp_path / "taken.partial.npz").mkdir()
    for command, out, message in [
            ("workspace", locked / "ws", "cannot write in the folder"),
            ("map", locked / "m", "cannot write in the folder"),
            ("workspace", tmp_path / "afile" / "ws", "is not a folder"),
            ("workspace", tmp_path / "taken", "not a file")]:
        extra = ["--coords", "x", "y", "z", "--n", "4"] if command == "workspace" else \
            ["--axes", "x", "y", "--n", "4"]
        assert cli.main([command, "stewart", *extra, "--quiet", "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.startswith("pkm-pin: error:") and message in err and err.count("\n") == 1
    assert sorted(p.name for p in locked.iterdir()) == []
    locked.chmod(0o700)


def _npz(path) -> dict:
    with np.load(path) as z:
        return {k: z[k] for k in z.files}


def _run_until_partial(argv: list[str], partial: Path, signum: int):
    """Run ``pkm-pin argv`` in a subprocess, send it ``signum`` once ``partial`` exists
    (its first chunk is written), and return (status, stderr)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([sys.executable, "-m", "pkm_pin.cli", *argv], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not partial.exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=120)
    return proc.returncode, err


@pytest.mark.parametrize("signum,command", [
    (signal.SIGINT, ["workspace", "stewart", "--coords", "x", "y", "z", "--n", "16",
                     "--chunk-size", "200"]),
    (signal.SIGTERM, ["map", "stewart", "--axes", "x", "y", "--n", "70",
                      "--chunk-size", "200"]),
    # a general mechanism's workspace: its cell analyses are checkpointed too
    (signal.SIGINT, ["workspace", str(ROOT / "models" / "loops" / "five_bar.urdf"), "--n",
                     "40", "--chunk-size", "40"]),
    # and its map over actuated coordinates: the rows of its sweep, resumed from the last
    (signal.SIGTERM, ["map", str(ROOT / "models" / "loops" / "five_bar.urdf"), "--n", "40",
                      "--chunk-size", "100"])])
def test_the_cli_signalled_after_its_first_chunk_resumes_to_identical_arrays(
        tmp_path, capsys, signum, command):
    """pkm-pin sent SIGINT (workspace) or SIGTERM (map) after its first chunk is written
    exits 130 / 143 with one line giving the command to continue, which ends with the
    arrays of an uninterrupted run."""
    base = command + ["--quiet"]
    assert cli.main(base + ["--out", str(tmp_path / "ref")]) == 0
    capsys.readouterr()
    status, err = _run_until_partial(base + ["--out", str(tmp_path / "run")],
                                     tmp_path / "run.partial.npz", signum)
    assert status == 128 + signum, err
    line = err.strip().splitlines()[-1]
    assert line.startswith("pkm-pin: interrupted (") and " of " in line, err
    continue_with = line.split("continue with: ")[1]
    assert continue_with.endswith(f"--resume {tmp_path / 'run'}")
    with np.load(tmp_path / "run.partial.npz") as z:
        done = z["cells.done"] if "cells.done" in z.files else z["sweep.done"]
        assert 0 < done.sum() < done.size  # stopped part way
    assert not (tmp_path / "run.npz").exists()
    argv = shlex.split(continue_with)[1:]
    assert cli.main(argv) == 0
    ref, run = _npz(tmp_path / "ref.npz"), _npz(tmp_path / "run.npz")
    assert ref.keys() == run.keys()
    for k in ref:
        assert _same(run[k], ref[k]), k
    assert not (tmp_path / "run.partial.npz").exists()


@pytest.mark.dask
def test_a_dask_worker_killed_mid_sweep_costs_time_not_the_result(stewart, tmp_path):
    """A Dask LocalCluster worker process killed (SIGKILL) while the workspace runs: its
    chunks are run again elsewhere and the arrays equal the uninterrupted run's."""
    distributed = pytest.importorskip("distributed")
    mech, ref = stewart
    killed = []
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        def kill_a_busy_worker(stage, recorded):
            if stage == "cells" and recorded == 2 and not killed:
                pids = client.run(os.getpid)
                busy = [a for a, keys in client.processing().items() if keys and a in pids]
                pid = pids[busy[0] if busy else next(iter(pids))]
                os.kill(pid, signal.SIGKILL)
                killed.append(pid)

        t0 = time.perf_counter()
        ws = mech.workspace(("x", "y", "z"), **STUDY, executor=client.get_executor(),
                            checkpoint=Checkpoint(tmp_path / "dask",
                                                  on_chunk=kill_a_busy_worker))
        # the lost chunks' time, not a stall (a stall never ends; the bound leaves room
        # for a loaded machine: 44 s seen with two other jobs on two cores)
        assert time.perf_counter() - t0 < 120
    assert killed
    with pytest.raises(ProcessLookupError):
        os.kill(killed[0], 0)
    _assert_same_workspace(ws, ref)


def test_a_full_disk_during_the_run_is_one_error_and_keeps_the_last_file(tmp_path, monkeypatch,
                                                                        capsys):
    """A write that fails for lack of space (after a first good one) ends the study with
    one error line, status 2; the partial file is the last whole one, no temporary left."""
    import pkm_pin.checkpoint as checkpoint

    savez, calls = np.savez, []

    def filling(f, **arrays):
        calls.append(1)
        if len(calls) > 1:
            f.write(b"PK\x03\x04 truncated")
            raise OSError(28, "No space left on device")
        savez(f, **arrays)

    monkeypatch.setattr(checkpoint, "WRITE_INTERVAL", 0.0)
    monkeypatch.setattr(checkpoint.np, "savez", filling)
    argv = ["workspace", "stewart", "--coords", "x", "y", "z", "--n", "6", "--chunk-size",
            "30", "--quiet", "--out", str(tmp_path / "ws")]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "No space left on device" in err, err
    assert "previous one is kept whole" in err
    monkeypatch.setattr(checkpoint.np, "savez", savez)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ws.partial.npz"]
    with np.load(tmp_path / "ws.partial.npz") as z:
        assert z["cells.done"].sum() == 30
    assert cli.main(argv[:-2] + ["--resume", str(tmp_path / "ws")]) == 0


# ------------------------------------------------- a general mechanism's workspace
#: A general (tree) mechanism's small study: the five-bar's point over a 12 × 12 grid in
#: chunks of 20 reached cells (62 cells reached: 4 chunks).
FIVE_BAR = ROOT / "models" / "loops" / "five_bar.urdf"
LINKAGE_STUDY = dict(n=12, chunk_size=20)


@pytest.fixture(scope="module")
def five_bar():
    """The five-bar (read by the general backend) and its uninterrupted small workspace."""
    import pkm_pin

    mech = pkm_pin.load_mechanism(FIVE_BAR)
    assert mech.backend == "general"
    return mech, mech.workspace(**LINKAGE_STUDY)


def test_a_general_workspace_interrupted_then_resumed_gives_identical_arrays(five_bar,
                                                                            tmp_path):
    """The general workspace's cell analyses are checkpointed as a platform's are: a
    KeyboardInterrupt after two chunks keeps them (40 of the 62 reached cells in the
    partial file), the resume analyses the rest and ends with the uninterrupted run's
    arrays, bit for bit, and removes the partial file; a resume with another grid is
    refused, naming what differs."""
    mech, ref = five_bar
    assert ref.counts["reachable"] == 62
    prefix = tmp_path / "ws"
    with pytest.raises(Interrupted) as info:
        mech.workspace(**LINKAGE_STUDY, checkpoint=Checkpoint(prefix,
                                                              on_chunk=_stop_at("cells", 2)))
    assert info.value.checkpoint.summary() == "40 of 62 cells done"
    with np.load(tmp_path / "ws.partial.npz") as z:
        assert int(z["cells.done"].sum()) == 40
        assert set(z["cells.singularity"][z["cells.done"]]) <= {"none", "I", "II", "III"}
    with pytest.raises(InputError, match="another study.*n"):
        mech.workspace(n=11, chunk_size=20, checkpoint=prefix, resume=True)
    ws = mech.workspace(**LINKAGE_STUDY, checkpoint=prefix, resume=True)
    _assert_same_workspace(ws, ref)
    assert not (tmp_path / "ws.partial.npz").exists()


def test_a_general_workspace_on_processes_gives_the_same_arrays(five_bar):
    """The cell analyses of a general workspace on a process pool (the linkage pickled to
    the workers, chunks gathered as they finish) give the sequential run's arrays."""
    from concurrent.futures import ProcessPoolExecutor

    mech, ref = five_bar
    with ProcessPoolExecutor(2) as executor:
        ws = mech.workspace(**LINKAGE_STUDY, executor=executor)
    _assert_same_workspace(ws, ref)


def test_the_cli_workspace_of_a_general_mechanism_takes_jobs(tmp_path, capsys):
    """pkm-pin workspace on a general mechanism: --jobs 2 gives the plain run's volumes
    (the signalled run resumed: above); a partial file of the API's study is not the
    CLI's (its identity holds the file); --at naming a varied coordinate is refused in
    one line (a slice at a held coordinate: test_workspace)."""
    base = ["workspace", str(FIVE_BAR), "--n", "12", "--chunk-size", "20", "--quiet",
            "--json"]
    assert cli.main(base + ["--out", str(tmp_path / "plain")]) == 0
    plain = capsys.readouterr().out
    assert cli.main(base + ["--jobs", "2", "--out", str(tmp_path / "jobs")]) == 0
    assert _volumes(capsys.readouterr().out) == _volumes(plain)
    import pkm_pin

    with pytest.raises(Interrupted):
        pkm_pin.load_mechanism(FIVE_BAR).workspace(**LINKAGE_STUDY, checkpoint=Checkpoint(
            tmp_path / "cut", on_chunk=_stop_at("cells", 1), keep=True))
    assert (tmp_path / "cut.partial.npz").exists()
    assert cli.main(base + ["--out", str(tmp_path / "cut"), "--resume",
                            str(tmp_path / "cut")]) == 2  # another study: the CLI's identity
    err = capsys.readouterr().err
    assert "another study" in err and err.count("\n") == 1
    assert cli.main(base + ["--at", "x=0.01", "--out", str(tmp_path / "at")]) == 2
    err = capsys.readouterr().err
    assert "at: x is varied" in err and err.count("\n") == 1


def _volumes(text: str) -> dict:
    import json

    data = json.loads(text)
    return {k: v for k, v in data["volumes"].items()}


def test_a_general_sweep_takes_the_sweep_keywords_and_resumes_to_identical_arrays(tmp_path):
    """A general mechanism's sweep takes Mechanism.sweep's keywords: progress, rtol,
    singular_tol, chunk_size and a checkpoint; interrupted after three chunks of seven
    rows (along a path that leaves the workspace and comes back, so that rows fail in
    between) and resumed, it ends with the uninterrupted sweep's arrays and failures, bit
    for bit: the rows after the resume start from the last recorded configuration. An
    executor is refused in a sentence (the rows follow one branch)."""
    import pkm_pin

    mech = pkm_pin.load_mechanism(FIVE_BAR)
    h = mech.home_assembly.q_actuated
    s = np.r_[np.linspace(0.0, 0.6, 25), np.linspace(0.6, 0.0, 25)]
    Q = h + s[:, None] * np.array([1.0, -0.7])
    ref = mech.sweep(Q, transmission=True)
    assert 0 < ref.ok.sum() < len(Q) and ref.ok[-1]
    plain = mech.sweep(Q, transmission=True, progress=False, chunk_size=7,
                       rtol=1e-9, singular_tol=1e-3)
    for key, value in ref.arrays().items():
        assert _same(plain.arrays()[key], value), key
    with pytest.raises(Interrupted):
        mech.sweep(Q, transmission=True, chunk_size=7,
                   checkpoint=Checkpoint(tmp_path / "s", on_chunk=_stop_at("sweep", 3)))
    with np.load(tmp_path / "s.partial.npz") as z:
        assert int(z["sweep.done"].sum()) == 21
    again = mech.sweep(Q, transmission=True, chunk_size=7,
                       checkpoint=Checkpoint(tmp_path / "s", resume=True))
    for key, value in ref.arrays().items():
        assert _same(again.arrays()[key], value), key
    assert again.failures == ref.failures and again.ok.sum() == ref.ok.sum()
    with np.load(tmp_path / "s.partial.npz") as z:  # a sweep leaves it to its caller
        assert bool(z["sweep.done"].all())
    with pytest.raises(InputError, match="executor: a general sweep follows one branch"):
        mech.sweep(Q, executor=object())


def test_a_map_over_actuated_coordinates_refuses_jobs_in_a_sentence(tmp_path, capsys):
    """map over actuated coordinates with --jobs 2: one error line (status 2) saying that
    the map follows one branch and runs in one process; nothing written."""
    argv = ["map", str(FIVE_BAR), "--n", "5", "--jobs", "2", "--quiet",
            "--out", str(tmp_path / "m")]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "follows one branch" in err
    assert list(tmp_path.iterdir()) == []
