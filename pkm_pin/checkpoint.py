"""Checkpoints of long studies: nothing computed is lost to an interrupt.

A sweep-based study (:func:`pkm_pin.sweep.sweep`, :func:`pkm_pin.workspace.workspace`,
``pkm-pin map`` and ``pkm-pin workspace``) given a :class:`Checkpoint` writes what it has
computed to ``PREFIX.partial.npz`` as it goes, chunk by chunk, and can continue from it.

File format (one ``numpy.savez`` archive, written to a temporary name in the same folder
and renamed over the final name: a reader never sees a truncated file):

* ``format``: ``"pkm_pin.partial/1"``;
* ``study``: the study's identity, a JSON object (mechanism, its file and the file's
  SHA-256, coordinates, bounds, grid, options, pkm_pin's version); a resume of another
  study is refused with the first key that differs;
* ``stages``: the names of the stages begun (a workspace: ``cells``, then ``refine``,
  the boundary cells' sub-points), and per stage ``S``:
  ``S.fingerprint`` (SHA-256 of the stage's poses, chunk size and options: the chunks
  of a resume are those of the first run), ``S.done`` (per pose), the sweep's per-pose
  arrays ``S.ok``, ``S.dof``, ``S.type_I``, ``S.type_II``, ``S.condition``, ``S.det``,
  ``S.q_actuated``, ``S.lti``, ``S.cti`` (the caller's pose order; meaningful where
  ``done``), ``S.failure_index`` and ``S.failure_reason``; a general mechanism's
  workspace keeps its cells' ``S.ok``, ``S.singularity``, ``S.det``, ``S.lti``,
  ``S.cti`` and ``S.dof`` instead (stage ``cells``, over the cells its continuation
  reached).

A chunk is recorded whole or not at all, and each chunk is evaluated from the same poses
whether or not the run was interrupted (every chunk warm-starts from home), so a resumed
study ends with arrays identical, bit for bit, to an uninterrupted one.

The file is written after the first chunk, then after the chunk that ends
:data:`WRITE_INTERVAL` seconds after the last write (or 20 times the last write's
duration when that is longer: writing costs at most ~5 % of the run), at the end of each
stage and when the study is interrupted (a process killed outright, SIGKILL or a power
cut, loses the chunks since the last write).

Interrupts: inside :func:`graceful_stop` (the CLI), the first SIGINT or SIGTERM asks the
running study to stop after its current chunk (:class:`Interrupted` is raised once the
file is written); a second one, or one outside a checkpointed loop, stops at once. A
``KeyboardInterrupt`` raised in the middle of a chunk without :func:`graceful_stop` (a
notebook) loses that chunk only: the chunks done are written and :class:`Interrupted`
is raised.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import shutil
import signal
import tempfile
import time
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np

from .errors import InputError, PkmError

#: The ``format`` entry of a partial file.
FORMAT = "pkm_pin.partial/1"
#: Time [s] between two writes of the partial file while a study runs (at least 20
#: times the last write's duration).
WRITE_INTERVAL = 10.0
#: Per-pose arrays of a sweep kept in a stage, with their fill values.
SWEEP_FIELDS = ("ok", "dof", "type_I", "type_II", "condition", "det", "q_actuated", "lti",
                "cti")


class CheckpointError(PkmError, OSError):
    """The partial file could not be written (a full disk, a folder made read-only
    during the run): the previous partial file is whole, the temporary one removed."""


class Interrupted(KeyboardInterrupt):
    """A checkpointed study stopped by SIGINT (Ctrl-C) or SIGTERM, its finished chunks
    written (a ``KeyboardInterrupt``: code that catches those still does).

    Attributes:
        signum: ``signal.SIGINT`` or ``signal.SIGTERM``.
        checkpoint: The :class:`Checkpoint` holding what was done (None when the
            interrupt came before a checkpointed loop started).
    """

    def __init__(self, signum: int = signal.SIGINT, checkpoint: Checkpoint | None = None):
        self.signum = int(signum)
        self.checkpoint = checkpoint
        super().__init__(self.summary())

    def summary(self) -> str:
        """``"N of M cells done"`` (or that nothing was saved)."""
        if self.checkpoint is None:
            return "no checkpointed work had started"
        return self.checkpoint.summary()

    @property
    def exit_status(self) -> int:
        """128 + the signal's number: 130 for SIGINT, 143 for SIGTERM."""
        return 128 + self.signum


