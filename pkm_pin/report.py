"""Reports of a mechanism at a pose: plain data (JSON), Markdown and text.

A report holds what :class:`~pkm_pin.analysis.Analysis` knows about one assembly: the
degree of freedom and motion type with a readable basis of the platform twists
described in words, the Grübler count and the redundant constraints, the constraint
wrenches in words, ``A`` and ``B`` of ``A Δ t = B q̇_a``, the singularity class and its
closeness indices, and the cross-check against the hand-written formulas of the
papers where they exist (:mod:`pkm_pin.crosscheck`).

Conventions: screws axis-first about the world origin, twists ``(ω; v_O)`` and wrenches
``(f; m_O)`` (see :mod:`pkm_pin.screws`); lengths [m], angles [rad], pitches [m/rad].

Readable basis (:func:`readable_basis`): first the pure translations (couples), along
world axes when the translation space contains them; then one screw per remaining
direction of ``ω`` (world axes first), each moved by the translations so that its axis
passes as near as possible to the platform centre (the origin of the platform frame).
The rows span the same screw system as ``Analysis.platform_twists``.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from .model.closure_model import duplicate_closures
from .tolerances import DIRECTION_SNAP

#: Components of a unit direction below this are printed as 0 (alias of
#: :data:`pkm_pin.tolerances.DIRECTION_SNAP`).
_SNAP = DIRECTION_SNAP


@dataclass(frozen=True)
class BasisScrew:
    """One screw of a readable basis, with its geometry.

    Attributes:
        kind: ``"couple"`` (pure translation / pure moment), ``"line"`` (rotation /
            pure force, pitch 0) or ``"screw"`` (finite non-zero pitch).
        screw: Axis-first coordinates (6,), about the world origin; the direction part
            is a unit vector (the moment part of a couple is).
        direction: Unit direction of the axis (of the translation for a couple).
        point: Point of the axis nearest the platform centre [m] (``None`` for a couple).
        pitch: Pitch [m/rad] (``inf`` for a couple).
    """

    kind: str
    screw: np.ndarray
    direction: np.ndarray
    point: np.ndarray | None
    pitch: float

    def words(self, wrench: bool = False) -> str:
        """The screw in words, as a twist (default) or as a wrench."""
        d = _vec(self.direction)
        if self.kind == "couple":
            return f"pure moment about {d}" if wrench else f"pure translation along {d}"
        p = _vec(self.point)
        if self.kind == "line":
            what = "force along" if wrench else "rotation about an axis through"
            return f"{what} {d} through {p}" if wrench else f"{what} {p} along {d}"
        return (f"{'wrench' if wrench else 'screw'} of pitch {_num(self.pitch)} m/rad "
                f"about an axis through {p} along {d}")

    def as_dict(self, wrench: bool = False) -> dict:
        """JSON-ready fields, ``words`` included (``point``/``pitch`` ``None`` for a couple)."""
        return {
            "kind": self.kind,
            "screw": self.screw.tolist(),
            "direction": self.direction.tolist(),
            "point": None if self.point is None else self.point.tolist(),
            "pitch": None if np.isinf(self.pitch) else float(self.pitch),
            "words": self.words(wrench),
        }


# ---------------------------------------------------------------- readable basis
def readable_directions(Q: np.ndarray) -> np.ndarray:
    """Orthonormal basis (k × 3) of the span of the rows of ``Q``, world axes first.

    The world axes are projected onto the subspace, longest projection first (x before
    y before z on ties), and orthonormalised greedily; each direction is signed so that
    its largest component is positive and round-off components are set to 0.
    """
    Q = np.atleast_2d(np.asarray(Q, dtype=float))
    if Q.size == 0:
        return np.zeros((0, 3))
    _, sv, Vt = np.linalg.svd(Q)
    k = int(np.sum(sv > 1e-9 * sv[0])) if sv[0] > 0 else 0
    B = Vt[:k]
    proj = np.eye(3) @ B.T @ B
    order = sorted(range(3), key=lambda i: -round(float(np.linalg.norm(proj[i])), 9))
    out: list[np.ndarray] = []
    for i in order:
        p = proj[i].copy()
        for q in out:
            p -= p.dot(q) * q
        n = np.linalg.norm(p)
        if n > 1e-6 and len(out) < k:
            out.append(p / n)
    return np.array([_tidy_direction(d) for d in out]).reshape(-1, 3)


def _tidy_direction(d: np.ndarray) -> np.ndarray:
    d = np.where(np.abs(d) < _SNAP, 0.0, d)
    d = d / np.linalg.norm(d)
    return (-d if d[np.argmax(np.abs(d))] < 0 else d) + 0.0


def readable_basis(S, centre, length: float, translations: int | None = None) -> list[BasisScrew]:
    """A readable basis of the screw system spanned by the rows of ``S``.

    Args:
        S: Screws (k × 6), axis-first about the world origin.
        centre: Point [m] that the axes should pass near (the platform centre).
        length: Characteristic length [m] of the mechanism (homogenises the tolerance).
        translations: Dimension of the couples in the system, when known (e.g.
            :attr:`Analysis.translations`); otherwise found with a relative tolerance
            of 1e-7 on the homogenised direction parts.

    Returns:
        The couples first, then one line or screw per direction of the direction parts.
    """
    S = np.atleast_2d(np.asarray(S, dtype=float)).reshape(-1, 6)
    centre = np.asarray(centre, dtype=float)
    if S.shape[0] == 0:
        return []
    H = S.copy()
    H[:, 3:] /= length
    H /= np.linalg.norm(H, axis=1, keepdims=True)
    U, sv, Vt = np.linalg.svd(H[:, :3], full_matrices=True)
    k = S.shape[0]
    rank_w = int(np.sum(sv > 1e-7)) if translations is None else k - int(translations)
    # combinations of rows with no direction part: the couples
    couples = U[:, rank_w:].T @ H
    T = readable_directions(couples[:, 3:]) if couples.shape[0] else np.zeros((0, 3))
    out = [BasisScrew("couple", np.r_[np.zeros(3), t], t, None, np.inf) for t in T]
    for d in readable_directions(Vt[:rank_w]):
        c, *_ = np.linalg.lstsq(H[:, :3].T, d, rcond=None)
        h = c @ H
        w, v = d, h[3:] * length  # h[:3] == d up to round-off
        v_centre = v + np.cross(w, centre)
        v_centre = v_centre - T.T @ (T @ v_centre) if T.size else v_centre
        v_centre = np.where(np.abs(v_centre) < _SNAP * length, 0.0, v_centre)
        p = w.dot(v_centre) / w.dot(w)
        point = centre + np.cross(w, v_centre) / w.dot(w)
        point = np.where(np.abs(point) < _SNAP * length, 0.0, point) + 0.0
        kind = "line" if abs(p) < 1e-9 * length else "screw"
        p = 0.0 if kind == "line" else float(p)
        screw = np.r_[w, v_centre - np.cross(w, centre)]
        out.append(BasisScrew(kind, screw, w, point, p))
    return out


# ------------------------------------------------------------------- report data
def report_data(subject, assembly=None, plots: Sequence[str | Path] = (), *,
                analysis=None) -> dict:
    """The report of a mechanism at an assembly as plain data (JSON-ready): one set of
    keys for every :class:`~pkm_pin.Mechanism`, whichever backend reads it.

    Args:
        subject: A mechanism (reported at ``assembly``, default its home assembly), or
            the per-leg :class:`~pkm_pin.analysis.Analysis` of one (its mechanism at its
            assembly).
        assembly: The mechanism's assembly (an :class:`~pkm_pin.assembly.Assembly` or a
            general backend's ``Assembly``).
        plots: Image files the report links.
        analysis: The mechanism's analysis at ``assembly``, when already made.

    Keys: the tree's (:func:`linkage_report_data`, read by the mechanism's general
    elimination, :attr:`Mechanism.general`: the output and how to choose another, the
    structure detected, the whole tree's configuration joint by joint, the mobility with
    its idle motions and generic ranks, the independent sub-mechanisms), with the numbers
    of the backend that reads the mechanism (``A``, ``B``, the bases, ``singularity``,
    ``indices``, ``transmission``; :attr:`Mechanism.backend`; a per-leg reading's
    ``indices`` end with its ``forward`` and ``inverse``, :attr:`Analysis.motion_indices`,
    so both readings report the same five); then ``backend``,
    ``description``, ``length`` (the characteristic length), ``length_unit``, ``legs``
    (the legs' names of a mechanism read per leg, else ``[]``), ``actuated`` (the
    names in the order of ``q_actuated`` and of ``A``'s rows), ``grubler`` and
    ``redundant_constraints`` (the per-leg engine's counts where it reads the machine),
    ``uncontrolled_twist`` (words, at a type II/III singularity, else ``None``),
    ``crosscheck`` (quantity → largest dimensionless difference from the hand-written
    formulas of the papers, or ``None``), ``crosscheck_max_error``, ``plots`` and
    ``failed_sections`` (section → error, for the optional sections that failed:
    :func:`optional`).
    """
    from .analysis import LegsAnalysis
    from .crosscheck import crosscheck

    if isinstance(subject, LegsAnalysis):
        mech, assembly, analysis = subject.mechanism, subject.assembly, subject
    else:
        mech = subject
        assembly = mech.home_assembly if assembly is None else assembly
    an = mech.analyze(assembly) if analysis is None else analysis
    per_leg = isinstance(an, LegsAnalysis)
    data = linkage_report_data(mech.general, assembly, an, plots,
                               transmission=(lambda: an.transmission) if per_leg else None)
    failed = data["failed_sections"]
    checks = optional("crosscheck", lambda: crosscheck(an), failed) if per_leg else None
    free = optional("uncontrolled_twist", lambda: an.uncontrolled_twist, failed)
    centre = assembly.output_pose.translation
    data.update({
        "backend": mech.backend,
        "description": mech.description,
        "length": an.length,
        "length_unit": getattr(mech, "length_unit", "m"),
        "legs": [leg.name for leg in mech.legs] if per_leg else [],
        "actuated": list(mech.actuated_names),
        "uncontrolled_twist": None if free is None else
        readable_basis(free[None], centre, an.length)[0].words(),
        "crosscheck": checks,
        "crosscheck_max_error": None if checks is None else max(checks.values()),
    })
    if per_leg:
        data.update(grubler=an.grubler, redundant_constraints=an.redundant_constraints,
                    constraint_singular=bool(an.constraint_singular))
        motion = optional("motion_indices", lambda: an.motion_indices, failed) or {}
        data["indices"].update({k: finite_or_none(v) for k, v in motion.items()})
    return data


def optional(section: str, compute, failed: dict):
    """``compute()`` of an optional section of a report, or ``None`` with the error
    recorded in ``failed[section]`` (``"Type: message"``): a section that fails on an
    unusual file (a transmission index, the cross-check, idle motions in words) costs
    that section, not the report."""
    try:
        return compute()
    except Exception as e:  # noqa: BLE001 (any failure of an optional section)
        failed[section] = f"{type(e).__name__}: {e}"[:300]
        return None


def failed_lines(r: dict) -> list[str]:
    """One text line per optional section that failed (:func:`optional`)."""
    return [f"{name:<18} not computed ({why})"
            for name, why in r.get("failed_sections", {}).items()]


def _transmission_of(compute) -> dict | None:
    """``compute()`` (a :class:`~pkm_pin.transmission.Transmission`) as plain data with
    the weakest index in words; ``None`` where it is not defined (a type II pose)."""
    from .errors import PkmError

    try:
        tr = compute()
    except (PkmError, np.linalg.LinAlgError):
        return None
    return transmission_data(tr)


def finite_or_none(x: float) -> float | None:
    """``x`` as a float, or ``None`` when it is not finite (JSON has no nan)."""
    x = float(x)
    return x if np.isfinite(x) else None


def strict_json(data) -> str:
    """``data`` as strict JSON text (indented): numpy numbers and arrays as plain
    numbers and lists, and every non-finite number (nan, ±inf: undefined at this
    configuration) as ``null``; where ``data`` is a mapping with such numbers, the key
    ``"non_finite"`` lists where they stood and what they were (``{"A[2][1]": "nan"}``),
    so that a strict parser reads the report and a reader knows why a value is missing."""
    found: dict = {}
    clean = _finite(data, "", found)
    if found and isinstance(clean, dict):
        clean["non_finite"] = found
    return json.dumps(clean, indent=2, allow_nan=False)


def _finite(x, where: str, found: dict):
    """:func:`strict_json`'s copy of ``x`` with non-finite numbers as ``None``."""
    if isinstance(x, Mapping):
        return {k: _finite(v, f"{where}.{k}" if where else str(k), found) for k, v in x.items()}
    if isinstance(x, np.ndarray):
        x = x.tolist()
    if isinstance(x, (list, tuple)):
        return [_finite(v, f"{where}[{i}]", found) for i, v in enumerate(x)]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        if np.isfinite(x):
            return float(x)
        found[where] = str(float(x))
        return None
    return x


def transmission_data(tr) -> dict:
    """A :class:`~pkm_pin.transmission.Transmission` as plain data (JSON-ready: nan is
    ``None``), with the weakest index in words."""
    return {"iti": [finite_or_none(v) for v in tr.iti],
            "oti": [finite_or_none(v) for v in tr.oti],
            "lti": finite_or_none(tr.lti), "cti": finite_or_none(tr.cti),
            "leg_cti": [finite_or_none(v) for v in tr.leg_cti], "good": tr.good,
            "words": tr.worst}


# ------------------------------------------------------------------- plain data
def pose_dict(pose: pin.SE3) -> dict:
    """``{"xyz": [m], "rpy": [rad]}`` of a placement (URDF roll, pitch, yaw)."""
    return {"xyz": pose.translation.tolist(), "rpy": pin.rpy.matrixToRpy(pose.rotation).tolist()}


def joint_values(model, q) -> dict:
    """The configuration ``q`` joint by joint: name → its coordinates (a list of
    ``nq`` numbers, e.g. a quaternion ``x, y, z, w`` for a spherical joint)."""
    tree = model.tree
    q = np.asarray(q, dtype=float)
    return {tree.names[j]: q[tree.joints[j].idx_q:tree.joints[j].idx_q + tree.joints[j].nq]
            .tolist() for j in range(1, tree.njoints) if tree.joints[j].nq}


def body_frames(model) -> list[str]:
    """Names of the tree's body frames (the choices of ``--output``), in tree order."""
    return [f.name for f in model.tree.frames if f.type == pin.FrameType.BODY
            and f.name != "universe"]


def output_hint(model, q) -> tuple[list[str], list[str]]:
    """``(likely, frames)`` for the ``--output`` hint at the assembled ``q``: the likely
    outputs (:func:`pkm_pin.output_choice.choose_output`: the body the mechanism exists
    to move and those that fit equally) and every body frame, the candidates in the
    rule's order first, then the frames of the closures (tree order); the frames in tree
    order and no likely one when the rule cannot be evaluated."""
    from .errors import PkmError
    from .output_choice import choose_output

    frames = body_frames(model)
    try:
        choice = choose_output(model, q)
    except (PkmError, np.linalg.LinAlgError):
        return [], frames
    ranked = [c.frame for c in choice.candidates]
    return list(choice.likely()), ranked + [f for f in frames if f not in set(ranked)]


def assembly_data(link, assembly) -> dict:
    """Plain data of an :class:`~pkm_pin.assembly.Assembly`: ``mechanism``,
    ``output``, ``output_is_point``, ``pose`` (the output frame's), ``actuated``,
    ``q_actuated``, ``q`` (the whole tree, Pinocchio's joint order, full precision),
    ``joint_names``, ``joints`` (:func:`joint_values`), ``actuator_matches`` (each
    actuator identifier of the file and the joints it picked), ``residual`` and ``closures``
    (name, kind, frames and residual of each)."""
    model = link.model
    return {
        "mechanism": link.name,
        "output": link.output,
        "output_is_point": bool(model.output_point),
        "pose": pose_dict(assembly.output_pose),
        "actuated": list(link.actuated),
        "actuator_matches": {name: list(joints) for name, joints in model.actuator_matches},
        "notes": list(model.notes),
        "q_actuated": assembly.q_actuated.tolist(),
        "q": assembly.q.tolist(),
        "joint_names": list(model.tree.names[1:]),
        "joints": joint_values(model, assembly.q),
        "residual": float(assembly.residual),
        "closures": [{"name": name, "kind": c.kind, "frame_a": c.frame_a,
                      "frame_b": c.frame_b, "residual": res}
                     for c, (name, res) in zip(model.closures,
                                                assembly.closure_residuals.items())],
    }


def linkage_report_data(link, assembly, analysis=None, plots: Sequence[str | Path] = (),
                        transmission=None) -> dict:
    """Plain-data summary (JSON-ready) of a linkage at an assembly: the tree's part of
    :func:`report_data` (``analysis``: the one to report, default ``link``'s own;
    ``transmission``: a function giving the :class:`~pkm_pin.transmission.Transmission`
    to report, default :meth:`Linkage.transmission` over the tree).

    Keys: those of :func:`assembly_data`, then ``description`` (``""``),
    ``output_named`` (the output was named by the file or the caller, not chosen by the
    default rule), ``output_likely`` (the frames that fit the rule best, the chosen one
    among them: :func:`output_hint`), ``structure``
    (:func:`structure_data`), ``duplicate_closures``, ``dof``,
    ``idle_dof``, ``idle_motions`` (sentences), ``singular`` (a rank below the generic
    one: :attr:`~pkm_pin.linkage.Mobility.singular`, ``None``: not decided),
    ``generic_dof``, ``generic_idle_dof``, ``representation_singularities`` (sentences),
    ``singular_words`` (the sentence, ``""`` when not singular),
    ``redundant_constraints``, ``grubler``,
    ``independent_actuators``, ``output_dof``, ``motion_type``, ``platform_twists`` (the
    readable basis of the output twists, as the text prints them: unit directions, lines
    through points), ``motion_basis`` and ``constraint_basis``
    (readable bases about the output origin, with ``words``), ``A``, ``B``,
    ``singularity``, ``constraint_singular`` (``None``: not decided), ``indices``
    (``None`` where undefined), ``indices_undefined`` (:func:`undefined_indices`: why
    each ``None`` index is not defined), ``submechanisms`` (:func:`submechanisms_data`: ``[]``
    for a single mechanism, ``None`` when it failed), and, as in the platform report,
    ``uncontrolled_twist``, ``crosscheck``, ``crosscheck_max_error`` (``None``: no
    hand-written formulas) and ``plots``.
    """
    an = analysis if analysis is not None else link.analyze(assembly)
    centre = assembly.output_pose.translation
    motion = readable_basis(an.platform_twists, centre, an.length, an.translations)
    constraints = readable_basis(an.constraint_wrenches, centre, an.length)
    mob = an.mobility
    data = assembly_data(link, assembly)
    failed: dict = {}
    data.update({
        "description": "",
        "output_named": bool(link.model.output_named),
        "output_likely": optional("output_likely",
                                  lambda: output_hint(link.model, assembly.q)[0], failed),
        "structure": structure_data(link),
        "duplicate_closures": [list(pair) for pair in duplicate_closures(link.model.closures)],
        "dof": mob.dof,
        "idle_dof": an.idle_dof,
        "idle_motions": list(mob.idle_motions),
        "singular": mob.singular,
        "generic_dof": mob.generic_dof,
        "generic_idle_dof": mob.generic_idle_dof,
        "representation_singularities": list(mob.representation),
        "singular_words": mob.singular_words,
        "redundant_constraints": an.redundant_constraints,
        "grubler": mob.grubler,
        "independent_actuators": list(mob.independent_actuators),
        "output_dof": an.output_dof,
        "motion_type": an.motion_type,
        "redundancy": int(getattr(an, "redundancy", 0)),
        "underactuation": int(getattr(an, "underactuation", 0)),
        "platform_twists": [b.screw.tolist() for b in motion],
        "motion_basis": [b.as_dict() for b in motion],
        "constraint_basis": [b.as_dict(wrench=True) for b in constraints],
        "A": an.A.tolist(),
        "B": an.B.tolist(),
        "singularity": an.singularity,
        "constraint_singular": an.constraint_singular,
        "indices": {k: finite_or_none(v) for k, v in an.indices.items()},
        "indices_undefined": undefined_indices(link, an),
        "transmission": optional("transmission", lambda: _tree_transmission(
            link, assembly) if transmission is None else _transmission_of(transmission),
            failed),
        "submechanisms": optional("submechanisms",
                                  lambda: submechanisms_data(link, assembly), failed),
        "uncontrolled_twist": None,
        "crosscheck": None,
        "crosscheck_max_error": None,
        "plots": [str(p) for p in plots],
        "failed_sections": failed,
    })
    return data


def undefined_indices(link, an) -> dict:
    """``{index: why it is not defined}`` for each index of the analysis ``an`` that is
    not finite (``null`` in the JSON, ``undefined`` in the text): no actuator; actuators
    whose wrench on the output is zero (rows of ``A`` that cannot be made unit: a type I
    singularity, e.g. the other leg's motors of a biped read with one foot); else ``A Δ``
    singular (an infinite condition number)."""
    bad = {k: float(v) for k, v in an.indices.items() if not np.isfinite(v)}
    if not bad:
        return {}
    A = np.asarray(an.A, dtype=float).reshape(-1, 6)
    zero = [n for n, row in zip(link.actuated, A) if not np.any(np.abs(row) > 1e-12)]
    if not link.actuated:
        why = "no actuator: A has no row"
    elif zero:
        why = (f"{len(zero)} actuator{'s' * (len(zero) != 1)} ({', '.join(zero[:6])}"
               f"{', …' if len(zero) > 6 else ''}) exert no wrench on the output: zero rows "
               "of A (a type I singularity), which cannot be scaled to unit length")
    else:
        why = "A Δ is singular here"
    return {k: f"{'infinite' if np.isinf(v) else 'not a number'}: {why}"
            for k, v in bad.items()}


def submechanisms_data(link, assembly) -> list:
    """The independent sub-mechanisms of the linkage at the assembly
    (:meth:`Linkage.submechanisms`: a biped's legs), each ``{"name", "joints"`` (its
    tree's joints), ``"actuated", "output", "dof", "idle_dof", "motion_type",
    "singularity", "indices"}``; ``[]`` when the linkage is one mechanism (the report is
    its own)."""
    subs = link.submechanisms(assembly.q)
    if len(subs) == 1 and subs[0] is link:
        return []
    out = []
    for sub in subs:
        an = sub.analyze(sub.home_assembly)
        out.append({"name": sub.name, "joints": sub.model.tree.njoints - 1,
                    "actuated": list(sub.actuated), "output": sub.output, "dof": an.dof,
                    "idle_dof": an.idle_dof, "motion_type": an.motion_type,
                    "singularity": an.singularity,
                    "indices": {k: finite_or_none(v) for k, v in an.indices.items()}})
    return out


def everywhere_lines(r: dict) -> list[str]:
    """The report's lines on a class that holds at every configuration
    (``docs/indices.md``): a kinematic redundancy (``r["redundancy"]``), an
    under-actuation (``r["underactuation"]``); none when neither."""
    out: list[str] = []
    if r.get("redundancy"):
        n = r["redundancy"]
        out += [f"redundancy         kinematically redundant: "
                f"{len(r['independent_actuators'])} independent actuators for an output that "
                f"moves in at most {6 if not r.get('output_is_point') else 3} directions: at "
                f"least {n} self-motion{'s' * (n > 1)} (actuators moving with the output "
                "held) at every configuration, so the type I and inverse indices are 0 and "
                "the class I everywhere: it marks the redundancy, not a singular pose "
                "(analyse one output per sub-mechanism, or fewer actuators, to find those)"]
    if r.get("underactuation"):
        n = r["underactuation"]
        out += [f"under-actuated     the output moves with every actuator locked ({n} "
                f"direction{'s' * (n > 1)}) here and at every configuration nearby (the "
                "ranks are the generic ones): springs or passive joints without a motor "
                "(see the idle motions); the forward and type II indices are 0 and the "
                "class II there: it marks the under-actuation, not a singular pose (actuate "
                "or lock those joints, or choose an output they do not move)"]
    return out


def submechanism_lines(r: dict) -> list[str]:
    """Two text lines per sub-mechanism (:func:`submechanisms_data`), none for one."""
    subs = r.get("submechanisms") or []
    if not subs:
        return []
    out = [f"sub-mechanisms     {len(subs)} independent (no movable joint shared; each "
           "analysed with the others held, with its own output: the singularity class "
           "above is that of one output for all of them):"]
    for s in subs:
        idx = ", ".join(f"{k} {_index(v, 'undefined', '.3g')}" for k, v in s["indices"].items())
        out += [f"    {s['name']}: {s['joints']} joints, {len(s['actuated'])} actuators "
                f"({', '.join(s['actuated'])}), output {s['output']}",
                f"        DOF {s['dof']} (idle DOF {s['idle_dof']}; output motion "
                f"{s['motion_type']}; singularity {s['singularity']}); {idx}"]
    return out


def structure_data(link) -> dict:
    """The base–legs–platform structure detected in the linkage's model
    (:attr:`Linkage.platform_structure`): ``{"platform": True, "legs": [{"name", "kind",
    "joints"}]}``, or ``{"platform": False, "reason": …}``."""
    structure, reason = link.platform_structure
    if structure is None:
        return {"platform": False, "reason": reason}
    names = link.model.tree.names
    return {"platform": True, "legs": [
        {"name": leg.name, "kind": leg.kind, "joints": [names[j] for j in leg.joints]}
        for leg in structure.legs]}


def structure_line(r: dict) -> str:
    """One line: the structure found, and the backend that reads it per leg."""
    s = r.get("structure")
    if s is None:
        return ""
    if not s["platform"]:
        return f"structure          general linkage (not base–legs–platform: {s['reason']})"
    kinds = ", ".join(f"{leg['name']}: {leg['kind']}" for leg in s["legs"])
    seed = "seed 000's indices, each actuation wrench orthogonal to its own leg's constraints"
    how = (f"analysed per leg ({seed}; --backend general: the general elimination)"
           if r.get("backend") == "legs" else
           f"read by the general elimination; --backend legs analyses it per leg ({seed})")
    return (f"structure          base–legs–platform machine, {len(s['legs'])} legs ({kinds}); "
            f"{how}")


# ------------------------------------------------------------------------- text
def output_line(r: dict, frames: Sequence[str] = (), likely: Sequence[str] = ()) -> str:
    """The output frame, how it is analysed, and how to choose another: the ``likely``
    outputs first (:func:`output_hint`), then the other ``frames`` (eight in all)."""
    how, other = (("its origin as a point", "--body: as a body") if r["output_is_point"]
                  else ("as a body", "--point: its origin as a point"))
    rest = [f for f in frames if f not in set(likely)]
    n = max(8 - len(likely), 3)
    parts = [f"likely: {', '.join(likely)}"] if likely else []
    if rest:
        parts.append(("other frames: " if likely else "frames: ") + ", ".join(rest[:n])
                     + (", …" if len(rest) > n else ""))
    choices = f" ({'; '.join(parts)})" if parts else ""
    return (f"output             {r['output']}, {how}  [another frame: --output FRAME"
            f"{choices}; {other}]")


def joints_lines(r: dict) -> list[str]:
    """One line per joint: name and coordinates."""
    width = max((len(n) for n in r["joints"]), default=0)
    return [f"    {n:<{width}}  {_list(v)}" for n, v in r["joints"].items()]


def _tree_transmission(link, assembly) -> dict | None:
    """:meth:`Linkage.transmission` as plain data (ITI/OTI per actuator, LTI, CTI per
    actuator side and their minimum, the weakest in words); ``None`` where it is not
    defined."""
    return _transmission_of(lambda: link.transmission(assembly))


def _matches_words(matches: dict) -> str:
    """What the file's actuator identifiers picked, where one is not a joint's own name
    (``"  (name_mot 'mot' picked mot1, mot2)"``); ``""`` otherwise."""
    picked = [f"{name!r} picked {', '.join(joints)}" for name, joints in matches.items()
              if list(joints) != [name]]
    return f"  (identifiers: {'; '.join(picked)})" if picked else ""


def linkage_markdown(r: dict) -> str:
    """:func:`markdown` of a report's plain data (the name the linkage report had)."""
    return markdown(data=r)


def _submechanisms_markdown(subs: list) -> list[str]:
    """A table of the independent sub-mechanisms (:func:`submechanisms_data`), none for
    one mechanism."""
    if not subs:
        return []
    out = ["", f"{len(subs)} independent sub-mechanisms (no movable joint shared), each "
           "analysed with the others held and its own output:", "",
           "| sub-mechanism | actuators | output | DOF | idle DOF | motion | singularity |",
           "|---|---|---|---|---|---|---|"]
    out += [f"| {s['name']} | {', '.join(s['actuated']) or 'none'} | {s['output']} | "
            f"{s['dof']} | {s['idle_dof']} | {s['motion_type']} | {s['singularity']} |"
            for s in subs]
    return out


# ---------------------------------------------------------------------- Markdown
def markdown(subject=None, plots: Sequence[str | Path] = (), data: dict | None = None) -> str:
    """Markdown report of a mechanism (every backend): the summary (output, DOF, idle
    DOF, motion, class, the independent sub-mechanisms, duplicate closures, failed
    optional sections) before the pose, the joint table, mobility, actuation,
    singularity, transmission and cross-check sections; ``plots`` are image files linked
    at the end.

    Args:
        subject: What :func:`report_data` takes (a mechanism at its home, or a per-leg
            :class:`~pkm_pin.analysis.Analysis`), unless ``data`` is given.
        plots: Image files (e.g. from :func:`pkm_pin.plots.save_maps`); linked as given.
        data: :func:`report_data` already computed.
    """
    r = data if data is not None else report_data(subject, plots=plots)
    lines = [f"# {r['mechanism']}", ""] + ([r["description"], ""] if r.get("description")
                                             else [])
    for section in (_md_summary, _md_pose_and_joints, _md_mobility, _md_actuation,
                    _md_singularity, _md_transmission, _md_crosscheck):
        lines += section(r)
    if r["plots"]:
        lines += ["", "## Plots", ""]
        lines += [f"![{Path(p).stem}]({p})" for p in r["plots"]]
    return "\n".join(lines) + "\n"


def _md_summary(r: dict) -> list[str]:
    """The summary: output, DOF, idle DOF, motion, class, duplicate closures, failed
    optional sections, the independent sub-mechanisms."""
    xyz, rpy = r["pose"]["xyz"], r["pose"]["rpy"]
    how = "its origin, as a point" if r.get("output_is_point") else "as a body"
    lines = ["## Summary", "",
             f"- output frame `{r['output']}` ({how}) at xyz {_vec(xyz)} m, "
             f"rpy {_vec(rpy)} rad",
             f"- DOF **{r['dof']}**, idle DOF {r['idle_dof']}, output motion "
             f"{r['motion_type']}, singularity **{r['singularity']}**"]
    lines += [f"- duplicate closure `{a}` repeats `{b}`: its rows are redundant"
              for a, b in r.get("duplicate_closures", [])]
    lines += [f"- {name}: not computed ({why})"
              for name, why in r.get("failed_sections", {}).items()]
    return lines + _submechanisms_markdown(r.get("submechanisms") or [])


def _md_pose_and_joints(r: dict) -> list[str]:
    """The output pose (in the model's length unit) and the joint table."""
    u = r.get("length_unit", "m")
    lines = ["", "## Pose", "", f"| x [{u}] | y [{u}] | z [{u}] | roll [rad] | pitch [rad] | "
             "yaw [rad] |", "|---|---|---|---|---|---|",
             "| " + " | ".join(_num(v) for v in [*r["pose"]["xyz"], *r["pose"]["rpy"]]) + " |"]
    lines += ["", "## Configuration", "", "| joint | q |", "|---|---|"]
    return lines + [f"| {n} | {_vec(v)} |" for n, v in r["joints"].items()]


def _md_mobility(r: dict) -> list[str]:
    """DOF, idle motions, Grübler's count, redundancy, independent actuators and the
    bases of the output twists and constraint wrenches."""
    redundant = "constraints" if r.get("legs") else "closure equations"
    lines = ["", "## Mobility", "",
             f"- degree of freedom: **{r['dof']}** ({r['motion_type']})",
             f"- idle degrees of freedom: {r['idle_dof']}"]
    lines += [f"  - {m}" for m in r["idle_motions"]]
    if r.get("singular_words"):
        lines += [f"- {r['singular_words']}"]
    lines += [f"- Grübler–Kutzbach count: {r['grubler']}",
              f"- redundant {redundant}: {r['redundant_constraints']}",
              f"- independent actuators: {', '.join(r['independent_actuators']) or 'none'}",
              "", "Output twists (ω; v_O) about the world origin:", "",
              "| # | twist (ω; v_O) | in words |", "|---|---|---|"]
    lines += [f"| {i + 1} | {_vec(b['screw'])} | {b['words']} |"
              for i, b in enumerate(r["motion_basis"])]
    lines += ["", "Constraint wrenches (f; m_O) on the output:", ""]
    if not r["constraint_basis"]:
        return lines + ["none: the output is free in space."]
    lines += ["| # | wrench (f; m_O) | in words |", "|---|---|---|"]
    return lines + [f"| {i + 1} | {_vec(b['screw'])} | {b['words']} |"
                    for i, b in enumerate(r["constraint_basis"])]


def _md_actuation(r: dict) -> list[str]:
    """``A`` and ``B`` of ``A Δ t = B q̇_a`` as tables."""
    lines = ["", "## Actuation: A Δ t = B q̇_a", "",
             "Rows of A: the actuation wrenches (f; m_O), one per actuated joint.", ""]
    lines += _matrix_table(r["A"], r["actuated"], ["f_x", "f_y", "f_z", "m_x", "m_y", "m_z"])
    return lines + ["", "B (diagonal):", ""] + _matrix_table(r["B"], r["actuated"],
                                                            r["actuated"])


def _md_singularity(r: dict) -> list[str]:
    """The singularity class, the uncontrolled twist and the indices."""
    lines = ["", "## Singularity", "", f"- class: **{r['singularity']}**",
             f"- constraint singular: {'yes' if r.get('constraint_singular') else 'no'}"]
    if r.get("uncontrolled_twist"):
        lines += [f"- uncontrolled twist: {r['uncontrolled_twist']}"]
    lines += ["", "| index | value |", "|---|---|"]
    return lines + [f"| {k} | {'undefined' if v is None else _num(v)} |"
                    for k, v in r["indices"].items()]


def _md_transmission(r: dict) -> list[str]:
    """ITI and OTI per actuator, LTI and CTI (none where they are not defined)."""
    tr = r.get("transmission")
    if tr is None:
        return []
    lines = ["", "## Motion/force transmission", "", f"{tr['words']}.", "",
             "| actuator | ITI | OTI |", "|---|---|---|"]
    lines += [f"| {a} | {_index(i, '—')} | {_index(o, '—')} |"
              for a, i, o in zip(r["actuated"], tr["iti"], tr["oti"])]
    return lines + ["", f"LTI = {_index(tr['lti'])} (good transmission: ≥ 0.7), "
                    f"CTI = {_index(tr['cti'])}"]


def _md_crosscheck(r: dict) -> list[str]:
    """The largest differences from the papers' hand-written formulas, or that none
    exist for the mechanism."""
    lines = ["", "## Cross-check against the hand-written formulas", ""]
    if r.get("crosscheck") is None:
        return lines + ["No hand-written formulas exist for this mechanism."]
    lines += ["Largest dimensionless difference |Pinocchio − formulas|:", "",
              "| quantity | difference |", "|---|---|"]
    return lines + [f"| {k} | {v:.3g} |" for k, v in r["crosscheck"].items()]


def _matrix_table(M, rows: Sequence[str], columns: Sequence[str]) -> list[str]:
    M = np.atleast_2d(np.asarray(M, dtype=float))
    if M.size == 0:
        return ["(empty)"]
    out = ["| | " + " | ".join(columns) + " |", "|---" * (len(columns) + 1) + "|"]
    out += [f"| {name} | " + " | ".join(_num(x) for x in row) + " |"
            for name, row in zip(rows, M)]
    return out


# --------------------------------------------------------------------------- text
def text(r: dict, frames: Sequence[str] = (), likely: Sequence[str] | None = None) -> str:
    """Plain-text report (the output of ``pkm-pin analyze``) from :func:`report_data`,
    for every mechanism: what it is and its output (``frames``: the choices of
    ``--output`` to suggest, ``likely`` those named first, default the report's
    ``output_likely``: :func:`output_hint`), then the summary (DOF with the idle motions,
    one sentence each, Grübler's count, singularity class, uncontrolled twist, indices
    with why an undefined one is, transmission, cross-check, actuators), then the tables
    (the whole tree's configuration, output twists and constraint wrenches, ``A``,
    ``B``)."""
    likely = r.get("output_likely") or [] if likely is None else likely
    joints, closures = len(r["joints"]), len(r["closures"])
    tree = (f"{joints} joints, {closures} closure{'s' if closures != 1 else ''}"
            + ("; no closure: a tree, analysed as a serial chain" if not closures else ""))
    legs = r.get("legs") or []
    what = (f"{len(legs)} legs: {', '.join(legs)}; tree: {tree}" if legs else f"linkage: {tree}")
    out = [f"mechanism          {r['mechanism']}  ({what})"]
    out += [output_line(r, frames, likely)]
    out += [line for line in (structure_line(r),) if line]
    out += [f"note               {n}" for n in r.get("notes", [])]
    out += [f"pose               xyz {_list(r['pose']['xyz'])}  rpy {_list(r['pose']['rpy'])}",
            f"DOF                {r['dof']}  (idle DOF {r['idle_dof']}; output motion "
            f"{r['motion_type']}; singularity {r['singularity']})",
            "idle motions       " + ("none" if not r["idle_motions"] else
                                     f"{r['idle_dof']} (with every actuated joint locked):")]
    out += [f"    {m}" for m in r["idle_motions"]]
    if r.get("singular_words"):
        out += [f"singular           {r['singular_words']}"]
    out += everywhere_lines(r)
    out += submechanism_lines(r)
    out += [f"duplicate closure  {a!r} repeats {b!r}: its rows are redundant"
            for a, b in r.get("duplicate_closures", [])]
    out += [f"Grübler count      {r['grubler']}  (redundant "
            f"{'constraints' if legs else 'closure equations'}: {r['redundant_constraints']})",
            f"singularity        {r['singularity']}"
            + ("  (constraint singular)" if r.get("constraint_singular") else "")]
    if r.get("uncontrolled_twist"):
        out += [f"uncontrolled twist {r['uncontrolled_twist']}"]
    out += ["indices            " + ", ".join(
        f"{k} = {v:.6g}" if v is not None and np.isfinite(v) else f"{k} = undefined"
        for k, v in r["indices"].items())]
    out += [f"    {k} undefined ({why})" for k, why in r.get("indices_undefined", {}).items()]
    tr = r.get("transmission")
    if tr is not None:
        out += [f"transmission       LTI = {_index(tr['lti'], fmt='.3g')}, "
                f"CTI = {_index(tr['cti'], fmt='.3g')}: {tr['words']}"]
    if r.get("crosscheck") is None:
        out += ["cross-check        no hand-written formulas for this mechanism"]
    else:
        parts = ", ".join(f"{k} {v:.2g}" for k, v in r["crosscheck"].items())
        out += ["cross-check        max |Pinocchio − formulas| = "
                f"{r['crosscheck_max_error']:.3g}  ({parts})"]
    out += [f"actuated joints    {', '.join(r['actuated'])} = {_list(r['q_actuated'])}"
            + _matches_words(r.get("actuator_matches", {})),
            f"independent        {', '.join(r['independent_actuators']) or 'none'}",
            "joints (q):"] + joints_lines(r)
    out += [f"{'platform' if legs else 'output'} twists ({r['output']}; ω; v_O):"]
    out += [f"    {_row(b['screw'])}   {b['words']}" for b in r["motion_basis"]] or ["    none"]
    out += ["constraint wrenches on the output (f; m_O):"]
    out += [f"    {_row(b['screw'])}   {b['words']}" for b in r["constraint_basis"]] or ["    none"]
    out += ["A (actuation wrenches (f; m_O), A Δ t = B q̇_a):"]
    out += [f"    {_row(row)}" for row in r["A"]]
    out += ["B:"] + [f"    {_row(row)}" for row in r["B"]]
    out += failed_lines(r)
    out += [f"plot               {p}" for p in r.get("plots", [])]
    return "\n".join(out)


# ------------------------------------------------------------------------ numbers
def _index(x: float | None, missing: str = "n/a", fmt: str = "") -> str:
    """An index of :func:`transmission_data` in words: ``missing`` where it is not
    defined (``None``), else :func:`_num` (or ``format(x, fmt)``)."""
    if x is None:
        return missing
    return format(x, fmt) if fmt else _num(x)


def _num(x: float) -> str:
    """A number with 4 significant digits, no ``-0``."""
    x = float(x)
    if np.isinf(x):
        return "inf" if x > 0 else "-inf"
    s = f"{x:.4g}"
    return "0" if s in ("-0", "0") else s


def _vec(v) -> str:
    return "(" + ", ".join(_num(x) for x in np.asarray(v, dtype=float)) + ")"


def _list(v) -> str:
    return str((np.round(np.asarray(v, dtype=float), 6) + 0.0).tolist())


def _row(v) -> str:
    return " ".join(f"{x:10.5f}" for x in np.asarray(v, dtype=float) + 0.0)


# --------------------------------------------------------- fk and ik text
def fk_text(r: dict) -> str:
    """Text of ``pkm-pin fk`` / ``ik`` for a linkage from :func:`assembly_data` (and,
    for several independent sub-mechanisms, the ``submechanisms`` of
    :func:`fk_submechanisms_data`: each one's actuated values and output pose)."""
    out = [f"mechanism  {r['mechanism']}",
           f"actuated   {_actuated_words(r)}",
           f"output     {r['output']}{' (point)' if r['output_is_point'] else ''}: "
           f"xyz {_list(r['pose']['xyz'])}  rpy {_list(r['pose']['rpy'])}"]
    subs = r.get("submechanisms") or []
    if subs:
        out.append(f"sub-mechanisms  {len(subs)} independent, each with its own output "
                   "(fk --sub K Q…: the actuated values of sub-mechanism K alone, the "
                   "others held at the reference assembly):")
        for k, s in enumerate(subs):
            out += [f"    [{k}] {s['name']}: {_actuated_words(s)}",
                    f"        output {s['output']}: xyz {_list(s['pose']['xyz'])}  "
                    f"rpy {_list(s['pose']['rpy'])}"]
    out.append("joints (q):")
    return "\n".join(out + joints_lines(r) + [f"residual   {r['residual']:.2g}"]
                     + failed_lines(r))


def _actuated_words(r: dict) -> str:
    """``a, b = [values]``, or that there is no actuator."""
    if not r["actuated"]:
        return "none (no actuator: the assembly from the reference configuration)"
    return f"{', '.join(r['actuated'])} = {_list(r['q_actuated'])}"


def fk_submechanisms_data(link, subs, assembly) -> list:
    """For ``fk`` of a linkage with several independent sub-mechanisms ``subs``
    (:meth:`Linkage.submechanisms`), at the whole linkage's ``assembly``: each one's
    ``{"name", "actuated", "q_actuated", "output", "pose"}`` (its actuated values and its
    output frame's pose, read in the whole tree); ``[]`` for one mechanism."""
    if len(subs) <= 1:
        return []
    model = link.model
    kin = model.kinematics(assembly.q)
    values = dict(zip(link.actuated, assembly.q_actuated))
    out = []
    for sub in subs:
        M = kin.frame_placements[model.tree.getFrameId(sub.output)]
        out.append({"name": sub.name, "actuated": list(sub.actuated),
                    "q_actuated": [float(values[n]) for n in sub.actuated],
                    "output": sub.output, "pose": pose_dict(M)})
    return out
