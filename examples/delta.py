"""Delta robot (R + spatial parallelogram written with mimic joints): 3T mobility,
redundant constraints, velocity maps."""

import numpy as np

from pkm_pin.builders import MECHANISMS

if __name__ == "__main__":
    mech = MECHANISMS["delta"]().build()
    np.set_printoptions(precision=4, suppress=True)

    an = mech.analyze()
    print(f"{mech.name}: {an.dof} DOF ({an.motion_type}), Grübler {an.grubler}, "
          f"{an.redundant_constraints} redundant constraints")
    print("each leg constrains", [w.shape[0] for w in an.leg_constraint_wrenches], "rotations")

    # Velocity maps: actuated arm rates -> platform translation, and back
    t = an.forward_velocity([0.1, -0.05, 0.02])
    print("platform twist (w; v_O):", t)
    print("back to arm rates:", an.inverse_velocity(t))
    print("singularity:", an.singularity, an.indices)