# ---------------------------------------------------------------- stopping on a signal
_STOP: dict = {"signum": None, "loops": 0, "installed": False}


def stop_requested() -> int | None:
    """The signal that asked the running study to stop after its chunk (None: none)."""
    return _STOP["signum"]


@contextlib.contextmanager
def graceful_stop(message: Callable[[int], None] | None = None):
    """While inside, SIGINT and SIGTERM ask a checkpointed loop to stop after its
    current chunk (``message(signum)`` is called, e.g. to say so); a second signal, or one
    while no checkpointed loop runs, raises :class:`Interrupted` at once. Main thread
    only (elsewhere it does nothing)."""
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum, frame):
        if _STOP["signum"] is not None or not _STOP["loops"]:
            raise Interrupted(signum)
        _STOP["signum"] = signum
        if message is not None:
            message(signum)

    old = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
    _STOP.update(signum=None, installed=True)
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)
        _STOP.update(signum=None, installed=False)


# ---------------------------------------------------------------- atomic files
def atomic_write(path, write: Callable[[str], None], suffix: str = "") -> Path:
    """Write ``path`` through ``write(tmp)`` on a temporary name in the same folder, then
    rename it over ``path`` (``os.replace``): ``path`` is either the old file or the
    whole new one, never a truncated one. ``suffix``: the temporary name's ending
    (``numpy.savez`` appends ``.npz`` to names without it)."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix + ".tmp",
                               dir=path.parent)
    os.close(fd)
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.remove(tmp)
        raise
    return path


def atomic_savez(path, compressed: bool = False, **arrays) -> Path:
    """``numpy.savez`` (``savez_compressed``) of ``arrays`` to ``path`` by
    :func:`atomic_write`."""
    save = np.savez_compressed if compressed else np.savez

    def write(tmp):
        with open(tmp, "wb") as f:  # a file object: numpy adds no suffix
            save(f, **arrays)

    return atomic_write(path, write)


def check_writable(folder, what: str, need: int = 0) -> None:
    """An :class:`InputError` unless files can be created in ``folder`` (it exists, is a
    folder, a test file can be created and removed there) with ``need`` bytes free."""
    folder = Path(folder)
    if not folder.exists():
        raise InputError(f"{what}: the folder {folder} does not exist")
    if not folder.is_dir():
        raise InputError(f"{what}: {folder} is not a folder")
    try:
        fd, tmp = tempfile.mkstemp(prefix=".pkm_pin-write-test.", dir=folder)
        os.close(fd)
        os.remove(tmp)
    except OSError as e:
        raise InputError(f"{what}: cannot write in the folder {folder}: "
                         f"{e.strerror or e}") from e
    if need:
        free = shutil.disk_usage(folder).free
        if free < need:
            raise InputError(f"{what}: the folder {folder} has {free / 1e6:.1f} MB free, the "
                             f"study's files need about {need / 1e6:.1f} MB")


def file_digest(path) -> str:
    """SHA-256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _jsonable(x):
    if isinstance(x, Mapping):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple, np.ndarray)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x).hex()  # exact, and nan/inf are strings
    if isinstance(x, Path):
        return str(x)
    return x


def study_json(study: Mapping) -> str:
    """The canonical JSON of a study's identity (sorted keys, floats exact)."""
    return json.dumps(_jsonable(study), sort_keys=True, separators=(",", ":"))


