"""The fork server of the fuzz suite (one per session) and its tally per reader.

``--fuzz-examples N`` (declared in ``tests/conftest.py``, so that it exists wherever pytest
starts) sets the examples per reader; without it each reader gets :data:`CI_EXAMPLES`,
which keeps ``python -m pytest tests/fuzz`` under a minute on a small machine.
"""

from __future__ import annotations

import fuzz_tally
import pytest
from fork_server import ForkServer
from mutations import MJCF_CORPUS, MODELS, TOML_CORPUS

#: Examples per reader when --fuzz-examples is not given (CI's budget).
CI_EXAMPLES = 40


@pytest.fixture(scope="session")
def fuzz_examples(request) -> int:
    """Examples per reader (``--fuzz-examples``)."""
    return request.config.getoption("--fuzz-examples") or CI_EXAMPLES


@pytest.fixture(scope="session")
def fuzz_seed(request) -> int | None:
    """``--fuzz-seed``: None for hypothesis's derandomised examples."""
    return request.config.getoption("--fuzz-seed")


@pytest.fixture(scope="session")
def fork_server():
    """The fork server, warmed up on the small files of the corpus (lazy imports, numba's
    kernels compiled or loaded)."""
    files = [*TOML_CORPUS, *MJCF_CORPUS, *sorted((MODELS / "loops").glob("*.urdf"))]
    warm = [["analyze", str(f), "--json"] for f in files]
    server = ForkServer(warm)
    yield server
    server.close()


@pytest.fixture(scope="session")
def tally():
    """The per-reader outcomes (``fuzz_tally.TALLY``)."""
    return fuzz_tally.TALLY


def pytest_terminal_summary(terminalreporter):
    """One line per reader: cases run, outcomes, seconds per case."""
    if fuzz_tally.TALLY:
        terminalreporter.section("fuzz cases per reader")
        for line in fuzz_tally.lines():
            terminalreporter.write_line(line)
        fuzz_tally.write()
