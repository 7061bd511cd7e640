"""Planar 3-RPR of seed 000: mobility, velocity equation (58) and the type II pose.

Seed 000: Michalková & Guldan, see docs/references.md.
"""

import numpy as np

from pkm_pin.builders.planar import rpr3, rpr3_type2_pose
from pkm_pin.crosscheck import crosscheck

if __name__ == "__main__":
    mech = rpr3().build()

    # Mobility at home (seed 000, eq. 54-55)
    an = mech.analyze()
    print(f"{mech.name}: {an.dof} DOF ({an.motion_type}), Grübler {an.grubler}, "
          f"{an.redundant_constraints} redundant constraints")

    # Velocity equation A Δ t = B q̇_a (eq. 58) and the cross-check with the formulas
    np.set_printoptions(precision=4, suppress=True)
    print("A =\n", an.A, "\nB =\n", an.B)
    print("max |Pinocchio - formulas| =", max(crosscheck(an).values()))
    print("platform twist for q̇_a = (0.1, 0, 0):", an.forward_velocity([0.1, 0.0, 0.0]))

    # Type II singularity (eq. 60-61)
    singular = mech.analyze(rpr3_type2_pose())
    print(f"at the type II pose: class {singular.singularity}, "
          f"uncontrolled twist {singular.uncontrolled_twist}")