# ---------------------------------------------------------------- the checkpoint
class Checkpoint:
    """``PREFIX.partial.npz``: a study's results so far, per stage (module docstring).

    Args:
        prefix: The study's output prefix (the file is ``PREFIX.partial.npz``).
        resume: Continue the study saved there (it must exist and be the same study);
            otherwise an existing partial file is refused (nothing is overwritten).
        keep: Keep the file once the study has finished (the CLI removes it itself,
            after its outputs are written); otherwise the study removes it.
        interval: Time [s] between writes (:data:`WRITE_INTERVAL`; 0: after every
            chunk, as long as writing costs under ~5 %).
        on_chunk: Called as ``on_chunk(stage_name, chunks_recorded)`` after each chunk is
            recorded (tests inject interrupts with it).
        identity: More of the study's identity (the CLI: the mechanism file and its
            SHA-256), merged into what the study gives :meth:`begin`.

    Raises:
        InputError: the folder does not exist, is not a folder or is not writable; the
            partial file's name is taken by a folder; ``resume`` without a partial file,
            or a partial file without ``resume``.
    """

    def __init__(self, prefix, *, resume: bool = False, keep: bool = False,
                 interval: float | None = None,
                 on_chunk: Callable[[str, int], None] | None = None,
                 identity: Mapping | None = None):
        self.prefix = Path(prefix)
        self.identity = dict(identity or {})
        self.path = self.prefix.with_name(self.prefix.name + ".partial.npz")
        self.resume, self.keep = bool(resume), bool(keep)
        self.interval = float(WRITE_INTERVAL if interval is None else interval)
        self.on_chunk = on_chunk
        check_writable(self.path.parent, f"checkpoint {self.path}")
        if self.path.exists() and not self.path.is_file():
            raise InputError(f"checkpoint {self.path}: the name is taken by something that "
                             "is not a file")
        self.study: dict | None = None
        self.stages: dict[str, _Stage] = {}
        self._saved: dict[str, np.ndarray] = {}
        self._last_write: float | None = None
        self._write_cost = 0.0
        self._dirty = False
        #: Writes of the partial file so far, and the seconds they took.
        self.writes, self.write_seconds = 0, 0.0
        if self.resume:
            if not self.path.is_file():
                raise InputError(f"--resume {self.prefix}: there is no {self.path} to "
                                 "continue from")
            self._saved = _read(self.path)
        elif self.path.is_file():
            raise InputError(f"{self.path} holds an unfinished study: continue it with "
                             f"--resume {self.prefix}, or remove the file to start again")

    # ------------------------------------------------------------- identity
    def begin(self, study: Mapping, need: int = 0) -> None:
        """Set the study's identity (a JSON-able mapping); on resume, refuse a partial
        file of another study with the first key that differs. ``need``: bytes the
        folder must have free (an :class:`InputError` before the work starts)."""
        text = study_json({"pkm_pin": _version(), **study, **self.identity})
        if self.resume:
            saved = str(self._saved["study"])
            if saved != text:
                raise InputError(f"--resume {self.prefix}: {self.path} is another study "
                                 f"({_first_difference(json.loads(saved), json.loads(text))})"
                                 "; give the same command and options, or another --out")
        self.study = json.loads(text)
        self._text = text
        if need:
            check_writable(self.path.parent, f"checkpoint {self.path}", need)

    @contextlib.contextmanager
    def running(self):
        """While inside, a signal caught by :func:`graceful_stop` asks for a stop after
        the current chunk (outside, it stops at once)."""
        _STOP["loops"] += 1
        try:
            yield
        finally:
            _STOP["loops"] -= 1

    def stage(self, name: str) -> _Stage:
        """The stage ``name`` of the study (created on first use; a study not begun is
        begun with no more identity than its stages' poses)."""
        if self.study is None:
            self.begin({})
        if name not in self.stages:
            self.stages[name] = _Stage(self, name)
        return self.stages[name]

    # ------------------------------------------------------------- progress
    def summary(self) -> str:
        """What is done: ``"N of M cells done"`` per stage begun."""
        parts = []
        for st in self.stages.values():
            if st.done is None:
                continue
            what = "cells" if st.name in ("cells", "sweep", "poses") else \
                f"{st.name} points"
            parts.append(f"{int(st.done.sum())} of {st.done.size} {what} done")
        return ", ".join(parts) if parts else "nothing done yet"

    def poll(self) -> None:
        """Stop (write the file, raise :class:`Interrupted`) when a signal asked to."""
        signum = stop_requested()
        if signum is not None:
            self.flush()
            raise Interrupted(signum, self)

    def _recorded(self, stage: _Stage, check: bool = True) -> None:
        """After a chunk: write the file when due; with ``check``, stop when a signal
        asked to."""
        now = time.perf_counter()
        due = self._last_write is None or \
            now - self._last_write >= max(self.interval, 20.0 * self._write_cost)
        if due or stop_requested() is not None:
            self.flush()
        if self.on_chunk is not None:
            self.on_chunk(stage.name, stage.chunks_recorded)
        if check:
            self.poll()

    def flush(self) -> None:
        """Write the partial file now (atomically) when something changed."""
        if not self._dirty:
            return
        t = time.perf_counter()
        arrays = {"format": np.array(FORMAT), "study": np.array(self._text),
                  "stages": np.array(list(self.stages), dtype=str)}
        for st in self.stages.values():
            arrays.update(st.arrays())
        try:
            atomic_savez(self.path, **arrays)
        except OSError as e:
            self._dirty = False  # not tried again while the error goes up
            kept = " (the previous one is kept whole)" if self.path.is_file() else ""
            raise CheckpointError(f"cannot write the partial results {self.path}{kept}: "
                                  f"{e.strerror or e}") from e
        self._last_write = time.perf_counter()
        self._write_cost = self._last_write - t
        self.writes += 1
        self.write_seconds += self._write_cost
        self._dirty = False

    def interrupted(self, error: BaseException) -> None:
        """On any exception leaving a checkpointed loop: write what is done; a
        ``KeyboardInterrupt`` becomes :class:`Interrupted` (with this checkpoint)."""
        self.flush()
        if isinstance(error, Interrupted):
            if error.checkpoint is None:
                error.checkpoint = self
            raise error
        if isinstance(error, KeyboardInterrupt):
            raise Interrupted(signal.SIGINT, self) from error

    def finish(self) -> None:
        """The study has finished: remove the file unless ``keep`` (then write it
        whole)."""
        if self.keep:
            self.flush()
        else:
            self.remove()

    def remove(self) -> None:
        """Remove the partial file (once the study's outputs are written)."""
        with contextlib.suppress(FileNotFoundError):
            os.remove(self.path)


