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
def report_data(analysis, plots: Sequence[str | Path] = ()) -> dict:
    """Plain-data summary of an :class:`~pkm_pin.analysis.Analysis` (JSON-ready).

    Keys: ``mechanism``, ``description``, ``pose`` (``xyz`` [m], ``rpy`` [rad]),
    ``dof``, ``motion_type``, ``grubler``, ``redundant_constraints``, ``idle_dof`` and
    ``idle_motions`` (in words, from the closure model), ``length`` (the
    characteristic length), ``platform_twists`` (the readable basis of the text report:
    unit directions, lines through points; not scaled by the characteristic length),
    ``motion_basis`` and ``constraint_basis``
    (readable bases, see :func:`readable_basis`, with ``words``), ``actuated``, ``A``,
    ``B``, ``singularity``, ``constraint_singular``, ``indices``, ``transmission``
    (ITI, OTI per actuator, LTI, CTI, the weakest in words; ``None`` at a type II pose),
    ``uncontrolled_twist`` (words, at a type II/III singularity, else ``None``),
    ``crosscheck`` (quantity → largest dimensionless difference, or ``None``),
    ``crosscheck_max_error``, ``plots`` (file paths) and ``failed_sections`` (section →
    error, for the optional sections that failed: :func:`optional`).
    """
    from .crosscheck import crosscheck

    mech = analysis.mechanism
    failed: dict = {}
    checks = optional("crosscheck", lambda: crosscheck(analysis), failed)
    pose = analysis.assembly.pose
    centre = pose.translation
    motion = readable_basis(analysis.platform_twists, centre, analysis.length,
                            analysis.translations)
    constraints = readable_basis(analysis.constraint_wrenches, centre, analysis.length)
    free = optional("uncontrolled_twist", lambda: analysis.uncontrolled_twist, failed)
    idle = optional("idle_motions", lambda: _idle(analysis), failed) or []
    tr = optional("transmission", lambda: _transmission(analysis), failed)
    return {
        "mechanism": mech.name,
        "description": mech.description,
        "pose": {"xyz": pose.translation.tolist(),
                 "rpy": pin.rpy.matrixToRpy(pose.rotation).tolist()},
        "dof": analysis.dof,
        "motion_type": analysis.motion_type,
        "grubler": analysis.grubler,
        "redundant_constraints": analysis.redundant_constraints,
        "idle_dof": len(idle),
        "idle_motions": idle,
        "length": analysis.length,
        "length_unit": getattr(mech, "length_unit", "m"),
        "platform_twists": [b.screw.tolist() for b in motion],
        "motion_basis": [b.as_dict() for b in motion],
        "constraint_basis": [b.as_dict(wrench=True) for b in constraints],
        "actuated": mech.actuated_names,
        "A": analysis.A.tolist(),
        "B": analysis.B.tolist(),
        "singularity": analysis.singularity,
        "constraint_singular": bool(analysis.constraint_singular),
        "indices": analysis.indices,
        "transmission": tr,
        "uncontrolled_twist": None if free is None else
        readable_basis(free[None], centre, analysis.length)[0].words(),
        "crosscheck": checks,
        "crosscheck_max_error": None if checks is None else max(checks.values()),
        "plots": [str(p) for p in plots],
        "failed_sections": failed,
    }


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


def _transmission(analysis) -> dict | None:
    """The motion/force transmission indices (:attr:`Analysis.transmission`) as plain
    data with the weakest one in words; ``None`` where they are not defined (a type II
    pose)."""
    from .errors import PkmError

    try:
        tr = analysis.transmission
    except PkmError:
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


def _idle(analysis) -> list[str]:
    """The idle motions of the mechanism at the analysed assembly, in words: the motions
    of its joints that move neither an actuator nor the platform (a leg spinning about
    the line through its two spherical joints), read from its closure model
    (:meth:`Mechanism.mobility`, the general reading of its tree)."""
    mob = analysis.mechanism.mobility(analysis.assembly, nearby=0)
    return list(mob.idle_motions)


