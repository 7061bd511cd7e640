"""Seed 003: screw continuation on the 6-SPS body, motion by inertia on the 3-RPR, and
the iterative inverse problem of the 6R chain. Run: python examples/seed003_position.py

Seed 003: Demidov 2025, see docs/references.md.
"""

import numpy as np
import pinocchio as pin

from pkm_pin import Leg
from pkm_pin.builders import MECHANISMS, rpr3_type2_pose
from pkm_pin.builders.spatial import stewart
from pkm_pin.formulas.stewart import SEED003_DL, SEED003_LINES, seed003_geometry
from pkm_pin.position import iterative_ik, screw_step

print("screw step (w; v_O):", screw_step(SEED003_LINES, SEED003_DL))

base, plat = seed003_geometry()
sps = stewart(base, plat, home=pin.SE3.Identity(), name="6-SPS seed 003",
              slug="sps6_seed003", urdf_file="sps_leg_seed003.urdf").build()
target = sps.home_assembly.q_actuated + SEED003_DL
for n in (1, 2, 4, 8, 16):
    a = sps.forward_kinematics(target, steps=n, method="euler")  # seed 003 as printed
    print(f"N = {n:2d}: leg-length error after the polyline "
          f"{a.info['continuation_error'] * sps.characteristic_length:.2e} m, "
          f"then {a.info['newton_iterations']} Newton iterations")

rpr = MECHANISMS["rpr3"]().build()
P2 = rpr3_type2_pose()
pose = pin.SE3(P2.rotation, P2.translation + np.array([0.05, 0.0, 0.0]))
qa = rpr.inverse_kinematics(pose).q_actuated
for tol in (1e-2, 0.035):
    a = rpr.forward_kinematics(qa, inertia_tol=tol)
    print(f"3-RPR beyond the type II pose, inertia_tol {tol}: inertia moves "
          f"{a.info['inertia_steps']}, reached x = {a.pose.translation[0]:.4f} "
          f"(wanted {pose.translation[0]:.4f})")
print("3-RPR assembly modes there:", len(rpr.forward_kinematics_all(qa, starts=8)))

leg = Leg.from_urdf("models/urdf/chain_6r_seed003.urdf", "tip")
q0, q1 = np.radians([0, 30, 30, 30, 0, 0]), np.radians([10, 40, 40, 40, 10, 10])
r = iterative_ik(leg, leg.tip_placement(q1), q0, max_angle_step=np.radians(2),
                 max_translation_step=0.02)
print(f"6R: rotation {np.degrees(r.angle):.2f} deg about {np.round(r.axis, 3)}, "
      f"translation {np.linalg.norm(r.translation):.4f} m, {r.steps} steps; error "
      f"{r.error_after_steps[0]:.1e} m / {np.degrees(r.error_after_steps[1]):.2f} deg, "
      f"corrected {r.error_after_correction[0]:.1e} m")
