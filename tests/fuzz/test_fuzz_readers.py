"""Fuzzing every reader through the CLI (issue 28): ``pkm-pin analyze FILE --json`` on
structure-aware mutations of the real-files corpus (see ``mutations.py``), each case in a
child of the fork server (``fork_server.py``) under a wall-clock and a memory limit.

Each case must end in one of two ways:

- exit 0 and stdout one strict JSON document with finite numbers only (no NaN, no
  Infinity, no number that overflows to inf), nothing on stderr;
- exit 2 and stderr exactly one line ``pkm-pin: error: …`` naming one of the case's files.

Anything else — a traceback (an exception escaping ``main``), a hang (the wall-clock limit
passed), a crash (the child ended by a signal, a segfault or the memory limit), another
exit status, several lines, a warning — fails the test; the case is written to
:data:`FOUND` so that it can be kept as a regression test. ``--fuzz-examples N`` sets the
cases per reader.
"""

from __future__ import annotations

import hashlib
import json
import math
import tempfile
from pathlib import Path

import fuzz_tally
from fork_server import OUT_OF_MEMORY, TRACEBACK
from hypothesis import HealthCheck, given, seed, settings
from mutations import extended_urdf_case, mjcf_case, toml_case

#: Wall-clock limit per case [s]: far above the slowest corpus file (about 3 s alone,
#: more on a loaded machine), far below "hangs".
TIMEOUT = 30.0
#: Address space a case may add to the server's [bytes] (issue 28: under 500 MB).
MEMORY = 512 << 20
#: Where failing cases are written (one folder per case, named by its hash).
FOUND = Path(tempfile.gettempdir()) / "pkm_fuzz_found"


def _refuse_constant(name: str):
    raise ValueError(f"non-strict JSON constant {name}")


def _finite_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"JSON number {text} is not finite as a float")
    return value


#: numba's notice of a first compilation (pkm_pin.compiling): information, not an error
#: line; a child compiles what the server's warm-up did not reach.
COMPILE_NOTICE = ("pkm_pin: compiling ", "pkm_pin: compiled in ")


def _stderr(text: str) -> str:
    """``text`` less numba's compile notices."""
    return "\n".join(line for line in text.splitlines() if not line.startswith(COMPILE_NOTICE))


def classify(outcome, names: list[str]) -> str:
    """``"ok"``, ``"refused"``, or the kind of failure of one case."""
    if outcome.hung:
        return "hang"
    if outcome.signal is not None:
        return f"crash (signal {outcome.signal})"
    if outcome.status == TRACEBACK:
        return "traceback"
    if outcome.status == OUT_OF_MEMORY:
        return "out of memory"
    if outcome.status == 0:
        try:
            json.loads(outcome.stdout, parse_constant=_refuse_constant, parse_float=_finite_float)
        except ValueError:
            return "non-strict JSON"
        return "ok" if not _stderr(outcome.stderr).strip() else "stderr on success"
    if outcome.status == 2:
        lines = _stderr(outcome.stderr).strip().splitlines()
        if len(lines) != 1 or not lines[0].startswith("pkm-pin: error: "):
            return "not one error line"
        return "refused" if any(n in lines[0] for n in names) else "file not named"
    return f"exit status {outcome.status}"


def _keep(files: dict, main: str, outcome, kind: str) -> Path:
    """Write a failing case to FOUND; return its folder."""
    digest = hashlib.sha1(b"".join(k.encode() + v for k, v in sorted(files.items())))
    folder = FOUND / digest.hexdigest()[:12]
    folder.mkdir(parents=True, exist_ok=True)
    for name, data in files.items():
        (folder / name).write_bytes(data)
    (folder / "outcome.txt").write_text(f"{kind}: pkm-pin analyze {main} --json\n"
                                        f"status {outcome.status} signal {outcome.signal}\n"
                                        f"--- stderr\n{outcome.stderr[-5000:]}\n")
    return folder


def run_case(fork_server, reader: str, case: tuple[dict, str]) -> None:
    """Write the case into an empty folder, analyse it, tally and check the outcome."""
    files, main = case
    with tempfile.TemporaryDirectory(prefix="pkm_case_") as folder:
        for name, data in files.items():
            (Path(folder) / name).write_bytes(data)
        outcome = fork_server.run(["analyze", str(Path(folder) / main), "--json"],
                                  timeout=TIMEOUT, memory=MEMORY)
    kind = classify(outcome, list(files))
    fuzz_tally.record(reader, kind, outcome.seconds)
    if kind not in ("ok", "refused"):
        folder = _keep(files, main, outcome, kind)
        raise AssertionError(f"{reader}: {kind}, case kept in {folder}:\n"
                             f"{outcome.stderr[-3000:]}")


#: What a reader's tally may hold once its cases passed: counts of the two good outcomes.
GOOD = {"cases", "seconds", "slowest", "ok", "refused"}


def _fuzz(fork_server, tally, examples: int, fuzz_seed: int | None, reader: str,
          strategy) -> int:
    """``examples`` cases of ``strategy``: hypothesis's fixed ones, or drawn from
    ``fuzz_seed``; returns how many ran."""
    @settings(max_examples=examples, deadline=None, derandomize=fuzz_seed is None,
              database=None, suppress_health_check=list(HealthCheck))
    @given(case=strategy)
    def check(case):
        run_case(fork_server, reader, case)

    before = tally[reader]["cases"]
    (check if fuzz_seed is None else seed(fuzz_seed)(check))()
    return tally[reader]["cases"] - before


def test_extended_urdf_mutations(fork_server, tally, fuzz_examples, fuzz_seed):
    """Gepetto folders and shipped loop models: URDF and YAML mutated."""
    ran = _fuzz(fork_server, tally, fuzz_examples, fuzz_seed, "Extended URDF", extended_urdf_case())
    assert ran >= min(fuzz_examples, 1) and set(tally["Extended URDF"]) <= GOOD


def test_mjcf_mutations(fork_server, tally, fuzz_examples, fuzz_seed):
    """Pinocchio's Cassie MJCF and the shipped MJCF loop models mutated."""
    ran = _fuzz(fork_server, tally, fuzz_examples, fuzz_seed, "MJCF", mjcf_case())
    assert ran >= min(fuzz_examples, 1) and set(tally["MJCF"]) <= GOOD


def test_toml_mutations(fork_server, tally, fuzz_examples, fuzz_seed):
    """Shipped mechanism files (and sometimes the leg URDF they name) mutated."""
    ran = _fuzz(fork_server, tally, fuzz_examples, fuzz_seed, "TOML", toml_case())
    assert ran >= min(fuzz_examples, 1) and set(tally["TOML"]) <= GOOD
