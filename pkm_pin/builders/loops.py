"""Closed-loop models written as Extended URDF (URDF + YAML closures) and MJCF.

Each builder takes the dimensions [m] and returns a :class:`LoopModel`: the URDF text (the
loops cut open), the closures YAML in the layout of Gepetto's example-parallel-robots
(``closed_loop``, ``type``, ``name_mot``, ``joint_name``/``joint_type``, plus our
``output`` and ``output_point``), and for the planar four- and five-bar an MJCF
(``<equality><connect>``). :data:`LOOP_MODELS` names them; :func:`write_loop_models`
writes the committed files of ``models/loops/`` (``python -m pkm_pin.builders.loops``).

Every model is **assembled at ``q = 0``** (the URDF's reference configuration; the MJCF's
``qpos0``, the same configuration), in its intended assembly mode: the home pose is
written into the joint origins, so :meth:`pkm_pin.linkage.Linkage.assemble` from the
reference keeps it, and a joint's value is its angle from home. Every closure frame is a
link hung on a fixed joint; every revolute turns about its z axis (planar models) or y
axis (sagittal models). The MJCF bodies hang under one joint-less ``base`` body, so that
Pinocchio's own parser reads the whole tree.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin


@dataclass(frozen=True)
class LoopModel:
    """The files of one closed-loop model.

    Attributes:
        name: File stem (``models/loops/<name>.urdf`` …).
        urdf: URDF text.
        yaml: Closures YAML text.
        mjcf: MJCF text, or None.
    """

    name: str
    urdf: str
    yaml: str
    mjcf: str | None = None


# ------------------------------------------------------------------------ text helpers
def _f(x: float) -> str:
    return format(float(x), ".15g")


def _v(values) -> str:
    return " ".join(_f(x) for x in values)


def _joint(name: str, kind: str, parent: str, child: str, xyz=(0, 0, 0), rpy=(0, 0, 0),
           axis=(0, 0, 1)) -> str:
    """One URDF joint (revolute joints limited to ±π)."""
    lines = [f'  <joint name="{name}" type="{kind}">',
             f'    <origin xyz="{_v(xyz)}" rpy="{_v(rpy)}"/>',
             f'    <parent link="{parent}"/>', f'    <child link="{child}"/>']
    if kind == "revolute":
        lines += [f'    <axis xyz="{_v(axis)}"/>',
                  '    <limit lower="-3.14159265" upper="3.14159265" effort="10" '
                  'velocity="10"/>']
    return "\n".join(lines + ["  </joint>"])


def _urdf(name: str, header: tuple[str, str], links: list[str], joints: list[str]) -> str:
    body = [f'  <link name="{link}"/>' for link in links] + joints
    return ("<?xml version=\"1.0\"?>\n"
            f"<!-- {header[0]} -->\n<!-- {header[1]} -->\n"
            f'<robot name="{name}">\n' + "\n".join(body) + "\n</robot>\n")


def _yaml(header: tuple[str, str], loops: list, types: list, motors: list, output: str,
          joint_name: tuple = (), joint_type: tuple = (), output_point: bool = False) -> str:
    def listing(items) -> str:
        return "[" + ", ".join(f"'{x}'" for x in items) + "]"

    lines = [f"# {header[0]}", f"# {header[1]}",
             "closed_loop: [" + ", ".join(listing(p) for p in loops) + "]",
             f"type: {listing(types)}", f"name_mot: {listing(motors)}"]
    if joint_name:
        lines += [f"joint_name: {listing(joint_name)}", f"joint_type: {listing(joint_type)}"]
    lines.append(f"output: {output}")
    if output_point:
        lines.append("output_point: true")
    return "\n".join(lines) + "\n"


def _circle_intersection(p0, r0: float, p1, r1: float, sign: float) -> np.ndarray:
    """Planar point at distance ``r0`` from ``p0`` and ``r1`` from ``p1`` (2-vectors), on the
    left of ``p0 → p1`` for ``sign = +1``."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    d = np.linalg.norm(p1 - p0)
    a = (r0 ** 2 - r1 ** 2 + d ** 2) / (2 * d)
    h = math.sqrt(max(r0 ** 2 - a ** 2, 0.0))
    u = (p1 - p0) / d
    return p0 + a * u + sign * h * np.array([-u[1], u[0]])


def _angle(v) -> float:
    return math.atan2(v[1], v[0])


