"""Seed 002 manipulator (two revolute pairs, a prismatic pair, a spherical pair): link
screws and the velocity and acceleration of the end point E.

Seed 002: anon., Polish, 1987, see docs/references.md.
"""

import numpy as np

from pkm_pin import Leg
from pkm_pin.builders.serial_chains import manipulator_seed002_urdf

if __name__ == "__main__":
    leg = Leg.from_urdf(manipulator_seed002_urdf(), "tip", name="seed002")
    np.set_printoptions(precision=4, suppress=True)

    # A state with constant joint rates, as in the paper's example
    q = np.array([0.3, -0.4, 0.2, 0.1, 0.5, -0.2])
    qd = np.array([0.5, -0.3, 0.1, 0.8, -0.4, 0.6])
    qdd = np.zeros(6)

    # Instantaneous screw of every link: axis point, direction, pitch
    for name, s in leg.link_screws(q, qd).items():
        if s.at_rest:
            print(f"{name:>12}: at rest")
        else:
            print(f"{name:>12}: axis through {s.point} along {s.direction}, pitch {s.pitch:.4g}")

    # End point E (the tip frame's origin): velocity and classical acceleration
    print("v_E =", leg.point_velocity("tip", np.zeros(3), q, qd))
    print("a_E =", leg.point_acceleration("tip", np.zeros(3), q, qd, qdd))
    print("serial singularity index:", leg.serial_singularity_index(q))