# ---------------------------------------------------------------------- Markdown
def markdown(analysis, plots: Sequence[str | Path] = (), data: dict | None = None) -> str:
    """Markdown report of an analysis; ``plots`` are image files linked at the end.

    Args:
        analysis: The :class:`~pkm_pin.analysis.Analysis`.
        plots: Image files (e.g. from :func:`pkm_pin.plots.save_maps`); linked as given.
        data: :func:`report_data` of the same analysis, when already computed.
    """
    r = data if data is not None else report_data(analysis, plots)
    xyz, rpy = r["pose"]["xyz"], r["pose"]["rpy"]
    lines = [f"# {r['mechanism']}", ""]
    if r["description"]:
        lines += [r["description"], ""]
    u = r.get("length_unit", "m")
    lines += ["## Pose", "", f"| x [{u}] | y [{u}] | z [{u}] | roll [rad] | pitch [rad] | "
              "yaw [rad] |",
              "|---|---|---|---|---|---|",
              "| " + " | ".join(_num(v) for v in [*xyz, *rpy]) + " |", ""]
    lines += ["## Mobility", "",
              f"- degree of freedom: **{r['dof']}** ({r['motion_type']})",
              f"- Grübler–Kutzbach count: {r['grubler']}",
              f"- redundant constraints: {r['redundant_constraints']}",
              f"- idle motions: {r['idle_dof']}" + "".join(
                  f"\n  - {m}" for m in r["idle_motions"]),
              "", "Platform twists (ω; v_O) about the world origin:", "",
              "| # | twist (ω; v_O) | in words |", "|---|---|---|"]
    lines += [f"| {i + 1} | {_vec(b['screw'])} | {b['words']} |"
              for i, b in enumerate(r["motion_basis"])]
    lines += ["", "Constraint wrenches (f; m_O) on the platform:", ""]
    if r["constraint_basis"]:
        lines += ["| # | wrench (f; m_O) | in words |", "|---|---|---|"]
        lines += [f"| {i + 1} | {_vec(b['screw'])} | {b['words']} |"
                  for i, b in enumerate(r["constraint_basis"])]
    else:
        lines += ["none: the platform is free in space."]
    lines += ["", "## Actuation: A Δ t = B q̇_a", "",
              "Rows of A: the actuation wrenches (f; m_O), one per actuated joint.", ""]
    lines += _matrix_table(r["A"], r["actuated"], ["f_x", "f_y", "f_z", "m_x", "m_y", "m_z"])
    lines += ["", "B (diagonal):", ""]
    lines += _matrix_table(r["B"], r["actuated"], r["actuated"])
    lines += ["", "## Singularity", "", f"- class: **{r['singularity']}**",
              f"- constraint singular: {'yes' if r['constraint_singular'] else 'no'}"]
    if r["uncontrolled_twist"]:
        lines += [f"- uncontrolled twist: {r['uncontrolled_twist']}"]
    lines += ["", "| index | value |", "|---|---|"]
    lines += [f"| {k} | {_num(v)} |" for k, v in r["indices"].items()]
    tr = r.get("transmission")
    if tr is not None:
        lines += ["", "## Motion/force transmission", "", f"{tr['words']}.", "",
                  "| actuator | ITI | OTI |", "|---|---|---|"]
        lines += [f"| {a} | {_index(i, '—')} | {_index(o, '—')} |"
                  for a, i, o in zip(r["actuated"], tr["iti"], tr["oti"])]
        lines += ["", f"LTI = {_index(tr['lti'])} (good transmission: ≥ 0.7), "
                  f"CTI = {_index(tr['cti'])}"]
    lines += ["", "## Cross-check against the hand-written formulas", ""]
    if r["crosscheck"] is None:
        lines += ["No hand-written formulas exist for this mechanism."]
    else:
        lines += ["Largest dimensionless difference |Pinocchio − formulas|:", "",
                  "| quantity | difference |", "|---|---|"]
        lines += [f"| {k} | {v:.3g} |" for k, v in r["crosscheck"].items()]
    if r["plots"]:
        lines += ["", "## Plots", ""]
        lines += [f"![{Path(p).stem}]({p})" for p in r["plots"]]
    return "\n".join(lines) + "\n"


def _matrix_table(M, rows: Sequence[str], columns: Sequence[str]) -> list[str]:
    M = np.atleast_2d(np.asarray(M, dtype=float))
    if M.size == 0:
        return ["(empty)"]
    out = ["| | " + " | ".join(columns) + " |", "|---" * (len(columns) + 1) + "|"]
    out += [f"| {name} | " + " | ".join(_num(x) for x in row) + " |"
            for name, row in zip(rows, M)]
    return out


# --------------------------------------------------------------------------- text
def text(r: dict) -> str:
    """Plain-text report (the output of ``pkm-pin analyze``) from :func:`report_data`:
    the summary (DOF and motion type, Grübler count, singularity class, uncontrolled
    twist, indices; a non-finite index ``undefined``; the idle motions, one sentence
    each) before the tables."""
    out = [f"mechanism          {r['mechanism']}",
           f"pose               xyz {_list(r['pose']['xyz'])}  rpy {_list(r['pose']['rpy'])}",
           f"DOF                {r['dof']}  ({r['motion_type']})",
           f"Grübler count      {r['grubler']}  (redundant constraints: "
           f"{r['redundant_constraints']})",
           f"singularity        {r['singularity']}"
           + ("  (constraint singular)" if r["constraint_singular"] else "")]
    if r["uncontrolled_twist"]:
        out += [f"uncontrolled twist {r['uncontrolled_twist']}"]
    out += ["indices            " + ", ".join(
        f"{k} = {v:.6g}" if v is not None and np.isfinite(v) else f"{k} = undefined"
        for k, v in r["indices"].items())]
    idle = r.get("idle_motions") or []
    out += ["idle motions       " + (f"{len(idle)} (with every actuated joint locked):"
                                     if idle else "none")] + [f"    {m}" for m in idle]
    out += ["platform twists (ω; v_O):"]
    out += [f"    {_row(b['screw'])}   {b['words']}" for b in r["motion_basis"]]
    out += ["constraint wrenches (f; m_O):"]
    out += [f"    {_row(b['screw'])}   {b['words']}" for b in r["constraint_basis"]] or ["    none"]
    out += [f"actuated joints    {', '.join(r['actuated'])}",
            "A (actuation wrenches (f; m_O), A Δ t = B q̇_a):"]
    out += [f"    {_row(row)}" for row in r["A"]]
    out += ["B:"] + [f"    {_row(row)}" for row in r["B"]]
    tr = r.get("transmission")
    if tr is not None:
        out += [f"transmission       LTI = {_index(tr['lti'], fmt='.3g')}, "
                f"CTI = {_index(tr['cti'], fmt='.3g')}: {tr['words']}"]
    if r["crosscheck"] is None:
        out += ["cross-check        no hand-written formulas for this mechanism"]
    else:
        parts = ", ".join(f"{k} {v:.2g}" for k, v in r["crosscheck"].items())
        out += ["cross-check        max |Pinocchio − formulas| = "
                f"{r['crosscheck_max_error']:.3g}  ({parts})"]
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