# ----------------------------------------------------------------------------- four-bar
def four_bar_home(ground: float = 0.10, crank: float = 0.03, coupler: float = 0.09,
                  rocker: float = 0.07, crank_angle: float = math.pi / 3
                  ) -> tuple[float, float, float]:
    """Absolute angles from +x (crank θ2, coupler θ3, rocker θ4) of the four-bar
    assembled elbow up (the coupler–rocker joint left of the line from the crank end to
    the rocker pivot) at the crank angle ``crank_angle``."""
    B = crank * np.array([math.cos(crank_angle), math.sin(crank_angle)])
    C = _circle_intersection(B, coupler, (ground, 0.0), rocker, 1.0)
    return crank_angle, _angle(C - B), _angle(C - np.array([ground, 0.0]))


def four_bar(ground: float = 0.10, crank: float = 0.03, coupler: float = 0.09,
             rocker: float = 0.07, home_crank_angle: float = math.pi / 3) -> LoopModel:
    """Planar four-bar in the xy-plane: base pivots O2 = (0, 0) (crank, actuated) and
    O4 = (ground, 0) (rocker); the coupler tip is closed on the rocker tip by a point.
    ``q = 0`` is assembled at the crank angle ``home_crank_angle`` from +x, elbow up
    (:func:`four_bar_home`); each joint's value is its angle from there. Defaults:
    Grashof crank-rocker (0.03 + 0.10 < 0.09 + 0.07, crank shortest)."""
    header = ("Planar four-bar (Grashof crank-rocker), xy-plane, crank actuated",
              f"ground {ground} m, crank {crank} m, coupler {coupler} m, rocker {rocker} m")
    t2, t3, t4 = four_bar_home(ground, crank, coupler, rocker, home_crank_angle)
    links = ["base", "crank", "coupler", "coupler_tip", "rocker", "rocker_tip"]
    joints = [_joint("crank_joint", "revolute", "base", "crank", rpy=(0, 0, t2)),
              _joint("coupler_joint", "revolute", "crank", "coupler", (crank, 0, 0),
                     (0, 0, t3 - t2)),
              _joint("coupler_tip_frame", "fixed", "coupler", "coupler_tip", (coupler, 0, 0)),
              _joint("rocker_joint", "revolute", "base", "rocker", (ground, 0, 0), (0, 0, t4)),
              _joint("rocker_tip_frame", "fixed", "rocker", "rocker_tip", (rocker, 0, 0))]
    yaml = _yaml(header, [["coupler_tip", "rocker_tip"]], ["3d"], ["crank_joint"], "rocker")
    bodies = (f'<body name="crank" axisangle="0 0 1 {_f(t2)}">\n'
              '  <joint name="crank_joint" type="hinge" axis="0 0 1"/>\n'
              f'  <body name="coupler" pos="{_f(crank)} 0 0" axisangle="0 0 1 {_f(t3 - t2)}">\n'
              '    <joint name="coupler_joint" type="hinge" axis="0 0 1"/>\n'
              '  </body>\n</body>\n'
              f'<body name="rocker" pos="{_f(ground)} 0 0" axisangle="0 0 1 {_f(t4)}">\n'
              '  <joint name="rocker_joint" type="hinge" axis="0 0 1"/>\n</body>\n')
    mjcf = _mjcf("four_bar", header, bodies,
                 f'    <connect name="coupler_rocker" body1="coupler" body2="rocker" '
                 f'anchor="{_f(coupler)} 0 0"/>\n', ["crank_joint"], output="rocker")
    return LoopModel("four_bar", _urdf("four_bar", header, links, joints), yaml, mjcf)


def _mjcf(name: str, header: tuple[str, str], bodies: str, equality: str,
          motors: list[str], output: str | None = None) -> str:
    """MJCF text: ``bodies`` (unindented) under one joint-less ``base`` body; ``output``:
    the output frame, named in ``<custom>`` (:data:`pkm_pin.model.mjcf.OUTPUT_KEY`;
    without it pkm_pin chooses the output by its rule)."""
    actuators = "".join(f'    <motor name="{m}_motor" joint="{m}"/>\n' for m in motors)
    inner = "".join(f"      {line}\n" for line in bodies.splitlines())
    custom = ("" if output is None else
              f'  <custom>\n    <text name="pkm_pin:output" data="{output}"/>\n  </custom>\n')
    return (f"<!-- {header[0]} -->\n<!-- {header[1]}; assembled at qpos0 = 0 -->\n"
            f'<mujoco model="{name}">\n  <compiler angle="radian"/>\n{custom}'
            f'  <worldbody>\n    <body name="base">\n{inner}    </body>\n  </worldbody>\n'
            f"  <equality>\n{equality}  </equality>\n"
            f"  <actuator>\n{actuators}  </actuator>\n</mujoco>\n")


