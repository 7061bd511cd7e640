"""The shipped 3-PRS (issue 17, items 4-5): its assembly modes against an independent
elimination, an unreachable target, partial poses (z, roll, pitch) and the CLI.

The reference (:func:`reference_modes`) knows nothing of pkm_pin's solvers. With the
actuators vertical, leg i's sphere centre moves in the vertical plane through the z axis
at azimuth φ_i: ``C_i(θ_i) = (R_b + l cos θ_i) u_i + (s_i + l sin θ_i) e_z`` (``s_i`` the
slider's travel, ``θ_i`` the rod's angle from the radial direction ``u_i``). The platform
holds the three centres at the corners of an equilateral triangle of side ``√3 r_p``, so
forward kinematics is three equations ``|C_i − C_j|² = 3 r_p²`` in the three angles:
bilinear in the half-angle tangents of two angles each, a multihomogeneous Bézout count
of 16 complex solutions, the known bound for the 3-PRS. Given ``θ_1``, the equations with
``C_2`` and ``C_3`` are each ``a cos θ + b sin θ = c``: two closed-form branches of ``θ_2``
and of ``θ_3``; the third equation's residual along the four branch pairs is scanned over
``θ_1`` for sign changes, each polished by Newton's method on the three equations. For the
shipped geometry 8 solutions are real at the home target, 4 of them with the R joints
within their limits (the rods pointing up; the other 4 hang the platform below the
sliders). A platform pose follows from the three centres (its anchors' best rigid fit).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pinocchio as pin
import pytest
from test_partial_poses import round_trip

from pkm_pin.builders import MECHANISMS, prs3
from pkm_pin.cli import main
from pkm_pin.errors import ForwardKinematicsError

#: The shipped geometry (the builder's defaults), spelled out for the reference [m].
GEOMETRY = dict(base_radius=1.0, platform_radius=0.4, leg_length=1.0, height=1.0)
_AZ = np.radians([0.0, 120.0, 240.0])
_U = np.column_stack([np.cos(_AZ), np.sin(_AZ), np.zeros(3)])
_EZ = np.array([0.0, 0.0, 1.0])
_PAIRS = ((0, 1), (1, 2), (0, 2))
#: The rod's angle from the radial direction at home (3-4-5 triangle: up and inwards);
#: the R joints turn it by ±π/2 at most.
THETA_HOME = math.atan2(0.8, -0.6)


@pytest.fixture(scope="module")
def mech():
    return MECHANISMS["prs3"]().build()


# ---------------------------------------------------------------------- reference
def centres(theta, s, g=GEOMETRY) -> np.ndarray:
    """(..., 3, 3) sphere centres in the world (rows: legs) for rod angles ``theta``
    (..., 3) and slider travels ``s`` (3,) [m]."""
    theta = np.asarray(theta, float)
    r = g["base_radius"] + g["leg_length"] * np.cos(theta)
    z = np.asarray(s, float) + g["leg_length"] * np.sin(theta)
    return r[..., None] * _U + z[..., None] * _EZ


def equations(theta, s, g=GEOMETRY) -> tuple[np.ndarray, np.ndarray]:
    """The three distance equations ``|C_i − C_j|² − 3 r_p²`` (..., 3) and their
    Jacobian (..., 3, 3) in the rod angles ``theta`` (..., 3)."""
    theta = np.asarray(theta, float)
    C = centres(theta, s, g)
    dC = g["leg_length"] * (-np.sin(theta)[..., None] * _U + np.cos(theta)[..., None] * _EZ)
    F, J = np.zeros(theta.shape), np.zeros(theta.shape + (3,))
    for k, (i, j) in enumerate(_PAIRS):
        d = C[..., i, :] - C[..., j, :]
        F[..., k] = np.sum(d * d, axis=-1) - 3.0 * g["platform_radius"] ** 2
        J[..., k, i] = 2.0 * np.sum(d * dC[..., i, :], axis=-1)
        J[..., k, j] = -2.0 * np.sum(d * dC[..., j, :], axis=-1)
    return F, J


def _partners(t1: np.ndarray, j: int, s, g) -> tuple[np.ndarray, np.ndarray]:
    """Both branches of ``θ_j`` with ``|C_1(θ_1) − C_j(θ_j)|² = 3 r_p²`` (NaN where
    none): ``a cos θ_j + b sin θ_j = c``."""
    Rb, rod, rp = g["base_radius"], g["leg_length"], g["platform_radius"]
    r1 = Rb + rod * np.cos(t1)
    dz = s[0] + rod * np.sin(t1) - s[j]
    cos_az = _U[0] @ _U[j]
    a = 2.0 * rod * (Rb - r1 * cos_az)
    b = -2.0 * rod * dz
    c = -(r1 ** 2 + Rb ** 2 + rod ** 2 - 2.0 * r1 * Rb * cos_az + dz ** 2 - 3.0 * rp ** 2)
    phase = np.arctan2(b, a)
    with np.errstate(invalid="ignore"):
        spread = np.arccos(c / np.hypot(a, b))
    return phase + spread, phase - spread


def _wrapped(x):
    return (np.asarray(x) + np.pi) % (2.0 * np.pi) - np.pi


def _newton(theta, s, g=GEOMETRY, iterations: int = 50) -> np.ndarray:
    """Newton's method on the three equations from the angles ``theta`` (..., 3), every
    start at once (a start whose Jacobian is singular stays where it is)."""
    theta = np.array(theta, float)
    for _ in range(iterations):
        F, J = equations(theta, s, g)
        with np.errstate(all="ignore"):
            ok = np.isfinite(F).all(axis=-1) & (np.abs(np.linalg.det(J)) > 1e-14)
            theta[ok] -= np.linalg.solve(J[ok], F[ok][..., None])[..., 0]
    return theta


def _distinct_solutions(theta, s, g=GEOMETRY) -> list[np.ndarray]:
    """The rows of ``theta`` that solve the equations to 1e-12, wrapped to (−π, π],
    distinct to 1e-8."""
    out: list[np.ndarray] = []
    F, _ = equations(theta, s, g)
    for t, f in zip(theta, F):
        if np.all(np.isfinite(f)) and np.abs(f).max() < 1e-12:
            t = _wrapped(t)
            if all(np.abs(_wrapped(t - o)).max() > 1e-8 for o in out):
                out.append(t)
    return out


def reference_modes(s, g=GEOMETRY, n: int = 20000) -> list[np.ndarray]:
    """Every real solution ``θ`` (3 rod angles) for the slider travels ``s`` (module
    docstring): a scan of ``θ_1`` over n + 1 points, sign changes of the third equation
    along the four closed-form branches, Newton polishing to 1e-12; distinct to 1e-8."""
    s = np.asarray(s, float)
    t1 = np.linspace(-np.pi, np.pi, n + 1)
    starts = []
    for t2 in _partners(t1, 1, s, g):
        for t3 in _partners(t1, 2, s, g):
            f = equations(np.c_[t1, t2, t3], s, g)[0][:, 1]  # |C_2 − C_3|² − 3 r_p²
            ok = np.isfinite(f[:-1]) & np.isfinite(f[1:])
            k = np.nonzero(ok & (np.sign(f[:-1]) != np.sign(f[1:])))[0]
            starts.append(np.c_[t1[k], t2[k], t3[k]])
    return _distinct_solutions(_newton(np.vstack(starts), s, g), s, g)


def within_limits(theta) -> bool:
    """The R joints within ±π/2 of home (the spherical joints reach every rotation)."""
    return bool(np.all(np.abs(_wrapped(np.asarray(theta) - THETA_HOME)) <= np.pi / 2))


def platform_pose(theta, s, anchors) -> pin.SE3:
    """The platform placement whose anchor points (platform frame) best fit the sphere
    centres (Kabsch; exact for a solution)."""
    C = centres(theta, s)
    P = np.array([a.translation for a in anchors])
    c, p = C.mean(axis=0), P.mean(axis=0)
    U, _, Vt = np.linalg.svd((C - c).T @ (P - p))
    R = U @ np.diag([1.0, 1.0, np.linalg.det(U @ Vt)]) @ Vt
    return pin.SE3(R, c - R @ p)


def _distance(a: pin.SE3, b: pin.SE3) -> float:
    e = pin.log6(a.actInv(b)).vector
    return float(np.abs(e).max())


def test_shipped_geometry_is_the_reference_geometry(mech):
    """The shipped 3-PRS is prs3(**GEOMETRY): the reference describes it."""
    other = prs3(**GEOMETRY).build()
    for a, b in zip(mech.anchors, other.anchors):
        assert _distance(a, b) < 1e-15
    assert _distance(mech.home, other.home) < 1e-15
    th = np.full(3, THETA_HOME)
    s = mech.home_assembly.q_actuated
    assert np.abs(equations(th, s)[0]).max() < 1e-14
    assert _distance(platform_pose(th, s, mech.anchors), mech.home) < 1e-14


def test_reference_agrees_with_a_dense_random_newton():
    """The scan's solutions are exactly those that Newton's method reaches from 2000
    random angle triples (an independent check of the reference itself)."""
    rng = np.random.default_rng(0)
    for s, real in (([0.2, 0.2, 0.2], 8), ([0.1, 0.6, 0.3], 4)):
        ref = reference_modes(s)
        newton = _distinct_solutions(_newton(rng.uniform(-np.pi, np.pi, (2000, 3)), s), s)
        assert len(ref) == len(newton) == real
        for t in newton:
            assert min(np.abs(_wrapped(t - o)).max() for o in ref) < 1e-8


# ------------------------------------------------------------------ assembly modes
@pytest.mark.parametrize("s, real, modes", [([0.2, 0.2, 0.2], 8, 4),
                                            ([0.25, 0.15, 0.3], 8, 4),
                                            ([0.1, 0.6, 0.3], 4, 2)])
def test_assembly_modes_are_the_reference_ones(mech, s, real, modes):
    """forward_kinematics_all finds every real solution of the reference with the R
    joints within their limits, no other: each closes (residual 1e-12), has the actuated
    values asked for, is distinct, and has the reference's pose to 1e-9."""
    ref = reference_modes(s)
    assert len(ref) == real  # of the 16 complex ones
    expected = [platform_pose(t, s, mech.anchors) for t in ref if within_limits(t)]
    assert len(expected) == modes
    found = mech.forward_kinematics_all(s)
    assert (found.method, found.complete) == ("multistart", False)
    assert len(found) == modes
    for a in found:
        assert a.residual <= 1e-12
        np.testing.assert_allclose(a.q_actuated, s, atol=1e-12)
        assert all(leg.within_limits(q) for leg, q in zip(mech.legs, a.leg_q))
        assert min(_distance(a.pose, p) for p in expected) < 1e-9
    for i, a in enumerate(found):  # distinct: no two are the same pose
        assert all(_distance(a.pose, b.pose) > 1e-3 for b in found[i + 1:])


