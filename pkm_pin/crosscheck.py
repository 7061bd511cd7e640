"""Cross-checks of the Pinocchio path against the hand-written formulas of the papers.

This module is the only meeting point of the two independent paths: the screw analysis
of :mod:`pkm_pin.analysis` (Pinocchio Jacobians) and :mod:`pkm_pin.formulas` (numpy
only). Each check returns the largest absolute difference of each compared quantity;
differences of moments and linear velocities are divided by the mechanism's
characteristic length so that every number is dimensionless.
"""

from __future__ import annotations

import numpy as np

from . import formulas
from .analysis import Analysis


def _screw_error(a: np.ndarray, b: np.ndarray, length: float) -> float:
    d = np.atleast_2d(np.asarray(a, float) - np.asarray(b, float))
    return float(np.max(np.abs(np.hstack([d[:, :3], d[:, 3:] / length])))) if d.size else 0.0


def rpr3(analysis: Analysis) -> dict[str, float]:
    """Compare a 3-RPR of seed 000 (Michalková & Guldan, see docs/references.md; legs A,
    B, C: R-P-R in the xz-plane) with :mod:`pkm_pin.formulas.rpr3`: joint screws
    (50)–(52), constraint system (54), the rows of ``A`` and ``B`` (58) with unit screws,
    and the forward velocity map."""
    mech, L = analysis.mechanism, analysis.length
    xs = [leg.base.translation[0] for leg in mech.legs]
    L3, L6 = xs[1] - xs[0], xs[2] - xs[1]
    q = analysis.assembly.leg_q
    angles = [-qi[0] for qi in q]  # a revolute about +y by q turns +x to angle -q
    lengths = [qi[1] for qi in q]
    legs_f = formulas.rpr3.joint_screws(L3, L6, angles, lengths)
    err = {"joint_screws": max(_screw_error(ls.jacobian.T, f, L)
                               for ls, f in zip(analysis.legs, legs_f))}
    err["platform_twists"] = _span_error(analysis.platform_twists,
                                         formulas.rpr3.platform_twists(), L)
    err["A"] = _screw_error(analysis.A,
                            formulas.rpr3.actuation_wrenches(L3, L6, angles, lengths), L)
    a3, b3 = formulas.rpr3.velocity_equation(L3, L6, angles, lengths)
    err["B"] = float(np.max(np.abs(np.diag(analysis.B) - np.diag(b3)) / np.r_[1.0, L, 1.0]))
    G_f = np.linalg.solve(a3, b3)  # (w_y, v_x, v_z) per unit actuated rate
    G_p = np.array([analysis.forward_velocity(e)[[1, 3, 5]] for e in np.eye(3)]).T
    unit = np.diag([1.0, 1.0 / L, 1.0 / L]), np.diag([L, 1.0, L])  # dimensionless
    err["forward_velocity"] = float(np.max(np.abs(unit[0] @ (G_p - G_f) @ unit[1])))
    return err


def stewart(analysis: Analysis) -> dict[str, float]:
    """Compare a Gough–Stewart platform (legs ending in a prismatic actuator between
    two joint centres) with :mod:`pkm_pin.formulas.stewart`: the rows of ``A`` are the
    unit Plücker lines of the legs, ``B`` is the identity."""
    mech, L = analysis.mechanism, analysis.length
    base = np.array([leg.base.translation for leg in mech.legs])
    tips = np.array([leg.tip_placement(q).translation
                     for leg, q in zip(mech.legs, analysis.assembly.leg_q)])
    lines = formulas.stewart.leg_lines(base, tips)
    return {"A": _screw_error(analysis.A, lines, L),
            "B": float(np.max(np.abs(analysis.B - np.eye(len(mech.legs)))))}


def _span_error(S: np.ndarray, F: np.ndarray, length: float) -> float:
    """Largest distance of the rows of F from span(S), in homogenised units."""
    Sh, Fh = S.copy(), F.copy()
    Sh[:, 3:] /= length
    Fh[:, 3:] /= length
    Q, _ = np.linalg.qr(Sh.T)
    return float(np.max(np.abs(Fh.T - Q @ (Q.T @ Fh.T)))) if S.size else float(np.abs(Fh).max())


def _is_rpr3(mech) -> bool:
    """Three R-P-R legs actuated as in seed 000 (P of A, R at B0, P of C)."""
    kinds = [[leg.model.joints[leg.model.getJointId(n)].shortname() for n in leg.joint_names]
             for leg in mech.legs]
    return (len(mech.legs) == 3
            and all(len(k) == 3 and k[0].startswith("JointModelR") and k[1].startswith(
                "JointModelP") and k[2].startswith("JointModelR") for k in kinds)
            and [list(leg.actuated_v) for leg in mech.legs] == [[1], [0], [1]])


def _is_stewart(mech) -> bool:
    """Legs with one actuated prismatic joint each, as many legs as actuators (6)."""
    return len(mech.legs) == 6 and all(
        len(leg.actuated) == 1 and leg.model.joints[leg.model.getJointId(leg.actuated[0])]
        .shortname().startswith("JointModelP") for leg in mech.legs)


#: mechanism-name prefix -> (structure test, check)
CHECKS = {"3-RPR": (_is_rpr3, rpr3), "6-UPS": (_is_stewart, stewart),
          "6-SPS": (_is_stewart, stewart)}


def crosscheck(analysis: Analysis) -> dict[str, float] | None:
    """The check that fits the mechanism (by name and structure), or ``None``."""
    for prefix, (fits, check) in CHECKS.items():
        if analysis.mechanism.name.startswith(prefix) and fits(analysis.mechanism):
            return check(analysis)
    return None
