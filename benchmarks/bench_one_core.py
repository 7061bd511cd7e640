"""One machine, one answer, one speed: the shipped 6-UPS as TOML legs and as an Extended URDF.

The Extended URDF is written by :func:`pkm_pin.builders.extended_urdf.write_extended_urdf`
the way robot files cut a hexapod open: the tree runs through leg 1 and its S joint to
the platform; legs 2–6 end after their prismatic joint and close on the platform with
five 3D point closures; the six prismatic joints are actuated. Three readings of the
same machine, at the same poses (home and ``n`` random poses around it):

  * ``toml``: ``load_mechanism("stewart.toml")`` (the per-leg engine);
  * ``urdf/legs``: ``load_mechanism(urdf)`` at the TOML's home (the default: the
    structure detected in the file is read per leg, :meth:`Mechanism.from_closure_model`);
  * ``urdf/general``: ``load_mechanism(urdf, backend="general")`` (the general
    elimination; its characteristic length is the detected legs' —
    :func:`pkm_pin.model.structure.legs_length` — so its indices are the machine's too),
    analysed at each pose's configuration of the URDF's tree (the TOML assembly's joint
    values, :func:`urdf_q`; their closure residuals checked).

Prints the largest difference of the type I/II indices and the condition of A between
the TOML and each URDF reading at every pose (target: 1e-9), and the analysis time per
pose of each, with the ratio to the TOML's measured in the same run (target ≤ ×1.5 for
``urdf/legs`` and ``urdf/general``).
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pinocchio as pin
from timing import best_of_each

from pkm_pin import Mechanism, load_mechanism
from pkm_pin.builders.extended_urdf import write_extended_urdf
from pkm_pin.model import configuration

STEWART = Path(__file__).resolve().parents[1] / "models" / "mechanisms" / "stewart.toml"
KEYS = ("type_I", "type_II", "condition_A")


def poses(home: pin.SE3, n: int, seed: int = 0) -> list:
    """Home and ``n`` poses within ±3 cm and ±0.08 rad of it."""
    rng = np.random.default_rng(seed)
    return [home] + [home * pin.SE3(pin.rpy.rpyToMatrix(*rng.uniform(-0.08, 0.08, 3)),
                                    rng.uniform(-0.03, 0.03, 3)) for _ in range(n)]


def urdf_q(toml, general, assembly) -> np.ndarray:
    """The configuration of the URDF's tree at a TOML assembly (its legs' joint values:
    leg 1 with its S joint, legs 2–6 up to their prismatic joint)."""
    tree, q = general.model.tree, np.array(general.model.reference)
    for i, (leg, q_leg) in enumerate(zip(toml.legs, assembly.leg_q)):
        for name, value in zip(leg.joint_names, q_leg):
            if tree.existJointName(f"leg{i + 1}_{name}"):
                q[tree.joints[tree.getJointId(f"leg{i + 1}_{name}")].idx_q] = value
    return q


def readings(folder: Path):
    """The TOML mechanism, the URDF through the legs backend and the general backend."""
    toml = load_mechanism(STEWART)
    path = write_extended_urdf(toml, folder)
    general = load_mechanism(path, backend="general")
    q = urdf_q(toml, general, toml.home_assembly)
    legs = type(toml).from_closure_model(general.model, q)
    return toml, legs, general, q


def main(n: int = 50, repeat: int = 5) -> dict:
    """Print the index differences and the per-pose times; return them."""
    with tempfile.TemporaryDirectory() as folder:
        toml, legs, general, q_home = readings(Path(folder))
    targets = poses(toml.home, n)
    toml_an = [toml.analyze(p) for p in targets]
    legs_an = [legs.analyze(p) for p in targets]
    general_q = [configuration(toml, toml.assemble(p)) for p in targets]
    flat = load_mechanism(STEWART, backend="general")  # the general backend, TOML's tree
    general_an = [flat.analyze(q) for q in general_q]
    diff_legs = max(abs(a.indices[k] - b.indices[k]) for a, b in zip(toml_an, legs_an)
                    for k in KEYS)
    diff_general = max(abs(a.indices[k] - b.indices[k]) for a, b in zip(toml_an, general_an)
                       for k in KEYS)
    urdf_q_all = [urdf_q(toml, general, toml.assemble(p)) for p in targets]
    residual = max(np.abs(general.model.closure_residual(q)).max() for q in urdf_q_all)
    assert residual < 1e-9, f"the URDF configurations do not close ({residual:.1e})"
    urdf_an = [general.analyze(q) for q in urdf_q_all]
    diff_urdf = max(abs(a.indices[k] - b.indices[k]) for a, b in zip(toml_an, urdf_an)
                    for k in KEYS)
    assert np.allclose(urdf_q_all[0], q_home)
    times = best_of_each({
        "toml": lambda: [toml.analyze(p) for p in targets],
        "urdf/legs": lambda: [legs.analyze(p) for p in targets],
        "urdf/general": lambda: [general.analyze(q) for q in urdf_q_all],
    }, repeat)
    per_pose = {k: v / len(targets) * 1e6 for k, v in times.items()}
    print("one class: " + ", ".join(f"{key} {'Mechanism' if isinstance(m, Mechanism) else '?'}"
                                    f"(backend {m.backend!r})" for key, m in
                                    (("toml", toml), ("urdf/legs", legs),
                                     ("urdf/general", general))))
    print(f"6-UPS, {len(targets)} poses: largest index difference to the TOML "
          f"(type I, type II, condition of A)")
    print(f"  urdf/legs                         {diff_legs:.2e}   (target 1e-9)")
    print(f"  general, TOML's tree (welds)      {diff_general:.2e}")
    print(f"  general, URDF's tree (points)     {diff_urdf:.2e}   (the legs' characteristic "
          "length, legs_length: the machine's, not the tree's; every pose)")
    print("analysis per pose (TOML, urdf/legs: assemble + analyze; urdf/general: analyze at "
          "the pose's configuration of the URDF's tree), ratio to the TOML's in this run "
          "(target for urdf/general: x1.5):")
    for key, us in per_pose.items():
        print(f"  {key:<13} {us:9.1f} µs   x{us / per_pose['toml']:.2f}")
    return {"diff_legs": diff_legs, "diff_general": diff_general, "diff_urdf": diff_urdf,
            "per_pose": per_pose}


if __name__ == "__main__":
    main()
