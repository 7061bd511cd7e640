"""Gough–Stewart 6-UPS: mobility, the leg Plücker lines as A, forward kinematics and its
assembly modes."""

import numpy as np

from pkm_pin import screws
from pkm_pin.builders import MECHANISMS
from pkm_pin.crosscheck import crosscheck

if __name__ == "__main__":
    mech = MECHANISMS["stewart"]().build()
    np.set_printoptions(precision=4, suppress=True)

    # Mobility and the inverse Jacobian (rows: unit Plücker lines of the legs)
    an = mech.analyze()
    print(f"{mech.name}: {an.dof} DOF ({an.motion_type}), Grübler {an.grubler}")
    print("A (leg lines) =\n", an.A)
    print("max |Pinocchio - formulas| =", max(crosscheck(an).values()))

    # Forward kinematics from leg lengths (screw continuation + Newton)
    target = screws.exp(np.array([0.05, -0.03, 0.02, 0.04, 0.0, 0.03])) * mech.home
    lengths = mech.inverse_kinematics(target).q_actuated
    fk = mech.forward_kinematics(lengths)
    print("FK pose error:", np.linalg.norm((fk.pose.inverse() * target).translation))
    print("steps, Newton iterations:", fk.info["steps"], fk.info["newton_iterations"])

    # Assembly modes at the home leg lengths
    modes = mech.forward_kinematics_all(mech.home_assembly.q_actuated, starts=8)
    print(f"{len(modes)} assembly modes found; platform heights:",
          [round(float(m.pose.translation[2]), 4) for m in modes])
