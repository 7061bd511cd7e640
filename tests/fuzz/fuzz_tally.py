"""The outcomes of the fuzz cases, per reader: "cases", "seconds" (in the children) and
the "slowest" case, "ok" (exit 0, strict finite JSON), "refused" (exit 2, one line naming
the file), and each kind of failure. Printed at the end of the run (``conftest.py``)
and, while a long run goes on, written to ``$PKM_FUZZ_TALLY`` every 50 cases of a
reader."""

from __future__ import annotations

import json
import os
from collections import Counter, defaultdict

TALLY: dict[str, Counter] = defaultdict(Counter)


def record(reader: str, kind: str, seconds: float) -> None:
    """Count one case of ``reader`` that ended as ``kind``."""
    TALLY[reader]["cases"] += 1
    TALLY[reader]["seconds"] += seconds
    TALLY[reader]["slowest"] = max(TALLY[reader]["slowest"], seconds)
    TALLY[reader][kind] += 1
    if TALLY[reader]["cases"] % 50 == 0 or kind not in ("ok", "refused"):
        write()


def write() -> None:
    """The tally as JSON into ``$PKM_FUZZ_TALLY`` when that is set."""
    path = os.environ.get("PKM_FUZZ_TALLY")
    if path:
        with open(path + ".tmp", "w") as f:
            json.dump(TALLY, f)
        os.replace(path + ".tmp", path)


def lines() -> list[str]:
    """One line per reader: cases, outcomes, failures by kind, seconds per case."""
    out = []
    for reader, c in sorted(TALLY.items()):
        fails = {k: v for k, v in c.items()
                 if k not in ("cases", "ok", "refused", "seconds", "slowest")}
        out.append(f"{reader:14s} cases {c['cases']:7d}  ok {c['ok']:7d}  "
                   f"refused {c['refused']:7d}  failures {sum(fails.values())} "
                   f"{dict(fails) or ''}  {c['seconds'] / max(c['cases'], 1):.3f} s/case, "
                   f"slowest {c['slowest']:.2f} s")
    return out
