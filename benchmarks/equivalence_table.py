"""Equivalence of the general linkage reading with seed 000's per-leg reading.

For every shipped TOML mechanism (``models/mechanisms/*.toml``) loaded as one tree plus
closures (``Linkage(closure_model.from_mechanism(mech))``), analysed at home, against
``pkm_pin.Analysis`` (``mech.home_analysis``): DOF, motion type, singularity class, and
the largest differences of A, B and the indices ``type_I``, ``type_II``,
``condition_A`` (both readings homogenise about the platform's origin). Prints a
Markdown table (pasted into ``docs/closed_loops.md``); ``python
benchmarks/equivalence_table.py``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import pkm_pin
from pkm_pin.linkage import Linkage
from pkm_pin.model.closure_model import configuration, from_mechanism

MECHANISMS = sorted((Path(__file__).resolve().parents[1] / "models" / "mechanisms")
                    .glob("*.toml"))
INDICES = ("type_I", "type_II", "condition_A")


def _difference(a: float, b: float) -> float:
    """|a − b|, 0 when both are the same infinity."""
    return 0.0 if a == b else abs(a - b)


def compare(path: Path) -> dict:
    """One row: the two readings of the mechanism at ``path`` at home."""
    mech = pkm_pin.load_mechanism(path)
    link = Linkage(from_mechanism(mech))
    ref = mech.home_analysis
    an = link.analyze(configuration(mech, mech.home_assembly))
    same = (an.dof == ref.dof and an.motion_type == ref.motion_type
            and an.singularity == ref.singularity)
    return {"mechanism": path.stem, "dof": f"{an.dof} / {ref.dof}",
            "motion": f"{an.motion_type} / {ref.motion_type}",
            "class": f"{an.singularity} / {ref.singularity}", "same": same,
            "dA": float(np.abs(an.A - ref.A).max()), "dB": float(np.abs(an.B - ref.B).max()),
            "dindex": max(_difference(an.indices[k], ref.indices[k]) for k in INDICES)}


def main() -> list[dict]:
    """Print the table; returns its rows."""
    rows = [compare(path) for path in MECHANISMS]
    print("| mechanism | dof (tree / seed 000) | motion type | class | max abs dA | "
          "max abs dB | max d indices |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['mechanism']} | {r['dof']} | {r['motion']} | {r['class']} | "
              f"{r['dA']:.1e} | {r['dB']:.1e} | {r['dindex']:.1e} |")
    return rows


if __name__ == "__main__":
    main()
