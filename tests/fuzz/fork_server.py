"""A fork server that runs ``pkm-pin`` on one file per case, in a child process bounded in
time and memory.

Starting ``python -m pkm_pin.cli`` costs 1–2 s (importing Pinocchio, numpy, numba); a
fuzz run of 100 000 cases cannot pay that each time. The server is a long-lived process
that imports :func:`pkm_pin.cli.main` once, runs it once on a few files (so that the lazy
imports are done and numba's kernels are compiled or loaded; children never compile:
:data:`pkm_pin.compiling.PLAIN_CALLS` is raised), then reads one request per line on
stdin and ``os.fork()``\\ s a child per request:

- the child sets ``RLIMIT_AS`` (its address space: the server's own plus a headroom) and
  an alarm (``SIGALRM`` kills it after the time limit, rounded up to whole seconds),
  points its stdout and stderr at two files, runs ``main(argv)`` and leaves with
  ``os._exit(status)``; an exception escaping ``main`` is printed as a traceback and
  leaves with :data:`TRACEBACK` (a ``MemoryError`` with :data:`OUT_OF_MEMORY`);
- the server waits for it with a wall-clock limit (``pidfd`` + ``select``), kills it with
  ``SIGKILL`` when it passes, and answers one JSON line: the exit status, or the signal
  that ended the child, whether it hung, the seconds it took, its stdout and stderr.

:class:`ForkServer` is the test side: it starts the server, sends requests, and parses
the answers into :class:`Outcome`. Run directly (``python fork_server.py``) this module is
the server.
"""

from __future__ import annotations

import json
import os
import select
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

#: Exit status of a child whose ``main`` raised (a traceback is on its stderr).
TRACEBACK = 70
#: Exit status of a child whose ``main`` raised MemoryError (it passed RLIMIT_AS).
OUT_OF_MEMORY = 71
#: Bytes of stdout/stderr sent back per case (the rest is cut; the size is still known).
MAX_OUTPUT = 4_000_000

ROOT = Path(__file__).resolve().parents[2]


# ------------------------------------------------------------------------ server side
def _vm_size() -> int:
    """The server's address space [bytes] (``VmSize`` of /proc/self/status)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmSize:"):
            return int(line.split()[1]) * 1024
    return 0


def _child(main, request: dict, out: str, err: str) -> None:
    """The forked child: limits, redirections, ``main(argv)``; never returns."""
    import resource
    import traceback

    status = TRACEBACK
    try:
        limit = _vm_size() + int(request["memory"])
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
        signal.signal(signal.SIGALRM, signal.SIG_DFL)
        signal.alarm(max(1, int(request["timeout"] + 0.999)))
        for fd, path in ((1, out), (2, err)):
            os.dup2(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600), fd)
        try:
            status = main(request["argv"])
        except MemoryError:
            status = OUT_OF_MEMORY
            traceback.print_exc()
        except BaseException:  # noqa: BLE001 (anything escaping main is the finding)
            traceback.print_exc()
        sys.stdout.flush()
        sys.stderr.flush()
    finally:
        os._exit(status if isinstance(status, int) else TRACEBACK)


def _wait(pid: int, timeout: float) -> tuple[int, bool]:
    """Wait for child ``pid`` at most ``timeout`` seconds, then SIGKILL it: its wait
    status and whether it was killed for passing the limit."""
    fd = os.pidfd_open(pid)
    try:
        hung = not select.select([fd], [], [], timeout)[0]
    finally:
        os.close(fd)
    if hung:
        os.kill(pid, signal.SIGKILL)
    return os.waitpid(pid, 0)[1], hung


def _read(path: str) -> str:
    with open(path, "rb") as f:
        data = f.read(MAX_OUTPUT)
    return data.decode("utf-8", errors="replace")


def _serve_one(main, request: dict, scratch: Path) -> dict:
    """Fork, run, wait: the answer to one request."""
    out, err = str(scratch / "stdout"), str(scratch / "stderr")
    sys.stdout.flush()
    sys.stderr.flush()
    start = time.perf_counter()
    pid = os.fork()
    if pid == 0:
        _child(main, request, out, err)
    wait_status, hung = _wait(pid, float(request["timeout"]))
    answer = {"seconds": time.perf_counter() - start, "hung": hung, "status": None,
              "signal": None}
    if os.WIFSIGNALED(wait_status):
        answer["signal"] = os.WTERMSIG(wait_status)
    else:
        answer["status"] = os.WEXITSTATUS(wait_status)
    answer["stdout"], answer["stderr"] = _read(out), _read(err)
    return answer


def serve(warm: list[list[str]]) -> None:
    """The server loop: warm up on ``warm`` (argv lists), then answer requests until EOF."""
    import contextlib
    import gc
    import io
    import tempfile
    import warnings

    warnings.simplefilter("default")  # what a user's interpreter shows
    from pkm_pin import compiling
    from pkm_pin.cli import main

    compiling.PLAIN_CALLS = 0  # warming up: compile (or load) every kernel it meets
    for argv in warm:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            main(argv)
    # A child never compiles (40 s, killed at the time limit, its work lost with it): a
    # kernel the warm-up did not meet runs its plain-Python path, as a one-off run on a
    # fresh installation does.
    compiling.PLAIN_CALLS = 10**9
    gc.collect()
    gc.freeze()  # the children's collector leaves the server's objects (and pages) alone
    protocol = sys.stdout
    print(json.dumps({"ready": True, "vm_size": _vm_size()}), file=protocol, flush=True)
    with tempfile.TemporaryDirectory(prefix="pkm_fuzz_") as scratch:
        for line in sys.stdin:
            answer = _serve_one(main, json.loads(line), Path(scratch))
            print(json.dumps(answer), file=protocol, flush=True)


# -------------------------------------------------------------------------- test side
@dataclass(frozen=True)
class Outcome:
    """What one case gave: ``status`` (None when a signal ended it), ``signal``, ``hung``
    (killed at the wall-clock limit), the seconds, stdout and stderr."""

    status: int | None
    signal: int | None
    hung: bool
    seconds: float
    stdout: str
    stderr: str


class ForkServer:
    """The server process, started with ``warm`` argv lists; :meth:`run` is one case."""

    def __init__(self, warm: list[list[str]]):
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(
            [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])]))
        self.process = subprocess.Popen(
            [sys.executable, __file__, json.dumps(warm)], stdin=subprocess.PIPE,
            stdout=subprocess.PIPE, text=True, env=env, cwd=str(ROOT))
        hello = self.process.stdout.readline()
        if not hello:
            raise RuntimeError("the fuzz fork server did not start (see its stderr above)")
        self.vm_size = json.loads(hello)["vm_size"]

    def run(self, argv: list[str], timeout: float = 20.0, memory: int = 1 << 30) -> Outcome:
        """``pkm-pin ARGV`` in a fresh child: at most ``timeout`` seconds of wall-clock
        time and ``memory`` bytes of address space beyond the server's."""
        request = {"argv": argv, "timeout": timeout, "memory": memory}
        self.process.stdin.write(json.dumps(request) + "\n")
        self.process.stdin.flush()
        answer = self.process.stdout.readline()
        if not answer:
            raise RuntimeError("the fuzz fork server died")
        a = json.loads(answer)
        return Outcome(a["status"], a["signal"], a["hung"], a["seconds"], a["stdout"],
                       a["stderr"])

    def close(self) -> None:
        """Stop the server (EOF on its stdin) and wait for it."""
        self.process.stdin.close()
        try:
            self.process.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()


if __name__ == "__main__":
    serve(json.loads(sys.argv[1]))
