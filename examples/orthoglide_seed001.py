"""Orthoglide of seed 001: mobility, closed forms vs Pinocchio, sensitivity, calibration.

Seed 001: Pashkevich & Gomolitsky 2007, see docs/references.md.
"""

import numpy as np
import pinocchio as pin

from pkm_pin.builders.orthoglide import QUASI, orthoglide_quasi
from pkm_pin.calibration import calibrate
from pkm_pin.formulas import orthoglide as og
from pkm_pin.sensitivity import perturb, sensitivity

if __name__ == "__main__":
    np.set_printoptions(precision=5, suppress=True)
    mech = orthoglide_quasi().build()
    params = og.OrthoglideParameters(**QUASI, e=0.1)

    # Mobility (3T, each leg constrains two rotations)
    an = mech.analyze()
    print(f"{mech.name}: {an.dof} DOF ({an.motion_type}), Grübler {an.grubler}, "
          f"{an.redundant_constraints} redundant constraints, singularity {an.singularity}")

    # Inverse and forward kinematics: eq. (3) and (6)-(14) against the Pinocchio path
    p = np.array([0.05, -0.03, 0.02])
    rho = mech.inverse_kinematics(pin.SE3(np.eye(3), p)).q_actuated
    print("rho (Pinocchio) =", rho, " eq. (3):", og.inverse_kinematics(p, params))
    a = mech.forward_kinematics(rho)
    both = og.forward_kinematics_both(rho, params)
    print("FK (Pinocchio)  =", a.pose.translation, " both roots:", both)

    # Sensitivity to the paper's parameters vs A^-1 B_L, -A^-1 B_phi, A^-1 B_d (eq. 16)
    S = og.sensitivities(p, rho, params)
    sens = sensitivity(mech, a)
    for leg, i in (("legx", 0), ("legy", 1), ("legz", 2)):
        err = max(np.abs(sens.column(f"{leg}/Pa2/origin.x")[3:] - S["L"][:, i]).max(),
                  np.abs(sens.column(f"{leg}/P/axis.ry")[3:] + S["phi"][:, i]).max(),
                  np.abs(sens.column(f"{leg}/P/origin.z")[3:] - S["dd"][:, i]).max())
        print(f"{leg}: |generic sensitivity - closed form| = {err:.1e}")
    print(f"{len(sens.parameters)} URDF parameters, {len(sens.incompatible)} of them cannot be "
          "absorbed by the overconstrained machine")

    # Calibration: inject errors, measure 25 noisy positions, identify
    rng = np.random.default_rng(0)
    names = [f"leg{x}/{q}" for x in "xyz" for q in ("Pa2/origin.x", "P/axis.ry", "P/origin.z")]
    true = {n: rng.normal(0, 2e-3) for n in names}
    truth = perturb(mech, true)
    qs = [mech.home_assembly.q_actuated + rng.uniform(-0.2, 0.2, 3) for _ in range(25)]
    samples = [(q, truth.forward_kinematics(q).pose.translation + rng.normal(0, 1e-6, 3))
               for q in qs]
    res = calibrate(mech, samples, names + ["legx/R1/origin.z"])
    print(f"residual {res.residual_before:.2e} m -> {res.residual_after:.2e} m; "
          f"unidentifiable {res.unidentifiable}")
    for n in res.parameters:
        print(f"  {n:20s} true {true[n]: .6f}  found {res.errors[n]: .6f} ± {res.std[n]:.1e}")
