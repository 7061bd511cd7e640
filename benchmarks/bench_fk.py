"""Forward kinematics of the 6-UPS to 1e-10 from a guess 5 cm / 5° away.

pkm_pin's ``Mechanism.forward_kinematics`` (default method: the compiled
predictor–corrector continuation; and seed 003's Euler continuation) against
``scipy.optimize.root`` on the hand-written closed form (leg lengths of
:mod:`pkm_pin.formulas.stewart` as functions of position and rotation vector), on the
same targets and guesses; prints the time per solve, the ratio and the accuracy.
"""

from __future__ import annotations

import time

import numpy as np
import pinocchio as pin
from scipy.optimize import root

from pkm_pin import formulas, screws
from pkm_pin.builders import MECHANISMS


def cases(mech, n: int, seed: int = 0):
    """(target pose, target leg lengths, guess assembly) triples."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        t = np.r_[rng.normal(size=3) * 0.05, rng.normal(size=3) * 0.03]
        target = screws.exp(np.r_[t[3:], t[:3]]) * mech.home
        q = mech.assemble(target).q_actuated
        d = rng.normal(size=6)
        d[:3] *= np.deg2rad(5) / np.linalg.norm(d[:3])
        d[3:] *= 0.05 / np.linalg.norm(d[3:])
        guess = mech.assemble(screws.exp(d) * target)
        out.append((target, q, guess))
    return out


def scipy_fk(base, local, lengths, guess: pin.SE3) -> pin.SE3:
    """Closed-form residual (leg lengths) solved by scipy.optimize.root (hybr)."""
    def residual(x):
        R = formulas.stewart.rodrigues(x[3:]) @ guess.rotation
        tips = local @ R.T + x[:3]
        return formulas.stewart.leg_lengths(base, tips) - lengths

    sol = root(residual, np.r_[guess.translation, np.zeros(3)], tol=1e-14)
    return pin.SE3(formulas.stewart.rodrigues(sol.x[3:]) @ guess.rotation, sol.x[:3])


def main(n: int = 20) -> tuple[float, float, float, float]:
    mech = MECHANISMS["stewart"]().build()
    base = np.array([leg.base.translation for leg in mech.legs])
    local = np.array([a.translation for a in mech.anchors])
    data = cases(mech, n)
    t0 = time.perf_counter()
    mech.forward_kinematics(data[0][1], data[0][2], tol=1e-10)  # compile / load the kernels
    t_first = time.perf_counter() - t0
    t0 = time.perf_counter()
    ours = [mech.forward_kinematics(q, guess, tol=1e-10) for _, q, guess in data]
    t_ours = (time.perf_counter() - t0) / n
    t0 = time.perf_counter()
    euler = [mech.forward_kinematics(q, guess, tol=1e-10, method="euler") for _, q, guess in data]
    t_euler = (time.perf_counter() - t0) / n
    t0 = time.perf_counter()
    ref = [scipy_fk(base, local, q, guess.pose) for _, q, guess in data]
    t_ref = (time.perf_counter() - t0) / n
    assert all(a.info["method"] == "compiled" for a in ours)
    err_ours = max(np.linalg.norm(pin.log6(a.pose.actInv(t)).vector) for a, (t, _, _) in
                   zip(ours, data))
    err_ref = max(np.linalg.norm(pin.log6(a.actInv(t)).vector) for a, (t, _, _) in zip(ref, data))
    print(f"6-UPS forward kinematics from 5 cm / 5° guesses ({n} solves):")
    err_euler = max(np.linalg.norm(pin.log6(a.pose.actInv(t)).vector) for a, (t, _, _) in
                    zip(euler, data))
    print(f"  pkm_pin forward_kinematics   {1e3 * t_ours:8.2f} ms/solve   "
          f"max pose error {err_ours:.1e}   (compiled predictor-corrector)")
    print(f"  pkm_pin, method='euler'      {1e3 * t_euler:8.2f} ms/solve   "
          f"max pose error {err_euler:.1e}   (seed 003 as printed, x{t_euler / t_ref:.1f} scipy)")
    print(f"  scipy.optimize.root (hybr)   {1e3 * t_ref:8.2f} ms/solve   "
          f"max pose error {err_ref:.1e}")
    print(f"  ratio pkm_pin / scipy: x{t_ours / t_ref:.2f}   (target: below 1)")
    print(f"  (first call of the process, numba kernels compiled or loaded: "
          f"{1e3 * t_first:.0f} ms, not in the figures)")
    return t_ours, t_ref, err_ours, err_ref


if __name__ == "__main__":
    main()