# ----------------------------------------------------------------------------- five-bar
def five_bar_home(half_base: float = 0.05, proximal: float = 0.10, distal: float = 0.12,
                  point: tuple = (0.0, 0.15)) -> tuple[tuple[float, float], ...]:
    """Absolute angles from +x ``((θ_p1, θ_d1), (θ_p2, θ_d2))`` of the proximal and
    distal links of the five-bar with the tip at ``point``, elbows out."""
    P = np.asarray(point, float)
    out = []
    for x, sign in ((-half_base, 1.0), (half_base, -1.0)):
        A = np.array([x, 0.0])
        C = _circle_intersection(A, proximal, P, distal, sign)
        out.append((_angle(C - A), _angle(P - C)))
    return tuple(out)


def five_bar(half_base: float = 0.05, proximal: float = 0.10, distal: float = 0.12,
             home_point: tuple = (0.0, 0.15)) -> LoopModel:
    """Planar five-bar in the xy-plane: motors ``mot1`` at (−half_base, 0) and ``mot2`` at
    (half_base, 0), proximal then distal links; the distal tips (``closedloop1_A`` on
    distal 1, ``closedloop1_B`` on distal 2) closed by a point; the output is the pin
    (``effector`` at distal 1's tip, ``output_point: true``: motion type 2T). ``q = 0``
    is assembled with the tip at ``home_point``, elbows out (:func:`five_bar_home`); each
    joint's value is its angle from there."""
    e, l1, l2 = half_base, proximal, distal
    header = ("Planar five-bar (2 motors at the base, point closure at the distal joint)",
              f"base {2 * e} m, proximal {l1} m, distal {l2} m")
    home = five_bar_home(e, l1, l2, home_point)
    links = ["base", "proximal1", "distal1", "closedloop1_A", "effector",
             "proximal2", "distal2", "closedloop1_B"]
    joints, legs = [], []
    for i, (x, (t1, t2)) in enumerate(zip((-e, e), home), start=1):
        joints += [_joint(f"mot{i}", "revolute", "base", f"proximal{i}", (x, 0, 0),
                          (0, 0, t1)),
                   _joint(f"free{i}", "revolute", f"proximal{i}", f"distal{i}", (l1, 0, 0),
                          (0, 0, t2 - t1))]
        tip = "closedloop1_A" if i == 1 else "closedloop1_B"
        joints.append(_joint(f"{tip}_frame", "fixed", f"distal{i}", tip, (l2, 0, 0)))
        if i == 1:
            joints.append(_joint("effector_frame", "fixed", "distal1", "effector", (l2, 0, 0)))
        effector = f'    <body name="effector" pos="{_f(l2)} 0 0"/>\n' if i == 1 else ""
        legs.append(f'<body name="proximal{i}" pos="{_f(x)} 0 0" axisangle="0 0 1 {_f(t1)}">\n'
                    f'  <joint name="mot{i}" type="hinge" axis="0 0 1"/>\n'
                    f'  <body name="distal{i}" pos="{_f(l1)} 0 0" axisangle="0 0 1 '
                    f'{_f(t2 - t1)}">\n    <joint name="free{i}" type="hinge" axis="0 0 1"/>\n'
                    f'{effector}  </body>\n</body>\n')
    yaml = _yaml(header, [["closedloop1_A", "closedloop1_B"]], ["3d"], ["mot1", "mot2"],
                 "effector", output_point=True)
    mjcf = _mjcf("five_bar", header, "".join(legs),
                 f'    <connect name="distal_tips" body1="distal1" body2="distal2" '
                 f'anchor="{_f(l2)} 0 0"/>\n', ["mot1", "mot2"])
    return LoopModel("five_bar", _urdf("five_bar", header, links, joints), yaml, mjcf)


