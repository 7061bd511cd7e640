"""Reports of a general linkage (:class:`~pkm_pin.linkage.Linkage`) at one configuration:
plain data (JSON), text and Markdown; and the maps of ``pkm-pin map`` over two actuated
coordinates.

A linkage report holds what :class:`~pkm_pin.linkage.LinkageAnalysis` knows about one
assembly: the whole tree's configuration (joint by joint), the output frame and its pose,
the mobility (DOF, idle DOF with each idle motion in words, redundant closure equations,
Grübler's count, the actuated joints that can be driven independently), the output's
motion type with a readable basis of its twists and of its constraint wrenches (see
:func:`pkm_pin.report.readable_basis`, about the output frame's origin), ``A`` and ``B``
of ``A Δ t = B q̇_a``, the singularity class and the indices.

Conventions as :mod:`pkm_pin.report`: screws axis-first about the world origin, twists
``(ω; v_O)``, wrenches ``(f; m_O)``; lengths [m], angles [rad]. Poses are the output
frame's placement: ``xyz`` [m] and URDF ``rpy`` [rad]. In the plain data, an index that
is undefined (NaN) or infinite is ``None`` (JSON ``null``), so the JSON is standard.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pinocchio as pin

from .model.closure_model import duplicate_closures
from .report import (
    _index,
    _list,
    _num,
    _row,
    _vec,
    failed_lines,
    finite_or_none,
    optional,
    readable_basis,
    transmission_data,
)

#: Colours of the singularity classes in the maps.
CLASS_COLOURS = {"none": "#ffffff", "I": "#f4a582", "II": "#92c5de", "III": "#b2abd2"}
#: Level of the forward and inverse indices drawn as iso-lines on the class map.
ISO_LEVEL = 0.05


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
    """Plain data of a :class:`~pkm_pin.linkage.LinkageAssembly`: ``mechanism``,
    ``output``, ``output_is_point``, ``pose`` (the output frame's), ``actuated``,
    ``q_actuated``, ``q`` (the whole tree, Pinocchio's joint order, full precision),
    ``joint_names``, ``joints`` (:func:`joint_values`), ``actuator_matches`` (each
    actuator identifier of the file and the joints it picked), ``residual`` and ``closures``
    (name, kind, frames and residual of each)."""
    model = link.model
    return {
        "kind": "linkage",
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


def linkage_report_data(link, assembly, analysis=None, plots: Sequence[str | Path] = ()) -> dict:
    """Plain-data summary (JSON-ready) of a linkage at an assembly.

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
    analysis basis of the output twists), ``motion_basis`` and ``constraint_basis``
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
        "dof": an.dof,
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
        "platform_twists": an.platform_twists.tolist(),
        "motion_basis": [b.as_dict() for b in motion],
        "constraint_basis": [b.as_dict(wrench=True) for b in constraints],
        "A": an.A.tolist(),
        "B": an.B.tolist(),
        "singularity": an.singularity,
        "constraint_singular": an.constraint_singular,
        "indices": {k: finite_or_none(v) for k, v in an.indices.items()},
        "indices_undefined": undefined_indices(link, an),
        "transmission": optional("transmission", lambda: _transmission(link, assembly),
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
    return (f"structure          base–legs–platform machine, {len(s['legs'])} legs ({kinds}); "
            "--backend legs analyses it per leg (seed 000's indices, each actuation wrench "
            "orthogonal to its own leg's constraints)")


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


def linkage_text(r: dict, frames: Sequence[str] = (), likely: Sequence[str] = ()) -> str:
    """Plain-text report (the output of ``pkm-pin analyze`` for a linkage) from
    :func:`linkage_report_data`; ``frames``: the choices of ``--output`` to suggest,
    ``likely`` those named first (:func:`output_hint`)."""
    idx = ", ".join(f"{k} = {'undefined' if v is None else f'{v:.6g}'}"
                    for k, v in r["indices"].items())
    out = [f"mechanism          {r['mechanism']}  (linkage: {len(r['joints'])} joints, "
           f"{len(r['closures'])} closure{'s' if len(r['closures']) != 1 else ''}"
           + ("; no closure: a tree, analysed as a serial chain)" if not r["closures"] else ")"),
           output_line(r, frames, likely)] + [line for line in (structure_line(r),) if line] + [
           f"note               {n}" for n in r.get("notes", [])] + [
           f"output pose        xyz {_list(r['pose']['xyz'])}  rpy {_list(r['pose']['rpy'])}"]
    out += [f"DOF                {r['dof']}  (idle DOF {r['idle_dof']}; output motion "
            f"{r['motion_type']}; singularity {r['singularity']})",
            "idle motions       " + ("none" if not r["idle_motions"] else
                                     f"{r['idle_dof']} (with every actuated joint locked):")]
    out += [f"    {m}" for m in r["idle_motions"]]
    if r.get("singular_words"):
        out += [f"singular           {r['singular_words']}"]
    out += submechanism_lines(r)
    out += [f"duplicate closure  {a!r} repeats {b!r}: its rows are redundant"
            for a, b in r.get("duplicate_closures", [])]
    out += [f"Grübler count      {r['grubler']}  (redundant closure equations: "
            f"{r['redundant_constraints']})",
            f"actuated joints    {', '.join(r['actuated'])} = {_list(r['q_actuated'])}"
            + _matches_words(r.get("actuator_matches", {})),
            f"independent        {', '.join(r['independent_actuators']) or 'none'}",
            "joints (q):"] + joints_lines(r) + [f"output twists ({r['output']}; ω; v_O):"]
    out += [f"    {_row(b['screw'])}   {b['words']}" for b in r["motion_basis"]] or ["    none"]
    out += ["constraint wrenches on the output (f; m_O):"]
    out += [f"    {_row(b['screw'])}   {b['words']}" for b in r["constraint_basis"]] or ["    none"]
    out += ["A (actuation wrenches (f; m_O), A Δ t = B q̇_a):"]
    out += [f"    {_row(row)}" for row in r["A"]]
    out += ["B:"] + [f"    {_row(row)}" for row in r["B"]]
    out += [f"singularity        {r['singularity']}", f"indices            {idx}"]
    out += [f"    {k} undefined ({why})" for k, why in r.get("indices_undefined", {}).items()]
    tr = r.get("transmission")
    if tr is not None:
        out += [f"transmission       LTI = {_index(tr['lti'], fmt='.3g')}: {tr['words']}"]
    out += failed_lines(r)
    out += [f"plot               {p}" for p in r.get("plots", [])]
    return "\n".join(out)


def _transmission(link, assembly) -> dict | None:
    """:meth:`Linkage.transmission` as plain data (ITI/OTI per actuator, LTI, CTI per
    actuator side and their minimum, the weakest in words); ``None`` where it is not defined."""
    from .errors import PkmError

    try:
        tr = link.transmission(assembly)
    except (PkmError, np.linalg.LinAlgError):
        return None
    return transmission_data(tr)


def _matches_words(matches: dict) -> str:
    """What the file's actuator identifiers picked, where one is not a joint's own name
    (``"  (name_mot 'mot' picked mot1, mot2)"``); ``""`` otherwise."""
    picked = [f"{name!r} picked {', '.join(joints)}" for name, joints in matches.items()
              if list(joints) != [name]]
    return f"  (identifiers: {'; '.join(picked)})" if picked else ""


def linkage_markdown(r: dict) -> str:
    """Markdown report of a linkage from :func:`linkage_report_data`: the summary
    (output, DOF, idle DOF, motion, class, the independent sub-mechanisms, duplicate
    closures, failed optional sections) before the joint table and the matrices."""
    how = "its origin, as a point" if r["output_is_point"] else "as a body"
    lines = [f"# {r['mechanism']}", "", "## Summary", "",
             f"- output frame `{r['output']}` ({how}) at xyz {_vec(r['pose']['xyz'])} m, "
             f"rpy {_vec(r['pose']['rpy'])} rad",
             f"- DOF **{r['dof']}**, idle DOF {r['idle_dof']}, output motion "
             f"{r['motion_type']}, singularity **{r['singularity']}**"]
    lines += [f"- duplicate closure `{a}` repeats `{b}`: its rows are redundant"
              for a, b in r.get("duplicate_closures", [])]
    lines += [f"- {name}: not computed ({why})"
              for name, why in r.get("failed_sections", {}).items()]
    lines += _submechanisms_markdown(r.get("submechanisms") or [])
    lines += ["", "## Configuration", "", "| joint | q |", "|---|---|"]
    lines += [f"| {n} | {_vec(v)} |" for n, v in r["joints"].items()]
    lines += ["", "## Mobility", "",
              f"- degree of freedom: **{r['dof']}**, output motion {r['motion_type']}",
              f"- idle degrees of freedom: {r['idle_dof']}"]
    lines += [f"  - {m}" for m in r["idle_motions"]]
    if r.get("singular_words"):
        lines += [f"- {r['singular_words']}"]
    lines += [f"- Grübler–Kutzbach count: {r['grubler']}",
              f"- redundant closure equations: {r['redundant_constraints']}",
              f"- independent actuators: {', '.join(r['independent_actuators']) or 'none'}",
              "", "Output twists (ω; v_O) about the world origin:", "",
              "| # | twist (ω; v_O) | in words |", "|---|---|---|"]
    lines += [f"| {i + 1} | {_vec(b['screw'])} | {b['words']} |"
              for i, b in enumerate(r["motion_basis"])]
    lines += ["", "Constraint wrenches (f; m_O) on the output:", "",
              "| # | wrench (f; m_O) | in words |", "|---|---|---|"]
    lines += [f"| {i + 1} | {_vec(b['screw'])} | {b['words']} |"
              for i, b in enumerate(r["constraint_basis"])]
    lines += ["", "## Actuation: A Δ t = B q̇_a", "", "| joint | A row (f; m_O) | B |",
              "|---|---|---|"]
    lines += [f"| {n} | {_vec(a)} | {_num(b[k])} |"
              for k, (n, a, b) in enumerate(zip(r["actuated"], r["A"], r["B"]))]
    lines += ["", "## Singularity", "", f"- class: **{r['singularity']}**", "",
              "| index | value |", "|---|---|"]
    lines += [f"| {k} | {'undefined' if v is None else _num(v)} |"
              for k, v in r["indices"].items()]
    if r["plots"]:
        lines += ["", "## Plots", ""] + [f"![{Path(p).stem}]({p})" for p in r["plots"]]
    return "\n".join(lines) + "\n"


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


# ------------------------------------------------------------------------- maps
def save_linkage_maps(data: Mapping, prefix: str | Path, title: str = "") -> list[Path]:
    """PNG maps of a sweep over actuated coordinates (``pkm-pin map`` of a linkage).

    Two varied coordinates (``u``, ``v`` and arrays shaped (n_v, n_u)): writes
    ``PREFIX_singularity.png`` (the class of each grid point, grey where it does not
    assemble, with the iso-lines :data:`ISO_LEVEL` of the forward and inverse indices) and
    ``PREFIX_indices.png`` (the forward and inverse indices). One coordinate (``u`` and
    arrays (n_u,)): ``PREFIX_indices.png`` only, the two indices along it.

    Returns:
        The paths written.
    """
    from .plots import _figure

    prefix = Path(prefix)
    labels = [str(x) for x in data["labels"]]
    head = f"{title}: " if title else ""
    indices = prefix.with_name(prefix.name + "_indices.png")
    if "v" not in data:
        fig, ax = _figure(f"{head}forward and inverse indices", [labels[0], "index"])
        ax.set_facecolor("white")
        for key, colour in (("forward", "#2166ac"), ("inverse", "#b2182b")):
            ax.plot(data["u"], data[key], color=colour, label=f"{key} index")
        ax.legend(fontsize=8)
        fig.savefig(indices)
        return [indices]
    sing = prefix.with_name(prefix.name + "_singularity.png")
    _class_map(data, labels, f"{head}singularity classes", sing)
    _index_maps(data, labels, head, indices)
    return [sing, indices]


def _class_map(data: Mapping, labels: list, title: str, path: Path) -> None:
    from matplotlib.colors import ListedColormap
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    from .plots import _contour, _figure

    u, v, ok = data["u"], data["v"], np.asarray(data["converged"], bool)
    cls = np.asarray(data["singularity"]).astype(str)
    names = list(CLASS_COLOURS)
    codes = np.full(cls.shape, np.nan)
    for k, name in enumerate(names):
        codes[ok & (cls == name)] = k
    fig, ax = _figure(title, labels)
    ax.pcolormesh(u, v, np.ma.masked_invalid(codes), cmap=ListedColormap(list(
        CLASS_COLOURS.values())), vmin=-0.5, vmax=len(names) - 0.5, shading="nearest")
    handles = [Patch(facecolor=c, edgecolor="0.5", label=f"class {n}")
               for n, c in CLASS_COLOURS.items() if np.any(ok & (cls == n))]
    for key, colour in (("forward", "k"), ("inverse", "#b2182b")):
        if _contour(ax, u, v, np.where(ok, data[key], np.nan), ISO_LEVEL, colors=colour,
                    linewidths=1.2):
            handles.append(Line2D([], [], color=colour, lw=1.2,
                                  label=f"{key} index = {ISO_LEVEL:g}"))
    handles.append(Patch(color="0.82", label="does not assemble"))
    ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.85)
    fig.savefig(path)


def _index_maps(data: Mapping, labels: list, head: str, path: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11.0, 4.8), dpi=110, layout="constrained")
    FigureCanvasAgg(fig)
    ok = np.asarray(data["converged"], bool)
    for k, key in enumerate(("forward", "inverse")):
        ax = fig.add_subplot(1, 2, k + 1)
        ax.set_facecolor("0.82")
        mesh = ax.pcolormesh(data["u"], data["v"],
                             np.ma.masked_invalid(np.where(ok, data[key], np.nan)),
                             vmin=0.0, vmax=1.0, cmap="viridis", shading="nearest")
        fig.colorbar(mesh, ax=ax)
        ax.set_xlabel(labels[0])
        ax.set_ylabel(labels[1])
        ax.set_title(f"{head}{key} index (0: singular)")
    fig.savefig(path)