def test_unreachable_target_raises():
    """With a 3 m stroke, sliders at 0, 2.9, 0 leave no solution at all (the reference
    finds none): forward_kinematics_all raises, saying the target is unreachable."""
    long_stroke = prs3(**GEOMETRY, stroke=(0.0, 3.0)).build()
    assert reference_modes([0.0, 2.9, 0.0]) == []
    with pytest.raises(ForwardKinematicsError, match="unreachable"):
        long_stroke.forward_kinematics_all([0.0, 2.9, 0.0])


def test_cli_fk_all_lists_the_modes_and_exits_2_when_unreachable(tmp_path, capsys):
    """pkm-pin fk prs3 Q --all prints the 4 modes (JSON: full precision) with status 0;
    an unreachable target (a mechanism file with a 3 m stroke) and a target beyond the
    stroke exit with status 2 and say why."""
    assert main(["fk", "prs3", "0.25", "0.15", "0.3", "--all"]) == 0
    out = capsys.readouterr().out
    assert out.count("\nmode ") == 4
    assert main(["fk", "prs3", "0.25", "0.15", "0.3", "--all", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    expected = [platform_pose(t, [0.25, 0.15, 0.3], MECHANISMS["prs3"]().build().anchors)
                for t in reference_modes([0.25, 0.15, 0.3]) if within_limits(t)]
    assert len(rows) == 4
    for row in rows:
        pose = pin.SE3(pin.rpy.rpyToMatrix(np.array(row["pose"]["rpy"])),
                       np.array(row["pose"]["xyz"]))
        assert min(_distance(pose, p) for p in expected) < 1e-9
    prs3(**GEOMETRY, stroke=(0.0, 3.0)).write(tmp_path)
    file = str(tmp_path / "mechanisms" / "prs3.toml")
    assert main(["fk", file, "0", "2.9", "0", "--all"]) == 2
    assert "unreachable" in capsys.readouterr().err
    assert main(["fk", "prs3", "0.25", "0.15", "1.3", "--all"]) == 2
    assert "outside its joint limits" in capsys.readouterr().err


# ------------------------------------------------------------------- partial poses
@pytest.mark.parametrize("given", [dict(z=1.0, roll=0.0, pitch=0.0),
                                   dict(z=1.2, roll=0.15, pitch=-0.1),
                                   dict(z=0.95, roll=-0.25, pitch=0.2)])
def test_round_trip_by_z_roll_pitch(mech, given):
    """Driven by z, roll, pitch: FK(IK(partial pose)) has them to 1e-10, and the
    completed pose lies on the reference's solution set (its sphere centres keep the
    platform's triangle for the actuated values)."""
    coords, actuated = round_trip(mech, given)
    assert coords <= 1e-10 and actuated <= 1e-10
    q = mech.inverse_kinematics(given).q_actuated
    pose = mech.complete_pose(**given)
    ref = [platform_pose(t, q, mech.anchors) for t in reference_modes(q) if within_limits(t)]
    assert min(_distance(pose, p) for p in ref) < 1e-9


def test_cli_map_over_z_and_roll(tmp_path, capsys):
    """pkm-pin map prs3 --axes z roll --at pitch=0 (15 × 15 over the sliders' reach)
    assembles 201 of the 225 cells and says so; each cell it could not assemble needs a
    slider beyond its stroke (inverse kinematics of a 3-PRS with a longer one)."""
    prefix = tmp_path / "zr"
    assert main(["map", "prs3", "--axes", "z", "roll", "--at", "pitch=0", "--range", "0.85",
                 "1.75", "-0.4", "0.4", "--n", "15", "--out", str(prefix), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "assembled  201 of 225" in out and "solved for x, y, yaw" in out
    data = np.load(tmp_path / "zr.npz")
    assert data["ok"].sum() == 201
    longer = prs3(**GEOMETRY, stroke=(-1.0, 2.0)).build()
    for i, j in np.argwhere(~data["ok"]):
        q = longer.inverse_kinematics(dict(z=data["u"][j], roll=data["v"][i],
                                          pitch=0.0)).q_actuated
        assert q.min() < 0.0 or q.max() > 1.0


# -------------------------------------------------------------------------- view
def _transforms(path) -> dict:
    """The meshcat transforms (path: column-major 4 × 4) embedded in a written page."""
    import base64
    import re

    import umsgpack

    commands = [umsgpack.unpackb(base64.b64decode(b)) for b in
                re.findall(r'pkmRun\("([A-Za-z0-9+/=]+)"\);', path.read_text(encoding="utf-8"))]
    return {c["path"]: c["matrix"] for c in commands if c["type"] == "set_transform"}


def test_cli_view_at_a_partial_pose(mech, tmp_path, capsys):
    """pkm-pin view prs3 --at z=1.1 roll=0.1 pitch=0 prints the completed pose and draws
    the mechanism there (every transform that of view() at mech.assemble of the partial
    pose); --at with --pose or --q, or a parasitic coordinate, exits with status 2."""
    from pkm_pin.view import view

    page = tmp_path / "at.html"
    assert main(["view", "prs3", "--at", "z=1.1", "roll=0.1", "pitch=0", "--html",
                 str(page)]) == 0
    out = capsys.readouterr().out
    assert "given      z=1.1, roll=0.1, pitch=0" in out and "rpy [0.1, 0, 0]" in out
    given = dict(z=1.1, roll=0.1, pitch=0.0)
    view(mech, mech.assemble(given), html=tmp_path / "api.html")
    drawn = _transforms(page)
    assert drawn == _transforms(tmp_path / "api.html")
    platform = np.reshape(drawn["/meshcat/pkm/3-PRS/platform"], (4, 4)).T
    np.testing.assert_allclose(platform, mech.complete_pose(**given).homogeneous, atol=1e-12)
    for extra in (["--pose", "0", "0", "1", "0", "0", "0"], ["--q", "0.2", "0.2", "0.2"]):
        assert main(["view", "prs3", "--at", "z=1.1", *extra, "--html", str(page)]) == 2
        assert "not both" in capsys.readouterr().err
    assert main(["view", "prs3", "--at", "x=0.1", "z=1.1", "--html", str(page)]) == 2
    assert "not independent" in capsys.readouterr().err