class _Stage:
    """One sweep of a study: its per-pose arrays and ``done`` mask."""

    def __init__(self, cp: Checkpoint, name: str):
        self.cp, self.name = cp, name
        self.done: np.ndarray | None = None
        self.values: dict[str, np.ndarray] = {}
        self.failures: dict[int, str] = {}
        self.fingerprint = ""
        self.chunks_recorded = 0
        #: The per-pose arrays kept (a sweep's :data:`SWEEP_FIELDS`, or the keys of
        #: the ``empty`` arrays the stage began with).
        self.fields: tuple[str, ...] = SWEEP_FIELDS

    def begin(self, X: np.ndarray, chunks: list, options: Mapping,
              empty: dict[str, np.ndarray]) -> list:
        """Start the stage on the poses ``X`` cut in ``chunks`` (``empty``: the caller's
        per-pose arrays, not yet computed, filled from the file); returns per chunk the
        part restored from the file (as :func:`pkm_pin.sweep.evaluate_chunk` returns
        it), or None (to evaluate)."""
        h = hashlib.sha256(np.ascontiguousarray(X, dtype=float).tobytes())
        h.update(study_json({"options": options, "chunks": [len(c) for c in chunks],
                             "order": hashlib.sha256(np.concatenate(chunks).astype(np.int64)
                                                     .tobytes()).hexdigest()
                             if chunks else ""}).encode())
        self.fingerprint = h.hexdigest()
        self.fields = tuple(empty)
        N = len(X)
        saved = self.cp._saved
        key = f"{self.name}.fingerprint"
        self.values = empty
        self.done = np.zeros(N, bool)
        self.failures = {}
        parts: list = [None] * len(chunks)
        if key in saved:
            if str(saved[key]) != self.fingerprint:
                raise InputError(f"--resume {self.cp.prefix}: the {self.name} of "
                                 f"{self.cp.path} were computed from other poses or options")
            self.done = saved[f"{self.name}.done"].astype(bool).copy()
            for f in self.fields:
                self.values[f] = saved[f"{self.name}.{f}"].copy()
            self.failures = {int(i): str(r) for i, r in
                             zip(saved[f"{self.name}.failure_index"],
                                 saved[f"{self.name}.failure_reason"])}
            for k, c in enumerate(chunks):
                if self.done[c].all():
                    part = {f: self.values[f][c] for f in self.fields}
                    part["failures"] = [(i, self.failures[int(g)]) for i, g in enumerate(c)
                                        if int(g) in self.failures]
                    parts[k] = part
        self.cp._dirty = True
        return parts

    def record(self, idx: np.ndarray, part: Mapping, check: bool = True) -> None:
        """A chunk's results (poses ``idx``): kept, then written when due
        (:meth:`Checkpoint._recorded`; ``check``: then stop if a signal asked to)."""
        for f in self.fields:
            self.values[f][idx] = part[f]
        for i, reason in part["failures"]:
            self.failures[int(idx[i])] = reason
        self.done[idx] = True
        self.chunks_recorded += 1
        self.cp._dirty = True
        self.cp._recorded(self, check)

    def end(self) -> None:
        """Every chunk done: write the file (a later stage may be interrupted)."""
        self.cp.flush()

    def arrays(self) -> dict[str, np.ndarray]:
        if self.done is None:
            return {}
        idx = sorted(self.failures)
        out = {f"{self.name}.fingerprint": np.array(self.fingerprint),
               f"{self.name}.done": self.done,
               f"{self.name}.failure_index": np.array(idx, dtype=np.int64),
               f"{self.name}.failure_reason": np.array([self.failures[i] for i in idx],
                                                       dtype=str)}
        out.update({f"{self.name}.{f}": self.values[f] for f in self.fields})
        return out