# -------------------------------------------------------------------------------- ankle
def ankle(rod: float = 0.30, crank: float = 0.05, half_width: float = 0.04) -> LoopModel:
    """Humanoid parallel ankle: the shank is the base, the ankle centre its origin (z up,
    x forward). The foot hangs on a universal joint ``ankle`` (``UJOINT_XY``: roll
    ``ankle_X`` then pitch ``ankle_Y``); motors ``motor_1``/``motor_2`` (axis y) at
    (0, ±half_width, rod) turn cranks pointing −x; a rod of length ``rod`` hangs from each
    crank end on a ball joint (``SPHERICAL``) and is closed by a point on the foot at
    (−crank, ±half_width, 0). ``q = 0`` is assembled (foot flat, cranks level, rods
    vertical). 2 DOF plus the two rods' idle spins."""
    h, r, w = rod, crank, half_width
    header = ("Humanoid parallel ankle: foot on a U joint, 2 motor cranks + 2 S-S rods",
              f"rod {h} m, crank {r} m, motor spacing {2 * w} m; shank is the base")
    links = ["shank", "foot", "foot_attach_1", "foot_attach_2"]
    joints = [_joint("ankle", "revolute", "shank", "foot", axis=(1, 0, 0))]
    for i, y in ((1, w), (2, -w)):
        links += [f"crank_{i}", f"rod_{i}", f"rod_{i}_tip"]
        joints += [_joint(f"motor_{i}", "revolute", "shank", f"crank_{i}", (0, y, h),
                          axis=(0, 1, 0)),
                   _joint(f"rod_{i}_ball", "revolute", f"crank_{i}", f"rod_{i}", (-r, 0, 0)),
                   _joint(f"rod_{i}_tip_frame", "fixed", f"rod_{i}", f"rod_{i}_tip",
                          (0, 0, -h)),
                   _joint(f"foot_attach_{i}_frame", "fixed", "foot", f"foot_attach_{i}",
                          (-r, y, 0))]
    yaml = _yaml(header, [["rod_1_tip", "foot_attach_1"], ["rod_2_tip", "foot_attach_2"]],
                 ["3d", "3d"], ["motor_1", "motor_2"], "foot",
                 ("ankle", "rod_1_ball", "rod_2_ball"), ("UJOINT_XY", "SPHERICAL", "SPHERICAL"))
    return LoopModel("ankle", _urdf("ankle", header, links, joints), yaml)


# ------------------------------------------------------------------------ Cassie-like leg
#: Home points (x, z) [m] of :func:`cassie_knee` in the thigh frame (x forward, z up).
CASSIE_POINTS = {
    "knee": (0.0, 0.0), "knee_motor": (-0.05, 0.10), "knee_crank_end": (-0.09, 0.10),
    "knee_drive": (-0.04, -0.03), "achilles": (-0.06, -0.02), "tarsus": (0.03, -0.40),
    "heel": (-0.01, -0.38), "foot_motor": (0.04, -0.05), "foot_crank_end": (0.08, -0.05),
    "foot": (0.03, -0.80), "toe": (0.08, -0.79),
}


