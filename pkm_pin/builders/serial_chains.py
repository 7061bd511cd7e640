"""URDF models of the serial chains of the source papers (seeds 002 and 003).

Seed 002: anon., Polish, 1987; seed 003: Demidov 2025; see docs/references.md.

Every chain is written with :func:`pkm_pin.builders.urdf_writer.chain_urdf`: a root
link ``base``, one link ``<joint>_link`` per joint, and the frame ``tip`` fixed to the
last link. Lengths in metres, angles in radians.

Seed 003 — the 6R chain of the inverse-problem example (:func:`chain_6r_seed003_urdf`)
--------------------------------------------------------------------------------------
The paper: "six revolute pairs whose axes cross at right angles, all links 0.2 m";
the links are first "stretched along one line, the x axis", each joint axis then being
given by a dual angle (angle and distance) to the ``y`` axis; the angles are measured
"from the extensions of the links". This is the standard Denavit–Hartenberg chain

    ``T_0,tip = Π_{i=1..6} Rz(φ_i) · Tx(a) · Rx(α)``,  ``a = 0.2 m``, ``α = +90°``,
    ``d_i = 0``,

i.e. consecutive axes are skew at 90° with common normals of 0.2 m along the links, the
stretched chain (all ``φ = 0``) lies along ``x``, and the tip frame sits 0.2 m beyond
the sixth axis (the sixth link). This reading is confirmed by the paper's own numbers:
from the start ``φ1 = φ5 = φ6 = 0°, φ2 = φ3 = φ4 = 30°`` to the target
``φ1 = φ5 = φ6 = 10°, φ2 = φ3 = φ4 = 40°`` it gives a rotation of 18.49° about
``L = (0.370, −0.711, 0.598)`` (paper: 18.5°, "0.37 −0.711, 0.6") and a tip
displacement ``(−0.00178, 0.160, 0.067) m`` (paper: the same), and ``a11 = 0.9598`` at
the target (paper: 0.96). The paper's expansion of ``a11`` has a slip: the third bracket
must read ``cos φ1 cos φ2 sin φ3 − sin φ1 cos φ3`` (printed ``… − sin φ1 sin φ3``); with
that correction it is identical to the DH product above. ``α = −90°`` gives the mirror
image (same angle, ``z`` components negated), alternating signs do not fit.

Seed 003 — the chain with a prismatic second pair, figs. 4–5 (:func:`chain_rprrrr_seed003_urdf`)
-----------------------------------------------------------------------------------------------
The paper names the coordinates ``φ1, S2, φ3, …, φ6`` (pair 2 prismatic, the others
revolute) but prints no dimensions. Decided here: the 6R geometry above with pair 2
turned into a prismatic pair *along the line that was the second revolute axis*
(``T_12 = Tx(0.2) Rx(90°) Tz(S2)``), which is how the paper's dual-vector formalism
treats a prismatic pair (a unit free vector along the pair's axis). ``S2 ∈ [−0.2, 0.2] m``;
at ``S2 = 0`` the chain coincides with the 6R chain at ``φ2 = 0``.

Seed 002 §6 — the manipulator with mobility six (:func:`manipulator_seed002_urdf`)
---------------------------------------------------------------------------------
Read from the (OCR-damaged) paper: two revolute pairs, one prismatic pair and a
spherical pair; the local rotation matrices are ``U1 = Rz(φ1)``, ``U2 = Rx(φ2)``,
``U3 = I`` (the prismatic pair, relative velocity ``v = (0, v, 0)``: along ``y``) and
``U4 = Rx(φ3) Rz(φ5) Ry(−φ4)`` (reconstructed entry by entry from the printed matrix
``[[C4C5, −S5, −S4C5], …, [C3S4 + S3C4S5, S3C5, C3C4 − S3S4S5]]``); the motor graph
(Fig. 7) runs ``A → B → C' → C → D → E``: ``v_B = B_AB ω01``, ``v_C' = v_B + B_BC' ω02``,
``v_C = v_C' + v``, ``v_D = v_C + B_CD ω03`` with ``ω03 = ω02``,
``v_E = v_D + B_DE ω04``; the end point is ``r_E = (0, l, 0, 1)`` in the last link. The
dimensions are not legible; chosen here (documented, reasonable):

* ``A`` = base origin, pair 1 revolute about ``z`` (``φ1``);
* ``B = A + (0, 0, 0.4)``, pair 2 revolute about ``x`` (``φ2``);
* ``C' = B + (0, 0.3, 0)``, pair 3 prismatic along ``y`` (``s ∈ [0, 0.4] m``), ``C``
  the moving pole;
* ``D = C + (0, 0.2, 0)``: spherical pair written as three revolutes with coinciding
  frames about ``x`` (``φ3``), ``z`` (``φ5``) and ``−y`` (``φ4``), in this order, so
  that their product is ``U4``;
* ``E = D + (0, 0.15, 0)`` in the last link: the frame ``tip``.

The joints are named after the paper's coordinates: ``phi1``, ``phi2``, ``s``,
``phi3``, ``phi5``, ``phi4``.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from .urdf_writer import JointSpec, chain_urdf

#: Link length and twist of the seed 003 chains [m], [rad].
SEED003_LINK = 0.2
SEED003_TWIST = math.pi / 2

#: Seed 003 inverse-problem example: start and target joint angles [rad].
SEED003_START = np.radians([0.0, 30.0, 30.0, 30.0, 0.0, 0.0])
SEED003_TARGET = np.radians([10.0, 40.0, 40.0, 40.0, 10.0, 10.0])

#: Seed 002 manipulator dimensions chosen here [m] (the paper's are not legible).
SEED002_DIMENSIONS = {"AB": 0.4, "BC": 0.3, "CD": 0.2, "DE": 0.15, "stroke": 0.4}

#: File names written by :func:`write_serial_models` (inside ``<models_dir>/urdf``).
SERIAL_MODEL_FILES = {
    "chain_6r_seed003": "chain_6r_seed003.urdf",
    "chain_rprrrr_seed003": "chain_rprrrr_seed003.urdf",
    "manipulator_seed002": "manipulator_seed002.urdf",
}


def _dh_joint(name: str, first: bool, kind: str = "revolute",
              lower: float = -math.pi, upper: float = math.pi) -> JointSpec:
    """Joint ``i`` of the seed 003 chain: origin ``Tx(a) Rx(α)`` after the previous
    joint (identity for the first), motion about / along the local ``z``."""
    xyz = (0.0, 0.0, 0.0) if first else (SEED003_LINK, 0.0, 0.0)
    rpy = (0.0, 0.0, 0.0) if first else (SEED003_TWIST, 0.0, 0.0)
    return JointSpec(name, kind, xyz=xyz, rpy=rpy, axis=(0.0, 0.0, 1.0), lower=lower, upper=upper)


def _seed003_tip() -> dict:
    return {"tip_xyz": (SEED003_LINK, 0.0, 0.0), "tip_rpy": (SEED003_TWIST, 0.0, 0.0)}


def chain_6r_seed003_urdf() -> str:
    """URDF of the seed 003 6R chain (DH: ``a = 0.2 m``, ``α = 90°``, ``d = 0``).

    Joints ``phi1`` … ``phi6`` (revolute about the local ``z``, limits ±π), tip frame
    ``tip`` 0.2 m beyond the sixth axis. See the module docstring for the derivation.
    """
    joints = [_dh_joint(f"phi{i}", i == 1) for i in range(1, 7)]
    return chain_urdf("chain_6r_seed003", joints, tip="tip", **_seed003_tip())


def chain_rprrrr_seed003_urdf() -> str:
    """URDF of the seed 003 chain with a prismatic second pair (``φ1, S2, φ3 … φ6``).

    The 6R geometry with pair 2 prismatic along the line of the 6R chain's second axis,
    ``S2 ∈ [−0.2, 0.2] m``; joints ``phi1``, ``s2``, ``phi3`` … ``phi6``.
    """
    joints = [_dh_joint("phi1", True),
              _dh_joint("s2", False, "prismatic", -SEED003_LINK, SEED003_LINK)]
    joints += [_dh_joint(f"phi{i}", False) for i in range(3, 7)]
    return chain_urdf("chain_rprrrr_seed003", joints, tip="tip", **_seed003_tip())


def manipulator_seed002_urdf() -> str:
    """URDF of the seed 002 §6 manipulator: R(z) R(x) P(y) + spherical pair (x, z, −y).

    Joints ``phi1``, ``phi2``, ``s``, ``phi3``, ``phi5``, ``phi4`` (the paper's
    coordinates); the tip frame is the end point ``E``. Dimensions in
    :data:`SEED002_DIMENSIONS`; see the module docstring.
    """
    d = SEED002_DIMENSIONS
    joints = [
        JointSpec("phi1", axis=(0.0, 0.0, 1.0)),
        JointSpec("phi2", xyz=(0.0, 0.0, d["AB"]), axis=(1.0, 0.0, 0.0)),
        JointSpec("s", "prismatic", xyz=(0.0, d["BC"], 0.0), axis=(0.0, 1.0, 0.0),
                  lower=0.0, upper=d["stroke"]),
        JointSpec("phi3", xyz=(0.0, d["CD"], 0.0), axis=(1.0, 0.0, 0.0)),
        JointSpec("phi5", axis=(0.0, 0.0, 1.0)),
        JointSpec("phi4", axis=(0.0, -1.0, 0.0)),
    ]
    return chain_urdf("manipulator_seed002", joints, tip="tip", tip_xyz=(0.0, d["DE"], 0.0))


def write_serial_models(models_dir: str | os.PathLike) -> list[Path]:
    """Write the three serial-chain URDFs into ``<models_dir>/urdf/``.

    Files: ``chain_6r_seed003.urdf``, ``chain_rprrrr_seed003.urdf`` and
    ``manipulator_seed002.urdf`` (:data:`SERIAL_MODEL_FILES`).

    Returns:
        The paths written.
    """
    folder = Path(models_dir) / "urdf"
    folder.mkdir(parents=True, exist_ok=True)
    texts = {
        "chain_6r_seed003": chain_6r_seed003_urdf(),
        "chain_rprrrr_seed003": chain_rprrrr_seed003_urdf(),
        "manipulator_seed002": manipulator_seed002_urdf(),
    }
    paths = []
    for key, text in texts.items():
        path = folder / SERIAL_MODEL_FILES[key]
        path.write_text(text)
        paths.append(path)
    return paths


if __name__ == "__main__":
    import sys

    for p in write_serial_models(sys.argv[1] if len(sys.argv) > 1 else "models"):
        print(p)