@contextlib.contextmanager
def recording(stage: _Stage | None):
    """The chunk loop of a checkpointed study, around which it runs (``stage`` None: no
    checkpoint, nothing done): a signal caught by :func:`graceful_stop` stops it after
    the current chunk (:meth:`Checkpoint.running`); any exception leaving it writes the
    chunks recorded (:meth:`Checkpoint.interrupted`: a ``KeyboardInterrupt`` becomes
    :class:`Interrupted`); a loop that ends writes the file (:meth:`_Stage.end`)."""
    if stage is None:
        yield
        return
    try:
        with stage.cp.running():
            yield
    except BaseException as e:  # Ctrl-C, SIGTERM, a failed chunk: keep the chunks done
        stage.cp.interrupted(e)
        raise
    stage.end()


def checkpoint_of(checkpoint, resume: bool = False) -> Checkpoint | None:
    """A :class:`Checkpoint` from an API's ``checkpoint`` argument: None, a Checkpoint, or
    an output prefix (``resume``: continue the study saved there)."""
    if checkpoint is None or isinstance(checkpoint, Checkpoint):
        if resume and checkpoint is None:
            raise InputError("resume=True needs checkpoint=PREFIX (the study to continue)")
        return checkpoint
    if isinstance(checkpoint, (str, os.PathLike)):
        return Checkpoint(checkpoint, resume=resume)
    raise InputError(f"checkpoint must be an output prefix or a pkm_pin.checkpoint."
                     f"Checkpoint, got {type(checkpoint).__name__}")


def _read(path: Path) -> dict[str, np.ndarray]:
    """Every array of a partial file (an :class:`InputError` when it is not one)."""
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except (OSError, ValueError, EOFError) as e:
        raise InputError(f"{path} is not a readable partial file: {e}") from e
    if str(data.get("format", "")) != FORMAT or "study" not in data:
        raise InputError(f"{path} is not a pkm_pin partial file (format "
                         f"{str(data.get('format', 'missing'))[:40]!r})")
    return data


def _first_difference(a, b, where: str = "") -> str:
    """The first key where two studies differ: ``"n: 60 there, 30 here"``."""
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if a.get(k) != b.get(k):
                return _first_difference(a.get(k), b.get(k), f"{where}.{k}" if where else k)
    return f"{where or 'study'}: {_shown(a)} there, {_shown(b)} here"


def _shown(x) -> str:
    def unhex(v):
        if isinstance(v, str) and v.startswith(("0x", "-0x")) and "p" in v:
            return float.fromhex(v)
        if isinstance(v, list):
            return [unhex(u) for u in v]
        return v

    text = json.dumps(unhex(x))
    return text if len(text) <= 80 else text[:77] + "..."


def interrupt_line(error: Interrupted, command: str | None) -> str:
    """The one line the CLI prints on an interrupt: what is done, where, how to continue."""
    sig = "SIGTERM" if error.signum == signal.SIGTERM else "SIGINT"
    cp = error.checkpoint
    if cp is None or not cp.path.is_file():
        return f"pkm-pin: interrupted ({sig}); nothing was saved"
    return (f"pkm-pin: interrupted ({sig}): {error.summary()}, saved in {cp.path}; "
            f"continue with: {command}")


__all__ = ["Checkpoint", "CheckpointError", "Interrupted", "atomic_savez", "atomic_write",
           "check_writable", "checkpoint_of", "file_digest",
           "graceful_stop", "recording", "stop_requested", "study_json"]


def _version() -> str:
    """pkm_pin's installed version (part of a study's identity)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("pkm_pin")
    except PackageNotFoundError:  # pragma: no cover (run from a source tree)
        return "unknown"