def cassie_knee(points: dict | None = None) -> LoopModel:
    """Cassie-like leg in the sagittal xz-plane (every joint about y), three loops, spring-free:
    the thigh is the base; the knee (passive) is driven by ``knee_motor`` through a crank and
    a rod (loop 1); the tarsus turns on the shin and an achilles rod from the thigh holds its
    heel (loop 2); the foot turns on the tarsus and ``foot_motor`` on the shin drives it
    through a crank and a plantar rod (loop 3). Points: :data:`CASSIE_POINTS` at ``q = 0``,
    which is assembled. 2 DOF."""
    p = {k: np.array([v[0], 0.0, v[1]]) for k, v in (points or CASSIE_POINTS).items()}
    header = ("Cassie-like leg, sagittal plane: knee drive, achilles rod and plantar rod loops",
              "thigh is the base; points [m] in pkm_pin.builders.loops.CASSIE_POINTS")
    links = ["thigh", "shin", "knee_drive_point", "tarsus", "heel_point", "foot", "toe_point",
             "knee_crank", "knee_rod", "knee_rod_tip", "achilles_rod", "achilles_rod_tip",
             "foot_crank", "plantar_rod", "plantar_rod_tip"]
    y = (0, 1, 0)
    joints = [
        _joint("knee", "revolute", "thigh", "shin", p["knee"], axis=y),
        _joint("knee_drive_frame", "fixed", "shin", "knee_drive_point",
               p["knee_drive"] - p["knee"]),
        _joint("tarsus_joint", "revolute", "shin", "tarsus", p["tarsus"] - p["knee"], axis=y),
        _joint("heel_frame", "fixed", "tarsus", "heel_point", p["heel"] - p["tarsus"]),
        _joint("foot_joint", "revolute", "tarsus", "foot", p["foot"] - p["tarsus"], axis=y),
        _joint("toe_frame", "fixed", "foot", "toe_point", p["toe"] - p["foot"]),
        *_crank_rod("knee_motor", "thigh", "knee_crank", "knee_rod", p["knee_motor"],
                    p["knee_crank_end"], p["knee_drive"], y),
        _joint("achilles", "revolute", "thigh", "achilles_rod", p["achilles"], axis=y),
        _joint("achilles_rod_tip_frame", "fixed", "achilles_rod", "achilles_rod_tip",
               p["heel"] - p["achilles"]),
        *_crank_rod("foot_motor", "shin", "foot_crank", "plantar_rod",
                    p["foot_motor"] - p["knee"], p["foot_crank_end"] - p["knee"],
                    p["toe"] - p["knee"], y),
    ]
    yaml = _yaml(header, [["knee_rod_tip", "knee_drive_point"],
                          ["achilles_rod_tip", "heel_point"],
                          ["plantar_rod_tip", "toe_point"]], ["3d"] * 3,
                 ["knee_motor", "foot_motor"], "foot")
    return LoopModel("cassie_knee", _urdf("cassie_knee", header, links, joints), yaml)


def _crank_rod(motor: str, parent: str, crank: str, rod: str, pivot, crank_end, target,
               axis) -> list[str]:
    """Motor joint at ``pivot`` (in ``parent``), crank to ``crank_end``, rod on a revolute
    to the tip frame ``<rod>_tip`` at ``target`` (all at ``q = 0``, unrotated frames)."""
    pivot, crank_end, target = (np.asarray(v, float) for v in (pivot, crank_end, target))
    return [_joint(motor, "revolute", parent, crank, pivot, axis=axis),
            _joint(f"{rod}_joint", "revolute", crank, rod, crank_end - pivot, axis=axis),
            _joint(f"{rod}_tip_frame", "fixed", rod, f"{rod}_tip", target - crank_end)]


# -------------------------------------------------------------------------------- Delta
def delta_home(base_radius: float = 0.20, platform_radius: float = 0.05, arm: float = 0.20,
               forearm: float = 0.45, height: float = 0.35) -> tuple[float, float]:
    """Angles (θ hip, σ forearm) [rad] of every leg of :func:`delta` with the platform
    centred at ``(0, 0, −height)``, elbows out: the arm points along ``R_y(θ) x̂``, the
    forearm along ``R_y(σ) x̂`` in the leg's frame (σ = θ + the elbow's y angle). The
    wrist centre is at ``(x, 0, z) = (r_p − r_b, 0, −height)`` from the hip, so
    ``A cos θ + B sin θ = C`` with ``A = −2 x ℓ_a``, ``B = 2 z ℓ_a``, ``C = ℓ_f² − x² − z² −
    ℓ_a²``, θ = atan2(B, A) + acos(C / |(A, B)|)."""
    x, z = platform_radius - base_radius, -height
    A, B = -2 * x * arm, 2 * z * arm
    C = forearm * forearm - x * x - z * z - arm * arm
    theta = math.atan2(B, A) + math.acos(C / math.hypot(A, B))
    elbow = np.array([arm * math.cos(theta), -arm * math.sin(theta)])
    return theta, math.atan2(-(z - elbow[1]), x - elbow[0])


def delta(base_radius: float = 0.20, platform_radius: float = 0.05, arm: float = 0.20,
          forearm: float = 0.45, height: float = 0.35) -> LoopModel:
    """Delta as a tree plus 3 welds: three R-U-U legs (Tsai's equivalent of the
    parallelogram) from the base (z up) at angles 0, 120°, 240°, hip ``hip_i`` (axis:
    the leg frame's y, tangential) then arm along the leg frame's x; elbow U ``elbow_i_1``
    (y) then ``elbow_i_2`` (z); forearm along x; wrist U ``wrist_i_1`` (z) then
    ``wrist_i_2`` (y). The platform is a free body (``platform_joint``, floating) and each
    leg tip is welded to it at radius ``platform_radius``. ``q = 0`` is assembled with the
    platform at ``(0, 0, −height)``, unrotated, elbows out (:func:`delta_home`; the home
    angles are in the origins of the y-axis joints): 3 DOF, translational."""
    header = ("Delta (3-RUU equivalent): three legs as branches, platform free, 3 welds",
              f"base radius {base_radius} m, platform radius {platform_radius} m, "
              f"arm {arm} m, forearm {forearm} m; home height {height} m")
    theta, sigma = delta_home(base_radius, platform_radius, arm, forearm, height)
    links, joints, loops = ["base", "platform"], [
        _joint("platform_joint", "floating", "base", "platform", (0, 0, -height))], []
    for i in range(1, 4):
        phi = 2 * math.pi * (i - 1) / 3
        c, s = math.cos(phi), math.sin(phi)
        links += [f"arm_{i}", f"elbow_{i}", f"forearm_{i}", f"wrist_{i}", f"leg_{i}_tip",
                  f"platform_anchor_{i}"]
        joints += [
            _joint(f"hip_{i}", "revolute", "base", f"arm_{i}", (base_radius * c,
                   base_radius * s, 0), (0, theta, phi), (0, 1, 0)),
            _joint(f"elbow_{i}_1", "revolute", f"arm_{i}", f"elbow_{i}", (arm, 0, 0),
                   (0, sigma - theta, 0), (0, 1, 0)),
            _joint(f"elbow_{i}_2", "revolute", f"elbow_{i}", f"forearm_{i}"),
            _joint(f"wrist_{i}_1", "revolute", f"forearm_{i}", f"wrist_{i}", (forearm, 0, 0)),
            _joint(f"wrist_{i}_2", "revolute", f"wrist_{i}", f"leg_{i}_tip",
                   rpy=(0, -sigma, 0), axis=(0, 1, 0)),
            _joint(f"platform_anchor_{i}_frame", "fixed", "platform", f"platform_anchor_{i}",
                   (platform_radius * c, platform_radius * s, 0), (0, 0, phi))]
        loops.append([f"leg_{i}_tip", f"platform_anchor_{i}"])
    yaml = _yaml(header, loops, ["6d"] * 3, ["hip_1", "hip_2", "hip_3"], "platform")
    return LoopModel("delta_loops", _urdf("delta_loops", header, links, joints), yaml)


#: Builder of every model of ``models/loops/`` (same call: ``builder() -> LoopModel``).
LOOP_MODELS: dict[str, Callable[[], LoopModel]] = {
    "four_bar": four_bar, "five_bar": five_bar, "ankle": ankle,
    "cassie_knee": cassie_knee, "delta_loops": delta,
}


def write_loop_models(folder: str | Path) -> list[Path]:
    """Write every model of :data:`LOOP_MODELS` into ``folder``; returns the paths."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for build in LOOP_MODELS.values():
        model = build()
        files = {".urdf": model.urdf, ".yaml": model.yaml, ".xml": model.mjcf}
        for suffix, text in files.items():
            if text is not None:
                path = folder / f"{model.name}{suffix}"
                path.write_text(text)
                written.append(path)
    return written


if __name__ == "__main__":
    for path in write_loop_models(Path(__file__).resolve().parents[2] / "models" / "loops"):
        print(path)


def with_random_inertias(model, seed: int = 0):
    """``model`` (a :class:`~pkm_pin.model.ClosureModel`) with a seeded random inertia on
    every body: masses in [0.5, 2] kg, centres within 0.2 L of the joint, principal
    moments m (0.1 L)² (1 + 0.3 u) in a random frame. For exercising dynamics on shipped
    models that carry no masses (tests, benchmarks); never a designer's numbers."""


    rng = np.random.default_rng(seed)
    tree, L = pin.Model(model.tree), model.length
    for j in range(1, tree.njoints):
        m = rng.uniform(0.5, 2.0)
        d = m * (0.1 * L) ** 2 * (1 + 0.3 * rng.uniform(size=3))
        R = pin.rpy.rpyToMatrix(*rng.uniform(-np.pi, np.pi, 3))
        tree.inertias[j] = pin.Inertia(m, rng.normal(size=3) * 0.2 * L, R @ np.diag(d) @ R.T)
    return dataclasses.replace(model, tree=tree)
